#include "model/robot/drive_parameters.hpp"

#include <nlohmann/json.hpp>

#include <cmath>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<DriveField>& driveFields() {
  static const std::vector<DriveField> fields = {
      {"motor_inertia_kgm2", &DriveParameters::motor_inertia_kgm2, true},
      {"viscous_friction_nms_per_rad", &DriveParameters::viscous_friction_nms_per_rad, false},
      {"coulomb_friction_nm", &DriveParameters::coulomb_friction_nm, false},
      {"coulomb_velocity_scale_rad_per_s", &DriveParameters::coulomb_velocity_scale_rad_per_s, true},
      {"transmission_damping_nms_per_rad", &DriveParameters::transmission_damping_nms_per_rad, false},
      {"kp_nm_per_rad", &DriveParameters::kp_nm_per_rad, false},
      {"ki_nm_per_rad_s", &DriveParameters::ki_nm_per_rad_s, false},
      {"kd_nms_per_rad", &DriveParameters::kd_nms_per_rad, false},
  };
  return fields;
}

std::vector<std::string> driveParameterNames(const Robot& robot) {
  std::vector<std::string> names;
  for (const Joint& joint : robot.joints) {
    for (const DriveField& f : driveFields()) names.push_back(joint.name + "." + f.key);
  }
  return names;
}

std::vector<double> driveParameters(const std::vector<DriveParameters>& drives) {
  std::vector<double> values;
  for (const DriveParameters& d : drives) {
    for (const DriveField& f : driveFields()) values.push_back(d.*f.member);
  }
  return values;
}

void setDriveParameters(std::vector<DriveParameters>& drives, const Robot& robot, const std::vector<double>& values) {
  const std::size_t per_joint = driveFields().size();
  if (drives.size() != static_cast<std::size_t>(robot.dof()) || values.size() != drives.size() * per_joint) {
    throw ParameterError("drive parameters: expected " + std::to_string(robot.dof() * per_joint) + " values for " +
                         std::to_string(robot.dof()) + " drives, found " + std::to_string(values.size()) + " for " +
                         std::to_string(drives.size()));
  }
  for (std::size_t k = 0; k < values.size(); ++k) {  // everything is checked before anything changes
    const DriveField& f = driveFields()[k % per_joint];
    const double x = values[k];
    if (!std::isfinite(x) || (f.positive ? !(x > 0.0) : x < 0.0)) {
      throw ParameterError("drive parameters: " + robot.joints[k / per_joint].name + "." + f.key + " is " +
                           std::to_string(x) + "; it must be finite and " + (f.positive ? "positive" : "not negative"));
    }
  }
  for (std::size_t k = 0; k < values.size(); ++k)
    drives[k / per_joint].*(driveFields()[k % per_joint].member) = values[k];
}

std::vector<DriveParameters> drivesFromJson(const nlohmann::json& plant, const Robot& robot, const std::string& path) {
  JsonFields fields(plant, path);
  const nlohmann::json& joints = fields.array("joints");
  if (static_cast<int>(joints.size()) != robot.dof()) {
    fields.fail("joints", "expected one entry per joint (" + std::to_string(robot.dof()) + "), found " +
                              std::to_string(joints.size()));
  }
  std::vector<DriveParameters> drives(robot.dof());
  for (int j = 0; j < robot.dof(); ++j) {
    JsonFields joint(joints[j], fields.pathOf("joints[" + std::to_string(j) + "]"));
    const std::string name = joint.text("joint");
    if (name != robot.joints[j].name) joint.fail("joint", "expected '" + robot.joints[j].name + "' at this position");
    for (const DriveField& f : driveFields()) {
      drives[j].*f.member = f.positive ? joint.positiveNumber(f.key) : joint.nonNegativeNumber(f.key);
    }
    joint.rejectUnknownKeys();
  }
  fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  return drives;
}

nlohmann::json drivesToJson(const std::vector<DriveParameters>& drives, const Robot& robot) {
  nlohmann::json joints = nlohmann::json::array();
  for (int j = 0; j < robot.dof(); ++j) {
    nlohmann::json joint = {{"joint", robot.joints[j].name}};
    for (const DriveField& f : driveFields()) joint[f.key] = drives[j].*f.member;
    joints.push_back(joint);
  }
  return {{"joints", joints}};
}

}  // namespace jointcomp
