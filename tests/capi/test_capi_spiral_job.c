/* The Monte Carlo entry points from C99 (jc_spiral_job_*, jc_robot_load_text, jc_forward_kinematics_batch):
 * the job's draw at the nominal values is jc_spiral_experiment_truth with the nominal truth, bit for bit; a
 * batch of poses is the poses one by one; every error path names its argument. */
#define _POSIX_C_SOURCE 200809L

#include "capi_check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char* read_file(const char* path) {
  FILE* file = fopen(path, "rb");
  long size;
  char* text;
  if (!file) return NULL;
  fseek(file, 0, SEEK_END);
  size = ftell(file);
  fseek(file, 0, SEEK_SET);
  text = (char*)calloc((size_t)size + 1, 1);
  if (text && fread(text, 1, (size_t)size, file) != (size_t)size) text[0] = '\0';
  fclose(file);
  return text;
}

/* The "value" of every entry of jc_spiral_job_parameters' JSON, in order. */
static int nominal_values(const char* json, double* values, int capacity) {
  int count = 0;
  const char* at = json;
  while ((at = strstr(at, "\"value\":")) != NULL && count < capacity) {
    at += strlen("\"value\":");
    values[count++] = strtod(at, NULL);
  }
  return count;
}

static void test_job(jc_robot* robot) {
  jc_spiral_job* job = NULL;
  int32_t m = 0, p = 0, length = 0, k;
  double metrics[15], reference[15], *errors, *reference_errors, *time, *plan_time, values[512];
  char* json;
  EXPECT_OK(jc_spiral_job_create(robot, 0, &job));
  EXPECT_OK(jc_spiral_job_sizes(job, &m, &p));
  CHECK(m > 1000 && p > 20 && p < 512);
  EXPECT_OK(jc_spiral_job_parameters(job, NULL, 0, &length));
  json = (char*)malloc((size_t)length + 1);
  EXPECT_OK(jc_spiral_job_parameters(job, json, length + 1, &length));
  CHECK(strstr(json, "\"joint_2.stiffness_nm_per_rad\"") && strstr(json, "\"joint_6.placement_rz_rad\""));
  CHECK(nominal_values(json, values, 512) == p);
  errors = (double*)malloc(sizeof(double) * 9 * (size_t)m);
  reference_errors = (double*)malloc(sizeof(double) * 9 * (size_t)m);
  time = (double*)malloc(sizeof(double) * (size_t)m);
  plan_time = (double*)malloc(sizeof(double) * (size_t)m);
  EXPECT_OK(jc_spiral_job_time(job, time, m));
  EXPECT_OK(jc_spiral_plan(robot, plan_time, m, NULL, 0, NULL, 0, NULL, 0));
  CHECK(memcmp(time, plan_time, sizeof(double) * (size_t)m) == 0);
  /* The nominal values and tracker seed 7 are jc_spiral_experiment_truth with the robot as its own truth. The
     values went through JSON text: %.17g keeps every bit. */
  EXPECT_OK(jc_spiral_job_run(job, values, p, 7, metrics, 15, errors, 9 * m));
  EXPECT_OK(jc_spiral_experiment_truth(robot, robot, 0, reference, 15, reference_errors, 9 * m));
  CHECK(memcmp(metrics, reference, sizeof metrics) == 0);
  CHECK(memcmp(errors, reference_errors, sizeof(double) * 9 * (size_t)m) == 0);
  /* Stiffer joints in the truth (every value above 1e4: the stiffnesses in N m/rad) leave other errors. */
  for (k = 0; k < p; ++k) {
    if (values[k] > 1e4) values[k] *= 1.2;
  }
  for (k = 0; k < p - 1 && !(values[k] > 1e4); ++k) {}
  EXPECT_OK(jc_spiral_job_run(job, values, p, 7, metrics, 15, NULL, 0));
  CHECK(memcmp(metrics, reference, sizeof metrics) != 0);
  values[k] = -1.0;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "stiffness", jc_spiral_job_run(job, values, p, 7, metrics, 15, NULL, 0));
  values[k] = NAN;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "is NaN", jc_spiral_job_run(job, values, p, 7, metrics, 15, NULL, 0));
  values[k] = 1e5;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "values_len",
                jc_spiral_job_run(job, values, p - 1, 7, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "noise_seed is -1",
                jc_spiral_job_run(job, values, p, -1, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "errors_len", jc_spiral_job_run(job, values, p, 7, metrics, 15, errors, 9));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "job is NULL", jc_spiral_job_run(NULL, values, p, 7, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_robot",
                jc_spiral_job_run((jc_spiral_job*)(void*)robot, values, p, 7, metrics, 15, NULL, 0));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "got a jc_spiral_job", jc_robot_dof((jc_robot*)(void*)job, &m));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "use_plant is 2", jc_spiral_job_create(robot, 2, &job));
  EXPECT_OK(jc_spiral_job_free(job));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "already freed", jc_spiral_job_sizes(job, &m, &p));
  EXPECT_STATUS(JC_ERROR_WRONG_HANDLE, "already freed", jc_spiral_job_free(job));
  EXPECT_OK(jc_spiral_job_free(NULL));
  free(json);
  free(errors);
  free(reference_errors);
  free(time);
  free(plan_time);
}

static void test_batch_kinematics(jc_robot* robot) {
  double q[18], poses[48], one[16], bad[6];
  int k;
  for (k = 0; k < 18; ++k) q[k] = 0.1 * (k % 7) - 0.2;
  EXPECT_OK(jc_forward_kinematics_batch(robot, 3, q, 18, poses, 48));
  for (k = 0; k < 3; ++k) {
    EXPECT_OK(jc_forward_kinematics(robot, q + 6 * k, 6, one, 16));
    CHECK(memcmp(one, poses + 16 * k, sizeof one) == 0);
  }
  EXPECT_OK(jc_forward_kinematics_batch(robot, 0, NULL, 0, NULL, 0));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "count is -1", jc_forward_kinematics_batch(robot, -1, q, 18, poses, 48));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q_len is 17", jc_forward_kinematics_batch(robot, 3, q, 17, poses, 48));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "poses_len is 47", jc_forward_kinematics_batch(robot, 3, q, 18, poses, 47));
  memcpy(bad, q, sizeof bad);
  bad[4] = INFINITY;
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "q[4] is +infinity",
                jc_forward_kinematics_batch(robot, 1, bad, 6, poses, 16));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "16 x count",
                jc_forward_kinematics_batch(robot, 200000000, q, 1200000000, poses, 48));
}

int main(void) {
  char* urdf = read_file(JOINTCOMP_TEST_URDF);
  char* parameters = read_file(JOINTCOMP_TEST_PARAMETERS);
  jc_robot* robot = NULL;
  CHECK(urdf && parameters);
  EXPECT_OK(jc_robot_load_text(urdf, parameters, &robot));
  EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "urdf_text is NULL", jc_robot_load_text(NULL, parameters, &robot));
  EXPECT_STATUS(JC_ERROR_FILE, "urdf_text", jc_robot_load_text("<robot", parameters, &robot));
  {
    /* Without drives there is no plant to follow the spiral with; the job refuses before planning. */
    jc_robot* bare = NULL;
    jc_spiral_job* job = NULL;
    EXPECT_OK(jc_robot_load_text(urdf, NULL, &bare));
    EXPECT_STATUS(JC_ERROR_INVALID_ARGUMENT, "use_plant is 1 but", jc_spiral_job_create(bare, 1, &job));
    CHECK(job == NULL);
    EXPECT_OK(jc_robot_free(bare));
  }
  test_job(robot);
  test_batch_kinematics(robot);
  EXPECT_OK(jc_robot_free(robot));
  free(urdf);
  free(parameters);
  printf("test_capi_spiral_job: %d checks, %d failures\n", checks, failures);
  return failures == 0 ? 0 : 1;
}
