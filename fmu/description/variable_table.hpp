// The FMU's variables for one robot, built at run time from the robot and its parameter file: the same
// table serves `jointcomp export-fmu` (which writes it as modelDescription.xml) and the FMU's binary
// (which builds it again from its resources at instantiation and checks the instantiation token), so one
// binary serves every robot and the table is never written down twice.
//
// Value references are the table's indices (0 .. size-1), so a lookup is a bounds check. Variables of one
// role over the joints (q_desired, q_link, ...) are consecutive, in the chain's joint order.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "model/io/parameter_file.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp::fmu {

enum class VariableType : std::uint8_t { Real, Integer, Boolean, Enumeration };
enum class Causality : std::uint8_t { Parameter, Input, Output, Independent };
enum class Variability : std::uint8_t { Fixed, Tunable, Discrete, Continuous };
// What a parameter sets in the model (None: the instance code reads it by its role).
enum class Binding : std::uint8_t { None, Plant, Compensator, Drive, Integrator };

struct Variable {
  std::uint32_t vr = 0;  // == its index in the table
  std::string name;      // FMI structured name, e.g. q_desired.joint_2, plant.joint_1.stiffness
  VariableType type = VariableType::Real;
  Causality causality = Causality::Parameter;
  Variability variability = Variability::Fixed;
  bool has_start = false;                 // parameters and inputs have one, outputs and the time do not
  double start = 0.0;                     // 0 when there is none; Booleans 0 or 1
  bool has_min = false, has_max = false;  // declared in modelDescription.xml
  // What set accepts: the declared bounds, -inf / +inf where none is declared, an enumeration's items' range.
  double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
  Binding binding = Binding::None;
  std::string key;          // the bound parameter's name in the model ("joint_1.stiffness_nm_per_rad"), "" else
  std::string unit;         // one of VariableTable::units, "" for none
  std::string enumeration;  // the declared type of an Enumeration
  std::string description;
  std::vector<int> depends;  // the inputs an output depends on directly (indices), sorted
};

struct Unit {
  std::string name;
  // Exponents of kg, m, s, A, K, mol, cd, rad (FMI's BaseUnit attributes, in that order).
  std::array<int, 8> exponents{};
  std::string description;
};

struct EnumerationItem {
  std::string name;
  int value = 0;
  std::string description;
};
struct EnumerationType {
  std::string name;
  std::vector<EnumerationItem> items;
};

struct LogCategory {
  std::string name, description;
};

// Model-level attributes of modelDescription.xml.
struct ModelAttributes {
  std::string model_name = "jointcomp";
  std::string model_identifier = "jointcomp";  // the binary's name
  std::string description, author = "jointcomp", copyright = "jointcomp authors", license = "BSD-3-Clause";
  std::string version;  // the project's version
  std::string generation_tool = "jointcomp export-fmu";
  double start_time = 0.0, stop_time = 30.0, step_size = 0.001;  // the default experiment
};

// Indices of the variables the instance refers to by role. Per-joint roles have one index per joint.
struct Roles {
  int time = -1, compensation = -1, use_velocity_inputs = -1, compensate_wrench = -1, reference = -1;
  std::vector<int> q_desired, qd_desired, qdd_desired;
  std::array<int, 6> wrench{};  // force x, y, z, moment x, y, z
  std::vector<int> q_motor, qd_motor, q_link, qd_link, dq_predicted, dq_actual, q_ref, q_planned;
  std::array<int, 3> tool_position{};
};

struct VariableTable {
  ModelAttributes model;
  std::vector<Unit> units;                    // only those the variables use
  std::vector<EnumerationType> enumerations;  // CompensationMode, ReferenceSource
  std::vector<LogCategory> log_categories;    // in the order the instance's categories are numbered
  std::vector<Variable> variables;            // index == value reference
  Roles roles;
  std::string robot_name;
  std::vector<std::string> joint_names;
  std::string instantiation_token;  // "{xxxxxxxx-xxxx-...}"

  int dof() const { return static_cast<int>(joint_names.size()); }
  int size() const { return static_cast<int>(variables.size()); }
  // The index of a value reference, -1 if the table has none.
  int indexOf(std::uint32_t vr) const { return vr < variables.size() ? static_cast<int>(vr) : -1; }
  // -1 if no variable has that name.
  int indexOfName(const std::string& name) const;
};

// The most joints an FMU has (a bound on every per-joint allocation of the instance).
inline constexpr int kMaxFmuJoints = 64;

// The table of the robot's FMU: every parameter of the parameter file's effects (as plant.* for the
// simulated robot and compensator.* for the compensator's nominal model), the drives' gains, the plant's
// integrator options, and the per-joint inputs and outputs named after the URDF's joints. `parameters`
// must have drives (its "plant" object). Throws jointcomp::Error naming what the FMU cannot represent: no
// drives, more than kMaxFmuJoints joints, two parameters of one name, a start value outside the bounds
// the FMU declares (a stiffness below what its plant accepts, ...), a non-finite value.
VariableTable buildVariableTable(const Robot& robot, const ParameterSet& parameters, const ModelAttributes& model,
                                 const std::string& instantiation_token);

// An FMU's resources as its binary reads them: <resource_dir>/robot.json and <resource_dir>/parameters.json
// (each at most 64 MB), and the variable table built from them with the token of their bytes and `version`.
// Throws jointcomp::Error naming the file at fault or what the FMU cannot represent, and, first of all, when
// `expected_token` is given and is not the token of the resources' bytes (they are another FMU's).
struct FmuResources {
  std::shared_ptr<const Robot> robot;
  ParameterSet parameters;
  VariableTable table;
};
FmuResources loadFmuResources(const std::string& resource_dir, const std::string& version,
                              const std::string& expected_token = "");

// The token of an FMU whose resources are these bytes (robot.json, parameters.json) for this version of
// jointcomp: export-fmu writes it into modelDescription.xml, the binary computes it from its resources and
// refuses an importer's token that differs. A UUID-shaped text of a 128-bit FNV-1a hash.
std::string instantiationToken(const std::string& robot_json, const std::string& parameters_json,
                               const std::string& version);

// A name FMI's structured naming accepts for one part: the text itself when it is an identifier
// ([A-Za-z_][A-Za-z0-9_]*), else quoted ('...' with ' and \ escaped by a backslash).
std::string structuredNamePart(const std::string& text);

// "vr 12 (q_desired.joint_3)", for messages.
std::string describeVariable(const VariableTable& table, int index);

}  // namespace jointcomp::fmu
