/* What the C tests of the API share (test_capi.c, test_capi_plant.c, test_capi_spiral_job.c): the check macros
 * and their counters, comparisons of arrays, temporary files, and the posture the tests use. */
#ifndef JOINTCOMP_TESTS_CAPI_CHECK_H
#define JOINTCOMP_TESTS_CAPI_CHECK_H

#include <jointcomp/jointcomp.h>

#include <math.h>
#include <stddef.h>

#ifndef JOINTCOMP_TEST_URDF
#error "JOINTCOMP_TEST_URDF (the RX170's URDF) must be defined"
#endif

extern int checks;
extern int failures;

#define CHECK(condition)                                                                                             \
  do {                                                                                                               \
    ++checks;                                                                                                        \
    if (!(condition)) {                                                                                              \
      ++failures;                                                                                                    \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__, __LINE__, #condition, jc_last_error()); \
    }                                                                                                                \
  } while (0)

/* A call must return `expected`; an error's message must name the function and contain `fragment`. */
#define EXPECT_STATUS(expected, fragment, call) expect_status((expected), (fragment), (call), #call, __FILE__, __LINE__)
#define EXPECT_OK(call) EXPECT_STATUS(JC_OK, "", call)

void expect_status(jc_status expected, const char* fragment, jc_status got, const char* call, const char* file,
                   int line);
int same_bits(const double* a, const double* b, size_t count);
double max_abs_difference(const double* a, const double* b, size_t count);
/* Writes `text` into a new temporary file; returns its path (static storage, one at a time). */
const char* temporary_file(const char* text);

static const double kNaN = NAN;
static const double kInf = INFINITY;
#define DEG (3.14159265358979323846 / 180.0)

/* A posture in front of the robot, away from singularities and limits. */
static const double kPosture[6] = {10 * DEG, 60 * DEG, 70 * DEG, 5 * DEG, 40 * DEG, 15 * DEG};

/* The plant's and the identification's tests (test_capi_plant.c). */
void test_plant(jc_plant* plant);
void test_plant_watchdog(jc_plant* plant);
void test_identification(jc_robot* robot, jc_robot* bare);

#endif
