// The model inside the FMU (Reference-FMUs' model.c, behind the generic core of fmu/core): the robot and
// parameter set from the resources, the flexible-joint plant with the compensator in front of it, its
// state, the reference for the current inputs, the outputs, and one communication step.
//
// What one communication step does (the C++ sequence a test can replay on FlexibleJointPlant and
// Compensator directly, bit for bit):
//   at time t (the importer's currentCommunicationPoint) with inputs q_desired, qd_desired, tool_wrench:
//   1. v = qd_desired if use_velocity_inputs, else the slope at t of the parabola through q_desired at the
//      last three communication points (after the first step the change over that step; 0 on the first),
//      and 0 (with the acceleration of step 2) for a joint whose q_desired stepped (held_steps.hpp);
//   2. Q_ref = q_desired when compensation is none, else Compensator(nominal, mask).compensate() with
//      ctx.q = q_desired, ctx.velocity = v, ctx.time = t, ctx.tool_wrench = tool_wrench if
//      compensate_wrench else 0; mask = nominal.loadsAnd({"compliance"}) (mode 1, the paper's stiffness
//      correction) or nominal.allEffects() (mode 2: every effect of the parameter file, the paper's
//      compliance and transmission error for the shipped RX170, and what discovery added to a file);
//      compensation = dynamic (3): OnlineDynamicCompensator(nominal, drives).compensate() from the state
//      after the previous steps' samples, with q_desired, v and a = qdd_desired if use_velocity_inputs, else
//      the second derivative of the parabola through q_desired at the last three communication points (0
//      before there are three); it gives Q_ref and its velocity, which replaces v below; its state moves on
//      only when the step succeeds;
//   3. plant.setToolWrench(tool_wrench) if it differs from the wrench last applied;
//   4. plant.setReference(Q_ref, v); plant.advance(t + h).
// Initialisation (exitInitializationMode): plant.setToolWrench(tool_wrench); plant.reset(Q_ref, t0), Q_ref
// as in 1-2 with no previous step (v = 0 unless use_velocity_inputs).
// The plant's truth is the parameter file with the plant.* parameters applied; the compensator's nominal
// model is the same file with the compensator.* parameters applied.
#pragma once

#include <memory>
#include <vector>

#include "fmu/core/model.hpp"
#include "fmu/robot/robot_state.hpp"
#include "fmu/robot/variable_binding.hpp"
#include "model/compensation/compensator.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp::fmu {

// Groups of outputs computed together, lazily, as bits (a get computes only the groups it reads).
enum OutputGroup : unsigned {
  kLinkOutputs = 1u,
  kToolOutputs = 2u,
  kPredictedOutputs = 4u,
  kReferenceOutputs = 8u,
  kMotorOutputs = 16u,
  kLinkVelocityOutputs = 32u,
};

// The reference parameter's items (ReferenceSource) and the CompensationMode item "dynamic".
constexpr double kReferenceAuto = 0.0;
constexpr double kReferenceDemo = 2.0;
constexpr int kCompensationDynamic = 3;

class RobotModel final : public Model {
public:
  RobotModel(std::shared_ptr<const Robot> robot, ParameterSet parameters, VariableTable table);

  const VariableTable& table() const override { return table_; }
  VariableTraits traits(int index) const override;
  void setTolerance(CoreState& state, double tolerance) override;
  void initialize(CoreState& state) override;
  void startSteps(CoreState& state) override;
  Status computeOutputs(CoreState& state, unsigned groups, const char* function, ModelLog& log) override;
  Status doStep(CoreState& state, double end, const char* function, ModelLog& log) override;
  void onSet(CoreState& state, int index, bool changed, bool before_step) override;
  std::string restriction(const CoreState& state) const override;
  void reset(const CoreState& state) override;

  std::unique_ptr<ModelState> newState() const override;
  void saveState(const CoreState& state, ModelState& into) const override;
  void restoreState(const CoreState& state, const ModelState& from) override;
  std::uint32_t stateShape() const override { return static_cast<std::uint32_t>(dof_); }
  void writeState(const CoreState& state, const ModelState& from, StateWriter& writer) const override;
  void readState(const CoreState& state, ModelState& into, StateReader& reader) const override;

private:
  bool fixedParametersDiffer(const std::vector<double>& values) const;
  // Builds the models, the plant and the compensator from the fixed parameters when they changed since
  // the last build (or were never built). Throws jointcomp::Error naming the parameter at fault.
  void ensureModels(CoreState& state);
  void ensureCompensator(const CoreState& state);
  // Q_ref and v for the current inputs, cached until an input or the compensation mode changes.
  Status ensureReference(const CoreState& state, const char* function, ModelLog& log);
  Status compensateReference(const CoreState& state, const JointVector& velocity, const JointVector& acceleration,
                             const char* function, ModelLog& log);
  // A step the plant could not finish (solver failure, limits left): discarded, with the reason.
  Status discardStep(const char* function, const char* why, ModelLog& log);
  void computePlantOutputs(CoreState& state, unsigned missing);
  void computePredictedOutputs(CoreState& state, const double* link, const double* link_velocity, const double* motor);
  // Drops the caches that follow from the values when the core said they changed.
  void absorbValueChanges() {
    if (!values_changed_) return;
    values_changed_ = false;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
  }
  // The robot's variables by role (inline: an offset from this, no reference to load).
  const Roles& roles() const { return table_.roles; }
  // The inline flags the core reads, from live_.
  void updateCoreFlags() {
    watches_reals_ = !live_.desired_inputs_set;
    restricts_inputs_ = live_.demo;
  }

  VariableTable table_;
  int dof_;
  std::vector<bool> fixed_parameter_;
  std::vector<bool> desired_input_;

  std::shared_ptr<const Robot> robot_;
  ParameterSet base_;  // the parameter file as shipped
  VariableBinding binding_;

  // Built from the fixed parameters (built_values), rebuilt when they change.
  bool built_ = false;
  std::vector<double> built_values_;
  std::unique_ptr<JointErrorModel> nominal_;
  std::unique_ptr<FlexibleJointPlant> plant_;
  std::vector<DriveParameters> drives_;               // the plant's drives: the dynamic mode inverts their tracking
  std::unique_ptr<Compensator> compensator_;          // after nominal: it refers to it
  std::unique_ptr<OnlineDynamicCompensator> online_;  // compensation = dynamic; refers to nominal too
  int compensator_mode_ = -1;

  JointContext compensation_ctx_;
  JointContext prediction_ctx_;
  JointErrorWorkspace prediction_ws_;

  RobotState live_;  // the robot's part of the instance's state (the plant's own is in plant_)
  // Derived from the values and live_, cached:
  bool reference_valid_ = false;
  unsigned outputs_valid_ = 0;        // OutputGroup bits
  JointVector reference_;             // Q_ref for the current inputs
  JointVector reference_velocity_;    // v for the current inputs
  JointVector planned_;               // Q_theo: the q_desired inputs, or the demo move
  OnlineDynamicState dynamic_after_;  // compensation = dynamic: the filter with the current sample
};

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
