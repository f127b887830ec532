#include "model/io/robot_file.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include <nlohmann/json.hpp>

#include "model/common/bits.hpp"
#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/common/strict_json.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp {
namespace {

constexpr const char* kFormat = "jointcomp-robot/1";

// nlohmann writes doubles in the shortest form that reads back to the same value.
nlohmann::ordered_json vector3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::ordered_json matrix3(const Eigen::Matrix3d& m) {
  nlohmann::ordered_json values = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) values.push_back(m(r, c));
  }
  return values;
}

nlohmann::ordered_json pose(const Eigen::Isometry3d& transform) {
  nlohmann::ordered_json json;
  json["rotation"] = matrix3(transform.linear());
  json["translation_m"] = vector3(transform.translation());
  return json;
}

// A limit: a number, or null for an unlimited (continuous) joint.
nlohmann::ordered_json limit(double value) {
  if (std::isinf(value)) return nullptr;
  return value;
}

Eigen::Vector3d readVector3(JsonFields& fields, const std::string& key) {
  const std::vector<double> v = fields.numbers(key, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Matrix3d readMatrix3(JsonFields& fields, const std::string& key) {
  const std::vector<double> v = fields.numbers(key, 9);
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = v[3 * r + c];
  }
  return m;
}

Eigen::Isometry3d readPose(JsonFields& parent, const std::string& key) {
  JsonFields fields(parent.object(key), parent.pathOf(key));
  const Eigen::Matrix3d rotation = readMatrix3(fields, "rotation");
  if (!(rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).isZero(1e-9) || rotation.determinant() < 0.0) {
    fields.fail("rotation", "not a rotation matrix (orthonormal, determinant +1)");
  }
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = rotation;
  transform.translation() = readVector3(fields, "translation_m");
  fields.rejectUnknownKeys();
  return transform;
}

// A limit: a finite number, or null for an unlimited (continuous) joint.
double readLimit(const nlohmann::json& object, const std::string& key, const std::string& path, double unlimited) {
  if (!object.contains(key)) throw ParameterError(path + "." + key + ": missing");
  const nlohmann::json& value = object.at(key);
  if (value.is_null()) return unlimited;
  if (!value.is_number()) throw ParameterError(path + "." + key + ": expected a number or null (unlimited)");
  const double x = value.get<double>();
  if (!std::isfinite(x)) throw ParameterError(path + "." + key + ": not finite");
  return x;
}

Joint readJoint(const nlohmann::json& object, const std::string& path) {
  if (!object.is_object()) throw ParameterError(path + ": expected a JSON object");
  const double infinity = std::numeric_limits<double>::infinity();
  Joint joint;
  joint.lower = readLimit(object, "lower_rad", path, -infinity);
  joint.upper = readLimit(object, "upper_rad", path, infinity);
  if (joint.lower > joint.upper) throw ParameterError(path + ".lower_rad: greater than upper_rad");
  nlohmann::json rest = object;  // the limits, which may be null, are read above
  rest.erase("lower_rad");
  rest.erase("upper_rad");
  JsonFields fields(rest, path);
  joint.name = fields.text("name");
  joint.child_link = fields.text("child_link");
  joint.placement = readPose(fields, "placement");
  joint.axis = readVector3(fields, "axis");
  if (std::abs(joint.axis.norm() - 1.0) > 1e-12) fields.fail("axis", "not a unit vector");
  joint.velocity_limit = fields.nonNegativeNumber("velocity_limit_rad_per_s");
  joint.effort_limit = fields.nonNegativeNumber("effort_limit_nm");
  JsonFields body(fields.object("body"), fields.pathOf("body"));
  joint.body.mass = body.nonNegativeNumber("mass_kg");
  joint.body.com = readVector3(body, "com_m");
  joint.body.inertia = readMatrix3(body, "inertia_kgm2");
  body.rejectUnknownKeys();
  fields.rejectUnknownKeys();
  return joint;
}

}  // namespace

std::string robotToJson(const Robot& robot) {
  nlohmann::ordered_json document;
  document["format"] = kFormat;
  document["name"] = robot.name;
  document["root_link"] = robot.root_link;
  document["tip_link"] = robot.tip_link;
  document["link_without_inertial"] = robot.link_without_inertial;
  document["gravity_m_per_s2"] = vector3(robot.gravity);
  document["tool"] = pose(robot.tool);
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (const Joint& joint : robot.joints) {
    nlohmann::ordered_json j;
    j["name"] = joint.name;
    j["child_link"] = joint.child_link;
    j["placement"] = pose(joint.placement);
    j["axis"] = vector3(joint.axis);
    j["lower_rad"] = limit(joint.lower);
    j["upper_rad"] = limit(joint.upper);
    j["velocity_limit_rad_per_s"] = joint.velocity_limit;
    j["effort_limit_nm"] = joint.effort_limit;
    j["body"]["mass_kg"] = joint.body.mass;
    j["body"]["com_m"] = vector3(joint.body.com);
    j["body"]["inertia_kgm2"] = matrix3(joint.body.inertia);
    joints.push_back(j);
  }
  document["joints"] = joints;
  return document.dump(2) + "\n";
}

Robot robotFromJson(const std::string& json_text, const std::string& source_name) {
  nlohmann::json document;
  try {
    document = parseStrictJson(json_text, source_name);
  } catch (const ParameterError& error) {
    throw UrdfError(error.what());
  }
  try {
    JsonFields fields(document, source_name + ": ");
    const std::string format = fields.text("format");
    if (format != kFormat) fields.fail("format", "expected \"" + std::string(kFormat) + "\", found \"" + format + "\"");
    Robot robot;
    robot.source = source_name;
    robot.name = fields.text("name");
    robot.root_link = fields.text("root_link");
    robot.tip_link = fields.text("tip_link");
    robot.link_without_inertial = fields.text("link_without_inertial");
    robot.gravity = readVector3(fields, "gravity_m_per_s2");
    robot.tool = readPose(fields, "tool");
    const nlohmann::json& joints = fields.array("joints");
    if (joints.empty()) fields.fail("joints", "no joints");
    if (joints.size() > static_cast<std::size_t>(kMaxJoints)) {
      fields.fail("joints",
                  std::to_string(joints.size()) + " joints; at most " + std::to_string(kMaxJoints) + " are supported");
    }
    for (std::size_t i = 0; i < joints.size(); ++i) {
      robot.joints.push_back(readJoint(joints[i], fields.pathOf("joints[" + std::to_string(i) + "]")));
    }
    fields.rejectUnknownKeys();
    return robot;
  } catch (const ParameterError& error) {
    throw UrdfError(error.what());
  }
}

Robot loadRobotFile(const std::string& path) {
  std::string text;
  try {
    text = readTextFile(path, "robot file", kMaxJsonFileBytes);
  } catch (const Error& error) {
    throw UrdfError(error.what());
  }
  return robotFromJson(text, path);
}

namespace {

using ::jointcomp::sameBits;  // doubles (model/common/bits.hpp); matrices below

template <typename Matrix>
bool sameBits(const Matrix& a, const Matrix& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    for (Eigen::Index c = 0; c < a.cols(); ++c) {
      if (!sameBits(a(r, c), b(r, c))) return false;
    }
  }
  return true;
}

}  // namespace

bool sameRobot(const Robot& a, const Robot& b) {
  if (a.name != b.name || a.root_link != b.root_link || a.tip_link != b.tip_link ||
      a.link_without_inertial != b.link_without_inertial || a.dof() != b.dof() || !sameBits(a.gravity, b.gravity) ||
      !sameBits(a.tool.matrix(), b.tool.matrix())) {
    return false;
  }
  for (int i = 0; i < a.dof(); ++i) {
    const Joint& x = a.joints[i];
    const Joint& y = b.joints[i];
    if (x.name != y.name || x.child_link != y.child_link || !sameBits(x.placement.matrix(), y.placement.matrix()) ||
        !sameBits(x.axis, y.axis) || !sameBits(x.lower, y.lower) || !sameBits(x.upper, y.upper) ||
        !sameBits(x.velocity_limit, y.velocity_limit) || !sameBits(x.effort_limit, y.effort_limit) ||
        !sameBits(x.body.mass, y.body.mass) || !sameBits(x.body.com, y.body.com) ||
        !sameBits(x.body.inertia, y.body.inertia)) {
      return false;
    }
  }
  return true;
}

}  // namespace jointcomp
