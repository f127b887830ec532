// The robot model's part of FMU states (robot_model.hpp): taken, restored, written and read back with
// every field checked. The core writes its own part before it (fmu/core/state_bytes.cpp).
#include "fmu/core/state_bytes.hpp"
#include "fmu/robot/robot_model.hpp"

namespace jointcomp::fmu {

namespace {

const RobotState& robotState(const ModelState& state) { return static_cast<const RobotState&>(state); }

void writePlantState(const PlantState& p, StateWriter& w) {
  w.put(p.time);
  w.put(p.y);
  w.put(p.reference);
  w.put(p.reference_velocity);
  w.put(p.reference_acceleration);
  w.put(p.feedforward);
  w.put(p.feedforward_rate);
  w.put(p.reference_time);
  w.put(p.blend_offset);
  w.put(p.blend_offset_velocity);
  w.put(p.blend_offset_acceleration);
  w.put(p.feedforward_offset);
  w.put(p.feedforward_offset_rate);
  w.put(p.blend_duration);
  for (int k = 0; k < 6; ++k) w.put(p.tool_wrench[k]);
  w.put(p.payload_mass);
  for (int k = 0; k < 3; ++k) w.put(p.payload_com[k]);
}

void readPlantState(StateReader& r, std::uint32_t n, PlantState& p) {
  p.time = r.finite("the plant's time");
  r.vector(p.y, 5 * n, "the plant's state vector");
  r.vector(p.reference, n, "the plant's reference");
  r.vector(p.reference_velocity, n, "the plant's reference velocity");
  r.vector(p.reference_acceleration, n, "the plant's reference acceleration");
  r.vector(p.feedforward, n, "the plant's feed-forward");
  r.vector(p.feedforward_rate, n, "the plant's feed-forward rate");
  p.reference_time = r.finite("the plant's reference time");
  r.vector(p.blend_offset, n, "the plant's reference blend offset");
  r.vector(p.blend_offset_velocity, n, "the plant's reference blend offset velocity");
  r.vector(p.blend_offset_acceleration, n, "the plant's reference blend offset acceleration");
  r.vector(p.feedforward_offset, n, "the plant's feed-forward blend offset");
  r.vector(p.feedforward_offset_rate, n, "the plant's feed-forward blend offset rate");
  p.blend_duration = r.finite("the plant's reference blend duration");
  if (p.blend_duration < 0.0) throw Error("the plant's reference blend duration is negative");
  for (int k = 0; k < 6; ++k) p.tool_wrench[k] = r.finite("the plant's tool wrench");
  p.payload_mass = r.finite("the plant's payload mass");
  for (int k = 0; k < 3; ++k) p.payload_com[k] = r.finite("the plant's payload centre");
}

void readSteps(StateReader& r, std::uint32_t dof, RobotState& s) {
  s.has_last_step = r.flag("the last-step flag");
  r.vector(s.last_q_desired, dof, "the last desired positions");
  s.last_step_time = r.finite("the last step time");
  s.has_earlier_step = r.flag("the earlier-step flag");
  r.vector(s.earlier_q_desired, dof, "the earlier desired positions");
  s.earlier_step_time = r.finite("the earlier step time");
  s.has_earliest_step = r.flag("the earliest-step flag");
  r.vector(s.earliest_q_desired, dof, "the earliest desired positions");
  s.earliest_step_time = r.finite("the earliest step time");
}

void readDynamic(StateReader& r, std::uint32_t dof, OnlineDynamicState& d) {
  d.started = r.flag("the dynamic compensation's start flag");
  d.time = r.finite("the dynamic compensation's time");
  r.vector(d.correction, dof, "the dynamic compensation's correction");
  r.vector(d.demand_at_start, dof, "the dynamic compensation's initial demand");
  r.vector(d.demand, dof, "the dynamic compensation's demand");
  r.vector(d.delta, dof, "the dynamic compensation's drive offset");
  r.vector(d.integral, dof, "the dynamic compensation's drive integral");
}

}  // namespace

std::unique_ptr<ModelState> RobotModel::newState() const {
  return std::make_unique<RobotState>(RobotState::atStart(dof_));
}

void RobotModel::saveState(const CoreState& state, ModelState& into) const {
  RobotState& s = static_cast<RobotState&>(into);
  s = live_;
  if (state.initialized) s.plant = plant_->saveState();
  if (!s.has_last_step) s.last_q_desired = JointVector::Zero(dof_);  // not used: written as zeros
  if (!s.has_earlier_step) s.earlier_q_desired = JointVector::Zero(dof_);
  if (!s.has_earliest_step) s.earliest_q_desired = JointVector::Zero(dof_);
}

void RobotModel::restoreState(const CoreState& state, const ModelState& from) {
  const RobotState& s = robotState(from);
  CoreState restored = state;  // built from the state's values; its initialized flag is the state's
  if (state.initialized) {
    ensureModels(restored);
    plant_->restoreState(s.plant);
  } else if (built_) {
    ensureCompensator(restored);
  }
  live_ = s;
  reference_valid_ = false;
  outputs_valid_ = 0;
  updateCoreFlags();
}

void RobotModel::writeState(const CoreState& state, const ModelState& from, StateWriter& w) const {
  const RobotState& s = robotState(from);
  if (state.initialized) writePlantState(s.plant, w);
  w.flag(s.has_last_step);
  w.put(s.last_q_desired);
  w.put(s.last_step_time);
  w.flag(s.has_earlier_step);
  w.put(s.earlier_q_desired);
  w.put(s.earlier_step_time);
  w.flag(s.has_earliest_step);
  w.put(s.earliest_q_desired);
  w.put(s.earliest_step_time);
  w.flag(s.dynamic.started);
  w.put(s.dynamic.time);
  for (const JointVector* v :
       {&s.dynamic.correction, &s.dynamic.demand_at_start, &s.dynamic.demand, &s.dynamic.delta, &s.dynamic.integral})
    w.put(*v);
  for (int k = 0; k < 6; ++k) w.put(s.applied_wrench[k]);
  w.flag(s.desired_inputs_set);
  w.flag(s.demo);
}

void RobotModel::readState(const CoreState& state, ModelState& into, StateReader& r) const {
  RobotState& s = static_cast<RobotState&>(into);
  const auto dof = static_cast<std::uint32_t>(dof_);
  if (state.initialized) readPlantState(r, dof, s.plant);
  readSteps(r, dof, s);
  readDynamic(r, dof, s.dynamic);
  for (int k = 0; k < 6; ++k) s.applied_wrench[k] = r.finite("the applied wrench");
  s.desired_inputs_set = r.flag("the desired-inputs flag");
  s.demo = r.flag("the demo flag");
}

}  // namespace jointcomp::fmu
