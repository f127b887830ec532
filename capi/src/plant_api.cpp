// Plant handles: the flexible-joint plant, its inputs, outputs, state and snapshots.
#include <algorithm>

#include "api_support.hpp"
#include "json_options.hpp"
#include "model/plant/plant_options_by_name.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

// Snapshot layout (doubles): format, n, time, y (5 n), reference, reference velocity, reference
// acceleration, feed-forward, feed-forward rate (n each), reference time, tool wrench (6), payload mass,
// payload centre (3). The leading format and n let a restore reject a snapshot it cannot read.
constexpr double kSnapshotFormat = 1.0;

std::int64_t snapshotSize(int n) { return 10 * static_cast<std::int64_t>(n) + 14; }

void appendJoints(std::vector<double>& out, const JointVector& values) {
  out.insert(out.end(), values.data(), values.data() + values.size());
}

JointVector takeJoints(const double*& cursor, int n) {
  JointVector values = Eigen::Map<const Eigen::VectorXd>(cursor, n);
  cursor += n;
  return values;
}

template <class Read>
void readJoints(jc_plant* plant, double* values, int32_t values_len, Read read) {
  jc_plant& handle = plantHandle(plant);
  requireOutput(values, values_len, handle.plant->dof(), "values", "the robot's number of joints");
  const std::lock_guard<std::mutex> lock(handle.mutex);
  copyJoints(read(*handle.plant), values);
}

// A plant of the robot with the options of options_json (NULL: the defaults), by the names of
// kPlantOptionsByName, the FMU's too.
void createPlant(jc_robot* robot, const char* options_json, jc_plant** plant) {
  jc_robot& source = robotHandle(robot);
  requirePointer(plant, "plant");
  if (source.drives.empty()) invalid("the robot's parameters have no \"plant\" object (drives and controller gains)");
  PlantOptions options;
  readOptions(options_json, [&options](JsonFields& fields) {
    for (const PlantOptionByName& option : kPlantOptionsByName) {
      if (!fields.has(option.name)) continue;
      // The plant checks each value's range and names the option.
      switch (option.kind) {
        case PlantOptionByName::Kind::Switch: option.set(options, fields.flagOr(option.name, false) ? 1.0 : 0.0); break;
        case PlantOptionByName::Kind::Integer: option.set(options, fields.integer(option.name)); break;
        case PlantOptionByName::Kind::Number: option.set(options, fields.number(option.name)); break;
      }
    }
  });
  auto created = std::make_unique<FlexibleJointPlant>(source.model, source.drives, options);
  *plant = publish(std::make_unique<jc_plant>(std::move(created)));
}

}  // namespace

extern "C" {

jc_status jc_plant_create(jc_robot* robot, jc_plant** plant) {
  return CAPI_ENTRY({ createPlant(robot, nullptr, plant); });
}

jc_status jc_plant_create_with_options(jc_robot* robot, const char* options_json, jc_plant** plant) {
  return CAPI_ENTRY({ createPlant(robot, options_json, plant); });
}

jc_status jc_plant_free(jc_plant* plant) {
  return CAPI_ENTRY({ freeHandle(plant, "plant"); });
}

jc_status jc_plant_dof(jc_plant* plant, int32_t* dof) {
  return CAPI_ENTRY({
    const jc_plant& handle = plantHandle(plant);
    requirePointer(dof, "dof");
    *dof = handle.plant->dof();
  });
}

jc_status jc_plant_reset(jc_plant* plant, const double* command, int32_t command_len, double start_time) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const JointVector commanded = jointInput(command, command_len, handle.plant->dof(), "command");
    finiteScalar(start_time, "start_time");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->reset(commanded, start_time);
  });
}

jc_status jc_plant_set_reference(jc_plant* plant, const double* position, int32_t position_len, const double* velocity,
                                 int32_t velocity_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const int n = handle.plant->dof();
    const JointVector target = jointInput(position, position_len, n, "position");
    const JointVector moving = jointInput(velocity, velocity_len, n, "velocity");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->setReference(target, moving);
  });
}

jc_status jc_plant_set_tool_wrench(jc_plant* plant, const double* wrench, int32_t wrench_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const Vector6 value = vector6Input(wrench, wrench_len, "wrench");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->setToolWrench(value);
  });
}

jc_status jc_plant_set_payload(jc_plant* plant, double mass, const double* com, int32_t com_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    if (!(finiteScalar(mass, "mass") >= 0.0)) invalid("mass is negative");
    const Eigen::Vector3d centre = vector3Input(com, com_len, "com");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->setPayload(mass, centre);
  });
}

jc_status jc_plant_advance(jc_plant* plant, double end_time) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    finiteScalar(end_time, "end_time");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->advance(end_time);
  });
}

jc_status jc_plant_set_watchdog(jc_plant* plant, double tracking_envelope_rad, double joint_limit_margin_rad) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->setWatchdog(tracking_envelope_rad, joint_limit_margin_rad);
  });
}

jc_status jc_plant_time(jc_plant* plant, double* time) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    requirePointer(time, "time");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    *time = handle.plant->time();
  });
}

jc_status jc_plant_link_positions(jc_plant* plant, double* values, int32_t values_len) {
  return CAPI_ENTRY(
      { readJoints(plant, values, values_len, [](FlexibleJointPlant& p) { return p.linkPositions(); }); });
}

jc_status jc_plant_link_velocities(jc_plant* plant, double* values, int32_t values_len) {
  return CAPI_ENTRY(
      { readJoints(plant, values, values_len, [](FlexibleJointPlant& p) { return p.linkVelocities(); }); });
}

jc_status jc_plant_motor_positions(jc_plant* plant, double* values, int32_t values_len) {
  return CAPI_ENTRY(
      { readJoints(plant, values, values_len, [](FlexibleJointPlant& p) { return p.motorPositions(); }); });
}

jc_status jc_plant_motor_velocities(jc_plant* plant, double* values, int32_t values_len) {
  return CAPI_ENTRY(
      { readJoints(plant, values, values_len, [](FlexibleJointPlant& p) { return p.motorVelocities(); }); });
}

jc_status jc_plant_motor_torques(jc_plant* plant, double* values, int32_t values_len) {
  return CAPI_ENTRY({ readJoints(plant, values, values_len, [](FlexibleJointPlant& p) { return p.motorTorques(); }); });
}

jc_status jc_plant_state(jc_plant* plant, double* state, int32_t state_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const int n = handle.plant->dof();
    requireOutput(state, state_len, 5 * n, "state", "5 x the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    const double* y = handle.plant->state();
    std::copy(y, y + 5 * n, state);
  });
}

jc_status jc_plant_statistics(jc_plant* plant, int64_t* counts, int32_t counts_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    requirePointer(counts, "counts");
    requireLength(counts_len, 5, "counts", "steps, right-hand sides, Jacobians, error-test and convergence failures");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    const PlantStatistics statistics = handle.plant->statistics();
    counts[0] = statistics.steps;
    counts[1] = statistics.rhs_evaluations;
    counts[2] = statistics.jacobian_evaluations;
    counts[3] = statistics.error_test_failures;
    counts[4] = statistics.nonlinear_convergence_failures;
  });
}

jc_status jc_plant_snapshot_size(jc_plant* plant, int32_t* size) {
  return CAPI_ENTRY({
    const jc_plant& handle = plantHandle(plant);
    requirePointer(size, "size");
    *size = static_cast<int32_t>(snapshotSize(handle.plant->dof()));
  });
}

jc_status jc_plant_save(jc_plant* plant, double* snapshot, int32_t snapshot_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const int n = handle.plant->dof();
    requireOutput(snapshot, snapshot_len, snapshotSize(n), "snapshot", "jc_plant_snapshot_size");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    const PlantState state = handle.plant->saveState();
    std::vector<double> out;
    out.reserve(static_cast<std::size_t>(snapshotSize(n)));
    out.push_back(kSnapshotFormat);
    out.push_back(n);
    out.push_back(state.time);
    out.insert(out.end(), state.y.begin(), state.y.end());
    for (const JointVector* part : {&state.reference, &state.reference_velocity, &state.reference_acceleration,
                                    &state.feedforward, &state.feedforward_rate}) {
      appendJoints(out, *part);
    }
    out.push_back(state.reference_time);
    out.insert(out.end(), state.tool_wrench.data(), state.tool_wrench.data() + 6);
    out.push_back(state.payload_mass);
    out.insert(out.end(), state.payload_com.data(), state.payload_com.data() + 3);
    if (static_cast<std::int64_t>(out.size()) != snapshotSize(n)) throw std::logic_error("snapshot size mismatch");
    std::copy(out.begin(), out.end(), snapshot);
  });
}

jc_status jc_plant_restore(jc_plant* plant, const double* snapshot, int32_t snapshot_len) {
  return CAPI_ENTRY({
    jc_plant& handle = plantHandle(plant);
    const int n = handle.plant->dof();
    requirePointer(snapshot, "snapshot");
    requireLength(snapshot_len, snapshotSize(n), "snapshot", "jc_plant_snapshot_size");
    requireFinite(snapshot, snapshot_len, "snapshot");
    if (snapshot[0] != kSnapshotFormat) invalid("snapshot[0] is not a snapshot format this library reads");
    if (snapshot[1] != n) invalid("snapshot is of a plant with another number of joints");
    const double* cursor = snapshot + 2;
    PlantState state;
    state.time = *cursor++;
    state.y.assign(cursor, cursor + 5 * n);
    cursor += 5 * n;
    state.reference = takeJoints(cursor, n);
    state.reference_velocity = takeJoints(cursor, n);
    state.reference_acceleration = takeJoints(cursor, n);
    state.feedforward = takeJoints(cursor, n);
    state.feedforward_rate = takeJoints(cursor, n);
    state.reference_time = *cursor++;
    state.tool_wrench = Eigen::Map<const Vector6>(cursor);
    cursor += 6;
    state.payload_mass = *cursor++;
    if (state.payload_mass < 0.0) invalid("snapshot holds a negative payload mass");
    state.payload_com = Eigen::Vector3d(cursor[0], cursor[1], cursor[2]);
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.plant->restoreState(state);
  });
}

}  // extern "C"
