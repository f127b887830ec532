/* Every entry point of the C API, from C99: results that can be checked by identities (inverse of
 * forward kinematics, Jacobian against finite differences, compensation against prediction, snapshots
 * against uninterrupted runs) and every error path: NULL pointers, wrong lengths, NaN and infinities,
 * handles of the wrong kind or already freed, broken files, unreachable poses, solvers that fail. */
#define _POSIX_C_SOURCE 200809L

#include <jointcomp/jointcomp.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capi_check.h"

/* Gear train of the RX170's parameter file, for the broken parameter texts below. */
#define RX170_GEARS                                                                                      \
  "\"gears\": {\"joints\": [{\"joint\": \"joint_1\", \"stage_ratios\": [3.0, 40.0]},"                    \
  "{\"joint\": \"joint_2\", \"stage_ratios\": [3.0, 40.0]}, {\"joint\": \"joint_3\", \"stage_ratios\": " \
  "[2.5, 40.0]}, {\"joint\": \"joint_4\", \"stage_ratios\": [72.0]}, {\"joint\": \"joint_5\", "          \
  "\"stage_ratios\": [64.0]}, {\"joint\": \"joint_6\", \"stage_ratios\": [28.0]}]}"

static const char* kMinimalParameters =
    "{\"format\": \"jointcomp-parameters/1\", \"robot\": \"rx170\", \"effects\": []}";
/* Joints so soft that the links never settle. */
static const char* kSoftParameters =
    "{\"format\": \"jointcomp-parameters/1\", \"robot\": \"rx170\", \"effects\": [{\"type\": \"compliance\", "
    "\"stiffness_nm_per_rad\": [1, 1, 1, 1, 1, 1]}]}";
/* A transmission error so large and fast-varying that compensation cannot converge. */
static const char* kWildParameters =
    "{\"format\": \"jointcomp-parameters/1\", \"robot\": \"rx170\", " RX170_GEARS
    ", \"effects\": [{\"type\": \"transmission_error\", \"harmonics\": [{\"joint\": \"joint_2\", \"of\": \"motor\", "
    "\"cycles_per_revolution\": 2, \"amplitude_deg\": 5, \"phase_rad\": 1}]}]}";

static void test_library(void) {
  const char* version = jc_version();
  CHECK(version != NULL && strchr(version, '.') != NULL);
  CHECK(jc_abi_version() == JC_ABI_VERSION);
  CHECK(strcmp(jc_status_name(JC_OK), "JC_OK") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_INVALID_ARGUMENT), "JC_ERROR_INVALID_ARGUMENT") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_FILE), "JC_ERROR_FILE") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_UNREACHABLE), "JC_ERROR_UNREACHABLE") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_SOLVER), "JC_ERROR_SOLVER") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_WRONG_HANDLE), "JC_ERROR_WRONG_HANDLE") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_OUT_OF_MEMORY), "JC_ERROR_OUT_OF_MEMORY") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_INTERNAL), "JC_ERROR_INTERNAL") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_PLANT_LIMIT), "JC_ERROR_PLANT_LIMIT") == 0);
  CHECK(strcmp(jc_status_name(JC_ERROR_BUSY), "JC_ERROR_BUSY") == 0);
  CHECK(strcmp(jc_status_name(42), "JC_UNKNOWN_STATUS") == 0);
  /* The message is cleared by the next successful call. */
  CHECK(jc_accuracy_metrics(NULL, 3, NULL, 5) == JC_ERROR_INVALID_ARGUMENT);
  CHECK(jc_last_error()[0] != '\0');
  CHECK(jc_robot_free(NULL) == JC_OK);
  CHECK(jc_last_error()[0] == '\0');
}

/* Choosing the chain: the tip of a URDF with a fixed branch (a camera beside the tool), a sub-chain, and
   the errors of an unknown link, an ambiguous tree and both kinds of parameters at once. */
static void test_loading_chains(void) {
  jc_robot* robot = NULL;
  int32_t dof = 0;
  char name[64];
  int32_t length = 0;
  const char* two_tools = temporary_file(
      "<robot name='two'><link name='base'/>"
      "<joint name='j1' type='revolute'><parent link='base'/><child link='l1'/><axis xyz='0 0 1'/>"
      "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint><link name='l1'/>"
      "<joint name='j2' type='revolute'><parent link='l1'/><child link='l2'/><origin xyz='0 0 0.5'/>"
      "<axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint><link name='l2'/>"
      "<joint name='t' type='fixed'><parent link='l2'/><child link='tool'/><origin xyz='0 0 0.3'/></joint>"
      "<link name='tool'/>"
      "<joint name='c' type='fixed'><parent link='l2'/><child link='camera'/><origin xyz='0.1 0 0'/></joint>"
      "<link name='camera'/></robot>");
  EXPECT_STATUS(JC_ERROR_FILE, "branches at link 'l2'", jc_robot_load_chain(two_tools, NULL, NULL, NULL, NULL, &robot));
  EXPECT_STATUS(JC_ERROR_FILE, "tip link 'gripper' does not exist",
                jc_robot_load_chain(two_tools, NULL, "gripper", NULL, NULL, &robot));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "not both",
                jc_robot_load_chain(two_tools, NULL, "tool", "/tmp/p.json", kMinimalParameters, &robot));
  CHECK(robot == NULL);
  EXPECT_OK(jc_robot_load_chain(two_tools, "", "camera", NULL, NULL, &robot));
  EXPECT_OK(jc_robot_dof(robot, &dof));
  CHECK(dof == 2);
  EXPECT_OK(jc_robot_free(robot));
  robot = NULL;
  EXPECT_OK(jc_robot_load_chain(two_tools, "l1", "tool", NULL, NULL, &robot));
  EXPECT_OK(jc_robot_dof(robot, &dof));
  CHECK(dof == 1);
  EXPECT_OK(jc_robot_name(robot, name, (int32_t)sizeof name, &length));
  CHECK(strcmp(name, "two") == 0);
  EXPECT_OK(jc_robot_free(robot));
  unlink(two_tools);
}

static void test_loading(void) {
  jc_robot* robot = NULL;
  const char* path;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL", jc_robot_load(JOINTCOMP_TEST_URDF, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "urdf_path is NULL", jc_robot_load(NULL, NULL, &robot));
  EXPECT_STATUS(JC_ERROR_FILE, "/nonexistent/robot.urdf", jc_robot_load("/nonexistent/robot.urdf", NULL, &robot));
  path = temporary_file("<robot name='broken'><link name='a'/>");
  EXPECT_STATUS(JC_ERROR_FILE, "", jc_robot_load(path, NULL, &robot));
  unlink(path);
  EXPECT_STATUS(JC_ERROR_FILE, "/nonexistent/params.json",
                jc_robot_load(JOINTCOMP_TEST_URDF, "/nonexistent/params.json", &robot));
  path = temporary_file("{\"format\": \"jointcomp-parameters/1\", \"robot\": ");
  EXPECT_STATUS(JC_ERROR_FILE, path, jc_robot_load(JOINTCOMP_TEST_URDF, path, &robot));
  unlink(path);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "parameters_json is NULL",
                jc_robot_load_json(JOINTCOMP_TEST_URDF, NULL, &robot));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL",
                jc_robot_load_json(JOINTCOMP_TEST_URDF, kMinimalParameters, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "urdf_path is NULL", jc_robot_load_json(NULL, kMinimalParameters, &robot));
  EXPECT_STATUS(JC_ERROR_FILE, "parameters_json", jc_robot_load_json(JOINTCOMP_TEST_URDF, "{not json", &robot));
  EXPECT_STATUS(
      JC_ERROR_FILE, "rx160",
      jc_robot_load_json(JOINTCOMP_TEST_URDF,
                         "{\"format\": \"jointcomp-parameters/1\", \"robot\": \"rx160\", \"effects\": []}", &robot));
  /* A "plant" object is optional, but an invalid one is an error. */
  EXPECT_STATUS(JC_ERROR_FILE, "plant",
                jc_robot_load_json(JOINTCOMP_TEST_URDF,
                                   "{\"format\": \"jointcomp-parameters/1\", \"robot\": \"rx170\", \"effects\": [], "
                                   "\"plant\": {\"joints\": 3}}",
                                   &robot));
  CHECK(robot == NULL); /* failures leave the output untouched */
  EXPECT_OK(jc_robot_load_json(JOINTCOMP_TEST_URDF, kMinimalParameters, &robot));
  CHECK(robot != NULL);
  EXPECT_OK(jc_robot_free(robot));
  test_loading_chains();
}

static void test_queries(jc_robot* robot, jc_robot* bare) {
  int32_t dof = 0, length = -1, has_drives = -1;
  char name[16];
  char tiny[3];
  double lower[6], upper[6];
  char* json;
  jc_robot* reloaded = NULL;
  double errors_a[6], errors_b[6];
  EXPECT_OK(jc_robot_dof(robot, &dof));
  CHECK(dof == 6);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "dof is NULL", jc_robot_dof(robot, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL", jc_robot_dof(NULL, &dof));

  EXPECT_OK(jc_robot_name(robot, NULL, 0, &length));
  CHECK(length == 5);
  EXPECT_OK(jc_robot_name(robot, name, (int32_t)sizeof name, &length));
  CHECK(strcmp(name, "rx170") == 0 && length == 5);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "needs 6", jc_robot_name(robot, tiny, (int32_t)sizeof tiny, &length));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "capacity is negative", jc_robot_name(robot, name, -1, &length));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "buffer is NULL", jc_robot_name(robot, NULL, 8, &length));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "length is NULL", jc_robot_name(robot, name, 16, NULL));

  EXPECT_OK(jc_robot_joint_limits(robot, lower, 6, upper, 6));
  CHECK(lower[0] < -2.7 && upper[0] > 2.7 && lower[5] < upper[5]);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "upper_len is 5", jc_robot_joint_limits(robot, lower, 6, upper, 5));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "lower is NULL", jc_robot_joint_limits(robot, NULL, 6, upper, 6));

  EXPECT_OK(jc_robot_has_drives(robot, &has_drives));
  CHECK(has_drives == 1);
  EXPECT_OK(jc_robot_has_drives(bare, &has_drives));
  CHECK(has_drives == 0);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "has_drives is NULL", jc_robot_has_drives(robot, NULL));

  /* A maker's parameter file carries no calibrated target and no base frame: zero, the identity, and 0. */
  {
    double target[3] = {1, 1, 1};
    double frame[16];
    int32_t has = 7;
    EXPECT_OK(jc_robot_tool_target(robot, target, 3, &has));
    CHECK(has == 0 && target[0] == 0.0 && target[1] == 0.0 && target[2] == 0.0);
    EXPECT_OK(jc_robot_base_frame(robot, frame, 16, &has));
    CHECK(has == 0 && frame[0] == 1.0 && frame[3] == 0.0 && frame[5] == 1.0 && frame[15] == 1.0);
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "has_target is NULL", jc_robot_tool_target(robot, target, 3, NULL));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "pose_len is 15", jc_robot_base_frame(robot, frame, 15, &has));
  }

  /* The parameters written out load back into a robot that predicts the same errors. */
  EXPECT_OK(jc_robot_parameters_json(robot, NULL, 0, &length));
  CHECK(length > 100);
  json = (char*)malloc((size_t)length + 1);
  EXPECT_OK(jc_robot_parameters_json(robot, json, length + 1, &length));
  CHECK(strlen(json) == (size_t)length && strstr(json, "transmission_error") != NULL && strstr(json, "plant") != NULL);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "buffer holds", jc_robot_parameters_json(robot, json, length, &length));
  EXPECT_OK(jc_robot_load_json(JOINTCOMP_TEST_URDF, json, &reloaded));
  free(json);
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors_a, 6));
  EXPECT_OK(jc_predict_joint_errors(reloaded, NULL, kPosture, 6, NULL, 0, errors_b, 6));
  CHECK(max_abs_difference(errors_a, errors_b, 6) < 1e-12);
  EXPECT_OK(jc_robot_free(reloaded));
}

static void test_handles(jc_robot* robot, jc_plant* plant) {
  int32_t dof = 0;
  double time = 0.0;
  uint64_t not_a_handle[8] = {0};
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_plant", jc_robot_dof((jc_robot*)(void*)plant, &dof));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_robot", jc_plant_time((jc_plant*)(void*)robot, &time));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "not a live jointcomp handle",
                jc_robot_dof((jc_robot*)(void*)not_a_handle, &dof));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "expected a jc_robot", jc_robot_free((jc_robot*)(void*)plant));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "expected a jc_plant", jc_plant_free((jc_plant*)(void*)robot));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "plant is NULL", jc_plant_time(NULL, &time));
  CHECK(jc_plant_free(NULL) == JC_OK);
  {
    /* A freed handle is recognised from the table of live handles, without reading its memory (so this runs
       under AddressSanitizer too). */
    jc_robot* freed = NULL;
    EXPECT_OK(jc_robot_load(JOINTCOMP_TEST_URDF, NULL, &freed));
    EXPECT_OK(jc_robot_free(freed));
    EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "already freed", jc_robot_dof(freed, &dof));
    EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "already freed", jc_robot_free(freed));
  }
}

static void test_kinematics(jc_robot* robot, jc_robot* ur10) {
  double pose[16], pose_back[16], q[6], solutions[48], jacobian[36], torques[6], bad[6];
  double far_pose[16], skewed[16];
  int32_t singular = -1, count = 0, k, j;
  const double step = 1e-7;

  EXPECT_OK(jc_forward_kinematics(robot, kPosture, 6, pose, 16));
  CHECK(pose[12] == 0.0 && pose[13] == 0.0 && pose[14] == 0.0 && pose[15] == 1.0);
  CHECK(pose[3] > 0.5); /* in front of the robot */
  memcpy(bad, kPosture, sizeof bad);
  bad[2] = kNaN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q[2] is NaN", jc_forward_kinematics(robot, bad, 6, pose_back, 16));
  bad[2] = -kInf;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q[2] is -infinity", jc_forward_kinematics(robot, bad, 6, pose_back, 16));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q_len is 5", jc_forward_kinematics(robot, kPosture, 5, pose_back, 16));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q is NULL", jc_forward_kinematics(robot, NULL, 6, pose_back, 16));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "pose is NULL", jc_forward_kinematics(robot, kPosture, 6, NULL, 16));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "pose_len is 12", jc_forward_kinematics(robot, kPosture, 6, pose_back, 12));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL", jc_forward_kinematics(NULL, kPosture, 6, pose_back, 16));

  /* Inverse kinematics returns to the posture it started from. */
  EXPECT_OK(jc_inverse_kinematics(robot, pose, 16, kPosture, 6, q, 6, &singular));
  CHECK(max_abs_difference(q, kPosture, 6) < 1e-9);
  CHECK(singular == 0);
  EXPECT_OK(jc_inverse_kinematics(robot, pose, 16, kPosture, 6, q, 6, NULL));
  EXPECT_OK(jc_forward_kinematics(robot, q, 6, pose_back, 16));
  CHECK(max_abs_difference(pose, pose_back, 16) < 1e-9);
  memcpy(far_pose, pose, sizeof far_pose);
  far_pose[3] = 10.0;
  EXPECT_STATUS(JC_ERROR_UNREACHABLE, "", jc_inverse_kinematics(robot, far_pose, 16, kPosture, 6, q, 6, NULL));
  memcpy(skewed, pose, sizeof skewed);
  skewed[0] *= 1.1;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "not a rotation",
                jc_inverse_kinematics(robot, skewed, 16, kPosture, 6, q, 6, NULL));
  memcpy(skewed, pose, sizeof skewed);
  skewed[14] = 0.5;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "last row",
                jc_inverse_kinematics(robot, skewed, 16, kPosture, 6, q, 6, NULL));
  skewed[14] = kNaN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "pose[14] is NaN",
                jc_inverse_kinematics(robot, skewed, 16, kPosture, 6, q, 6, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "seed_len is 7",
                jc_inverse_kinematics(robot, pose, 16, kPosture, 7, q, 6, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q is NULL",
                jc_inverse_kinematics(robot, pose, 16, kPosture, 6, NULL, 6, NULL));

  /* Every closed-form solution reaches the pose; the seed's own is among them. */
  EXPECT_OK(jc_inverse_kinematics_all(robot, pose, 16, kPosture, 6, solutions, 48, &count));
  CHECK(count >= 2 && count <= 8);
  for (k = 0; k < count; ++k) {
    EXPECT_OK(jc_forward_kinematics(robot, solutions + 6 * k, 6, pose_back, 16));
    CHECK(max_abs_difference(pose, pose_back, 16) < 1e-9);
  }
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "at least 48",
                jc_inverse_kinematics_all(robot, pose, 16, kPosture, 6, solutions, 47, &count));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "count is NULL",
                jc_inverse_kinematics_all(robot, pose, 16, kPosture, 6, solutions, 48, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "",
                jc_inverse_kinematics_all(ur10, pose, 16, kPosture, 6, solutions, 48, &count));

  /* The Jacobian's linear rows are the derivatives of the tool position. */
  EXPECT_OK(jc_jacobian(robot, kPosture, 6, jacobian, 36));
  for (j = 0; j < 6; ++j) {
    double plus[6], minus[6], pose_plus[16], pose_minus[16];
    int r;
    memcpy(plus, kPosture, sizeof plus);
    memcpy(minus, kPosture, sizeof minus);
    plus[j] += step;
    minus[j] -= step;
    EXPECT_OK(jc_forward_kinematics(robot, plus, 6, pose_plus, 16));
    EXPECT_OK(jc_forward_kinematics(robot, minus, 6, pose_minus, 16));
    for (r = 0; r < 3; ++r) {
      const double derivative = (pose_plus[4 * r + 3] - pose_minus[4 * r + 3]) / (2 * step);
      CHECK(fabs(jacobian[r * 6 + j] - derivative) < 1e-6);
    }
  }
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "jacobian_len is 30", jc_jacobian(robot, kPosture, 6, jacobian, 30));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q_len is 0", jc_jacobian(robot, kPosture, 0, jacobian, 36));

  EXPECT_OK(jc_gravity_torques(robot, kPosture, 6, torques, 6));
  CHECK(fabs(torques[1]) > 100.0 && torques[0] == torques[0]);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "torques is NULL", jc_gravity_torques(robot, kPosture, 6, NULL, 6));
  bad[2] = kInf;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q[2] is +infinity", jc_gravity_torques(robot, bad, 6, torques, 6));
}

static void test_errors_and_compensation(jc_robot* robot) {
  double errors[6], errors_all[6], errors_loaded[6], reference[6], moved[6], bad[6];
  const double velocity[6] = {0.1, -0.1, 0.05, 0, 0, 0};
  const double com[3] = {0.0, 0.0, 0.1};
  const double wrench[6] = {0, 0, -200, 0, 0, 0};
  const double zero_wrench[6] = {0, 0, 0, 0, 0, 0};
  int32_t iterations = 0, j;
  jc_robot* soft = NULL;
  jc_robot* wild = NULL;

  /* No error effect selected: no error. */
  EXPECT_OK(jc_predict_joint_errors(robot, "", kPosture, 6, NULL, 0, errors, 6));
  for (j = 0; j < 6; ++j) CHECK(errors[j] == 0.0);
  EXPECT_OK(jc_predict_joint_errors(robot, "compliance", kPosture, 6, velocity, 6, errors, 6));
  CHECK(fabs(errors[1]) > 1e-5 && fabs(errors[1]) < 1e-2);
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors_all, 6));
  EXPECT_OK(jc_predict_joint_errors(robot, " compliance , transmission_error ", kPosture, 6, NULL, 0, errors, 6));
  CHECK(same_bits(errors, errors_all, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "'bogus'",
                jc_predict_joint_errors(robot, "compliance,bogus", kPosture, 6, NULL, 0, errors, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "velocity_len is 3",
                jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 3, errors, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "command is NULL",
                jc_predict_joint_errors(robot, NULL, NULL, 6, NULL, 0, errors, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "errors_len is 0",
                jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors, 0));
  memcpy(bad, velocity, sizeof bad);
  bad[5] = kNaN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "velocity[5] is NaN",
                jc_predict_joint_errors(robot, NULL, kPosture, 6, bad, 6, errors, 6));

  /* Conditions: a payload and a pushing wrench change the errors; zero restores them. */
  EXPECT_OK(jc_robot_set_payload(robot, 20.0, com, 3));
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors_loaded, 6));
  CHECK(fabs(errors_loaded[1] - errors_all[1]) > 1e-6);
  EXPECT_OK(jc_robot_set_payload(robot, 0.0, com, 3));
  EXPECT_OK(jc_robot_set_tool_wrench(robot, wrench, 6));
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors_loaded, 6));
  CHECK(fabs(errors_loaded[1] - errors_all[1]) > 1e-6);
  EXPECT_OK(jc_robot_set_tool_wrench(robot, zero_wrench, 6));
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, kPosture, 6, NULL, 0, errors, 6));
  CHECK(same_bits(errors, errors_all, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "mass is negative", jc_robot_set_payload(robot, -1.0, com, 3));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "mass is NaN", jc_robot_set_payload(robot, kNaN, com, 3));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "com_len is 2", jc_robot_set_payload(robot, 1.0, com, 2));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "com is NULL", jc_robot_set_payload(robot, 1.0, NULL, 3));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "wrench_len is 3", jc_robot_set_tool_wrench(robot, wrench, 3));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "wrench is NULL", jc_robot_set_tool_wrench(robot, NULL, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL", jc_robot_set_tool_wrench(NULL, wrench, 6));

  /* Compensation inverts the prediction: the reference plus its predicted error is the planned posture. */
  EXPECT_OK(jc_compensate_point(robot, NULL, kPosture, 6, velocity, 6, reference, 6, &iterations));
  CHECK(iterations >= 2);
  EXPECT_OK(jc_predict_joint_errors(robot, NULL, reference, 6, velocity, 6, errors, 6));
  for (j = 0; j < 6; ++j) moved[j] = reference[j] + errors[j];
  CHECK(max_abs_difference(moved, kPosture, 6) < 1e-10);
  CHECK(max_abs_difference(reference, kPosture, 6) > 1e-5);
  EXPECT_OK(jc_compensate_point(robot, "", kPosture, 6, NULL, 0, reference, 6, NULL));
  CHECK(same_bits(reference, kPosture, 6));
  EXPECT_STATUS(
      JC_ERROR_INVALID_ARGUMENT, "planned[0] is NaN",
      jc_compensate_point(robot, NULL, (const double[]){kNaN, 0, 0, 0, 0, 0}, 6, NULL, 0, reference, 6, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "reference_len is 7",
                jc_compensate_point(robot, NULL, kPosture, 6, NULL, 0, reference, 7, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "'nothing'",
                jc_compensate_point(robot, "nothing", kPosture, 6, NULL, 0, reference, 6, NULL));
  /* A payload the joints cannot carry: the reference would leave the joint limits, which is an error. */
  EXPECT_OK(jc_robot_set_payload(robot, 1e6, com, 3));
  EXPECT_STATUS(JC_ERROR_UNREACHABLE, "outside its limits",
                jc_compensate_point(robot, NULL, kPosture, 6, NULL, 0, reference, 6, NULL));
  EXPECT_OK(jc_robot_set_payload(robot, 0.0, com, 3));

  /* Solvers that fail say so. */
  EXPECT_OK(jc_robot_load_json(JOINTCOMP_TEST_URDF, kSoftParameters, &soft));
  EXPECT_STATUS(JC_ERROR_SOLVER, "did not settle",
                jc_predict_joint_errors(soft, NULL, kPosture, 6, NULL, 0, errors, 6));
  EXPECT_OK(jc_robot_load_json(JOINTCOMP_TEST_URDF, kWildParameters, &wild));
  EXPECT_STATUS(JC_ERROR_SOLVER, "did not converge",
                jc_compensate_point(wild, NULL, kPosture, 6, NULL, 0, reference, 6, NULL));
  EXPECT_STATUS(JC_ERROR_SOLVER, "trajectory point 0",
                jc_compensate_trajectory(wild, NULL, kPosture, 6, NULL, 0, reference, 6, NULL, NULL));
  EXPECT_OK(jc_robot_free(soft));
  EXPECT_OK(jc_robot_free(wild));
}

/* The dynamic compensation of a robot held still is the static compensation of its posture (no motion, no
   lag), found on the first run of the nominal plant; malformed calls are refused with the reason. */
static void test_dynamic_compensation(jc_robot* robot, jc_robot* bare) {
  enum { kSamples = 10 };
  double times[kSamples], planned[6 * kSamples], velocities[6 * kSamples], references[6 * kSamples];
  double reference_velocities[6 * kSamples], point_reference[6], max_link_error = -1.0;
  int32_t runs = 0, k, j;
  for (k = 0; k < kSamples; ++k) {
    times[k] = 0.004 * k;
    for (j = 0; j < 6; ++j) {
      planned[6 * k + j] = kPosture[j];
      velocities[6 * k + j] = 0.0;
    }
  }
  EXPECT_OK(jc_compensate_trajectory_dynamic(robot, times, kSamples, planned, 6 * kSamples, velocities, 6 * kSamples,
                                             references, 6 * kSamples, reference_velocities, 6 * kSamples, &runs,
                                             &max_link_error));
  CHECK(runs == 1 && max_link_error >= 0.0 && max_link_error < 1e-9);
  EXPECT_OK(jc_compensate_point(robot, NULL, kPosture, 6, NULL, 0, point_reference, 6, NULL));
  for (k = 0; k < kSamples; ++k) {
    CHECK(max_abs_difference(references + 6 * k, point_reference, 6) < 1e-9);
    CHECK(max_abs_difference(reference_velocities + 6 * k, velocities, 6) < 1e-6);
  }
  CHECK(max_abs_difference(point_reference, kPosture, 6) > 1e-5); /* the posture does need a correction */
  EXPECT_OK(jc_compensate_trajectory_dynamic(robot, times, kSamples, planned, 6 * kSamples, velocities, 6 * kSamples,
                                             references, 6 * kSamples, NULL, 0, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "no \"plant\" object",
                jc_compensate_trajectory_dynamic(bare, times, kSamples, planned, 6 * kSamples, velocities, 6 * kSamples,
                                                 references, 6 * kSamples, NULL, 0, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "at least 3 samples",
                jc_compensate_trajectory_dynamic(robot, times, 2, planned, 12, velocities, 12, references, 12, NULL, 0,
                                                 NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "planned_len",
                jc_compensate_trajectory_dynamic(robot, times, kSamples, planned, 6 * kSamples - 1, velocities,
                                                 6 * kSamples, references, 6 * kSamples, NULL, 0, NULL, NULL));
  times[4] = times[3];
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "increasing",
                jc_compensate_trajectory_dynamic(robot, times, kSamples, planned, 6 * kSamples, velocities,
                                                 6 * kSamples, references, 6 * kSamples, NULL, 0, NULL, NULL));
  times[4] = kNaN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "times[4] is NaN",
                jc_compensate_trajectory_dynamic(robot, times, kSamples, planned, 6 * kSamples, velocities,
                                                 6 * kSamples, references, 6 * kSamples, NULL, 0, NULL, NULL));
}

static void test_spiral(jc_robot* robot, jc_robot* bare) {
  int32_t m = 0, max_iterations = 0, k;
  double *time, *positions, *q, *qd, *references, *errors;
  double metrics[15], metrics_again[15], max_correction = 0.0, point_reference[6];
  double quasi_static[15];

  EXPECT_OK(jc_spiral_sample_count(robot, &m));
  CHECK(m > 1000);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "count is NULL", jc_spiral_sample_count(robot, NULL));
  time = (double*)malloc(sizeof(double) * (size_t)m);
  positions = (double*)malloc(sizeof(double) * 3 * (size_t)m);
  q = (double*)malloc(sizeof(double) * 6 * (size_t)m);
  qd = (double*)malloc(sizeof(double) * 6 * (size_t)m);
  references = (double*)malloc(sizeof(double) * 6 * (size_t)m);
  errors = (double*)malloc(sizeof(double) * 9 * (size_t)m);
  EXPECT_OK(jc_spiral_plan(robot, time, m, positions, 3 * m, q, 6 * m, qd, 6 * m));
  CHECK(time[0] == 0.0 && time[m - 1] > 20.0);
  CHECK(fabs(positions[2] - 0.2) < 1e-12 && fabs(positions[3 * (m - 1) + 2] - 0.2) < 1e-12);
  EXPECT_OK(jc_spiral_plan(robot, time, m, NULL, 0, NULL, 0, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q_len", jc_spiral_plan(robot, NULL, 0, NULL, 0, q, 6 * m - 1, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "time_len", jc_spiral_plan(robot, NULL, 5, NULL, 0, NULL, 0, NULL, 0));

  /* The whole trajectory compensated at once equals its points compensated one by one. */
  EXPECT_OK(
      jc_compensate_trajectory(robot, NULL, q, 6 * m, qd, 6 * m, references, 6 * m, &max_iterations, &max_correction));
  CHECK(max_iterations >= 2 && max_correction > 1e-5 && max_correction < 1e-2);
  for (k = 0; k < m; k += m / 7) {
    EXPECT_OK(jc_compensate_point(robot, NULL, q + 6 * k, 6, qd + 6 * k, 6, point_reference, 6, NULL));
    CHECK(same_bits(point_reference, references + 6 * k, 6));
  }
  EXPECT_OK(jc_compensate_trajectory(robot, "compliance", q, 6 * m, NULL, 0, references, 6 * m, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "multiple of 6",
                jc_compensate_trajectory(robot, NULL, q, 6 * m - 1, NULL, 0, references, 6 * m, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "velocities_len",
                jc_compensate_trajectory(robot, NULL, q, 6 * m, qd, 6, references, 6 * m, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "references_len",
                jc_compensate_trajectory(robot, NULL, q, 6 * m, NULL, 0, references, 6, NULL, NULL));
  q[6 * 100 + 3] = kNaN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "planned[603] is NaN",
                jc_compensate_trajectory(robot, NULL, q, 6 * m, NULL, 0, references, 6 * m, NULL, NULL));

  /* The paper's experiment: both corrections reduce Ra and Rz as much as the paper's did (85 %, 48 %),
     the stiffness correction alone less; identical numbers from run to run. */
  EXPECT_OK(jc_spiral_experiment(robot, 0, quasi_static, 15, NULL, 0));
  CHECK(quasi_static[10] < 0.15 * quasi_static[0] && quasi_static[11] < 0.52 * quasi_static[1]);
  CHECK(quasi_static[5] < quasi_static[0] && quasi_static[5] > quasi_static[10]);
  EXPECT_OK(jc_spiral_experiment(robot, 1, metrics, 15, errors, 9 * m));
  CHECK(metrics[10] < 0.15 * metrics[0] && metrics[11] < 0.52 * metrics[1]);
  CHECK(!same_bits(metrics, quasi_static, 15));
  {
    /* The errors returned give back the metrics. */
    double run_metrics[5];
    EXPECT_OK(jc_accuracy_metrics(errors + 2 * 3 * m, 3 * m, run_metrics, 5));
    CHECK(same_bits(run_metrics, metrics + 10, 5));
  }
  EXPECT_OK(jc_spiral_experiment(robot, 1, metrics_again, 15, NULL, 0));
  CHECK(same_bits(metrics, metrics_again, 15));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "no \"plant\" object", jc_spiral_experiment(bare, 1, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "use_plant is 2", jc_spiral_experiment(robot, 2, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "metrics_len is 5", jc_spiral_experiment(robot, 0, metrics, 5, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "errors_len", jc_spiral_experiment(robot, 0, metrics, 15, errors, 3 * m));
  {
    /* A given truth (jc_spiral_experiment_truth): the robot itself as its own truth leaves less after both
       corrections than the built-in perturbed truth does; the errors give back the metrics. */
    double own[15], run_metrics[5];
    EXPECT_OK(jc_spiral_experiment_truth(robot, robot, 0, own, 15, errors, 9 * m));
    CHECK(own[12] < quasi_static[12] && own[12] < 0.1 * own[2]);
    EXPECT_OK(jc_accuracy_metrics(errors + 2 * 3 * m, 3 * m, run_metrics, 5));
    CHECK(same_bits(run_metrics, own + 10, 5));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "truth is NULL",
                  jc_spiral_experiment_truth(robot, NULL, 0, own, 15, NULL, 0));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "truth's parameters have no \"plant\"",
                  jc_spiral_experiment_truth(robot, bare, 1, own, 15, NULL, 0));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "errors_len",
                  jc_spiral_experiment_truth(robot, robot, 0, own, 15, errors, 3 * m));
  }
  {
    /* The paper's whole method on a given truth (jc_identify_and_compensate): the robot as its own truth,
       measured and identified, leaves less after both corrections than the uncorrected run, about as
       little as its own model; bad options are refused with outputs untouched. */
    double identified_metrics[15], own[15];
    jc_robot* identified = NULL;
    jc_report* report = NULL;
    char* text = NULL;
    int32_t length = 0;
    EXPECT_OK(jc_spiral_experiment_truth(robot, robot, 0, own, 15, NULL, 0));
    EXPECT_OK(jc_identify_and_compensate(robot, robot, "{\"seed\": 3}", identified_metrics, 15, &identified, &report));
    CHECK(identified != NULL && report != NULL);
    CHECK(identified_metrics[10] < 0.1 * identified_metrics[0] && identified_metrics[10] < 2 * own[10]);
    CHECK(same_bits(identified_metrics, own, 5)); /* the uncorrected run does not depend on the model */
    EXPECT_OK(jc_report_json(report, NULL, 0, &length));
    text = (char*)malloc((size_t)length + 1);
    EXPECT_OK(jc_report_json(report, text, length + 1, &length));
    CHECK(strstr(text, "\"jointcomp-identification-reports/1\"") != NULL);
    free(text);
    EXPECT_OK(jc_report_free(report));
    EXPECT_OK(jc_robot_free(identified));
    identified = NULL;
    report = NULL;
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "metrics_len is 5",
                  jc_identify_and_compensate(robot, robot, NULL, identified_metrics, 5, &identified, &report));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "dynamic_correction",
                  jc_identify_and_compensate(robot, robot, "{\"dynamic_correction\": true}", identified_metrics, 20,
                                             &identified, &report));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "feed_rate_m_per_s",
                  jc_identify_and_compensate(robot, robot, "{\"feed_rate_m_per_s\": 5}", identified_metrics, 15,
                                             &identified, &report));
    EXPECT_STATUS(
        JC_ERROR_INVALID_ARGUMENT, "use_plant",
        jc_identify_and_compensate(robot, bare, "{\"use_plant\": true}", identified_metrics, 15, &identified, &report));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "truth is NULL",
                  jc_identify_and_compensate(robot, NULL, NULL, identified_metrics, 15, &identified, &report));
    CHECK(identified == NULL && report == NULL);
  }
  free(time);
  free(positions);
  free(q);
  free(qd);
  free(references);
  free(errors);
}

static void test_unreachable_spiral(jc_robot* ur10) {
  /* The UR10 reaches about 1.3 m: not the spiral 1.2 m out at 200 mm height with the tool pointing down. */
  int32_t m = -1;
  double time[4], metrics[15];
  EXPECT_STATUS(JC_ERROR_UNREACHABLE, "path sample 0", jc_spiral_sample_count(ur10, &m));
  CHECK(m == -1);
  EXPECT_STATUS(JC_ERROR_UNREACHABLE, "path sample 0", jc_spiral_plan(ur10, time, 4, NULL, 0, NULL, 0, NULL, 0));
  EXPECT_STATUS(JC_ERROR_UNREACHABLE, "path sample 0", jc_spiral_experiment(ur10, 0, metrics, 15, NULL, 0));
}

static void test_metrics(void) {
  const double errors[9] = {0.001, 0.0, 0.002, 0.0, 0.0, -0.002, 0.0, 0.003, 0.001};
  const double z[3] = {0.002, -0.002, 0.001};
  double metrics[5], ra = 0.0, rz = 0.0, bad[3] = {0.0, kNaN, 0.0};
  EXPECT_OK(jc_accuracy_metrics(errors, 9, metrics, 5));
  CHECK(fabs(metrics[0] - 0.005 / 3) < 1e-15 && fabs(metrics[1] - 0.004) < 1e-15);
  CHECK(fabs(metrics[3] - sqrt(0.000010)) < 1e-15);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "multiple of 3", jc_accuracy_metrics(errors, 8, metrics, 5));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "multiple of 3", jc_accuracy_metrics(errors, 0, metrics, 5));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "metrics_len is 4", jc_accuracy_metrics(errors, 9, metrics, 4));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "errors[1] is NaN", jc_accuracy_metrics(bad, 3, metrics, 5));
  EXPECT_OK(jc_average_absolute_deviation(z, 3, &ra));
  CHECK(fabs(ra - 0.005 / 3) < 1e-15);
  EXPECT_OK(jc_peak_to_peak_deviation(z, 3, &rz));
  CHECK(fabs(rz - 0.004) < 1e-15);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "z_len is 0", jc_average_absolute_deviation(z, 0, &ra));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "z[1] is NaN", jc_average_absolute_deviation(bad, 3, &ra));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "ra is NULL", jc_average_absolute_deviation(z, 3, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "z is NULL", jc_peak_to_peak_deviation(NULL, 3, &rz));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "rz is NULL", jc_peak_to_peak_deviation(z, 3, NULL));
}

int main(void) {
  jc_robot* robot = NULL;
  jc_robot* bare = NULL;
  jc_robot* ur10 = NULL;
  jc_plant* plant = NULL;
  jc_plant* no_plant = NULL;

  test_library();
  test_loading();
  EXPECT_OK(jc_robot_load(JOINTCOMP_TEST_URDF, JOINTCOMP_TEST_PARAMETERS, &robot));
  EXPECT_OK(jc_robot_load_json(JOINTCOMP_TEST_URDF, kMinimalParameters, &bare));
  EXPECT_OK(jc_robot_load(JOINTCOMP_TEST_UR10_URDF, NULL, &ur10));
  if (!robot || !bare || !ur10) {
    fprintf(stderr, "cannot load the test robots\n");
    return 1;
  }
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "no \"plant\" object", jc_plant_create(bare, &plant));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "plant is NULL", jc_plant_create(robot, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "robot is NULL", jc_plant_create(NULL, &no_plant));
  EXPECT_OK(jc_plant_create(robot, &plant));
  /* Options by name (jointcomp.h lists them); an unknown one is refused, naming it. */
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "step_past",
                jc_plant_create_with_options(robot, "{\"step_past\": 1}", &no_plant));
  EXPECT_OK(jc_plant_create_with_options(robot, "{\"step_past_updates_s\": 0.01, \"max_order\": 2}", &no_plant));
  EXPECT_OK(jc_plant_free(no_plant));
  no_plant = NULL;

  test_queries(robot, bare);
  test_handles(robot, plant);
  test_kinematics(robot, ur10);
  test_errors_and_compensation(robot);
  test_spiral(robot, bare);
  test_dynamic_compensation(robot, bare);
  test_unreachable_spiral(ur10);
  test_metrics();
  test_identification(robot, bare);
  /* The plant keeps its own copy of the model: the robot may go first. */
  EXPECT_OK(jc_robot_free(robot));
  test_plant(plant);
  test_plant_watchdog(plant);
  EXPECT_OK(jc_plant_free(plant));
  EXPECT_OK(jc_robot_free(bare));
  EXPECT_OK(jc_robot_free(ur10));

  printf("test_capi: %d checks, %d failed\n", checks, failures);
  return failures == 0 ? 0 : 1;
}
