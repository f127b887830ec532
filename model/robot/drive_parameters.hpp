// What the plant needs beyond the joint-error model: per joint, the drive (motor inertia reflected to
// the joint side, friction, transmission damping) and the gains of the motor-side position controller.
// They live in the parameter file's "plant" object: {"joints": [{"joint": "joint_1", ...}, ...]}.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "model/robot/robot.hpp"

namespace jointcomp {

struct DriveParameters {
  double motor_inertia_kgm2 = 1.0;                 // rotor (and first stage) inertia seen at the joint
  double viscous_friction_nms_per_rad = 0.0;       // motor side, joint units
  double coulomb_friction_nm = 0.0;                // motor side, joint units
  double coulomb_velocity_scale_rad_per_s = 1e-3;  // Coulomb friction = F tanh(v / scale): smooth at rest
  double transmission_damping_nms_per_rad = 0.0;   // in parallel with the joint spring
  double kp_nm_per_rad = 0.0;                      // controller: position gain on the motor
  double ki_nm_per_rad_s = 0.0;                    // integral gain
  double kd_nms_per_rad = 0.0;                     // velocity gain
};

// The fields of a drive by name: the parameter file's keys, the member, and what values are accepted
// (positive, or not negative). One table for reading, writing and naming the parameters.
struct DriveField {
  const char* key;  // "kp_nm_per_rad"
  double DriveParameters::*member;
  bool positive;  // true: > 0; false: >= 0
};
const std::vector<DriveField>& driveFields();

// The drives' parameters by name, like the effects' (effect.hpp): "<joint>.<key>" ("joint_2.kp_nm_per_rad"),
// joint by joint, each joint's fields in the order of driveFields().
std::vector<std::string> driveParameterNames(const Robot& robot);
std::vector<double> driveParameters(const std::vector<DriveParameters>& drives);
// Throws ParameterError naming the parameter for a value out of range or the wrong count; a refused
// update leaves the drives as they were.
void setDriveParameters(std::vector<DriveParameters>& drives, const Robot& robot, const std::vector<double>& values);

std::vector<DriveParameters> drivesFromJson(const nlohmann::json& plant, const Robot& robot, const std::string& path);
nlohmann::json drivesToJson(const std::vector<DriveParameters>& drives, const Robot& robot);

}  // namespace jointcomp
