// The robot model's part of an FMU instance's state (robot_model.hpp): what an FMU state carries beside the
// core's values and time.
#pragma once

#include "fmu/core/model.hpp"
#include "model/common/types.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp::fmu {

// The robot's part of an FMU state.
struct RobotState final : ModelState {
  PlantState plant;            // after initialisation: the plant's state (in a snapshot only; live in the plant)
  bool has_last_step = false;  // a step was done since initialisation: the velocity can be estimated
  JointVector last_q_desired;  // q_desired and time of that step
  double last_step_time = 0.0;
  bool has_earlier_step = false;  // and a step before that one: the velocity is estimated to second order
  JointVector earlier_q_desired;  // q_desired and time of that earlier step
  double earlier_step_time = 0.0;
  bool has_earliest_step = false;  // and one before that: a step of the inputs shows against the three before
  JointVector earliest_q_desired;  // q_desired and time of that earliest step
  double earliest_step_time = 0.0;
  // compensation = dynamic: the drive inverse filter after the samples of the steps done (not the current one)
  OnlineDynamicState dynamic;
  Vector6 applied_wrench = Vector6::Zero();  // what the plant was last given
  bool desired_inputs_set = false;           // the master set a q_desired or qd_desired input since instantiation
  bool demo = false;                         // the robot follows the built-in demo move (decided at initialisation)

  // As instantiated, for `dof` joints.
  static RobotState atStart(int dof);
};

}  // namespace jointcomp::fmu
