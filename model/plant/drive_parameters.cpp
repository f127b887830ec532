#include "model/plant/drive_parameters.hpp"

#include <nlohmann/json.hpp>

#include "model/common/json_fields.hpp"

namespace jointcomp {

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
    DriveParameters& d = drives[j];
    d.motor_inertia_kgm2 = joint.positiveNumber("motor_inertia_kgm2");
    d.viscous_friction_nms_per_rad = joint.nonNegativeNumber("viscous_friction_nms_per_rad");
    d.coulomb_friction_nm = joint.nonNegativeNumber("coulomb_friction_nm");
    d.coulomb_velocity_scale_rad_per_s = joint.positiveNumber("coulomb_velocity_scale_rad_per_s");
    d.transmission_damping_nms_per_rad = joint.nonNegativeNumber("transmission_damping_nms_per_rad");
    d.kp_nm_per_rad = joint.nonNegativeNumber("kp_nm_per_rad");
    d.ki_nm_per_rad_s = joint.nonNegativeNumber("ki_nm_per_rad_s");
    d.kd_nms_per_rad = joint.nonNegativeNumber("kd_nms_per_rad");
    joint.rejectUnknownKeys();
  }
  fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  return drives;
}

nlohmann::json drivesToJson(const std::vector<DriveParameters>& drives, const Robot& robot) {
  nlohmann::json joints = nlohmann::json::array();
  for (int j = 0; j < robot.dof(); ++j) {
    const DriveParameters& d = drives[j];
    joints.push_back({{"joint", robot.joints[j].name},
                      {"motor_inertia_kgm2", d.motor_inertia_kgm2},
                      {"viscous_friction_nms_per_rad", d.viscous_friction_nms_per_rad},
                      {"coulomb_friction_nm", d.coulomb_friction_nm},
                      {"coulomb_velocity_scale_rad_per_s", d.coulomb_velocity_scale_rad_per_s},
                      {"transmission_damping_nms_per_rad", d.transmission_damping_nms_per_rad},
                      {"kp_nm_per_rad", d.kp_nm_per_rad},
                      {"ki_nm_per_rad_s", d.ki_nm_per_rad_s},
                      {"kd_nms_per_rad", d.kd_nms_per_rad}});
  }
  return {{"joints", joints}};
}

}  // namespace jointcomp
