// Joint-error parameter files (JSON, one per robot): the gear train and the list of effects, every value
// with its unit in the key name, estimates marked with an "estimate" note. Format:
//   {"format": "jointcomp-parameters/1", "robot": "<URDF robot name>", "notes": "...",
//    "gears": {"joints": [{"joint": "joint_1", "stage_ratios": [..]}, ..], "coupling": [..]},
//    "effects": [{"type": "compliance", ..}, {"type": "spring_balancer", ..}, ..],
//    "plant": {"joints": [{"joint": "joint_1", "motor_inertia_kgm2": .., ..}, ..]},
//    "tool": {"flange_link": "flange", "link": "flange_target", "target_in_flange_m": [x, y, z]},
//    "base_frame": {"base_link": "base", "link": "measurement_frame", "base_xyz_m": [..], "base_rpy_rad": [..]}}
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "model/effects/joint_error_model.hpp"
#include "model/robot/drive_parameters.hpp"

namespace jointcomp {

class EffectRegistry;

// The tool point a calibration fitted (the "tool" object): the target in the frame of the URDF's tip link
// the campaigns were measured from (the flange), and the link the calibrated URDF carries it as, so that
// compensation and the plant work at that point. A maker's file has none.
struct ToolTarget {
  std::string flange_link;
  std::string link;
  Eigen::Vector3d in_flange = Eigen::Vector3d::Zero();  // m, within 10 m
};

// The frame a calibration's campaigns were measured in (the "base_frame" object): the pose of the URDF's
// root link in it (measured = base_in_frame * p_base; URDF roll-pitch-yaw, R = Rz Ry Rx) and the link the
// calibrated URDF carries it as. A calibration on campaigns in the base frame writes none.
struct BaseFrame {
  std::string base_link;
  std::string link;
  Eigen::Isometry3d base_in_frame = Eigen::Isometry3d::Identity();  // translation within 100 m
};

// Everything a parameter file says, read once: the joint-error model and, when the file has a "plant"
// object, the drives and controller gains of the plant, and the tool point when it has a "tool" object.
struct ParameterSet {
  JointErrorModel model;
  std::vector<DriveParameters> drives;  // empty when the file has no "plant" object
  std::optional<ToolTarget> tool;
  std::optional<BaseFrame> base_frame;
  bool hasDrives() const { return !drives.empty(); }
};

// Reads and fully validates the whole file, the "plant" object included (a malformed one is an error even
// for a caller that does not simulate). Effect types come from `registry` (the built-in one by default).
// Throws ParameterError naming the file and the JSON path of the offending field.
ParameterSet loadParameterSet(const std::string& path, std::shared_ptr<const Robot> robot);
ParameterSet loadParameterSet(const std::string& path, std::shared_ptr<const Robot> robot,
                              const EffectRegistry& registry);
ParameterSet parseParameterSet(const std::string& json_text, const std::string& source_name,
                               std::shared_ptr<const Robot> robot, const EffectRegistry& registry);

// Reads and fully validates a parameter file for `robot`. Throws ParameterError naming the file and the
// JSON path of the offending field (unknown keys, missing values, wrong types, out-of-range values).
JointErrorModel loadParameterFile(const std::string& path, std::shared_ptr<const Robot> robot);
JointErrorModel parseParameters(const std::string& json_text, const std::string& source_name,
                                std::shared_ptr<const Robot> robot);

// The "plant" object of a parameter file (drives and controller gains, see model/plant); throws
// ParameterError naming the file when the file has none or it is invalid.
std::vector<DriveParameters> loadDriveParameters(const std::string& path, const Robot& robot);
std::vector<DriveParameters> parseDriveParameters(const std::string& json_text, const std::string& source_name,
                                                  const Robot& robot);

// The file's text; the "plant" object is written when `drives` is not empty, the "tool" object when `tool`
// is given, the "base_frame" object when `base_frame` is.
std::string parametersToJson(const JointErrorModel& model, const std::vector<DriveParameters>& drives = {},
                             const ToolTarget* tool = nullptr, const BaseFrame* base_frame = nullptr);
// Writes whole or not at all (temporary file, then rename).
void saveParameterFile(const JointErrorModel& model, const std::string& path,
                       const std::vector<DriveParameters>& drives = {}, const ToolTarget* tool = nullptr,
                       const BaseFrame* base_frame = nullptr);

// A calibrated robot's two files: the URDF of model.robot() with the tool link (when `tool` is given and
// its flange is the robot's tip link) and the frame link (when `base_frame` is given), and the parameter
// file with "tool" and "base_frame". An empty path skips that file.
void saveCalibratedRobot(const JointErrorModel& model, const std::vector<DriveParameters>& drives,
                         const ToolTarget* tool, const BaseFrame* base_frame, const std::string& urdf_path,
                         const std::string& urdf_comment, const std::string& parameter_path);

}  // namespace jointcomp
