// The Robot written back as URDF (the inverse of model/robot/load_urdf.hpp), e.g. after a kinematic
// calibration changed the joint placements. One link per body (its merged inertial at the centre of mass,
// axes of the joint frame), one joint per revolute joint with the placement as <origin>, and the tool as a
// fixed joint to the tip link. Numbers carry 17 significant digits, so that loading the text gives back
// the same Robot to within about 1e-15 (fixed joints and links that the loader folded stay folded).
#pragma once

#include <string>
#include <vector>

#include "model/robot/robot.hpp"

namespace jointcomp {

// A point on the tool (a calibration's target) written as one more link, fixed to the tip link at
// `offset` (m, in the tip link's frame): loaded again, it is the chain's end, so that kinematics,
// compensation and the plant work at that point.
struct UrdfToolLink {
  std::string name;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

// The frame a calibration's campaigns were measured in (an instrument's or a cell's), written as one more
// link fixed to the root link, so that positions in that frame are one transform away: `base_in_frame` is
// the root link's pose in it (measured = base_in_frame * p_root). The root link stays the root, so the
// loaded robot's base and gravity do not change.
struct UrdfFrameLink {
  std::string name;
  Eigen::Isometry3d base_in_frame = Eigen::Isometry3d::Identity();
};

// `wanted`, with '_' appended until it names no link of the robot's chain and none of `also_taken`: the
// name of a link a calibrated URDF adds (the tool link "<tip>_target", the frame link
// "<root>_measurement_frame").
std::string uniqueLinkName(const Robot& robot, std::string wanted, const std::vector<std::string>& also_taken = {});

// `comment` (optional) goes into an XML comment at the top. Throws InvalidArgument for a robot the
// format cannot hold: no joints, non-finite values, a tool offset without a tip link of its own, a tool
// link named like a link of the robot.
std::string robotToUrdf(const Robot& robot, const std::string& comment = "", const UrdfToolLink* tool_link = nullptr,
                        const UrdfFrameLink* frame_link = nullptr);

// Writes whole or not at all (temporary file, then rename); throws Error naming the path.
void saveRobotUrdf(const Robot& robot, const std::string& path, const std::string& comment = "",
                   const UrdfToolLink* tool_link = nullptr, const UrdfFrameLink* frame_link = nullptr);

// The URDF roll-pitch-yaw angles of a rotation (R = Rz(yaw) Ry(pitch) Rx(roll)); they give back the
// rotation to rounding error everywhere, at and near pitch = +-pi/2 too.
Eigen::Vector3d rotationToRpy(const Eigen::Matrix3d& rotation);
// The rotation of URDF roll-pitch-yaw angles (rad): R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d rpyToRotation(const Eigen::Vector3d& rpy);

}  // namespace jointcomp
