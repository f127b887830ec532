#include "fmu/description/variable_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include "fmu/description/parameter_rows.hpp"
#include "model/common/errors.hpp"
#include "model/common/input_file.hpp"
#include "model/effects/registry.hpp"
#include "model/io/robot_file.hpp"

namespace jointcomp::fmu {

namespace {

// SI exponents of kg, m, s, A, K, mol, cd, rad.
const std::vector<Unit>& knownUnits() {
  static const std::vector<Unit> units = {
      {"s", {0, 0, 1, 0, 0, 0, 0, 0}, "second"},
      {"1/s", {0, 0, -1, 0, 0, 0, 0, 0}, "per second"},
      {"m", {0, 1, 0, 0, 0, 0, 0, 0}, "metre"},
      {"kg", {1, 0, 0, 0, 0, 0, 0, 0}, "kilogram"},
      {"kg.m2", {1, 2, 0, 0, 0, 0, 0, 0}, "kilogram square metre (inertia)"},
      {"rad", {0, 0, 0, 0, 0, 0, 0, 1}, "radian"},
      {"rad/s", {0, 0, -1, 0, 0, 0, 0, 1}, "radian per second"},
      {"rad/s2", {0, 0, -2, 0, 0, 0, 0, 1}, "radian per second squared"},
      {"rad/K", {0, 0, 0, 0, -1, 0, 0, 1}, "radian per kelvin (a temperature coefficient)"},
      {"N", {1, 1, -2, 0, 0, 0, 0, 0}, "newton"},
      {"N/m", {1, 0, -2, 0, 0, 0, 0, 0}, "newton per metre"},
      {"m/N", {-1, 0, 2, 0, 0, 0, 0, 0}, "metre per newton (a compliance)"},
      {"N.m", {1, 2, -2, 0, 0, 0, 0, 0}, "newton metre"},
      {"N.m2", {1, 3, -2, 0, 0, 0, 0, 0}, "newton square metre (a bending stiffness)"},
      {"N.m/rad", {1, 2, -2, 0, 0, 0, 0, -1}, "newton metre per radian (stiffness and position gain)"},
      {"rad/(N.m)", {-1, -2, 2, 0, 0, 0, 0, 1}, "radian per newton metre (a compliance)"},
      {"rad/(N.m)3", {-3, -6, 6, 0, 0, 0, 0, 1}, "radian per cubed newton metre (a cubic compliance)"},
      {"N.m.s/rad", {1, 2, -1, 0, 0, 0, 0, -1}, "newton metre second per radian (velocity gain, damping)"},
      {"N.m/(rad.s)", {1, 2, -3, 0, 0, 0, 0, -1}, "newton metre per radian second (integral gain)"},
  };
  return units;
}

// The inputs an output can depend on directly, as groups of variables (bits of JointRow::depends).
enum InputGroup : unsigned {
  kNoInputs = 0,
  kDependsOnQDesired = 1u << 0,
  kDependsOnQdDesired = 1u << 1,
  kDependsOnQddDesired = 1u << 2,
  kDependsOnWrench = 1u << 3,
};

// Per-joint inputs and outputs, one variable per joint each: role, name prefix, causality, unit, the
// description with %s for the joint's name, and the inputs it depends on directly.
struct JointRow {
  std::vector<int> Roles::*role;
  const char* prefix;
  Causality causality;
  const char* unit;
  const char* description;
  unsigned depends;  // the input groups it depends on directly (InputGroup bits)
};
const JointRow kInputRows[] = {
    {&Roles::q_desired, "q_desired", Causality::Input, "rad",
     "Desired (planned) position of joint %s, Q_theo, held over the communication step", kNoInputs},
    {&Roles::qd_desired, "qd_desired", Causality::Input, "rad/s",
     "Desired velocity of joint %s; used only when use_velocity_inputs is true", kNoInputs},
    {&Roles::qdd_desired, "qdd_desired", Causality::Input, "rad/s2",
     "Desired acceleration of joint %s; used by compensation = dynamic when use_velocity_inputs is true (else "
     "the curvature of the parabola through q_desired at the last three communication points, zero before "
     "there are three)",
     kNoInputs},
};
const JointRow kOutputRows[] = {
    {&Roles::q_motor, "q_motor", Causality::Output, "rad",
     "Motor position of joint %s in joint units (motor angle divided by the gear ratio)", kNoInputs},
    {&Roles::qd_motor, "qd_motor", Causality::Output, "rad/s", "Motor velocity of joint %s in joint units", kNoInputs},
    {&Roles::q_link, "q_link", Causality::Output, "rad", "Link position of joint %s: where the robot actually is",
     kNoInputs},
    {&Roles::qd_link, "qd_link", Causality::Output, "rad/s", "Link velocity of joint %s", kNoInputs},
    {&Roles::dq_predicted, "dq_predicted", Causality::Output, "rad",
     "Joint error of joint %s (link minus motor position) that the nominal model predicts at the current link "
     "and motor positions",
     kNoInputs},
    {&Roles::dq_actual, "dq_actual", Causality::Output, "rad",
     "Actual joint error of joint %s in the plant: link minus motor position (joint compliance, transmission "
     "error and every other effect)",
     kNoInputs},
    {&Roles::q_ref, "q_ref", Causality::Output, "rad",
     "Command sent to the controller for joint %s: Q_ref = Q_theo - dQ from the current inputs (Q_theo when "
     "compensation is none)",
     kDependsOnQDesired | kDependsOnQdDesired | kDependsOnQddDesired | kDependsOnWrench},
    {&Roles::q_planned, "q_planned", Causality::Output, "rad",
     "Planned position of joint %s (Q_theo) that the compensation works on: its q_desired input, or the demo "
     "move",
     kDependsOnQDesired},
};

std::string format(const char* pattern, const std::string& joint) {
  const std::string text = pattern;
  const std::size_t at = text.find("%s");
  return at == std::string::npos ? text : text.substr(0, at) + joint + text.substr(at + 2);
}

class TableBuilder {
public:
  TableBuilder(VariableTable& table) : table_(table) {}

  int add(Variable v) {
    v.vr = static_cast<std::uint32_t>(table_.variables.size());
    if (!names_.insert(v.name).second) {
      throw Error("FMU variables: the name '" + v.name + "' is made twice (two parameters of one name?)");
    }
    if (!v.unit.empty()) used_units_.insert(v.unit);
    table_.variables.push_back(std::move(v));
    return static_cast<int>(table_.variables.size()) - 1;
  }

  void addScalars();
  void addJointRows(const JointRow& row, const Robot& robot);
  void addWrenchAndTool();
  void addDependencies(const JointRow& row);
  void keepUsedUnits();

private:
  VariableTable& table_;
  std::set<std::string> names_;
  std::set<std::string> used_units_;
};

Variable scalar(const char* name, Causality causality, Variability variability, VariableType type, double start,
                const char* description) {
  Variable v;
  v.name = name;
  v.causality = causality;
  v.variability = variability;
  v.type = type;
  v.has_start = causality == Causality::Parameter || causality == Causality::Input;
  v.start = start;
  v.description = description;
  return v;
}

void TableBuilder::addScalars() {
  Roles& r = table_.roles;
  Variable time =
      scalar("time", Causality::Independent, Variability::Continuous, VariableType::Real, 0.0, "Simulation time");
  time.unit = "s";
  r.time = add(time);
  Variable compensation =
      scalar("compensation", Causality::Parameter, Variability::Tunable, VariableType::Enumeration, 2.0,
             "Offline compensation in front of the plant: none, stiffness (joint compliance), stiffness and "
             "kinematic (compliance, gear transmission error and every other effect of the parameter file; the "
             "command is Q_ref = Q_theo - dQ from the nominal model), or dynamic (the same under the motion's "
             "inertial load, plus the inverse of the drives' tracking, from q, qd and qdd desired)");
  compensation.enumeration = "CompensationMode";
  r.compensation = add(compensation);
  r.use_velocity_inputs =
      add(scalar("use_velocity_inputs", Causality::Parameter, Variability::Fixed, VariableType::Boolean, 0.0,
                 "true: the desired joint velocities are the qd_desired inputs; false: they are estimated from "
                 "q_desired at the last three communication points (the slope of the parabola through them; the "
                 "change over the last communication step after the first step, zero on the first)"));
  r.compensate_wrench =
      add(scalar("compensate_wrench", Causality::Parameter, Variability::Fixed, VariableType::Boolean, 0.0,
                 "true: the compensator also corrects the deflection caused by the tool wrench input (a process "
                 "force known in advance); false: it corrects gravity and the modelled loads only"));
  Variable reference =
      scalar("reference", Causality::Parameter, Variability::Fixed, VariableType::Enumeration, 0.0,
             "What the robot is asked to follow: auto (the built-in demo move unless a q_desired or qd_desired "
             "input is set before the end of initialisation), inputs, or demo; the q_planned outputs show what "
             "it is following");
  reference.enumeration = "ReferenceSource";
  r.reference = add(reference);
}

void TableBuilder::addJointRows(const JointRow& row, const Robot& robot) {
  std::vector<int>& indices = table_.roles.*row.role;
  for (const Joint& joint : robot.joints) {
    Variable v;
    v.name = std::string(row.prefix) + "." + structuredNamePart(joint.name);
    v.causality = row.causality;
    v.variability = Variability::Continuous;
    v.unit = row.unit;
    v.description = format(row.description, joint.name);
    if (row.causality == Causality::Input) {
      v.has_start = true;
      if (row.role == &Roles::q_desired) {  // the joint's limits bound it; it starts at 0 or the nearest limit
        v.has_min = std::isfinite(joint.lower);
        v.has_max = std::isfinite(joint.upper);
        v.min = v.has_min ? joint.lower : v.min;
        v.max = v.has_max ? joint.upper : v.max;
        v.start = std::clamp(0.0, v.has_min ? joint.lower : -1.0, v.has_max ? joint.upper : 1.0);
      }
    }
    indices.push_back(add(std::move(v)));
  }
}

void TableBuilder::addWrenchAndTool() {
  static const char* const kWrench[6][3] = {{"force_x", "N", "x force"},     {"force_y", "N", "y force"},
                                            {"force_z", "N", "z force"},     {"moment_x", "N.m", "x moment"},
                                            {"moment_y", "N.m", "y moment"}, {"moment_z", "N.m", "z moment"}};
  for (int k = 0; k < 6; ++k) {
    Variable v = scalar("", Causality::Input, Variability::Continuous, VariableType::Real, 0.0, "");
    v.name = std::string("tool_wrench.") + kWrench[k][0];
    v.unit = kWrench[k][1];
    v.description =
        std::string("External wrench the environment applies at the tool point, base frame: ") + kWrench[k][2];
    table_.roles.wrench[static_cast<std::size_t>(k)] = add(std::move(v));
  }
}

void TableBuilder::addDependencies(const JointRow& row) {
  std::vector<int> inputs;
  const Roles& r = table_.roles;
  auto append = [&inputs](const auto& indices) { inputs.insert(inputs.end(), indices.begin(), indices.end()); };
  if (row.depends & kDependsOnQDesired) append(r.q_desired);
  if (row.depends & kDependsOnQdDesired) append(r.qd_desired);
  if (row.depends & kDependsOnQddDesired) append(r.qdd_desired);
  if (row.depends & kDependsOnWrench) append(r.wrench);
  std::sort(inputs.begin(), inputs.end());
  for (int index : table_.roles.*row.role) table_.variables[static_cast<std::size_t>(index)].depends = inputs;
}

void TableBuilder::keepUsedUnits() {
  for (const Unit& unit : knownUnits()) {
    if (used_units_.count(unit.name)) table_.units.push_back(unit);
  }
  for (const std::string& name : used_units_) {
    const bool known =
        std::any_of(knownUnits().begin(), knownUnits().end(), [&name](const Unit& unit) { return unit.name == name; });
    if (!known) throw Error("FMU variables: unit '" + name + "' is not among the FMU's unit definitions");
  }
}

std::vector<EnumerationType> enumerations() {
  return {
      {"CompensationMode",
       {{"none", 0, "no correction: the plant is commanded Q_theo"},
        {"stiffness", 1, "joint compliance corrected (the paper's stiffness correction)"},
        {"stiffness_and_kinematic", 2,
         "every effect of the parameter file corrected: joint compliance and gear transmission error (the "
         "paper's stiffness and kinematic correction) and whatever discovery added"},
        {"dynamic", 3,
         "stiffness and kinematic correction under the motion's whole inverse-dynamics load, and the drives' "
         "tracking inverted, sample by sample (needs qd_desired and qdd_desired or estimates them)"}}},
      {"ReferenceSource",
       {{"auto", 0,
         "the built-in demo move when no q_desired or qd_desired input was set before the end of "
         "initialisation (a plain run shows the robot moving), the inputs otherwise"},
        {"inputs", 1, "the q_desired (and qd_desired) inputs"},
        {"demo", 2,
         "the built-in demo move: every joint swings smoothly from the middle of its range and back, 10 s per "
         "cycle; the inputs are not used"}}},
  };
}

// An enumeration's min and max are its items' range (what set accepts), not written to the XML.
void setEnumerationRanges(VariableTable& table) {
  for (Variable& v : table.variables) {
    if (v.type != VariableType::Enumeration) continue;
    for (const EnumerationType& type : table.enumerations) {
      if (type.name != v.enumeration) continue;
      v.min = type.items.front().value;
      v.max = type.items.back().value;
    }
  }
}

}  // namespace

int ModelVariables::indexOfName(const std::string& name) const {
  for (const Variable& v : variables) {
    if (v.name == name) return static_cast<int>(v.vr);
  }
  return -1;
}

VariableTable buildVariableTable(const Robot& robot, const ParameterSet& parameters, const ModelAttributes& model,
                                 const std::string& instantiation_token) {
  if (robot.dof() < 1 || robot.dof() > kMaxFmuJoints) {
    throw Error("FMU of robot '" + robot.name + "': it has " + std::to_string(robot.dof()) +
                " moving joints; an FMU has 1 to " + std::to_string(kMaxFmuJoints));
  }
  if (!parameters.hasDrives()) {
    throw Error("FMU of robot '" + robot.name +
                "': the parameter file has no \"plant\" object (the drives and their controllers), which the "
                "FMU's flexible-joint plant needs");
  }
  VariableTable table;
  table.model = model;
  table.robot_name = robot.name;
  for (const Joint& joint : robot.joints) table.joint_names.push_back(joint.name);
  table.instantiation_token = instantiation_token;
  table.enumerations = enumerations();
  table.log_categories = {
      {"logStatusWarning", "Warnings"},
      {"logStatusDiscard", "Discarded calls and steps, with the reason (CVODE's message for a failed integration)"},
      {"logStatusError", "Errors: calls in the wrong state, bad arguments, failures"},
      {"logCalls", "Every FMI call with its arguments (verbose)"}};

  TableBuilder builder(table);
  builder.addScalars();
  for (const JointRow& row : kInputRows) builder.addJointRows(row, robot);
  builder.addWrenchAndTool();
  for (const JointRow& row : kOutputRows) builder.addJointRows(row, robot);
  static const char* const kTool[3] = {"tool_x", "tool_y", "tool_z"};
  for (int k = 0; k < 3; ++k) {
    Variable v = scalar(kTool[k], Causality::Output, Variability::Continuous, VariableType::Real, 0.0, "");
    v.unit = "m";
    v.description = std::string("Tool point ") + "xyz"[k] + " in the base frame, from the link positions";
    table.roles.tool_position[static_cast<std::size_t>(k)] = builder.add(std::move(v));
  }
  for (const JointRow& row : kOutputRows) builder.addDependencies(row);
  for (Variable& v : parameterRows(robot, parameters)) builder.add(std::move(v));
  builder.keepUsedUnits();
  setEnumerationRanges(table);
  if (table.variables.size() > 32000) {
    throw Error("FMU of robot '" + robot.name + "': " + std::to_string(table.variables.size()) +
                " variables; an FMU has at most 32000 (a parameter file with very long periodic tables?)");
  }
  return table;
}

FmuResources loadFmuResources(const std::string& resource_dir, const std::string& version,
                              const std::string& expected_token) {
  std::string dir = resource_dir;
  if (!dir.empty() && dir.back() != '/') dir += '/';
  constexpr std::uintmax_t kMaxResourceBytes = std::uintmax_t{64} << 20;
  const std::string robot_text = readInputFile(dir + "robot.json", "FMU's robot", kMaxResourceBytes);
  const std::string parameter_path = dir + "parameters.json";
  const std::string parameter_text = readInputFile(parameter_path, "FMU's parameter file", kMaxResourceBytes);
  const std::string token = instantiationToken(robot_text, parameter_text, version);
  if (!expected_token.empty() && expected_token != token) {
    throw Error("the instantiation token '" + expected_token + "' is not that of the resources in " + dir + " (" +
                token + "): modelDescription.xml and resources/ come from different exports");
  }
  auto robot = std::make_shared<const Robot>(robotFromJson(robot_text, dir + "robot.json"));
  ParameterSet parameters = parseParameterSet(parameter_text, parameter_path, robot, EffectRegistry::builtin());
  ModelAttributes model;
  model.version = version;
  VariableTable table = buildVariableTable(*robot, parameters, model, token);
  return FmuResources{std::move(robot), std::move(parameters), std::move(table)};
}

namespace {
// FNV-1a, 64 bits, from a given offset basis.
std::uint64_t fnv1a(const std::string& text, std::uint64_t hash) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  return hash;
}
}  // namespace

std::string instantiationToken(const std::string& robot_json, const std::string& parameters_json,
                               const std::string& version) {
  // Lengths first, so that moving bytes from one part to the next changes the token.
  const std::string all = std::to_string(robot_json.size()) + ":" + robot_json +
                          std::to_string(parameters_json.size()) + ":" + parameters_json + version;
  const std::uint64_t high = fnv1a(all, 0xcbf29ce484222325ULL);
  const std::uint64_t low = fnv1a(all, high ^ 0x9e3779b97f4a7c15ULL);
  char text[40];
  std::snprintf(text, sizeof text, "{%08x-%04x-%04x-%04x-%012llx}", static_cast<unsigned>(high >> 32),
                static_cast<unsigned>((high >> 16) & 0xffffu), static_cast<unsigned>(high & 0xffffu),
                static_cast<unsigned>(low >> 48), static_cast<unsigned long long>(low & 0xffffffffffffULL));
  return text;
}

std::string structuredNamePart(const std::string& text) {
  const auto identifier_char = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  };
  const bool identifier =
      !text.empty() && !(text[0] >= '0' && text[0] <= '9') && std::all_of(text.begin(), text.end(), identifier_char);
  if (identifier) return text;
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "'";
}

std::string describeVariable(const ModelVariables& table, int index) {
  return "vr " + std::to_string(index) + " (" + table.variables[static_cast<std::size_t>(index)].name + ")";
}

}  // namespace jointcomp::fmu
