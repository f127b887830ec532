// The robot model behind an FMU instance (internal to fmu/): what the resources hold and what is built from
// them, shared by the FMI plumbing (instance.cpp) and the model's functions (instance_model.cpp).
#pragma once

#include <memory>
#include <vector>

#include "fmu/instance.hpp"
#include "fmu/variable_binding.hpp"
#include "model/compensation/compensator.hpp"
#include "model/plant/dynamic_compensation.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp::fmu {

struct Instance::RobotModels {
  RobotModels(std::shared_ptr<const Robot> loaded_robot, ParameterSet loaded, const VariableTable& table)
      : robot(std::move(loaded_robot)),
        base(std::move(loaded)),
        binding(base, *robot, table),
        compensation_ctx(robot->dof()),
        prediction_ctx(robot->dof()),
        prediction_ws(*robot) {}

  std::shared_ptr<const Robot> robot;
  ParameterSet base;  // the parameter file as shipped
  VariableBinding binding;

  // Built from the fixed parameters (built_values), rebuilt when they change.
  bool built = false;
  std::vector<double> built_values;
  std::unique_ptr<JointErrorModel> nominal;
  std::unique_ptr<FlexibleJointPlant> plant;
  std::vector<DriveParameters> drives;               // the plant's drives: the dynamic mode inverts their tracking
  std::unique_ptr<Compensator> compensator;          // after nominal: it refers to it
  std::unique_ptr<OnlineDynamicCompensator> online;  // compensation = dynamic; refers to nominal too
  int compensator_mode = -1;

  JointContext compensation_ctx;
  JointContext prediction_ctx;
  JointErrorWorkspace prediction_ws;
};
// The reference parameter's items (ReferenceSource) and the CompensationMode item "dynamic".
constexpr double kReferenceAuto = 0.0;
constexpr double kReferenceDemo = 2.0;
constexpr int kCompensationDynamic = 3;

// to = from, n joints: a plain loop where Eigen's assignment of a vector of run-time size is a call to
// memcpy or a loop with checks for aliasing. The two never overlap (__restrict).
inline void copyJointValues(const double* __restrict from, double* __restrict to, int n) {
  for (int j = 0; j < n; ++j) to[j] = from[j];
}
inline void copyJoints(const JointVector& from, JointVector& to) {
  to.resize(from.size());
  copyJointValues(from.data(), to.data(), static_cast<int>(from.size()));
}

inline Vector6 wrenchOf(const std::vector<double>& values, const Roles& roles) {
  Vector6 w;
  for (int k = 0; k < 6; ++k) w[k] = values[roles.wrench[k]];
  return w;
}

}  // namespace jointcomp::fmu
