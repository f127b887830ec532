/* Load test of the C API: a trajectory of a million points compensated by jc_compensate_trajectory, three
 * times. The references must be identical, bit for bit, every time, and the resident memory after each
 * call must stay where it was after the first (nothing kept or leaked per call).
 *   capi_load <URDF> <parameter file> [points, default 1000000] */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <jointcomp/jointcomp.h>

#define DOF 6
#define CALLS 3
#define ALLOWED_GROWTH_KIB 4096L

static long resident_kib(void) {
  char line[256];
  long kib = -1;
  FILE* status = fopen("/proc/self/status", "r");
  if (!status) return -1;
  while (fgets(line, sizeof line, status)) {
    if (strncmp(line, "VmRSS:", 6) == 0) kib = strtol(line + 6, NULL, 10);
  }
  fclose(status);
  return kib;
}

static double seconds_now(void) {
  struct timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

static void* allocate(size_t count) {
  void* memory = malloc(count * sizeof(double));
  if (!memory) {
    fprintf(stderr, "capi_load: out of memory\n");
    exit(1);
  }
  return memory;
}

int main(int argc, char** argv) {
  const double posture[DOF] = {0.0, -0.3, 0.5, 0.0, 0.6, 0.0};
  jc_robot* robot = NULL;
  long points, k, rss_before, rss_first = 0;
  int j, call, ok = 1;
  double *planned, *velocities, *first, *references;
  if (argc < 3) {
    fprintf(stderr, "usage: capi_load <URDF> <parameter file> [points]\n");
    return 2;
  }
  points = argc > 3 ? atol(argv[3]) : 1000000L;
  if (points < 1 || points > INT32_MAX / DOF) {
    fprintf(stderr, "capi_load: points must be between 1 and %d\n", INT32_MAX / DOF);
    return 2;
  }
  if (jc_robot_load(argv[1], argv[2], &robot) != JC_OK) {
    fprintf(stderr, "capi_load: %s\n", jc_last_error());
    return 1;
  }
  /* A slow motion of every joint around a working posture, with its velocities (a 2 ms sampling). */
  planned = allocate((size_t)points * DOF);
  velocities = allocate((size_t)points * DOF);
  first = allocate((size_t)points * DOF);
  references = allocate((size_t)points * DOF);
  for (k = 0; k < points; ++k) {
    const double t = 0.002 * (double)k;
    for (j = 0; j < DOF; ++j) {
      const double omega = 2.0 * 3.14159265358979323846 / (7.0 + 3.0 * j);
      planned[k * DOF + j] = posture[j] + 0.2 * sin(omega * t);
      velocities[k * DOF + j] = 0.2 * omega * cos(omega * t);
    }
  }
  memset(first, 0, (size_t)points * DOF * sizeof(double));
  memset(references, 0, (size_t)points * DOF * sizeof(double));
  rss_before = resident_kib();
  printf("%ld points: RSS %ld KiB with the inputs and outputs allocated\n", points, rss_before);
  for (call = 1; call <= CALLS; ++call) {
    int32_t max_iterations = 0;
    double max_correction = 0.0, started = seconds_now(), took;
    long rss;
    double* out = call == 1 ? first : references;
    const jc_status status =
        jc_compensate_trajectory(robot, NULL, planned, (int32_t)(points * DOF), velocities, (int32_t)(points * DOF),
                                 out, (int32_t)(points * DOF), &max_iterations, &max_correction);
    took = seconds_now() - started;
    rss = resident_kib();
    if (status != JC_OK) {
      printf("FAIL: call %d: %s\n", call, jc_last_error());
      return 1;
    }
    printf("call %d: %.2f s (%.2f million points/s), at most %d iterations, largest correction %.3g rad, RSS %ld KiB\n",
           call, took, 1e-6 * (double)points / took, (int)max_iterations, max_correction, rss);
    if (call == 1) {
      rss_first = rss;
    } else {
      if (memcmp(first, references, (size_t)points * DOF * sizeof(double)) != 0) {
        printf("FAIL: call %d gave other references than call 1\n", call);
        ok = 0;
      }
      if (rss - rss_first > ALLOWED_GROWTH_KIB) {
        printf("FAIL: the resident memory grew by %ld KiB since call 1 (allowed %ld)\n", rss - rss_first,
               ALLOWED_GROWTH_KIB);
        ok = 0;
      }
    }
  }
  for (k = 0; k < points * DOF && ok; ++k) {
    if (!isfinite(first[k])) {
      printf("FAIL: reference %ld is not finite\n", k);
      ok = 0;
    }
  }
  jc_robot_free(robot);
  free(planned);
  free(velocities);
  free(first);
  free(references);
  printf("%s\n", ok ? "PASS: references identical in every call, memory flat" : "FAIL");
  return ok ? 0 : 1;
}
