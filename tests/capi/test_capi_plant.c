/* The C API's plant (references, steps, snapshots, the watchdog) and identification (calibration and
 * discovery from campaigns, their reports and progress), from C99: called by test_capi.c's main. */
#define _POSIX_C_SOURCE 200809L

#include <jointcomp/jointcomp.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capi_check.h"

void test_plant(jc_plant* plant) {
  const double velocity[6] = {0.02, -0.01, 0.01, 0, 0, 0};
  const double wrench[6] = {0, 0, -50, 0, 0, 0};
  const double com[3] = {0, 0, 0.05};
  double target[6], q[6], qd[6], p[6], pd[6], torques[6], state[30], time = -1.0;
  double q_continued[6], q_restored[6], *snapshot, *snapshot_bad;
  int64_t counts[5];
  int32_t dof = 0, size = 0, j;

  EXPECT_OK(jc_plant_dof(plant, &dof));
  CHECK(dof == 6);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "dof is NULL", jc_plant_dof(plant, NULL));
  EXPECT_OK(jc_plant_reset(plant, kPosture, 6, 1.0));
  EXPECT_OK(jc_plant_time(plant, &time));
  CHECK(time == 1.0);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "time is NULL", jc_plant_time(plant, NULL));
  /* At rest in equilibrium: the links sag under gravity by the compliance, the motors sit at the command. */
  EXPECT_OK(jc_plant_link_positions(plant, q, 6));
  EXPECT_OK(jc_plant_motor_positions(plant, p, 6));
  CHECK(same_bits(p, kPosture, 6));
  CHECK(max_abs_difference(q, kPosture, 6) > 1e-6 && max_abs_difference(q, kPosture, 6) < 1e-2);
  EXPECT_OK(jc_plant_link_velocities(plant, qd, 6));
  EXPECT_OK(jc_plant_motor_velocities(plant, pd, 6));
  for (j = 0; j < 6; ++j) CHECK(qd[j] == 0.0 && pd[j] == 0.0);

  for (j = 0; j < 6; ++j) target[j] = kPosture[j] + velocity[j] * 0.01;
  EXPECT_OK(jc_plant_set_reference(plant, target, 6, velocity, 6));
  EXPECT_OK(jc_plant_advance(plant, 1.01));
  EXPECT_OK(jc_plant_time(plant, &time));
  CHECK(time == 1.01);
  EXPECT_OK(jc_plant_link_velocities(plant, qd, 6));
  CHECK(qd[0] > 0.0);
  EXPECT_OK(jc_plant_motor_torques(plant, torques, 6));
  CHECK(fabs(torques[1]) > 10.0);
  EXPECT_OK(jc_plant_state(plant, state, 30));
  EXPECT_OK(jc_plant_link_positions(plant, q, 6));
  EXPECT_OK(jc_plant_motor_velocities(plant, pd, 6));
  CHECK(same_bits(state, q, 6) && same_bits(state + 18, pd, 6));
  EXPECT_OK(jc_plant_statistics(plant, counts, 5));
  CHECK(counts[0] > 0 && counts[1] >= counts[0]);

  /* A snapshot restored continues exactly as the plant did after saving it. */
  EXPECT_OK(jc_plant_snapshot_size(plant, &size));
  CHECK(size == 10 * 6 + 14);
  snapshot = (double*)malloc(sizeof(double) * (size_t)size);
  snapshot_bad = (double*)malloc(sizeof(double) * (size_t)size);
  EXPECT_OK(jc_plant_save(plant, snapshot, size));
  EXPECT_OK(jc_plant_set_tool_wrench(plant, wrench, 6));
  EXPECT_OK(jc_plant_set_payload(plant, 5.0, com, 3));
  EXPECT_OK(jc_plant_advance(plant, 1.03));
  EXPECT_OK(jc_plant_link_positions(plant, q_continued, 6));
  EXPECT_OK(jc_plant_reset(plant, kPosture, 6, 0.0));
  EXPECT_OK(jc_plant_restore(plant, snapshot, size));
  EXPECT_OK(jc_plant_time(plant, &time));
  CHECK(time == 1.01);
  EXPECT_OK(jc_plant_set_tool_wrench(plant, wrench, 6));
  EXPECT_OK(jc_plant_set_payload(plant, 5.0, com, 3));
  EXPECT_OK(jc_plant_advance(plant, 1.03));
  EXPECT_OK(jc_plant_link_positions(plant, q_restored, 6));
  CHECK(same_bits(q_continued, q_restored, 6));

  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "snapshot_len", jc_plant_save(plant, snapshot, size - 1));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "snapshot_len", jc_plant_restore(plant, snapshot, size + 1));
  memcpy(snapshot_bad, snapshot, sizeof(double) * (size_t)size);
  snapshot_bad[0] = 99.0;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "format", jc_plant_restore(plant, snapshot_bad, size));
  snapshot_bad[0] = snapshot[0];
  snapshot_bad[1] = 7.0;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "another number of joints", jc_plant_restore(plant, snapshot_bad, size));
  snapshot_bad[1] = snapshot[1];
  snapshot_bad[10] = kInf;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "snapshot[10] is +infinity", jc_plant_restore(plant, snapshot_bad, size));
  snapshot_bad[10] = snapshot[10];
  snapshot_bad[size - 4] = -1.0;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "negative payload", jc_plant_restore(plant, snapshot_bad, size));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "snapshot is NULL", jc_plant_restore(plant, NULL, size));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "size is NULL", jc_plant_snapshot_size(plant, NULL));
  free(snapshot);
  free(snapshot_bad);

  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "not after", jc_plant_advance(plant, 1.0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "end_time is NaN", jc_plant_advance(plant, kNaN));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "start_time is +infinity", jc_plant_reset(plant, kPosture, 6, kInf));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "command_len is 2", jc_plant_reset(plant, kPosture, 2, 0.0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "velocity is NULL", jc_plant_set_reference(plant, kPosture, 6, NULL, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "position_len is 1",
                jc_plant_set_reference(plant, kPosture, 1, velocity, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "wrench_len is 5", jc_plant_set_tool_wrench(plant, wrench, 5));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "mass is negative", jc_plant_set_payload(plant, -2.0, com, 3));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "com_len is 0", jc_plant_set_payload(plant, 2.0, com, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values_len is 5", jc_plant_link_positions(plant, q, 5));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values is NULL", jc_plant_link_velocities(plant, NULL, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values_len is 7", jc_plant_motor_positions(plant, p, 7));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values_len is 0", jc_plant_motor_velocities(plant, pd, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values is NULL", jc_plant_motor_torques(plant, NULL, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "state_len is 6", jc_plant_state(plant, state, 6));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "counts_len is 4", jc_plant_statistics(plant, counts, 4));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "counts is NULL", jc_plant_statistics(plant, NULL, 5));
}

/* The watchdog: a 0.5 rad step of joint 1 (as an FMU master once sent) is a following error the drive
   cannot work off, a status naming the joint rather than a run that swings away with every call OK; the
   plant then refuses to advance until it is reset; a wider envelope lets the same step through. */
void test_plant_watchdog(jc_plant* plant) {
  const double zero[6] = {0, 0, 0, 0, 0, 0};
  double target[6], time = 0.0;
  int32_t j;
  for (j = 0; j < 6; ++j) target[j] = kPosture[j];
  target[0] -= 0.5;
  EXPECT_OK(jc_plant_reset(plant, kPosture, 6, 0.0));
  EXPECT_OK(jc_plant_set_reference(plant, target, 6, zero, 6));
  EXPECT_STATUS(JC_ERROR_PLANT_LIMIT, "joint_1 has a following error", jc_plant_advance(plant, 0.004));
  EXPECT_OK(jc_plant_time(plant, &time));
  CHECK(time == 0.004);
  EXPECT_STATUS(JC_ERROR_PLANT_LIMIT, "reset the plant", jc_plant_advance(plant, 0.008));

  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "tracking_envelope_rad must be finite and positive",
                jc_plant_set_watchdog(plant, 0.0, 0.02));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "joint_limit_margin_rad", jc_plant_set_watchdog(plant, 0.2, kNaN));
  EXPECT_OK(jc_plant_set_watchdog(plant, 1.0, 0.02));
  EXPECT_OK(jc_plant_reset(plant, kPosture, 6, 0.0));
  EXPECT_OK(jc_plant_set_reference(plant, target, 6, zero, 6));
  EXPECT_OK(jc_plant_advance(plant, 0.1));
  EXPECT_OK(jc_plant_set_watchdog(plant, 0.2, 0.02));
  EXPECT_OK(jc_plant_reset(plant, kPosture, 6, 0.0));
}

/* A report's JSON, read with the two-call protocol (length first); caller frees. */
static char* report_text(jc_report* report, int summary) {
  int32_t length = -1;
  char* text;
  if ((summary ? jc_report_summary(report, NULL, 0, &length) : jc_report_json(report, NULL, 0, &length)) != JC_OK)
    return NULL;
  text = (char*)malloc((size_t)length + 1);
  if (!text) return NULL;
  if ((summary ? jc_report_summary(report, text, length + 1, &length)
               : jc_report_json(report, text, length + 1, &length)) != JC_OK) {
    free(text);
    return NULL;
  }
  return text;
}

/* A fresh temporary path (the file exists, empty; the library replaces it). */
static void temporary_path(char* path, const char* stem) {
  int fd;
  sprintf(path, "/tmp/jointcomp_capi_%s_XXXXXX", stem);
  fd = mkstemp(path);
  if (fd >= 0) close(fd);
}

/* Counts the progress messages of the calling thread's long calls (user_data: an int). */
static int progress_messages = 0;
static void count_progress(const char* message, void* user_data) {
  if (message && message[0] != '\0') ++*(int*)user_data;
}

void test_identification(jc_robot* robot, jc_robot* bare) {
  char sweep[64], stiffness[64], poses[64], held[64], urdf[64], params[64], missing[80];
  char lists[200];
  jc_robot* identified = NULL;
  jc_robot* calibrated = NULL;
  jc_robot* extended = NULL;
  jc_robot* reloaded = NULL;
  jc_report* report = NULL;
  char* text;
  char small[8];
  int32_t length = 0;
  double errors_a[6], errors_b[6], pose_a[16], pose_b[16];
  temporary_path(sweep, "sweep");
  temporary_path(stiffness, "stiffness");
  temporary_path(poses, "poses");
  temporary_path(held, "held");
  temporary_path(urdf, "urdf");
  temporary_path(params, "params");
  sprintf(missing, "%s.missing", sweep);

  /* Simulation: the robot is the truth. */
  EXPECT_OK(jc_simulate_campaign(robot, "{\"protocol\": \"joint2-sweep\", \"seed\": 3, \"step_deg\": 0.25}", sweep));
  EXPECT_OK(jc_simulate_campaign(robot, "{\"protocol\": \"stiffness\", \"seed\": 4}", stiffness));
  EXPECT_OK(jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"seed\": 5, \"count\": 80}", poses));
  EXPECT_OK(jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"seed\": 6, \"count\": 40}", held));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "truth is NULL", jc_simulate_campaign(NULL, "{}", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "campaign_path is NULL",
                jc_simulate_campaign(robot, "{\"protocol\": \"random\"}", NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "protocol: is required", jc_simulate_campaign(robot, NULL, sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "not valid JSON", jc_simulate_campaign(robot, "{\"protocol\": ", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "JSON object", jc_simulate_campaign(robot, "[1, 2]", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "unknown protocol 'circle'",
                jc_simulate_campaign(robot, "{\"protocol\": \"circle\"}", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.speed",
                jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"speed\": 2}", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.joint",
                jc_simulate_campaign(robot, "{\"protocol\": \"joint-sweep\", \"joint\": 7}", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.seed",
                jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"seed\": -1}", sweep));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.pose_deg",
                jc_simulate_campaign(robot, "{\"protocol\": \"stiffness\", \"pose_deg\": [1, 2]}", sweep));
  EXPECT_OK(jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"count\": 5, \"warm_up\": [5, 600]}", urdf));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.warm_up",
                jc_simulate_campaign(robot, "{\"protocol\": \"random\", \"warm_up\": [5, -1]}", urdf));
  EXPECT_STATUS(JC_ERROR_FILE, "does not exist",
                jc_simulate_campaign(robot, "{\"protocol\": \"spiral\"}", "/nonexistent/folder/spiral.csv"));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "needs drives",
                jc_simulate_campaign(bare, "{\"protocol\": \"joint-sweep\", \"plant\": true}", sweep));

  /* Transmission error from the sweep. */
  EXPECT_OK(jc_identify_transmission_error(robot, sweep, "{\"joint\": 2, \"stage\": 2}", &identified, &report));
  CHECK(identified != NULL && report != NULL);
  text = report_text(report, 0);
  CHECK(text != NULL && strstr(text, "\"significant\": true") != NULL);
  free(text);
  text = report_text(report, 1);
  CHECK(text != NULL && strstr(text, "joint_2") != NULL);
  free(text);
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "buffer holds 8 bytes", jc_report_json(report, small, 8, &length));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "length is NULL", jc_report_summary(report, NULL, 0, NULL));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_robot", jc_report_json((jc_report*)robot, NULL, 0, &length));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_report", jc_robot_dof((jc_robot*)report, &length));
  /* Model = truth and noise small: the identified harmonics predict the truth's errors closely. */
  EXPECT_OK(jc_predict_joint_errors(robot, "transmission_error", kPosture, 6, NULL, 0, errors_a, 6));
  EXPECT_OK(jc_predict_joint_errors(identified, "transmission_error", kPosture, 6, NULL, 0, errors_b, 6));
  CHECK(fabs(errors_a[1]) > 1e-5 && fabs(errors_b[1] - errors_a[1]) < 0.1 * fabs(errors_a[1]));
  EXPECT_OK(jc_report_free(report));
  /* A freed report, as for robots above. */
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "already freed", jc_report_json(report, NULL, 0, &length));
  EXPECT_OK(jc_report_free(NULL));
  EXPECT_OK(jc_robot_free(identified));
  identified = NULL;
  report = NULL;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.stage",
                jc_identify_transmission_error(robot, sweep, "{\"stage\": 0}", &identified, &report));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.orders",
                jc_identify_transmission_error(robot, sweep, "{\"orders\": [2, -1]}", &identified, &report));
  EXPECT_STATUS(JC_ERROR_FILE, "jointcomp_capi_sweep",
                jc_identify_transmission_error(robot, missing, NULL, &identified, &report));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "campaign_path is NULL",
                jc_identify_transmission_error(robot, NULL, NULL, &identified, &report));
  CHECK(identified == NULL && report == NULL); /* failures leave the outputs untouched */

  /* Stiffness; the outputs are optional. */
  EXPECT_OK(jc_identify_stiffness(robot, stiffness, "{\"method\": \"global\"}", &identified, NULL));
  EXPECT_OK(jc_predict_joint_errors(robot, "compliance", kPosture, 6, NULL, 0, errors_a, 6));
  EXPECT_OK(jc_predict_joint_errors(identified, "compliance", kPosture, 6, NULL, 0, errors_b, 6));
  CHECK(fabs(errors_b[1] - errors_a[1]) < 0.1 * fabs(errors_a[1]));
  EXPECT_OK(jc_robot_free(identified));
  identified = NULL;
  EXPECT_OK(jc_identify_stiffness(robot, stiffness, NULL, NULL, &report));
  EXPECT_OK(jc_report_free(report));
  report = NULL;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.method",
                jc_identify_stiffness(robot, stiffness, "{\"method\": \"best\"}", &identified, &report));
  EXPECT_STATUS(JC_ERROR_FILE, "format",
                jc_identify_stiffness(robot, temporary_file("not a campaign\n"), NULL, &identified, &report));

  /* Calibration with a held-out campaign, then saving and reloading the calibrated robot. */
  sprintf(lists, "%s\n", held);
  progress_messages = 0;
  EXPECT_OK(jc_set_progress_callback(count_progress, &progress_messages));
  EXPECT_OK(jc_calibrate(robot, poses, lists, "{\"loss\": \"huber\", \"fixed\": []}", &calibrated, &report));
  EXPECT_OK(jc_set_progress_callback(NULL, NULL));
  CHECK(progress_messages >= 3); /* rows and parameters, then each accepted step of the fits */
  text = report_text(report, 0);
  CHECK(text != NULL && strstr(text, "jointcomp-calibration-report/1") != NULL && strstr(text, "holdout") != NULL);
  free(text);
  EXPECT_OK(jc_report_free(report));
  report = NULL;
  EXPECT_OK(jc_robot_save(calibrated, urdf, params));
  EXPECT_OK(jc_robot_load(urdf, params, &reloaded));
  EXPECT_OK(jc_forward_kinematics(calibrated, kPosture, 6, pose_a, 16));
  EXPECT_OK(jc_forward_kinematics(reloaded, kPosture, 6, pose_b, 16));
  CHECK(max_abs_difference(pose_a, pose_b, 16) < 1e-12);
  EXPECT_OK(jc_predict_joint_errors(calibrated, NULL, kPosture, 6, NULL, 0, errors_a, 6));
  EXPECT_OK(jc_predict_joint_errors(reloaded, NULL, kPosture, 6, NULL, 0, errors_b, 6));
  CHECK(max_abs_difference(errors_a, errors_b, 6) < 1e-12);
  EXPECT_OK(jc_robot_free(reloaded));
  EXPECT_OK(jc_robot_free(calibrated));
  calibrated = NULL;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "both NULL", jc_robot_save(robot, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "urdf_path is empty", jc_robot_save(robot, "", params));
  /* A path that cannot be written is a file error, not "a bug" (JC_ERROR_INTERNAL, issue 41). */
  EXPECT_STATUS(JC_ERROR_FILE, "/nonexistent/folder/r.urdf: cannot",
                jc_robot_save(robot, "/nonexistent/folder/r.urdf", NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.loss",
                jc_calibrate(robot, poses, NULL, "{\"loss\": \"square\"}", &calibrated, &report));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.fixed",
                jc_calibrate(robot, poses, NULL, "{\"fixed\": [1]}", &calibrated, &report));
  sprintf(lists, "%s\n%s", held, missing);
  EXPECT_STATUS(JC_ERROR_FILE, ".missing", jc_calibrate(robot, poses, lists, NULL, &calibrated, &report));
  CHECK(calibrated == NULL && report == NULL);

  /* Discovery: the truth is the model, so nothing is missing and nothing may be added. */
  sprintf(lists, "%s\r\n\n", poses);
  EXPECT_OK(
      jc_discover(robot, lists, held, "{\"max_steps\": 2, \"types\": [\"offset\", \"harmonic\"]}", &extended, &report));
  text = report_text(report, 0);
  CHECK(text != NULL && strstr(text, "jointcomp-discovery-report/1") != NULL && strstr(text, "\"steps\": []") != NULL);
  free(text);
  EXPECT_OK(jc_report_free(report));
  EXPECT_OK(jc_robot_free(extended));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "campaign_paths names no file",
                jc_discover(robot, "\n\n", NULL, NULL, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "campaign_paths is NULL", jc_discover(robot, NULL, NULL, NULL, NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "unknown effect type 'gremlin'",
                jc_discover(robot, poses, NULL, "{\"types\": [\"gremlin\"]}", NULL, NULL));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "options_json.folds",
                jc_discover(robot, poses, NULL, "{\"folds\": 1}", NULL, NULL));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "expected a jc_robot",
                jc_discover((jc_robot*)(void*)held, poses, NULL, NULL, NULL, NULL));

  remove(sweep);
  remove(stiffness);
  remove(poses);
  remove(held);
  remove(urdf);
  remove(params);
}
