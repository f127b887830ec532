/* Two handles in two threads give the same results, bit for bit, as one after the other; and one handle
 * shared by two threads stays consistent (its lock serialises the calls; calibration needs no lock). A handle
 * freed while a call uses it (from another thread, or from the call's own progress callback) is refused with
 * JC_ERROR_BUSY, and calls made after a free are JC_ERROR_WRONG_HANDLE, never a use of freed memory. Built
 * with -DJOINTCOMP_SANITIZE=thread, ThreadSanitizer checks that nothing is shared without synchronisation. */
#define _POSIX_C_SOURCE 200809L

#include <jointcomp/jointcomp.h>

#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define POSTURES 4
#define PLANT_PERIODS 50
#define DEG (3.14159265358979323846 / 180.0)

typedef struct {
  double pose[POSTURES][16];
  double jacobian[POSTURES][36];
  double gravity[POSTURES][6];
  double ik[POSTURES][6];
  double errors[POSTURES][6];
  double reference[POSTURES][6];
  double metrics[15];
  double plant_q[6];
  double plant_state[30];
  double calibrated_pose[16];    /* of the robot calibrated on the shared campaign */
  double* trajectory_references; /* 6 m */
  int failed;                    /* a call returned an error */
} Results;

typedef struct {
  jc_robot* robot;
  int with_experiment; /* the spiral experiment and a plant of its own */
  Results results;
} Work;

static jc_robot* load(void);
static int32_t sample_count = 0;
static char campaign_path[64]; /* a simulated campaign every thread calibrates on (read only) */
static double* spiral_q = NULL;
static double* spiral_qd = NULL;

static void posture(int k, double q[6]) {
  const double degrees[6] = {-20.0 + 10 * k, 40.0 + 7 * k, 50.0 + 9 * k, 15.0 - 8 * k, 30.0 + 5 * k, -40.0 + 20 * k};
  int j;
  for (j = 0; j < 6; ++j) q[j] = degrees[j] * DEG;
}

#define CALL(results, call)                                       \
  do {                                                            \
    if ((call) != JC_OK) {                                        \
      fprintf(stderr, "%s failed: %s\n", #call, jc_last_error()); \
      (results)->failed = 1;                                      \
    }                                                             \
  } while (0)

static void* work(void* argument) {
  Work* work_item = (Work*)argument;
  Results* out = &work_item->results;
  jc_robot* robot = work_item->robot;
  int k;
  for (k = 0; k < POSTURES; ++k) {
    double q[6], seed[6];
    int j;
    posture(k, q);
    for (j = 0; j < 6; ++j) seed[j] = q[j] + 0.05;
    CALL(out, jc_forward_kinematics(robot, q, 6, out->pose[k], 16));
    CALL(out, jc_jacobian(robot, q, 6, out->jacobian[k], 36));
    CALL(out, jc_gravity_torques(robot, q, 6, out->gravity[k], 6));
    CALL(out, jc_inverse_kinematics(robot, out->pose[k], 16, seed, 6, out->ik[k], 6, NULL));
    CALL(out, jc_predict_joint_errors(robot, NULL, q, 6, NULL, 0, out->errors[k], 6));
    CALL(out, jc_compensate_point(robot, NULL, q, 6, NULL, 0, out->reference[k], 6, NULL));
  }
  out->trajectory_references = (double*)malloc(sizeof(double) * 6 * (size_t)sample_count);
  CALL(out, jc_compensate_trajectory(robot, NULL, spiral_q, 6 * sample_count, spiral_qd, 6 * sample_count,
                                     out->trajectory_references, 6 * sample_count, NULL, NULL));
  {
    /* Calibration reads only the robot's immutable model: two threads may run it on one handle at once. */
    jc_robot* calibrated = NULL;
    double q[6];
    posture(2, q);
    CALL(out, jc_calibrate(robot, campaign_path, NULL, "{\"loss\": \"huber\"}", &calibrated, NULL));
    CALL(out, jc_forward_kinematics(calibrated, q, 6, out->calibrated_pose, 16));
    CALL(out, jc_robot_free(calibrated));
  }
  if (work_item->with_experiment) {
    jc_plant* plant = NULL;
    double start[6], velocity[6] = {0.05, -0.03, 0.04, 0.1, -0.1, 0.2};
    CALL(out, jc_spiral_experiment(robot, 0, out->metrics, 15, NULL, 0));
    CALL(out, jc_plant_create(robot, &plant));
    posture(1, start);
    CALL(out, jc_plant_reset(plant, start, 6, 0.0));
    for (k = 1; k <= PLANT_PERIODS && !out->failed; ++k) {
      double reference[6];
      int j;
      for (j = 0; j < 6; ++j) reference[j] = start[j] + velocity[j] * 0.004 * k;
      CALL(out, jc_plant_set_reference(plant, reference, 6, velocity, 6));
      CALL(out, jc_plant_advance(plant, 0.004 * k));
    }
    CALL(out, jc_plant_link_positions(plant, out->plant_q, 6));
    CALL(out, jc_plant_state(plant, out->plant_state, 30));
    CALL(out, jc_plant_free(plant));
  }
  return NULL;
}

/* ---- Freed while busy ---------------------------------------------------------------------------------- */

typedef struct {
  pthread_mutex_t mutex;
  pthread_cond_t changed;
  jc_robot* robot;
  int inside;         /* the calibration's callback has been entered */
  int may_leave;      /* the main thread has tried to free the robot */
  jc_status own_free; /* jc_robot_free(robot) from inside the callback */
  char own_message[512];
  jc_status calibrate_status;
} CallbackFree;

static void free_from_callback(const char* message, void* user_data) {
  CallbackFree* c = (CallbackFree*)user_data;
  (void)message;
  pthread_mutex_lock(&c->mutex);
  if (!c->inside) {
    /* The callback frees the robot of the call that runs it: refused, and the call goes on. */
    c->own_free = jc_robot_free(c->robot);
    snprintf(c->own_message, sizeof c->own_message, "%s", jc_last_error());
    c->inside = 1;
    pthread_cond_broadcast(&c->changed);
    while (!c->may_leave) pthread_cond_wait(&c->changed, &c->mutex);
  }
  pthread_mutex_unlock(&c->mutex);
}

static void* calibrate_with_callback(void* argument) {
  CallbackFree* c = (CallbackFree*)argument;
  jc_robot* calibrated = NULL;
  jc_set_progress_callback(free_from_callback, c);
  c->calibrate_status = jc_calibrate(c->robot, campaign_path, NULL, NULL, &calibrated, NULL);
  jc_set_progress_callback(NULL, NULL);
  jc_robot_free(calibrated);
  return NULL;
}

/* A robot freed while jc_calibrate runs on it, from the callback and from another thread: both refused. */
static int freed_during_calibration(void) {
  CallbackFree c;
  pthread_t thread;
  jc_status busy;
  int failures = 0;
  memset(&c, 0, sizeof c);
  pthread_mutex_init(&c.mutex, NULL);
  pthread_cond_init(&c.changed, NULL);
  c.robot = load();
  if (pthread_create(&thread, NULL, calibrate_with_callback, &c) != 0) return 1;
  pthread_mutex_lock(&c.mutex);
  while (!c.inside) pthread_cond_wait(&c.changed, &c.mutex);
  busy = jc_robot_free(c.robot); /* the calibration is inside its callback: the robot is busy */
  if (busy != JC_ERROR_BUSY || !strstr(jc_last_error(), "on other threads")) {
    fprintf(stderr, "free during jc_calibrate: %s (%s), expected JC_ERROR_BUSY\n", jc_status_name(busy),
            jc_last_error());
    ++failures;
  }
  c.may_leave = 1;
  pthread_cond_broadcast(&c.changed);
  pthread_mutex_unlock(&c.mutex);
  pthread_join(thread, NULL);
  if (c.own_free != JC_ERROR_BUSY || !strstr(c.own_message, "on this thread")) {
    fprintf(stderr, "free from jc_calibrate's callback: %s (%s), expected JC_ERROR_BUSY\n", jc_status_name(c.own_free),
            c.own_message);
    ++failures;
  }
  if (c.calibrate_status != JC_OK) {
    fprintf(stderr, "jc_calibrate failed after the refused frees\n");
    ++failures;
  }
  if (jc_robot_free(c.robot) != JC_OK) { /* idle now: freed */
    fprintf(stderr, "free after jc_calibrate returned: %s\n", jc_last_error());
    ++failures;
  }
  pthread_cond_destroy(&c.changed);
  pthread_mutex_destroy(&c.mutex);
  return failures;
}

typedef struct {
  pthread_mutex_t mutex;
  jc_robot* robot;
  jc_plant* plant;
  int calls; /* made so far */
  int freed; /* set by the main thread once both frees succeeded */
  int ok, refused, wrong;
} Race;

/* Calls on a robot and a plant while the main thread frees them: each call is JC_OK or, once the handle is
   gone, JC_ERROR_WRONG_HANDLE; none may succeed after the free returned. */
static void* call_while_freed(void* argument) {
  Race* r = (Race*)argument;
  double q[6], reference[6];
  int k;
  posture(1, q);
  for (k = 0; k < 400; ++k) {
    int freed;
    jc_status a, b;
    pthread_mutex_lock(&r->mutex);
    freed = r->freed;
    ++r->calls;
    pthread_mutex_unlock(&r->mutex);
    a = jc_compensate_point(r->robot, NULL, q, 6, NULL, 0, reference, 6, NULL);
    b = jc_plant_advance(r->plant, 0.001 * (k + 1));
    if (a == JC_OK && b == JC_OK && !freed)
      ++r->ok;
    else if ((a == JC_OK || a == JC_ERROR_WRONG_HANDLE) && (b == JC_OK || b == JC_ERROR_WRONG_HANDLE) &&
             (!freed || (a != JC_OK && b != JC_OK)))
      ++r->wrong;
    else
      ++r->refused; /* counted as a failure below */
    if (freed) break;
  }
  return NULL;
}

static int freed_during_calls(void) {
  Race r;
  pthread_t thread;
  double start[6];
  int robot_freed = 0, plant_freed = 0, busy = 0, bad = 0;
  memset(&r, 0, sizeof r);
  pthread_mutex_init(&r.mutex, NULL);
  r.robot = load();
  posture(1, start);
  if (jc_plant_create(r.robot, &r.plant) != JC_OK || jc_plant_reset(r.plant, start, 6, 0.0) != JC_OK) return 1;
  if (pthread_create(&thread, NULL, call_while_freed, &r) != 0) return 1;
  for (;;) { /* the frees begin while the calls are under way */
    int calls;
    pthread_mutex_lock(&r.mutex);
    calls = r.calls;
    pthread_mutex_unlock(&r.mutex);
    if (calls >= 20) break;
    sched_yield();
  }
  while (!robot_freed || !plant_freed) {
    jc_status status;
    if (!robot_freed) {
      status = jc_robot_free(r.robot);
      robot_freed = status == JC_OK;
      busy += status == JC_ERROR_BUSY;
      bad += status != JC_OK && status != JC_ERROR_BUSY;
    }
    if (!plant_freed) {
      status = jc_plant_free(r.plant);
      plant_freed = status == JC_OK;
      busy += status == JC_ERROR_BUSY;
      bad += status != JC_OK && status != JC_ERROR_BUSY;
    }
    if (bad) break;
  }
  pthread_mutex_lock(&r.mutex);
  r.freed = 1;
  pthread_mutex_unlock(&r.mutex);
  pthread_join(thread, NULL);
  pthread_mutex_destroy(&r.mutex);
  if (bad || r.refused) {
    fprintf(stderr, "freed during calls: %d frees neither OK nor busy, %d calls out of the rules\n", bad, r.refused);
    return 1;
  }
  printf("freed during calls: %d frees refused as busy, %d calls before and %d after the frees\n", busy, r.ok, r.wrong);
  return 0;
}

static int same_results(const Results* a, const Results* b, int with_experiment) {
  /* Field by field: the struct holds a pointer, and its padding is not part of the results. */
  if (a->failed || b->failed) return 0;
  if (memcmp(a->pose, b->pose, sizeof a->pose) || memcmp(a->jacobian, b->jacobian, sizeof a->jacobian) ||
      memcmp(a->gravity, b->gravity, sizeof a->gravity) || memcmp(a->ik, b->ik, sizeof a->ik) ||
      memcmp(a->errors, b->errors, sizeof a->errors) || memcmp(a->reference, b->reference, sizeof a->reference) ||
      memcmp(a->calibrated_pose, b->calibrated_pose, sizeof a->calibrated_pose)) {
    return 0;
  }
  if (memcmp(a->trajectory_references, b->trajectory_references, sizeof(double) * 6 * (size_t)sample_count)) return 0;
  if (with_experiment &&
      (memcmp(a->metrics, b->metrics, sizeof a->metrics) || memcmp(a->plant_q, b->plant_q, sizeof a->plant_q) ||
       memcmp(a->plant_state, b->plant_state, sizeof a->plant_state))) {
    return 0;
  }
  return 1;
}

static jc_robot* load(void) {
  jc_robot* robot = NULL;
  if (jc_robot_load(JOINTCOMP_TEST_URDF, JOINTCOMP_TEST_PARAMETERS, &robot) != JC_OK) {
    fprintf(stderr, "cannot load the robot: %s\n", jc_last_error());
    exit(1);
  }
  return robot;
}

int main(void) {
  Work sequential[2], parallel[2], shared[2];
  pthread_t threads[2];
  jc_robot* plan_robot = load();
  jc_robot* shared_robot;
  int i, failures = 0;

  if (jc_spiral_sample_count(plan_robot, &sample_count) != JC_OK) return 1;
  spiral_q = (double*)malloc(sizeof(double) * 6 * (size_t)sample_count);
  spiral_qd = (double*)malloc(sizeof(double) * 6 * (size_t)sample_count);
  if (jc_spiral_plan(plan_robot, NULL, 0, NULL, 0, spiral_q, 6 * sample_count, spiral_qd, 6 * sample_count) != JC_OK) {
    return 1;
  }
  strcpy(campaign_path, "/tmp/jointcomp_threads_XXXXXX");
  i = mkstemp(campaign_path);
  if (i < 0 || jc_simulate_campaign(plan_robot, "{\"protocol\": \"random\", \"seed\": 3, \"count\": 60}",
                                    campaign_path) != JC_OK) {
    fprintf(stderr, "cannot simulate the campaign: %s\n", jc_last_error());
    return 1;
  }
  close(i);
  jc_robot_free(plan_robot);

  /* One after the other, each with a handle of its own. */
  for (i = 0; i < 2; ++i) {
    memset(&sequential[i], 0, sizeof sequential[i]);
    sequential[i].robot = load();
    sequential[i].with_experiment = 1;
    work(&sequential[i]);
  }
  /* Two handles in two threads at once. */
  for (i = 0; i < 2; ++i) {
    memset(&parallel[i], 0, sizeof parallel[i]);
    parallel[i].robot = load();
    parallel[i].with_experiment = 1;
    if (pthread_create(&threads[i], NULL, work, &parallel[i]) != 0) return 1;
  }
  for (i = 0; i < 2; ++i) pthread_join(threads[i], NULL);
  /* One handle shared by two threads. */
  shared_robot = load();
  for (i = 0; i < 2; ++i) {
    memset(&shared[i], 0, sizeof shared[i]);
    shared[i].robot = shared_robot;
    shared[i].with_experiment = 0;
    if (pthread_create(&threads[i], NULL, work, &shared[i]) != 0) return 1;
  }
  for (i = 0; i < 2; ++i) pthread_join(threads[i], NULL);

  if (!same_results(&sequential[0].results, &sequential[1].results, 1)) {
    fprintf(stderr, "two sequential runs differ\n");
    ++failures;
  }
  for (i = 0; i < 2; ++i) {
    if (!same_results(&sequential[0].results, &parallel[i].results, 1)) {
      fprintf(stderr, "parallel run %d differs from the sequential one\n", i);
      ++failures;
    }
    if (!same_results(&sequential[0].results, &shared[i].results, 0)) {
      fprintf(stderr, "shared-handle run %d differs from the sequential one\n", i);
      ++failures;
    }
  }
  for (i = 0; i < 2; ++i) {
    jc_robot_free(sequential[i].robot);
    jc_robot_free(parallel[i].robot);
    free(sequential[i].results.trajectory_references);
    free(parallel[i].results.trajectory_references);
    free(shared[i].results.trajectory_references);
  }
  jc_robot_free(shared_robot);
  failures += freed_during_calibration();
  failures += freed_during_calls();
  remove(campaign_path);
  free(spiral_q);
  free(spiral_qd);
  printf("test_capi_threads: %d samples, 2 sequential, 2 parallel and 2 shared-handle runs, %d differ\n", sample_count,
         failures);
  return failures == 0 ? 0 : 1;
}
