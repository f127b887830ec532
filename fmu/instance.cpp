#include "fmu/instance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include <nlohmann/json.hpp>

#include "fmu/integrator_options.hpp"
#include "model/common/errors.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp::fmu {

using table::kVariables;
namespace role = table::role;

// ------------------------------------------------------------------------------------------------
// The FMU state.

struct Snapshot {
  unsigned phase = kInstantiated;
  std::vector<double> values;
  double time = 0.0;
  double start_time = 0.0;
  bool stop_time_defined = false;
  double stop_time = 0.0;
  bool initialized = false;
  PlantState plant;  // when initialized
  bool has_last_step = false;
  JointVector last_q_desired;
  double last_step_time = 0.0;
  Vector6 applied_wrench = Vector6::Zero();
};

// ------------------------------------------------------------------------------------------------
// What the resources hold and what is built from them.

struct Instance::Models {
  struct EffectSlot {
    int effect = -1;
    int parameter = -1;
  };

  Models(std::shared_ptr<const Robot> loaded_robot, JointErrorModel loaded_model, std::vector<DriveParameters> drives)
      : robot(std::move(loaded_robot)),
        base(std::move(loaded_model)),
        base_drives(std::move(drives)),
        slot(table::kCount),
        drive_joint(table::kCount, -1),
        drive_field(table::kCount),
        option(table::kCount, nullptr),
        compensation_ctx(robot->dof()),
        prediction_ctx(robot->dof()),
        prediction_ws(*robot) {}

  std::shared_ptr<const Robot> robot;
  JointErrorModel base;                    // the parameter file as shipped
  std::vector<DriveParameters> base_drives;
  // Where each bound parameter (by variable index) goes.
  std::vector<EffectSlot> slot;
  std::vector<int> drive_joint;
  std::vector<std::string> drive_field;
  std::vector<const IntegratorOption*> option;

  // Built from the fixed parameters (built_values), rebuilt when they change.
  bool built = false;
  std::vector<double> built_values;
  std::unique_ptr<JointErrorModel> nominal;
  std::unique_ptr<FlexibleJointPlant> plant;
  std::unique_ptr<Compensator> compensator;  // after nominal: it refers to it
  int compensator_mode = -1;

  JointContext compensation_ctx;
  JointContext prediction_ctx;
  JointErrorWorkspace prediction_ws;
};

namespace {

constexpr const char* kCategoryNames[] = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logCalls"};
static_assert(sizeof kCategoryNames / sizeof kCategoryNames[0] == table::kLogCategoryCount,
              "the log categories of model.json and of the instance differ");

const char* typeName(table::Type type) {
  switch (type) {
    case table::Type::Real: return "Real (fmi2Real, fmi3Float64)";
    case table::Type::Integer: return "Integer (fmi2Integer, fmi3Int32)";
    case table::Type::Boolean: return "Boolean";
    case table::Type::Enumeration: return "Enumeration (fmi2Integer, fmi3Int64)";
  }
  return "?";
}

unsigned typeBit(table::Type type) {
  switch (type) {
    case table::Type::Real: return kReal;
    case table::Type::Integer: return kInteger;
    case table::Type::Boolean: return kBoolean;
    case table::Type::Enumeration: return kEnumeration;
  }
  return 0;
}

// The output group of each variable (0 for non-outputs).
struct GroupTable {
  unsigned group[table::kCount] = {};
  GroupTable() {
    for (int j = 0; j < table::kDof; ++j) {
      for (int index : {role::q_motor[j], role::qd_motor[j], role::q_link[j], role::qd_link[j], role::dq_actual[j]}) {
        group[index] = 1u;  // kStateOutputs
      }
      group[role::dq_predicted[j]] = 4u;  // kPredictedOutputs
      group[role::q_ref[j]] = 8u;         // kReferenceOutputs
    }
    for (int index : role::tool_position) group[index] = 2u;  // kToolOutputs
  }
};
const GroupTable kGroups;

bool isFixedParameter(int index) {
  return kVariables[index].causality == table::Causality::Parameter &&
         kVariables[index].variability == table::Variability::Fixed;
}

JointVector gather(const std::vector<double>& values, const int (&indices)[table::kDof]) {
  JointVector v(table::kDof);
  for (int j = 0; j < table::kDof; ++j) v[j] = values[indices[j]];
  return v;
}

Vector6 wrenchOf(const std::vector<double>& values) {
  Vector6 w;
  for (int k = 0; k < 6; ++k) w[k] = values[role::wrench[k]];
  return w;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// ---- serialisation -----------------------------------------------------------------------------

constexpr char kMagic[8] = {'J', 'C', 'F', 'M', 'U', 'S', 'T', 'A'};
constexpr std::uint32_t kStateFormat = 1;

std::uint64_t fnv1a(const unsigned char* bytes, std::size_t size) {
  std::uint64_t hash = 1469598103934665603ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

class Writer {
public:
  template <typename T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void put(const JointVector& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (int i = 0; i < v.size(); ++i) put(v[i]);
  }
  void put(const std::vector<double>& v) {
    put(static_cast<std::uint32_t>(v.size()));
    for (double x : v) put(x);
  }
  std::vector<unsigned char> bytes;
};

class Reader {
public:
  Reader(const unsigned char* data, std::size_t size) : data_(data), size_(size) {}
  template <typename T>
  T get(const char* what) {
    if (size_ - offset_ < sizeof(T)) throw Error(std::string("the state ends inside ") + what);
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  double finite(const char* what) {
    const double x = get<double>(what);
    if (!std::isfinite(x)) throw Error(std::string(what) + " is not finite");
    return x;
  }
  bool flag(const char* what) {
    const auto b = get<std::uint8_t>(what);
    if (b > 1) throw Error(std::string(what) + " is not 0 or 1");
    return b == 1;
  }
  void vector(JointVector& v, std::uint32_t expected, const char* what) {
    if (get<std::uint32_t>(what) != expected) throw Error(std::string(what) + " has the wrong size");
    v.resize(expected);
    for (std::uint32_t i = 0; i < expected; ++i) v[i] = finite(what);
  }
  void vector(std::vector<double>& v, std::uint32_t expected, const char* what) {
    if (get<std::uint32_t>(what) != expected) throw Error(std::string(what) + " has the wrong size");
    v.resize(expected);
    for (std::uint32_t i = 0; i < expected; ++i) v[i] = finite(what);
  }
  std::size_t offset() const { return offset_; }

private:
  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
};

void writeSnapshot(const Snapshot& s, Writer& w) {
  w.bytes.insert(w.bytes.end(), kMagic, kMagic + sizeof kMagic);
  w.put(kStateFormat);
  w.put(std::uint64_t(0));  // total size, patched below
  const std::uint32_t token_length = static_cast<std::uint32_t>(std::strlen(table::kInstantiationToken));
  w.put(token_length);
  w.bytes.insert(w.bytes.end(), table::kInstantiationToken, table::kInstantiationToken + token_length);
  w.put(static_cast<std::uint32_t>(table::kCount));
  w.put(static_cast<std::uint32_t>(table::kDof));
  w.put(static_cast<std::uint32_t>(s.phase));
  w.put(s.values);
  w.put(s.time);
  w.put(s.start_time);
  w.put(static_cast<std::uint8_t>(s.stop_time_defined));
  w.put(s.stop_time);
  w.put(static_cast<std::uint8_t>(s.initialized));
  if (s.initialized) {
    const PlantState& p = s.plant;
    w.put(p.time);
    w.put(p.y);
    w.put(p.reference);
    w.put(p.reference_velocity);
    w.put(p.reference_acceleration);
    w.put(p.feedforward);
    w.put(p.feedforward_rate);
    w.put(p.reference_time);
    for (int k = 0; k < 6; ++k) w.put(p.tool_wrench[k]);
    w.put(p.payload_mass);
    for (int k = 0; k < 3; ++k) w.put(p.payload_com[k]);
  }
  w.put(static_cast<std::uint8_t>(s.has_last_step));
  w.put(s.last_q_desired);
  w.put(s.last_step_time);
  for (int k = 0; k < 6; ++k) w.put(s.applied_wrench[k]);
  const std::uint64_t total = w.bytes.size() + sizeof(std::uint64_t);  // with the checksum
  std::memcpy(w.bytes.data() + sizeof kMagic + sizeof kStateFormat, &total, sizeof total);
  w.put(fnv1a(w.bytes.data(), w.bytes.size()));
}

}  // namespace

const char* phaseName(unsigned phase) {
  switch (phase) {
    case kInstantiated: return "Instantiated";
    case kInitializationMode: return "InitializationMode";
    case kStepMode: return "StepMode";
    case kStepDiscarded: return "StepDiscarded";
    case kTerminated: return "Terminated";
    case kErrorState: return "Error";
    default: return "?";
  }
}

// ------------------------------------------------------------------------------------------------

Instance::Instance(std::string name, const std::string& resource_dir, LogSink sink, void* sink_context,
                   bool logging_on)
    : name_(std::move(name)), sink_(sink), sink_context_(sink_context) {
  for (bool& on : logging_) on = logging_on;
  logging_[kLogCalls] = false;  // verbose: only when asked for by name
  std::string dir = resource_dir;
  if (!dir.empty() && dir.back() != '/') dir += '/';
  auto robot = std::make_shared<const Robot>(loadRobotFile(dir + "robot.json"));
  if (robot->name != table::kRobotName || robot->dof() != table::kDof) {
    throw Error(dir + "robot.json describes robot '" + robot->name + "' with " + std::to_string(robot->dof()) +
                " joints; this FMU's variables are for '" + table::kRobotName + "' with " +
                std::to_string(table::kDof));
  }
  const std::string parameter_path = dir + "parameters.json";
  std::string text;
  try {
    text = readTextFile(parameter_path, "parameter file");
  } catch (const Error& error) {
    throw ParameterError(error.what());
  }
  JointErrorModel model = parseParameters(text, parameter_path, robot);
  std::vector<DriveParameters> drives = parseDriveParameters(text, parameter_path, *robot);
  models_ = std::make_unique<Models>(robot, std::move(model), std::move(drives));

  // Bind every parameter of the table to its place in the model; the resources must have them all.
  Models& m = *models_;
  const nlohmann::json drive_json = drivesToJson(m.base_drives, *robot);
  for (int i = 0; i < table::kCount; ++i) {
    const table::Variable& v = kVariables[i];
    switch (v.binding) {
      case table::Binding::None: break;
      case table::Binding::Plant:
      case table::Binding::Compensator: {
        for (int e = 0; e < m.base.effectCount() && m.slot[i].effect < 0; ++e) {
          const std::vector<std::string> names = m.base.effect(e).parameterNames();
          const auto found = std::find(names.begin(), names.end(), v.key);
          if (found != names.end()) m.slot[i] = {e, static_cast<int>(found - names.begin())};
        }
        if (m.slot[i].effect < 0) {
          throw ParameterError(parameter_path + ": no effect parameter '" + v.key + "' (FMU variable '" + v.name + "')");
        }
        break;
      }
      case table::Binding::Drive: {
        const std::string key = v.key;
        const std::size_t dot = key.find('.');
        const std::string joint = key.substr(0, dot);
        const std::string field = dot == std::string::npos ? "" : key.substr(dot + 1);
        for (int j = 0; j < robot->dof(); ++j) {
          if (robot->joints[j].name == joint) m.drive_joint[i] = j;
        }
        if (m.drive_joint[i] < 0 || !drive_json.at("joints").at(m.drive_joint[i]).contains(field)) {
          throw ParameterError(parameter_path + ": no drive parameter '" + key + "' (FMU variable '" + v.name + "')");
        }
        m.drive_field[i] = field;
        break;
      }
      case table::Binding::Integrator:
        m.option[i] = findIntegratorOption(v.key);
        if (!m.option[i]) throw Error(std::string("no integrator option '") + v.key + "' (FMU variable '" + v.name + "')");
        break;
    }
  }
  setStartValues();
}

Instance::~Instance() = default;

void Instance::setStartValues() {
  values_.assign(table::kCount, 0.0);
  for (int i = 0; i < table::kCount; ++i) values_[i] = kVariables[i].start;
}

std::string Instance::describe(int index) const {
  char text[64];
  std::snprintf(text, sizeof text, "vr %u (", kVariables[index].vr);
  return text + std::string(kVariables[index].name) + ")";
}

// ------------------------------------------------------------------------------------------------
// Logging and the state machine.

void Instance::log(Status status, const char* format, ...) {
  LogCategory category = kLogCalls;
  switch (status) {
    case Status::OK: category = kLogCalls; break;
    case Status::Warning: category = kLogWarning; break;
    case Status::Discard: category = kLogDiscard; break;
    case Status::Error:
    case Status::Fatal: category = kLogError; break;
  }
  const bool always = status == Status::Error || status == Status::Fatal;
  if (!sink_ || (!always && !logging_[category])) return;
  char buffer[1024];
  va_list args;
  va_start(args, format);
  const int length = std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  std::string message;
  if (length >= 0 && static_cast<std::size_t>(length) >= sizeof buffer) {
    message.resize(static_cast<std::size_t>(length) + 1);
    va_start(args, format);
    std::vsnprintf(message.data(), message.size(), format, args);
    va_end(args);
    message.pop_back();
  } else {
    message = length >= 0 ? buffer : "(message could not be formatted)";
  }
  sink_(sink_context_, status, kCategoryNames[category], message.c_str());
}

bool Instance::allowed(const char* function, unsigned phases) {
  if (phase_ & phases) return true;
  std::string list;
  for (unsigned bit = 1; bit < kAnyPhase; bit <<= 1) {
    if (phases & bit) list += std::string(list.empty() ? "" : ", ") + phaseName(bit);
  }
  log(Status::Error, "%s: not allowed in state %s (allowed in: %s)", function, phaseName(phase_),
      list.empty() ? "no state of this FMU" : list.c_str());
  return false;
}

Status Instance::fail(Status status, const char* function, const std::string& what) {
  log(status, "%s: %s", function, what.c_str());
  return status;
}

Status Instance::nullArgument(const char* function, const char* argument) {
  return fail(Status::Error, function, std::string("argument ") + argument + " is a null pointer");
}

Status Instance::internalError(const char* function, const char* what) {
  phase_ = kErrorState;
  return fail(Status::Error, function, std::string("failed: ") + what + " (the instance must be reset or freed)");
}

Status Instance::unsupported(const char* function, const char* why) { return fail(Status::Error, function, why); }

Status Instance::badArgument(const char* function, const char* why) { return fail(Status::Error, function, why); }

Status Instance::setDebugLogging(const char* function, bool on, std::size_t count, const char* const categories[]) {
  if (count == 0) {
    for (bool& flag : logging_) flag = on;
    return Status::OK;
  }
  if (!categories) return nullArgument(function, "categories");
  bool chosen[kLogCategoryCount] = {};
  for (std::size_t i = 0; i < count; ++i) {
    if (!categories[i]) return nullArgument(function, "categories[i]");
    int found = -1;
    for (int c = 0; c < kLogCategoryCount; ++c) {
      if (std::strcmp(categories[i], kCategoryNames[c]) == 0) found = c;
    }
    if (found < 0) {
      return fail(Status::Error, function,
                  std::string("unknown log category '") + categories[i] +
                      "' (known: logStatusWarning, logStatusDiscard, logStatusError, logCalls)");
    }
    chosen[found] = true;
  }
  for (int c = 0; c < kLogCategoryCount; ++c) {
    if (chosen[c]) logging_[c] = on;
  }
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Models, reference, outputs.

bool Instance::fixedParametersDiffer(const std::vector<double>& values) const {
  const Models& m = *models_;
  if (!m.built) return true;
  for (int i = 0; i < table::kCount; ++i) {
    if (isFixedParameter(i) && !sameBits(values[i], m.built_values[i])) return true;
  }
  return false;
}

void Instance::ensureModels() {
  Models& m = *models_;
  if (!fixedParametersDiffer(values_)) {
    ensureCompensator();
    return;
  }
  JointErrorModel truth = m.base;
  JointErrorModel nominal = m.base;
  for (int e = 0; e < m.base.effectCount(); ++e) {
    std::vector<double> truth_values = truth.effect(e).parameters();
    std::vector<double> nominal_values = nominal.effect(e).parameters();
    bool touched = false;
    for (int i = 0; i < table::kCount; ++i) {
      if (m.slot[i].effect != e) continue;
      touched = true;
      auto& target = kVariables[i].binding == table::Binding::Plant ? truth_values : nominal_values;
      target[m.slot[i].parameter] = values_[i];
    }
    if (!touched) continue;
    try {
      truth.effect(e).setParameters(truth_values);
    } catch (const Error& error) {
      throw ParameterError(std::string("plant parameters: ") + error.what());
    }
    try {
      nominal.effect(e).setParameters(nominal_values);
    } catch (const Error& error) {
      throw ParameterError(std::string("compensator parameters: ") + error.what());
    }
  }
  nlohmann::json drive_json = drivesToJson(m.base_drives, *m.robot);
  for (int i = 0; i < table::kCount; ++i) {
    if (m.drive_joint[i] >= 0) drive_json["joints"][m.drive_joint[i]][m.drive_field[i]] = values_[i];
  }
  std::vector<DriveParameters> drives = drivesFromJson(drive_json, *m.robot, "controller parameters");
  PlantOptions options;
  for (int i = 0; i < table::kCount; ++i) {
    if (m.option[i]) m.option[i]->set(options, values_[i]);
  }
  auto plant = std::make_unique<FlexibleJointPlant>(truth, std::move(drives), options);
  auto nominal_model = std::make_unique<JointErrorModel>(std::move(nominal));
  // Everything built: commit.
  m.compensator.reset();
  m.nominal = std::move(nominal_model);
  m.plant = std::move(plant);
  m.compensator_mode = -1;
  m.built_values = values_;
  m.built = true;
  initialized_ = false;
  ensureCompensator();
}

void Instance::ensureCompensator() {
  Models& m = *models_;
  const int mode = static_cast<int>(values_[role::compensation]);
  if (m.compensator && m.compensator_mode == mode) return;
  EffectMask mask = 0;
  if (mode == 1) mask = m.nominal->loadsAnd({"compliance"});
  // Mode 2 corrects every effect of the parameter file: for the shipped RX170 that is the paper's
  // compliance and transmission error; a file extended by discovery brings its effects along.
  if (mode == 2) mask = m.nominal->allEffects();
  m.compensator = std::make_unique<Compensator>(*m.nominal, mask);
  m.compensator_mode = mode;
  reference_valid_ = false;
  outputs_valid_ &= ~kReferenceOutputs;
}

Status Instance::ensureReference(const char* function) {
  if (reference_valid_) return Status::OK;
  Models& m = *models_;
  const JointVector q = gather(values_, role::q_desired);
  JointVector velocity = JointVector::Zero(table::kDof);
  if (values_[role::use_velocity_inputs] != 0.0) {
    velocity = gather(values_, role::qd_desired);
  } else if (has_last_step_ && time_ > last_step_time_) {
    velocity = (q - last_q_desired_) / (time_ - last_step_time_);
  }
  if (m.compensator_mode == 0) {
    reference_ = q;
  } else {
    JointContext& ctx = m.compensation_ctx;
    ctx.q = q;
    ctx.velocity = velocity;
    ctx.time = time_;
    ctx.tool_wrench = values_[role::compensate_wrench] != 0.0 ? wrenchOf(values_) : Vector6::Zero();
    const FixedPointReport report = m.compensator->compensate(ctx, reference_);
    if (!report.converged) {
      char text[160];
      std::snprintf(text, sizeof text, "the compensation did not converge at t = %.9g s (residual %g rad after %d iterations)",
                    time_, report.residual, report.iterations);
      return fail(Status::Discard, function, text);
    }
  }
  reference_velocity_ = velocity;
  reference_valid_ = true;
  return Status::OK;
}

void Instance::ensureInitialized() {
  ensureModels();
  if (initialized_) return;
  time_ = start_time_;
  has_last_step_ = false;
  reference_valid_ = false;
  if (ensureReference("initialization") != Status::OK) {
    throw SolverError("the compensation of the initial inputs did not converge");
  }
  Models& m = *models_;
  applied_wrench_ = wrenchOf(values_);
  m.plant->setToolWrench(applied_wrench_);
  m.plant->reset(reference_, start_time_);
  initialized_ = true;
  outputs_valid_ = 0;
}

Status Instance::updateOutputs(const char* function, unsigned groups) {
  Models& m = *models_;
  const unsigned missing = groups & ~outputs_valid_;
  if (missing == 0) return Status::OK;
  if (missing & kReferenceOutputs) {
    const Status status = ensureReference(function);
    if (status != Status::OK) return status;
    for (int j = 0; j < table::kDof; ++j) values_[role::q_ref[j]] = reference_[j];
  }
  const FlexibleJointPlant& plant = *m.plant;
  if (missing & (kStateOutputs | kToolOutputs | kPredictedOutputs)) {
    const JointVector q = plant.linkPositions();
    const JointVector p = plant.motorPositions();
    if (missing & kStateOutputs) {
      const JointVector qd = plant.linkVelocities();
      const JointVector pd = plant.motorVelocities();
      for (int j = 0; j < table::kDof; ++j) {
        values_[role::q_link[j]] = q[j];
        values_[role::qd_link[j]] = qd[j];
        values_[role::q_motor[j]] = p[j];
        values_[role::qd_motor[j]] = pd[j];
        values_[role::dq_actual[j]] = q[j] - p[j];
      }
    }
    if (missing & kToolOutputs) {
      forwardKinematics(*m.robot, m.prediction_ws.robot, q);
      const Eigen::Vector3d tool = m.prediction_ws.robot.tool_pose.translation();
      for (int k = 0; k < 3; ++k) values_[role::tool_position[k]] = tool[k];
    }
    if (missing & kPredictedOutputs) {
      // The nominal model's link-minus-command error at the plant's link and motor positions.
      JointContext& ctx = m.prediction_ctx;
      ctx.q = q;
      ctx.velocity = plant.linkVelocities();
      ctx.time = time_;
      ctx.tool_wrench = applied_wrench_;
      const EffectMask all = m.nominal->allEffects();
      computeLoadTorque(*m.nominal, all, m.prediction_ws, ctx);
      ctx.command = p;
      updateMotorAngles(*m.nominal, ctx);
      JointVector dq = JointVector::Zero(table::kDof);
      addSelectedJointErrors(*m.nominal, all, ctx, dq);
      for (int j = 0; j < table::kDof; ++j) values_[role::dq_predicted[j]] = dq[j];
    }
  }
  outputs_valid_ |= missing;
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Lifecycle.

Status Instance::setupExperiment(const char* function, bool tolerance_defined, double tolerance, double start_time,
                                 bool stop_time_defined, double stop_time) {
  if (!std::isfinite(start_time)) return fail(Status::Error, function, "startTime is not finite");
  if (stop_time_defined && !(std::isfinite(stop_time) && stop_time >= start_time)) {
    return fail(Status::Error, function, "stopTime must be finite and not before startTime");
  }
  if (tolerance_defined) {
    if (!(std::isfinite(tolerance) && tolerance > 0.0)) {
      return fail(Status::Error, function, "the tolerance must be positive and finite");
    }
    // The importer's tolerance becomes the integrator's relative tolerance (and its parameter's value).
    for (int i = 0; i < table::kCount; ++i) {
      if (models_->option[i] && std::strcmp(models_->option[i]->name, "relative_tolerance") == 0) values_[i] = tolerance;
    }
  }
  start_time_ = start_time;
  time_ = start_time;
  stop_time_defined_ = stop_time_defined;
  stop_time_ = stop_time;
  return Status::OK;
}

Status Instance::enterInitializationMode(const char*) {
  phase_ = kInitializationMode;
  initialized_ = false;
  time_ = start_time_;
  return Status::OK;
}

Status Instance::exitInitializationMode(const char* function) {
  try {
    ensureInitialized();
  } catch (const std::exception& error) {
    phase_ = kErrorState;
    return fail(Status::Error, function, std::string("cannot initialise: ") + error.what());
  }
  has_last_step_ = false;
  phase_ = kStepMode;
  return Status::OK;
}

Status Instance::doStep(const char* function, double current_time, double step, double* last_successful_time) {
  if (!std::isfinite(current_time) || !std::isfinite(step) || !(step > 0.0)) {
    char text[160];
    std::snprintf(text, sizeof text, "currentCommunicationPoint (%g) and communicationStepSize (%g) must be finite, "
                  "the step size positive", current_time, step);
    return fail(Status::Error, function, text);
  }
  const double tolerance = 1e-9 * std::max(1.0, std::abs(time_));
  if (std::abs(current_time - time_) > tolerance) {
    char text[160];
    std::snprintf(text, sizeof text, "currentCommunicationPoint %.17g is not the FMU's time %.17g", current_time, time_);
    return fail(Status::Error, function, text);
  }
  const double end = current_time + step;
  if (!(end > current_time && end > time_)) {
    return fail(Status::Error, function, "the step is too small to advance the time");
  }
  if (stop_time_defined_ && end > stop_time_ + tolerance) {
    char text[160];
    std::snprintf(text, sizeof text, "the step to %.17g s goes beyond the stop time %.17g s", end, stop_time_);
    return fail(Status::Error, function, text);
  }
  if (!sameBits(current_time, time_)) {
    // Within rounding of the FMU's time: the importer's clock is the one to follow.
    time_ = current_time;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
  }
  if (logging_[kLogCalls]) log(Status::OK, "%s(%.17g, %.17g)", function, current_time, step);
  Models& m = *models_;
  FlexibleJointPlant& plant = *m.plant;
  const Status reference = ensureReference(function);
  if (reference != Status::OK) {
    phase_ = kStepDiscarded;
    if (last_successful_time) *last_successful_time = time_;
    return reference;
  }
  const Vector6 wrench = wrenchOf(values_);
  if (wrench != applied_wrench_) {
    plant.setToolWrench(wrench);
    applied_wrench_ = wrench;
  }
  plant.setReference(reference_, reference_velocity_);
  try {
    plant.advance(end);
  } catch (const SolverError& error) {
    time_ = plant.time();
    phase_ = kStepDiscarded;
    reference_valid_ = false;
    outputs_valid_ = 0;
    if (last_successful_time) *last_successful_time = time_;
    return fail(Status::Discard, function, error.what());
  }
  has_last_step_ = true;
  last_q_desired_ = gather(values_, role::q_desired);
  last_step_time_ = time_;
  time_ = end;
  reference_valid_ = false;
  outputs_valid_ = 0;
  if (last_successful_time) *last_successful_time = time_;
  return Status::OK;
}

Status Instance::terminate(const char*) {
  phase_ = kTerminated;
  return Status::OK;
}

Status Instance::reset(const char*) {
  phase_ = kInstantiated;
  setStartValues();
  time_ = 0.0;
  start_time_ = 0.0;
  stop_time_defined_ = false;
  stop_time_ = 0.0;
  initialized_ = false;
  reference_valid_ = false;
  outputs_valid_ = 0;
  has_last_step_ = false;
  applied_wrench_.setZero();
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Values.

int Instance::indexOf(std::uint32_t vr) {
  const table::Variable* begin = kVariables;
  const table::Variable* end = kVariables + table::kCount;
  const table::Variable* found =
      std::lower_bound(begin, end, vr, [](const table::Variable& v, std::uint32_t key) { return v.vr < key; });
  return found != end && found->vr == vr ? static_cast<int>(found - begin) : -1;
}

Status Instance::checkValue(const char* function, int index, double value) {
  const table::Variable& v = kVariables[index];
  char text[256];
  switch (v.type) {
    case table::Type::Real:
      if (!std::isfinite(value)) {
        std::snprintf(text, sizeof text, "value %g for %s is not finite", value, describe(index).c_str());
        return fail(Status::Error, function, text);
      }
      break;
    case table::Type::Integer:
    case table::Type::Enumeration:
      if (value != std::floor(value) || value < -2147483648.0 || value > 9.2e18) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an integer in range", value, describe(index).c_str());
        return fail(Status::Error, function, text);
      }
      if (v.type == table::Type::Enumeration && (value < v.min || value > v.max)) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an item of its enumeration (%g to %g)", value,
                      describe(index).c_str(), v.min, v.max);
        return fail(Status::Error, function, text);
      }
      break;
    case table::Type::Boolean: break;
  }
  if (value < v.min || value > v.max) {
    std::snprintf(text, sizeof text, "value %.17g for %s is outside [%g, %g]; not set", value, describe(index).c_str(),
                  v.min, v.max);
    return fail(Status::Discard, function, text);
  }
  return Status::OK;
}

template <typename T>
Status Instance::get(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count, T values[]) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "vr[]");
  if (!values) return nullArgument(function, "value[]");
  unsigned groups = 0;
  bool outputs = false;
  for (std::size_t i = 0; i < count; ++i) {
    const int index = indexOf(vrs[i]);
    if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vrs[i]) + " is not a variable of this FMU");
    const table::Variable& v = kVariables[index];
    if (!(typeBit(v.type) & types)) {
      return fail(Status::Error, function, describe(index) + " is of type " + typeName(v.type) + "; use its own function");
    }
    if (v.causality == table::Causality::Output || v.causality == table::Causality::Independent) {
      if (phase_ == kInstantiated) {
        return fail(Status::Error, function, describe(index) + " is computed from initialization mode on");
      }
      outputs = true;
      groups |= kGroups.group[index];
    }
  }
  if (outputs) {
    if (phase_ == kInitializationMode) {
      try {
        ensureInitialized();
      } catch (const std::exception& error) {
        return fail(Status::Error, function, std::string("cannot compute the initial outputs: ") + error.what());
      }
    }
    if (initialized_) {
      const Status status = updateOutputs(function, groups);
      if (status != Status::OK) return status;
    }
    values_[role::time] = time_;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const int index = indexOf(vrs[i]);
    const double x = values_[index];
    values[i] = kVariables[index].type == table::Type::Boolean ? static_cast<T>(x != 0.0) : static_cast<T>(x);
  }
  return Status::OK;
}

template <typename T>
Status Instance::set(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count,
                     const T values[]) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "vr[]");
  if (!values) return nullArgument(function, "value[]");
  const bool before_step = phase_ == kInstantiated || phase_ == kInitializationMode;
  // Everything is checked before anything is set: a refused call changes nothing.
  for (std::size_t i = 0; i < count; ++i) {
    const int index = indexOf(vrs[i]);
    if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vrs[i]) + " is not a variable of this FMU");
    const table::Variable& v = kVariables[index];
    if (!(typeBit(v.type) & types)) {
      return fail(Status::Error, function, describe(index) + " is of type " + typeName(v.type) + "; use its own function");
    }
    switch (v.causality) {
      case table::Causality::Output:
        return fail(Status::Error, function, describe(index) + " is an output; it cannot be set");
      case table::Causality::Independent:
        return fail(Status::Error, function, describe(index) + " is the independent variable; it cannot be set");
      case table::Causality::Parameter:
        if (!before_step && v.variability != table::Variability::Tunable) {
          return fail(Status::Error, function,
                      describe(index) + " is a fixed parameter; it can be set only before exitInitializationMode");
        }
        break;
      case table::Causality::Input: break;
    }
    const double x = v.type == table::Type::Boolean ? (values[i] != T(0) ? 1.0 : 0.0) : static_cast<double>(values[i]);
    const Status status = checkValue(function, index, x);
    if (status != Status::OK) return status;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const int index = indexOf(vrs[i]);
    const table::Variable& v = kVariables[index];
    const double x = v.type == table::Type::Boolean ? (values[i] != T(0) ? 1.0 : 0.0) : static_cast<double>(values[i]);
    if (sameBits(values_[index], x)) continue;
    values_[index] = x;
    if (phase_ == kInitializationMode) initialized_ = false;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
    if (index == role::compensation && models_->built && !before_step) ensureCompensator();
  }
  return Status::OK;
}

template Status Instance::get<double>(const char*, unsigned, const std::uint32_t[], std::size_t, double[]);
template Status Instance::get<int>(const char*, unsigned, const std::uint32_t[], std::size_t, int[]);
template Status Instance::get<long>(const char*, unsigned, const std::uint32_t[], std::size_t, long[]);
template Status Instance::get<bool>(const char*, unsigned, const std::uint32_t[], std::size_t, bool[]);
template Status Instance::set<double>(const char*, unsigned, const std::uint32_t[], std::size_t, const double[]);
template Status Instance::set<int>(const char*, unsigned, const std::uint32_t[], std::size_t, const int[]);
template Status Instance::set<long>(const char*, unsigned, const std::uint32_t[], std::size_t, const long[]);
template Status Instance::set<bool>(const char*, unsigned, const std::uint32_t[], std::size_t, const bool[]);

Status Instance::noVariablesOfType(const char* function, const char* type_name, const std::uint32_t vrs[],
                                   std::size_t count) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "valueReferences[]");
  const int index = indexOf(vrs[0]);
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vrs[0]) + " is not a variable of this FMU");
  return fail(Status::Error, function,
              describe(index) + " is of type " + typeName(kVariables[index].type) + ", not " + type_name +
                  " (this FMU has no " + type_name + " variables)");
}

Status Instance::dependencies(const char* function, std::uint32_t vr, std::vector<std::uint32_t>& inputs) {
  const int index = indexOf(vr);
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vr) + " is not a variable of this FMU");
  inputs.clear();
  for (int k = table::kDependencyStart[index]; k < table::kDependencyStart[index + 1]; ++k) {
    inputs.push_back(kVariables[table::kDependencies[k]].vr);
  }
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// FMU state.

bool Instance::ownsState(const Snapshot* state) const {
  return std::any_of(states_.begin(), states_.end(), [&](const auto& s) { return s.get() == state; });
}

Status Instance::getState(const char* function, Snapshot** state) {
  if (!state) return nullArgument(function, "FMUstate");
  Snapshot* target = *state;
  if (target && !ownsState(target)) {
    return fail(Status::Error, function, "*FMUstate is neither null nor a state of this instance");
  }
  if (!target) {
    states_.push_back(std::make_unique<Snapshot>());
    target = states_.back().get();
  }
  Snapshot& s = *target;
  s.phase = phase_;
  s.values = values_;
  s.time = time_;
  s.start_time = start_time_;
  s.stop_time_defined = stop_time_defined_;
  s.stop_time = stop_time_;
  s.initialized = initialized_;
  if (initialized_) s.plant = models_->plant->saveState();
  s.has_last_step = has_last_step_;
  s.last_q_desired = has_last_step_ ? last_q_desired_ : JointVector::Zero(table::kDof);
  s.last_step_time = last_step_time_;
  s.applied_wrench = applied_wrench_;
  *state = target;
  return Status::OK;
}

Status Instance::setState(const char* function, const Snapshot* state) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  const Snapshot& s = *state;
  const std::vector<double> previous = values_;
  values_ = s.values;
  try {
    if (s.initialized) {
      ensureModels();
      models_->plant->restoreState(s.plant);
    } else if (models_->built) {
      ensureCompensator();
    }
  } catch (const std::exception& error) {
    values_ = previous;
    return fail(Status::Error, function, std::string("cannot restore the state: ") + error.what());
  }
  phase_ = s.phase;
  time_ = s.time;
  start_time_ = s.start_time;
  stop_time_defined_ = s.stop_time_defined;
  stop_time_ = s.stop_time;
  initialized_ = s.initialized;
  has_last_step_ = s.has_last_step;
  last_q_desired_ = s.last_q_desired;
  last_step_time_ = s.last_step_time;
  applied_wrench_ = s.applied_wrench;
  reference_valid_ = false;
  outputs_valid_ = 0;
  return Status::OK;
}

Status Instance::freeState(const char* function, Snapshot** state) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!*state) return Status::OK;  // freeing nothing is allowed
  const auto found = std::find_if(states_.begin(), states_.end(), [&](const auto& s) { return s.get() == *state; });
  if (found == states_.end()) return fail(Status::Error, function, "*FMUstate is not a state of this instance");
  states_.erase(found);
  *state = nullptr;
  return Status::OK;
}

Status Instance::serializedSize(const char* function, const Snapshot* state, std::size_t* size) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!size) return nullArgument(function, "size");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  Writer writer;
  writeSnapshot(*state, writer);
  *size = writer.bytes.size();
  return Status::OK;
}

Status Instance::serialize(const char* function, const Snapshot* state, unsigned char bytes[], std::size_t size) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!bytes) return nullArgument(function, "serializedState");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  Writer writer;
  writeSnapshot(*state, writer);
  if (size != writer.bytes.size()) {
    return fail(Status::Error, function,
                "size is " + std::to_string(size) + " bytes; the state needs " + std::to_string(writer.bytes.size()));
  }
  std::memcpy(bytes, writer.bytes.data(), size);
  return Status::OK;
}

Status Instance::deserialize(const char* function, const unsigned char bytes[], std::size_t size, Snapshot** state) {
  if (!bytes) return nullArgument(function, "serializedState");
  if (!state) return nullArgument(function, "FMUstate");
  if (*state && !ownsState(*state)) {
    return fail(Status::Error, function, "*FMUstate is neither null nor a state of this instance");
  }
  auto s = std::make_unique<Snapshot>();
  try {
    Reader r(bytes, size);
    char magic[sizeof kMagic];
    for (char& c : magic) c = r.get<char>("the header");
    if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) throw Error("not a jointcomp FMU state (wrong magic bytes)");
    const auto format = r.get<std::uint32_t>("the header");
    if (format != kStateFormat) throw Error("state format " + std::to_string(format) + ", expected " + std::to_string(kStateFormat));
    const auto total = r.get<std::uint64_t>("the header");
    if (total != size) throw Error("the state says it has " + std::to_string(total) + " bytes, given " + std::to_string(size));
    std::uint64_t stored_checksum;  // the last 8 bytes; the header read above has more than that
    std::memcpy(&stored_checksum, bytes + size - sizeof stored_checksum, sizeof stored_checksum);
    if (fnv1a(bytes, size - sizeof stored_checksum) != stored_checksum) {
      throw Error("the checksum does not match: the bytes were changed or truncated");
    }
    const auto token_length = r.get<std::uint32_t>("the header");
    if (token_length != std::strlen(table::kInstantiationToken)) throw Error("the state is from another FMU (instantiation token)");
    std::string token;
    for (std::uint32_t i = 0; i < token_length; ++i) token += r.get<char>("the header");
    if (token != table::kInstantiationToken) throw Error("the state is from another FMU (instantiation token " + token + ")");
    if (r.get<std::uint32_t>("the header") != static_cast<std::uint32_t>(table::kCount) ||
        r.get<std::uint32_t>("the header") != static_cast<std::uint32_t>(table::kDof)) {
      throw Error("the state has another variable table");
    }
    s->phase = r.get<std::uint32_t>("the phase");
    if (s->phase != kInstantiated && s->phase != kInitializationMode && s->phase != kStepMode &&
        s->phase != kStepDiscarded && s->phase != kTerminated) {
      throw Error("the state's phase is not one a state can be taken in");
    }
    r.vector(s->values, table::kCount, "the variable values");
    s->time = r.finite("the time");
    s->start_time = r.finite("the start time");
    s->stop_time_defined = r.flag("the stop-time flag");
    s->stop_time = r.finite("the stop time");
    s->initialized = r.flag("the initialised flag");
    if ((s->phase & (kStepMode | kStepDiscarded | kTerminated)) && !s->initialized) {
      throw Error("a state after initialisation without the plant's state");
    }
    if (s->initialized) {
      PlantState& p = s->plant;
      const std::uint32_t n = table::kDof;
      p.time = r.finite("the plant's time");
      r.vector(p.y, 5 * n, "the plant's state vector");
      r.vector(p.reference, n, "the plant's reference");
      r.vector(p.reference_velocity, n, "the plant's reference velocity");
      r.vector(p.reference_acceleration, n, "the plant's reference acceleration");
      r.vector(p.feedforward, n, "the plant's feed-forward");
      r.vector(p.feedforward_rate, n, "the plant's feed-forward rate");
      p.reference_time = r.finite("the plant's reference time");
      for (int k = 0; k < 6; ++k) p.tool_wrench[k] = r.finite("the plant's tool wrench");
      p.payload_mass = r.finite("the plant's payload mass");
      for (int k = 0; k < 3; ++k) p.payload_com[k] = r.finite("the plant's payload centre");
    }
    s->has_last_step = r.flag("the last-step flag");
    r.vector(s->last_q_desired, table::kDof, "the last desired positions");
    s->last_step_time = r.finite("the last step time");
    for (int k = 0; k < 6; ++k) s->applied_wrench[k] = r.finite("the applied wrench");
    if (r.offset() + sizeof(std::uint64_t) != size) throw Error("the state has bytes after its end");
    for (int i = 0; i < table::kCount; ++i) {
      const table::Causality c = kVariables[i].causality;
      if ((c == table::Causality::Parameter || c == table::Causality::Input) &&
          (s->values[i] < kVariables[i].min || s->values[i] > kVariables[i].max ||
           (kVariables[i].type != table::Type::Real && s->values[i] != std::floor(s->values[i])) ||
           (kVariables[i].type == table::Type::Boolean && s->values[i] != 0.0 && s->values[i] != 1.0))) {
        throw Error("the value of " + describe(i) + " is out of its range");
      }
    }
  } catch (const Error& error) {
    return fail(Status::Error, function, std::string("cannot read the state: ") + error.what());
  }
  if (*state) {
    **state = std::move(*s);
  } else {
    states_.push_back(std::move(s));
    *state = states_.back().get();
  }
  return Status::OK;
}

}  // namespace jointcomp::fmu
