// Robot handles: loading, queries, conditions, kinematics and gravity.
#include "api_support.hpp"
#include "model/effects/registry.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

// The "plant" object is optional in a parameter file; present, it must be valid (the set is read once).
std::unique_ptr<jc_robot> robotFromParameters(const std::shared_ptr<const Robot>& robot, const std::string& json_text,
                                              const std::string& source_name) {
  ParameterSet parameters = parseParameterSet(json_text, source_name, robot, EffectRegistry::builtin());
  auto made = std::make_unique<jc_robot>(robot, std::move(parameters.model), std::move(parameters.drives));
  made->tool = std::move(parameters.tool);
  made->base_frame = std::move(parameters.base_frame);
  return made;
}

// Kinematics and dynamics only: no joint errors, no drives.
std::unique_ptr<jc_robot> withoutParameters(const std::shared_ptr<const Robot>& robot) {
  return std::make_unique<jc_robot>(robot, JointErrorModel(robot, GearTrain::direct(robot->dof()), {}),
                                    std::vector<DriveParameters>{});
}

// The chain of the URDF between the links named (NULL or "": the URDF's root, the end of its longest moving
// chain), with the parameters of a file or JSON text (neither: kinematics and dynamics only).
std::unique_ptr<jc_robot> loadRobot(const char* urdf_path, const char* base_link, const char* tip_link,
                                    const char* parameter_path, const char* parameters_json) {
  UrdfChainOptions chain;
  if (base_link) chain.root_link = base_link;
  if (tip_link) chain.tip_link = tip_link;
  const auto loaded = std::make_shared<const Robot>(loadRobotFromUrdfFile(requireText(urdf_path, "urdf_path"), chain));
  if (parameters_json) return robotFromParameters(loaded, parameters_json, "parameters_json");
  if (!parameter_path) return withoutParameters(loaded);
  std::string text;
  try {
    text = readTextFile(parameter_path, "parameter file", kMaxJsonFileBytes);
  } catch (const ParameterError&) {
    throw;
  } catch (const Error& error) {
    throw ParameterError(error.what());  // as loadParameterFile reports it
  }
  return robotFromParameters(loaded, text, parameter_path);
}

}  // namespace

extern "C" {

jc_status jc_robot_load(const char* urdf_path, const char* parameter_path, jc_robot** robot) {
  return CAPI_ENTRY({
    requirePointer(robot, "robot");
    *robot = publish(loadRobot(urdf_path, nullptr, nullptr, parameter_path, nullptr));
  });
}

jc_status jc_robot_load_json(const char* urdf_path, const char* parameters_json, jc_robot** robot) {
  return CAPI_ENTRY({
    requirePointer(robot, "robot");
    requireText(parameters_json, "parameters_json");
    *robot = publish(loadRobot(urdf_path, nullptr, nullptr, nullptr, parameters_json));
  });
}

jc_status jc_robot_load_text(const char* urdf_text, const char* parameters_json, jc_robot** robot) {
  return CAPI_ENTRY({
    requirePointer(robot, "robot");
    const auto loaded =
        std::make_shared<const Robot>(loadRobotFromUrdfString(requireText(urdf_text, "urdf_text"), "urdf_text"));
    *robot = publish(parameters_json ? robotFromParameters(loaded, parameters_json, "parameters_json")
                                     : withoutParameters(loaded));
  });
}

jc_status jc_robot_load_chain(const char* urdf_path, const char* base_link, const char* tip_link,
                              const char* parameter_path, const char* parameters_json, jc_robot** robot) {
  return CAPI_ENTRY({
    requirePointer(robot, "robot");
    if (parameter_path && parameters_json) invalid("give parameter_path or parameters_json, not both");
    *robot = publish(loadRobot(urdf_path, base_link, tip_link, parameter_path, parameters_json));
  });
}

jc_status jc_robot_free(jc_robot* robot) {
  return CAPI_ENTRY({ freeHandle(robot, "robot"); });
}

jc_status jc_robot_dof(jc_robot* robot, int32_t* dof) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    requirePointer(dof, "dof");
    *dof = handle.robot->dof();
  });
}

jc_status jc_robot_name(jc_robot* robot, char* buffer, int32_t capacity, int32_t* length) {
  return CAPI_ENTRY({ copyText(robotHandle(robot).robot->name, buffer, capacity, length); });
}

jc_status jc_robot_joint_limits(jc_robot* robot, double* lower, int32_t lower_len, double* upper, int32_t upper_len) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    requireOutput(lower, lower_len, n, "lower", "the robot's number of joints");
    requireOutput(upper, upper_len, n, "upper", "the robot's number of joints");
    copyJoints(handle.robot->lowerLimits(), lower);
    copyJoints(handle.robot->upperLimits(), upper);
  });
}

jc_status jc_robot_has_drives(jc_robot* robot, int32_t* has_drives) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    requirePointer(has_drives, "has_drives");
    *has_drives = handle.drives.empty() ? 0 : 1;
  });
}

jc_status jc_robot_parameters_json(jc_robot* robot, char* buffer, int32_t capacity, int32_t* length) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    copyText(parametersToJson(handle.model, handle.drives, handle.tool ? &*handle.tool : nullptr,
                              handle.base_frame ? &*handle.base_frame : nullptr),
             buffer, capacity, length);
  });
}

jc_status jc_robot_tool_target(jc_robot* robot, double* target, int32_t target_len, int32_t* has_target) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    requirePointer(has_target, "has_target");
    requireOutput(target, target_len, 3, "target", "x, y, z in m");
    double* out = target;
    const Eigen::Vector3d value = handle.tool ? handle.tool->in_flange : Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) out[k] = value[k];
    *has_target = handle.tool ? 1 : 0;
  });
}

jc_status jc_robot_base_frame(jc_robot* robot, double* pose, int32_t pose_len, int32_t* has_base_frame) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    requirePointer(has_base_frame, "has_base_frame");
    requireOutput(pose, pose_len, 16, "pose", "a 4 x 4 transform, row-major");
    double* out = pose;
    const Eigen::Matrix4d value =
        handle.base_frame ? handle.base_frame->base_in_frame.matrix() : Eigen::Matrix4d::Identity();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) out[r * 4 + c] = value(r, c);
    }
    *has_base_frame = handle.base_frame ? 1 : 0;
  });
}

jc_status jc_robot_set_payload(jc_robot* robot, double mass, const double* com, int32_t com_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    if (!(finiteScalar(mass, "mass") >= 0.0)) invalid("mass is negative");
    const Eigen::Vector3d centre = vector3Input(com, com_len, "com");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.payload_mass = mass;
    handle.payload_com = centre;
  });
}

jc_status jc_robot_set_tool_wrench(jc_robot* robot, const double* wrench, int32_t wrench_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const Vector6 value = vector6Input(wrench, wrench_len, "wrench");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    handle.tool_wrench = value;
  });
}

jc_status jc_forward_kinematics(jc_robot* robot, const double* q, int32_t q_len, double* pose, int32_t pose_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const JointVector joints = jointInput(q, q_len, handle.robot->dof(), "q");
    requireOutput(pose, pose_len, 16, "pose", "a 4 x 4 transform, row-major");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    forwardKinematics(*handle.robot, handle.workspace.robot, joints);
    copyPose(handle.workspace.robot.tool_pose, pose);
  });
}

jc_status jc_forward_kinematics_batch(jc_robot* robot, int32_t count, const double* q, int32_t q_len, double* poses,
                                      int32_t poses_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    if (count < 0) invalid("count is " + std::to_string(count) + ", must be >= 0");
    requireLength(q_len, std::int64_t{count} * n, "q", "count x the robot's number of joints");
    if (std::int64_t{count} * 16 > INT32_MAX) {
      invalid("count is " + std::to_string(count) + ": its 16 x count pose values exceed int32_t lengths");
    }
    if (count == 0) {  // an empty batch: nothing to read or write
      requireLength(poses_len, 0, "poses", "count x 16 (4 x 4 transforms, row-major)");
      return;
    }
    requireOutput(poses, poses_len, std::int64_t{count} * 16, "poses", "count x 16 (4 x 4 transforms, row-major)");
    requirePointer(q, "q");
    requireFinite(q, q_len, "q");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    JointVector joints(n);
    for (std::int32_t k = 0; k < count; ++k) {
      for (int j = 0; j < n; ++j) joints[j] = q[std::int64_t{k} * n + j];
      forwardKinematics(*handle.robot, handle.workspace.robot, joints);
      copyPose(handle.workspace.robot.tool_pose, poses + std::int64_t{k} * 16);
    }
  });
}

jc_status jc_inverse_kinematics(jc_robot* robot, const double* pose, int32_t pose_len, const double* seed,
                                int32_t seed_len, double* q, int32_t q_len, int32_t* singular) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const Eigen::Isometry3d target = poseInput(pose, pose_len, "pose");
    const JointVector start = jointInput(seed, seed_len, n, "seed");
    requireOutput(q, q_len, n, "q", "the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    const IkSolution solution = handle.inverse_kinematics.solve(target, start);
    copyJoints(solution.q, q);
    if (singular) *singular = solution.singular ? 1 : 0;
  });
}

jc_status jc_inverse_kinematics_all(jc_robot* robot, const double* pose, int32_t pose_len, const double* seed,
                                    int32_t seed_len, double* solutions, int32_t solutions_len, int32_t* count) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const Eigen::Isometry3d target = poseInput(pose, pose_len, "pose");
    const JointVector start = jointInput(seed, seed_len, n, "seed");
    requirePointer(solutions, "solutions");
    if (solutions_len < 8 * n) {
      invalid("solutions_len is " + std::to_string(solutions_len) + ", must be at least " + std::to_string(8 * n) +
              " (8 solutions of the robot's number of joints)");
    }
    requirePointer(count, "count");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    std::array<IkSolution, 8> found;
    const int how_many = handle.inverse_kinematics.allSolutions(target, start, found);
    for (int k = 0; k < how_many; ++k) copyJoints(found[k].q, solutions + k * n);
    *count = how_many;
  });
}

jc_status jc_jacobian(jc_robot* robot, const double* q, int32_t q_len, double* jacobian, int32_t jacobian_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const JointVector joints = jointInput(q, q_len, n, "q");
    requireOutput(jacobian, jacobian_len, 6 * n, "jacobian", "6 x the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    forwardKinematics(*handle.robot, handle.workspace.robot, joints);
    Jacobian& result = handle.workspace.jacobian;
    toolJacobian(*handle.robot, handle.workspace.robot, result);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < n; ++c) jacobian[r * n + c] = result(r, c);
    }
  });
}

jc_status jc_gravity_torques(jc_robot* robot, const double* q, int32_t q_len, double* torques, int32_t torques_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const JointVector joints = jointInput(q, q_len, n, "q");
    requireOutput(torques, torques_len, n, "torques", "the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    JointVector tau;
    gravityTorques(*handle.robot, handle.workspace.robot, joints, tau);
    copyJoints(tau, torques);
  });
}

}  // extern "C"
