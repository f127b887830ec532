#include "model/robot/load_urdf.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>
#include <Eigen/Eigenvalues>

#include "model/common/errors.hpp"
#include "model/common/input_file.hpp"
#include "model/common/plain_text.hpp"

namespace jointcomp {
namespace {

// urdfdom reports why a file is rejected only through console_bridge. This handler keeps the last
// messages of the calling thread so that they can go into our exception instead of onto stderr.
class CapturingOutputHandler : public console_bridge::OutputHandler {
public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_WARN) return;
    std::string& buffer = capturedText();
    if (buffer.size() < 4096) buffer += (buffer.empty() ? "" : "; ") + text;
  }
  static std::string& capturedText() {
    thread_local std::string buffer;
    return buffer;
  }
};

void installCapturingHandlerOnce() {
  static CapturingOutputHandler handler;
  static std::once_flag once;
  std::call_once(once, [] { console_bridge::useOutputHandler(&handler); });
}

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond rotation(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  transform.linear() = rotation.normalized().toRotationMatrix();
  transform.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return transform;
}

std::string formatted(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

bool withinReach(const urdf::Pose& pose) {
  return std::abs(pose.position.x) <= kMaxUrdfDistance && std::abs(pose.position.y) <= kMaxUrdfDistance &&
         std::abs(pose.position.z) <= kMaxUrdfDistance;
}

bool isFinite(const urdf::Pose& pose) {
  return std::isfinite(pose.position.x) && std::isfinite(pose.position.y) && std::isfinite(pose.position.z) &&
         std::isfinite(pose.rotation.x) && std::isfinite(pose.rotation.y) && std::isfinite(pose.rotation.z) &&
         std::isfinite(pose.rotation.w);
}

const char* jointTypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

class ChainBuilder {
public:
  ChainBuilder(const urdf::ModelInterface& model, std::string source) : model_(model), source_(std::move(source)) {}

  Robot build(const UrdfChainOptions& options) {
    checkTree();
    Robot robot;
    robot.name = model_.getName();
    robot.source = source_;
    robot.root_link = options.root_link.empty() ? model_.getRoot()->name : options.root_link;
    urdf::LinkConstSharedPtr root = model_.getLink(robot.root_link);
    if (!root) fail("root link '" + robot.root_link + "' does not exist");
    robot.tip_link = options.tip_link.empty() ? longestChainTip(root) : options.tip_link;
    urdf::LinkConstSharedPtr tip = model_.getLink(robot.tip_link);
    if (!tip) fail("tip link '" + robot.tip_link + "' does not exist");

    std::vector<urdf::JointConstSharedPtr> path = pathFromRoot(root, tip);
    Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
    for (const auto& urdf_joint : path) {
      const std::string where = "joint '" + urdf_joint->name + "'";
      if (!isFinite(urdf_joint->parent_to_joint_origin_transform)) fail(where + ": <origin> is not finite");
      if (!withinReach(urdf_joint->parent_to_joint_origin_transform))
        fail(where + ": <origin> is more than " + formatted(kMaxUrdfDistance) + " m away");
      pending = pending * toIsometry(urdf_joint->parent_to_joint_origin_transform);
      if (urdf_joint->type == urdf::Joint::FIXED) continue;
      if (urdf_joint->type != urdf::Joint::REVOLUTE && urdf_joint->type != urdf::Joint::CONTINUOUS) {
        fail(where + " is " + jointTypeName(urdf_joint->type) +
             "; jointcomp models chains of revolute (and continuous) joints only");
      }
      if (urdf_joint->mimic) {
        fail(where + " mimics joint '" + urdf_joint->mimic->joint_name +
             "'; jointcomp models independently driven joints (choose a tip link before it)");
      }
      robot.joints.push_back(makeJoint(*urdf_joint, pending, where));
      pending.setIdentity();
    }
    if (robot.joints.empty()) fail("no revolute joint between '" + robot.root_link + "' and '" + robot.tip_link + "'");
    if (robot.dof() > kMaxJoints) {
      fail("the chain has " + std::to_string(robot.dof()) + " moving joints; at most " + std::to_string(kMaxJoints) +
           " are supported");
    }
    robot.tool = pending;

    // Every link moved by joint i and rigidly attached to its child link belongs to body i.
    for (int i = 0; i < robot.dof(); ++i) {
      Joint& joint = robot.joints[i];
      const std::string next_on_chain = i + 1 < robot.dof() ? robot.joints[i + 1].name : std::string();
      accumulateBody(model_.getLink(joint.child_link), Eigen::Isometry3d::Identity(), next_on_chain, path, joint.body);
      if (joint.body.mass <= 0.0 && robot.link_without_inertial.empty()) {
        robot.link_without_inertial = joint.child_link;
      }
    }
    return robot;
  }

private:
  [[noreturn]] void fail(const std::string& what) const { throw UrdfError(source_ + ": " + what); }

  // urdfdom lets a link be the child of two joints (the last one read wins, silently); a URDF is a tree.
  void checkTree() const {
    std::map<std::string, std::string> parent_joint_of;
    for (const auto& [name, joint] : model_.joints_) {
      const auto [first, inserted] = parent_joint_of.emplace(joint->child_link_name, name);
      if (!inserted) {
        fail("link '" + joint->child_link_name + "' is the child of joints '" + first->second + "' and '" + name +
             "'; a URDF is a tree: every link has one parent");
      }
    }
  }

  // The leaf below `root` with the most moving joints on its way: ROS-Industrial URDFs hang fixed frames
  // (base, flange, tool0, a camera) off the arm, and the arm is the longest moving chain. Of leaves with
  // as many moving joints, those that are fixed frames below the same last moving joint are one arm with
  // frames on its end: the deepest of them is the tool when it is the only one (a flange -> tool0
  // chain); otherwise the tip is ambiguous and must be named.
  std::string longestChainTip(const urdf::LinkConstSharedPtr& root) const {
    struct Leaf {
      std::string link;
      int moving = 0;
      int depth = 0;
    };
    std::vector<Leaf> leaves;
    std::vector<std::pair<urdf::LinkConstSharedPtr, Leaf>> stack = {{root, Leaf{root->name, 0, 0}}};
    while (!stack.empty()) {
      auto [link, at] = stack.back();
      stack.pop_back();
      if (link->child_joints.empty()) leaves.push_back({link->name, at.moving, at.depth});
      for (const auto& joint : link->child_joints) {
        const bool moving = joint->type != urdf::Joint::FIXED;
        stack.push_back(
            {model_.getLink(joint->child_link_name), Leaf{joint->child_link_name, at.moving + moving, at.depth + 1}});
      }
    }
    int most = 0;
    for (const Leaf& leaf : leaves) most = std::max(most, leaf.moving);
    std::vector<const Leaf*> longest;
    for (const Leaf& leaf : leaves) {
      if (leaf.moving == most) longest.push_back(&leaf);
    }
    std::sort(longest.begin(), longest.end(), [](const Leaf* a, const Leaf* b) { return a->depth > b->depth; });
    if (longest.size() > 1 && longest[0]->depth == longest[1]->depth) {
      std::string names;
      for (const Leaf* leaf : longest) names += (names.empty() ? "'" : ", '") + leaf->link + "'";
      fail("the tree branches at link '" + commonAncestor(longest[0]->link, longest[1]->link) + "' into " +
           std::to_string(longest.size()) + " tips with " + std::to_string(most) + " moving joints (" + names +
           "); name the tip link of the chain (--tip-link, tip_link)");
    }
    return longest.front()->link;
  }

  std::string commonAncestor(const std::string& a, const std::string& b) const {
    std::vector<std::string> above_a;
    for (auto link = model_.getLink(a); link; link = link->getParent()) above_a.push_back(link->name);
    for (auto link = model_.getLink(b); link; link = link->getParent()) {
      if (std::find(above_a.begin(), above_a.end(), link->name) != above_a.end()) return link->name;
    }
    return model_.getRoot()->name;
  }

  std::vector<urdf::JointConstSharedPtr> pathFromRoot(const urdf::LinkConstSharedPtr& root,
                                                      urdf::LinkConstSharedPtr link) const {
    std::vector<urdf::JointConstSharedPtr> reversed;
    const std::string tip_name = link->name;
    while (link->name != root->name) {
      if (!link->parent_joint) fail("tip link '" + tip_name + "' is not below root link '" + root->name + "'");
      reversed.push_back(link->parent_joint);
      link = model_.getLink(link->parent_joint->parent_link_name);
    }
    return {reversed.rbegin(), reversed.rend()};
  }

  Joint makeJoint(const urdf::Joint& urdf_joint, const Eigen::Isometry3d& placement, const std::string& where) const {
    Joint joint;
    joint.name = urdf_joint.name;
    joint.child_link = urdf_joint.child_link_name;
    joint.placement = placement;
    Eigen::Vector3d axis(urdf_joint.axis.x, urdf_joint.axis.y, urdf_joint.axis.z);
    if (!axis.allFinite() || axis.norm() < 1e-9) fail(where + ": <axis> is zero or not finite");
    joint.axis = axis.normalized();
    if (urdf_joint.type == urdf::Joint::CONTINUOUS) {
      joint.lower = -std::numeric_limits<double>::infinity();
      joint.upper = std::numeric_limits<double>::infinity();
    } else {
      if (!urdf_joint.limits) fail(where + ": a revolute joint needs <limit lower upper>");
      joint.lower = urdf_joint.limits->lower;
      joint.upper = urdf_joint.limits->upper;
      if (!std::isfinite(joint.lower) || !std::isfinite(joint.upper)) fail(where + ": <limit> is not finite");
      if (joint.lower > joint.upper) {
        fail(where + ": <limit> lower " + std::to_string(joint.lower) + " > upper " + std::to_string(joint.upper));
      }
    }
    if (urdf_joint.limits) {
      joint.velocity_limit = urdf_joint.limits->velocity;
      joint.effort_limit = urdf_joint.limits->effort;
      if (!std::isfinite(joint.velocity_limit) || joint.velocity_limit < 0.0 || !std::isfinite(joint.effort_limit) ||
          joint.effort_limit < 0.0) {
        fail(where + ": <limit> velocity and effort must be finite and non-negative");
      }
    }
    return joint;
  }

  // Adds the inertial of `link` (whose frame is `link_in_body` in the body frame) and of every link
  // fixed to it. A moving joint off the chain is a branch the model cannot represent. A stack, not
  // recursion: a URDF may hang thousands of fixed links in a row.
  void accumulateBody(const urdf::LinkConstSharedPtr& first, const Eigen::Isometry3d& first_in_body,
                      const std::string& next_on_chain, const std::vector<urdf::JointConstSharedPtr>& path,
                      BodyInertia& body) const {
    std::vector<std::pair<urdf::LinkConstSharedPtr, Eigen::Isometry3d>> stack = {{first, first_in_body}};
    while (!stack.empty()) {
      const auto [link, link_in_body] = stack.back();
      stack.pop_back();
      if (link->inertial) addInertial(*link, link_in_body, body);
      // Children in reverse, so that they are visited (and their inertias summed) in the URDF's order.
      for (auto child_it = link->child_joints.rbegin(); child_it != link->child_joints.rend(); ++child_it) {
        const urdf::JointConstSharedPtr& child = *child_it;
        if (child->name == next_on_chain) continue;
        const bool on_path =
            std::any_of(path.begin(), path.end(), [&](const auto& j) { return j->name == child->name; });
        if (child->type != urdf::Joint::FIXED) {
          // Moving joints below the last body lie beyond the tip: the chain ends there (as in KDL).
          if (on_path || next_on_chain.empty()) continue;
          fail("joint '" + child->name + "' branches off the chain at link '" + link->name +
               "'; jointcomp models a single serial chain (choose another tip link or remove the branch)");
        }
        stack.emplace_back(model_.getLink(child->child_link_name),
                           link_in_body * toIsometry(child->parent_to_joint_origin_transform));
      }
    }
  }

  void addInertial(const urdf::Link& link, const Eigen::Isometry3d& link_in_body, BodyInertia& body) const {
    const urdf::Inertial& inertial = *link.inertial;
    const std::string where = "link '" + link.name + "' <inertial>";
    Eigen::Matrix3d inertia;
    inertia << inertial.ixx, inertial.ixy, inertial.ixz, inertial.ixy, inertial.iyy, inertial.iyz, inertial.ixz,
        inertial.iyz, inertial.izz;
    if (!std::isfinite(inertial.mass) || !inertia.allFinite() || !isFinite(inertial.origin)) {
      fail(where + " has a value that is not finite");
    }
    if (inertial.mass <= 0.0) fail(where + ": <mass> must be positive, is " + std::to_string(inertial.mass));
    if (inertial.mass > kMaxUrdfMass || inertia.cwiseAbs().maxCoeff() > kMaxUrdfInertia ||
        !withinReach(inertial.origin)) {
      fail(where + ": a mass of " + formatted(inertial.mass) + " kg, an inertia of " +
           formatted(inertia.cwiseAbs().maxCoeff()) + " kg m^2 or an origin beyond " + formatted(kMaxUrdfDistance) +
           " m is no robot's link (at most " + formatted(kMaxUrdfMass) + " kg and " + formatted(kMaxUrdfInertia) +
           " kg m^2)");
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal(inertia);
    const Eigen::Vector3d& moments = principal.eigenvalues();
    const double tolerance = 1e-9 * std::max(1.0, moments.cwiseAbs().maxCoeff());
    if (moments.minCoeff() < -tolerance || moments[0] + moments[1] < moments[2] - tolerance) {
      fail(where +
           ": <inertia> is not a physical inertia tensor (principal moments must be non-negative and "
           "satisfy the triangle inequality)");
    }
    const Eigen::Isometry3d inertial_in_body = link_in_body * toIsometry(inertial.origin);
    const Eigen::Vector3d com = inertial_in_body.translation();
    const Eigen::Matrix3d rotated = inertial_in_body.linear() * inertia * inertial_in_body.linear().transpose();
    // Combine the two bodies about their common centre of mass (parallel-axis theorem).
    const double total = body.mass + inertial.mass;
    const Eigen::Vector3d combined_com = (body.mass * body.com + inertial.mass * com) / total;
    auto shifted = [&](double mass, const Eigen::Vector3d& from) {
      const Eigen::Vector3d d = from - combined_com;
      return Eigen::Matrix3d(mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
    };
    body.inertia = body.inertia + shifted(body.mass, body.com) + rotated + shifted(inertial.mass, com);
    body.com = combined_com;
    body.mass = total;
  }

  const urdf::ModelInterface& model_;
  std::string source_;
};

}  // namespace

namespace {

// Where `text` at `from` continues after the end of a markup item that starts there and ends with
// `closing`; text.size() when it never ends (the parser then reports the error).
std::size_t after(const std::string& text, std::size_t from, const char* closing) {
  const std::size_t at = text.find(closing, from);
  return at == std::string::npos ? text.size() : at + std::strlen(closing);
}

// The deepest nesting of elements in the XML `text`, counted without parsing it (TinyXML parses nested
// elements by recursion, and 200,000 levels crash it): comments, CDATA, processing instructions and
// declarations are skipped, quoted attribute values may hold '>'. Stops counting past `limit`.
int elementDepth(const std::string& text, int limit) {
  int depth = 0, deepest = 0;
  std::size_t at = 0;
  while ((at = text.find('<', at)) != std::string::npos && deepest <= limit) {
    if (text.compare(at, 4, "<!--") == 0) {
      at = after(text, at + 4, "-->");
    } else if (text.compare(at, 9, "<![CDATA[") == 0) {
      at = after(text, at + 9, "]]>");
    } else if (text.compare(at, 2, "<?") == 0) {
      at = after(text, at + 2, "?>");
    } else if (text.compare(at, 2, "<!") == 0 || text.compare(at, 2, "</") == 0) {
      if (text[at + 1] == '/') depth = std::max(0, depth - 1);
      at = after(text, at + 2, ">");
    } else {
      char quote = 0;
      std::size_t end = at + 1;
      for (; end < text.size() && (quote != 0 || text[end] != '>'); ++end) {
        if (quote == 0 && (text[end] == '"' || text[end] == '\''))
          quote = text[end];
        else if (text[end] == quote)
          quote = 0;
      }
      if (end >= text.size() || text[end - 1] != '/') deepest = std::max(deepest, ++depth);
      at = end;
    }
  }
  return deepest;
}

}  // namespace

Robot loadRobotFromUrdfString(const std::string& urdf_text, const std::string& source_name,
                              const UrdfChainOptions& options) {
  std::string storage;
  const std::string& urdf_xml = plainText<UrdfError>(urdf_text, source_name, storage);
  if (urdf_xml.size() > kMaxUrdfBytes) {
    throw UrdfError(source_name + ": the URDF has " + std::to_string(urdf_xml.size()) + " bytes; at most " +
                    std::to_string(kMaxUrdfBytes) + " are read (is it the right file?)");
  }
  if (elementDepth(urdf_xml, kMaxUrdfDepth) > kMaxUrdfDepth) {
    throw UrdfError(source_name + ": the URDF nests elements more than " + std::to_string(kMaxUrdfDepth) +
                    " deep; a robot description needs a few levels");
  }
  installCapturingHandlerOnce();
  CapturingOutputHandler::capturedText().clear();
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(urdf_xml);
  } catch (const std::exception& error) {
    throw UrdfError(source_name + ": " + error.what());
  }
  if (!model) {
    std::string reason = CapturingOutputHandler::capturedText();
    throw UrdfError(source_name + ": not a valid URDF" + (reason.empty() ? std::string() : " (" + reason + ")"));
  }
  return ChainBuilder(*model, source_name).build(options);
}

Robot loadRobotFromUrdfFile(const std::string& path, const UrdfChainOptions& options) {
  std::string text;
  try {
    text = readInputFile(path, "URDF", kMaxUrdfBytes);
  } catch (const UrdfError&) {
    throw;
  } catch (const Error& error) {
    throw UrdfError(error.what());
  }
  return loadRobotFromUrdfString(text, path, options);
}

}  // namespace jointcomp
