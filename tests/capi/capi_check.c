/* The check counters and helpers of capi_check.h. */
#define _POSIX_C_SOURCE 200809L

#include "capi_check.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int checks = 0;
int failures = 0;

void expect_status(jc_status expected, const char* fragment, jc_status got, const char* call, const char* file,
                   int line) {
  const char* message = jc_last_error();
  char function[64] = {0};
  size_t name_length = strcspn(call, "(");
  ++checks;
  if (name_length >= sizeof function) name_length = sizeof function - 1;
  memcpy(function, call, name_length);
  if (got != expected) {
    ++failures;
    fprintf(stderr, "%s:%d: %s returned %s, expected %s; last error: %s\n", file, line, call, jc_status_name(got),
            jc_status_name(expected), message);
    return;
  }
  if (expected == JC_OK) {
    if (message[0] != '\0') {
      ++failures;
      fprintf(stderr, "%s:%d: %s succeeded but left the message '%s'\n", file, line, call, message);
    }
    return;
  }
  if (strncmp(message, function, strlen(function)) != 0 || strstr(message, fragment) == NULL) {
    ++failures;
    fprintf(stderr, "%s:%d: %s: message '%s' should start with '%s' and contain '%s'\n", file, line, call, message,
            function, fragment);
  }
}

int same_bits(const double* a, const double* b, size_t count) { return memcmp(a, b, count * sizeof *a) == 0; }

double max_abs_difference(const double* a, const double* b, size_t count) {
  double worst = 0.0;
  size_t i;
  for (i = 0; i < count; ++i) {
    const double d = fabs(a[i] - b[i]);
    if (d > worst) worst = d;
  }
  return worst;
}

const char* temporary_file(const char* text) {
  static char path[64];
  int fd;
  FILE* file;
  strcpy(path, "/tmp/jointcomp_capi_XXXXXX");
  fd = mkstemp(path);
  if (fd < 0) return NULL;
  file = fdopen(fd, "w");
  fputs(text, file);
  fclose(file);
  return path;
}
