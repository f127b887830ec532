#include "model/io/urdf_writer.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "model/common/errors.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp {
namespace {

std::string number(double value) {
  if (value == 0.0) return "0";  // also turns -0 into 0
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string triple(const Eigen::Vector3d& v) { return number(v.x()) + " " + number(v.y()) + " " + number(v.z()); }

std::string escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string origin(const Eigen::Isometry3d& pose) {
  return "<origin xyz=\"" + triple(pose.translation()) + "\" rpy=\"" + triple(rotationToRpy(pose.linear())) + "\"/>";
}

void requireFinite(bool finite, const std::string& robot, const std::string& what) {
  if (!finite) throw InvalidArgument("robotToUrdf: robot '" + robot + "': " + what + " is not finite");
}

void requireNewLink(const Robot& robot, const std::string& name, const std::string& what) {
  bool taken = name.empty() || name == robot.root_link || name == robot.tip_link;
  for (const Joint& joint : robot.joints) taken = taken || name == joint.child_link;
  if (taken) {
    throw InvalidArgument("robotToUrdf: robot '" + robot.name + "': the " + what + "'s name '" + name +
                          "' is empty or that of a link of the robot");
  }
}

void writeFrameLink(std::ostringstream& xml, const Robot& robot, const UrdfFrameLink& frame) {
  requireFinite(frame.base_in_frame.matrix().allFinite(), robot.name, "frame link '" + frame.name + "' pose");
  requireNewLink(robot, frame.name, "frame link");
  xml << "  <joint name=\"" << escaped(frame.name) << "_joint\" type=\"fixed\">\n";
  xml << "    <parent link=\"" << escaped(robot.root_link) << "\"/>\n";
  xml << "    <child link=\"" << escaped(frame.name) << "\"/>\n";
  xml << "    " << origin(frame.base_in_frame.inverse()) << "\n";
  xml << "  </joint>\n";
  xml << "  <link name=\"" << escaped(frame.name) << "\"/>\n";
}

void writeToolLink(std::ostringstream& xml, const Robot& robot, const UrdfToolLink& tool) {
  requireFinite(tool.offset.allFinite(), robot.name, "tool link '" + tool.name + "' offset");
  requireNewLink(robot, tool.name, "tool link");
  xml << "  <joint name=\"" << escaped(tool.name) << "_joint\" type=\"fixed\">\n";
  xml << "    <parent link=\"" << escaped(robot.tip_link) << "\"/>\n";
  xml << "    <child link=\"" << escaped(tool.name) << "\"/>\n";
  xml << "    <origin xyz=\"" << triple(tool.offset) << "\" rpy=\"0 0 0\"/>\n";
  xml << "  </joint>\n";
  xml << "  <link name=\"" << escaped(tool.name) << "\"/>\n";
}

}  // namespace

std::string uniqueLinkName(const Robot& robot, std::string wanted, const std::vector<std::string>& also_taken) {
  const auto taken = [&](const std::string& n) {
    if (n == robot.root_link || n == robot.tip_link) return true;
    for (const std::string& other : also_taken)
      if (n == other) return true;
    for (const Joint& joint : robot.joints)
      if (n == joint.child_link) return true;
    return false;
  };
  while (taken(wanted)) wanted += "_";
  return wanted;
}

Eigen::Matrix3d rpyToRotation(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d rotationToRpy(const Eigen::Matrix3d& r) {
  // R = Rz(yaw) Ry(pitch) Rx(roll). Roll from the last row (any value at gimbal lock, where r21 = r22 = 0),
  // then pitch and yaw from M = R Rx(roll)^T = Rz(yaw) Ry(pitch), whose entries used here have magnitude 1
  // or 0: the three angles give back R to rounding error everywhere, gimbal lock included.
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const Eigen::Matrix3d m = r * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix().transpose();
  return {roll, std::atan2(-m(2, 0), m(2, 2)), std::atan2(-m(0, 1), m(1, 1))};
}

std::string robotToUrdf(const Robot& robot, const std::string& comment, const UrdfToolLink* tool_link,
                        const UrdfFrameLink* frame_link) {
  if (robot.joints.empty()) throw InvalidArgument("robotToUrdf: robot '" + robot.name + "' has no joints");
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n";
  if (!comment.empty()) {
    std::string text = comment;
    for (std::size_t at = text.find("--"); at != std::string::npos; at = text.find("--")) text.replace(at, 2, "- ");
    xml << "<!--\n" << text << "\n-->\n";
  }
  xml << "<robot name=\"" << escaped(robot.name) << "\">\n";
  xml << "  <link name=\"" << escaped(robot.root_link) << "\"/>\n";
  std::string parent = robot.root_link;
  for (const Joint& joint : robot.joints) {
    const std::string where = "joint '" + joint.name + "'";
    requireFinite(joint.placement.matrix().allFinite(), robot.name, where + " placement");
    requireFinite(joint.axis.allFinite(), robot.name, where + " axis");
    requireFinite(std::isfinite(joint.velocity_limit) && std::isfinite(joint.effort_limit), robot.name,
                  where + " velocity or effort limit");
    requireFinite(std::isfinite(joint.body.mass) && joint.body.com.allFinite() && joint.body.inertia.allFinite(),
                  robot.name, where + " body");
    const bool continuous = std::isinf(joint.lower) && std::isinf(joint.upper) && joint.lower < 0 && joint.upper > 0;
    if (!continuous)
      requireFinite(std::isfinite(joint.lower) && std::isfinite(joint.upper), robot.name, where + " limit");
    xml << "  <joint name=\"" << escaped(joint.name) << "\" type=\"" << (continuous ? "continuous" : "revolute")
        << "\">\n";
    xml << "    <parent link=\"" << escaped(parent) << "\"/>\n";
    xml << "    <child link=\"" << escaped(joint.child_link) << "\"/>\n";
    xml << "    " << origin(joint.placement) << "\n";
    xml << "    <axis xyz=\"" << triple(joint.axis) << "\"/>\n";
    xml << "    <limit ";
    if (!continuous) xml << "lower=\"" << number(joint.lower) << "\" upper=\"" << number(joint.upper) << "\" ";
    xml << "velocity=\"" << number(joint.velocity_limit) << "\" effort=\"" << number(joint.effort_limit) << "\"/>\n";
    xml << "  </joint>\n";
    xml << "  <link name=\"" << escaped(joint.child_link) << "\"";
    if (joint.body.mass > 0.0) {
      const Eigen::Matrix3d& i = joint.body.inertia;
      xml << ">\n    <inertial>\n";
      xml << "      <origin xyz=\"" << triple(joint.body.com) << "\" rpy=\"0 0 0\"/>\n";
      xml << "      <mass value=\"" << number(joint.body.mass) << "\"/>\n";
      xml << "      <inertia ixx=\"" << number(i(0, 0)) << "\" ixy=\"" << number(i(0, 1)) << "\" ixz=\""
          << number(i(0, 2)) << "\" iyy=\"" << number(i(1, 1)) << "\" iyz=\"" << number(i(1, 2)) << "\" izz=\""
          << number(i(2, 2)) << "\"/>\n";
      xml << "    </inertial>\n  </link>\n";
    } else {
      xml << "/>\n";
    }
    parent = joint.child_link;
  }
  requireFinite(robot.tool.matrix().allFinite(), robot.name, "tool");
  if (robot.tip_link != parent) {
    xml << "  <joint name=\"" << escaped(robot.tip_link) << "_fixed_joint\" type=\"fixed\">\n";
    xml << "    <parent link=\"" << escaped(parent) << "\"/>\n";
    xml << "    <child link=\"" << escaped(robot.tip_link) << "\"/>\n";
    xml << "    " << origin(robot.tool) << "\n";
    xml << "  </joint>\n";
    xml << "  <link name=\"" << escaped(robot.tip_link) << "\"/>\n";
  } else if (robot.tool.matrix() != Eigen::Matrix4d::Identity()) {
    throw InvalidArgument("robotToUrdf: robot '" + robot.name + "': the tool frame is offset from link '" + parent +
                          "' but the tip link is that link itself");
  }
  if (tool_link) writeToolLink(xml, robot, *tool_link);
  if (frame_link) {
    if (tool_link && tool_link->name == frame_link->name) {
      throw InvalidArgument("robotToUrdf: robot '" + robot.name + "': the tool and frame links are both named '" +
                            frame_link->name + "'");
    }
    writeFrameLink(xml, robot, *frame_link);
  }
  xml << "</robot>\n";
  return xml.str();
}

void saveRobotUrdf(const Robot& robot, const std::string& path, const std::string& comment,
                   const UrdfToolLink* tool_link, const UrdfFrameLink* frame_link) {
  writeFileAtomically(path, robotToUrdf(robot, comment, tool_link, frame_link));
}

}  // namespace jointcomp
