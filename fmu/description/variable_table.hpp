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

#include "fmu/description/variables.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp::fmu {

// Indices of the variables the instance refers to by role. Per-joint roles have one index per joint.
struct Roles {
  int time = -1, compensation = -1, use_velocity_inputs = -1, compensate_wrench = -1, reference = -1;
  std::vector<int> q_desired, qd_desired, qdd_desired;
  std::array<int, 6> wrench{};  // force x, y, z, moment x, y, z
  std::vector<int> q_motor, qd_motor, q_link, qd_link, dq_predicted, dq_actual, q_ref, q_planned;
  std::array<int, 3> tool_position{};
};

// The robot's table: the variables, and which of them play which role for the robot model.
struct VariableTable : ModelVariables {
  Roles roles;
  std::string robot_name;
  std::vector<std::string> joint_names;

  int dof() const { return static_cast<int>(joint_names.size()); }
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

}  // namespace jointcomp::fmu
