// The loaded Robot as JSON ("jointcomp-robot/1"): every field of model/robot/robot.hpp, doubles written
// with full round-trip precision, so that robotFromJson(robotToJson(r)) equals r bit for bit.
// The FMU ships its robot in this form (resources/robot.json), converted from the URDF at build time,
// so that the FMU's binary needs no URDF parser. Format:
//   {"format": "jointcomp-robot/1", "name": "rx170", "root_link": .., "tip_link": ..,
//    "link_without_inertial": "", "gravity_m_per_s2": [x, y, z],
//    "tool": {"rotation": [9 values, row-major], "translation_m": [x, y, z]},
//    "joints": [{"name": .., "child_link": .., "placement": {"rotation": [..], "translation_m": [..]},
//                "axis": [x, y, z], "lower_rad": number or null (-inf), "upper_rad": number or null (+inf),
//                "velocity_limit_rad_per_s": .., "effort_limit_nm": ..,
//                "body": {"mass_kg": .., "com_m": [..], "inertia_kgm2": [9 values, row-major]}}, ..]}
#pragma once

#include <string>

#include "model/robot/robot.hpp"

namespace jointcomp {

std::string robotToJson(const Robot& robot);

// Reads and validates a robot written by robotToJson; `source_name` names the text in messages and
// becomes Robot::source. Throws UrdfError naming the source and the field at fault (malformed JSON,
// unknown or missing keys, non-finite numbers, a rotation that is not orthonormal, an axis that is not
// a unit vector, lower > upper, negative limits or mass, no joints or more than kMaxJoints).
Robot robotFromJson(const std::string& json_text, const std::string& source_name);

// Reads the file; throws UrdfError naming it when it cannot be read or is invalid.
Robot loadRobotFile(const std::string& path);

// True when every field of the two robots is bitwise the same (Robot::source aside).
bool sameRobot(const Robot& a, const Robot& b);

}  // namespace jointcomp
