/*
 * The cost of one penalty increment called through libabut from C: the model of
 * examples/overhead.rs (the Rust reference), timed the same way. benches/bindings_overhead.py
 * runs both and the Python binding and writes the table.
 *
 *   cc -std=c11 -O2 -Iinclude examples/c/overhead.c -Ltarget/release -labut -lm -o overhead_c
 *   LD_LIBRARY_PATH=target/release ./overhead_c [cpu|vulkan|gl] <slaves> <increments>
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "abut.h"

static void check(AbutStatus s, const char *what) {
  if (s != ABUT_STATUS_OK) {
    char msg[1024];
    abut_last_error((uint8_t *)msg, sizeof msg, NULL);
    fprintf(stderr, "%s: %s\n", what, msg);
    exit(1);
  }
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
  const char *which = argc > 1 ? argv[1] : "cpu";
  size_t want = argc > 2 ? (size_t)atol(argv[2]) : 1000;
  int reps = argc > 3 ? atoi(argv[3]) : 10;
  size_t side = (size_t)llround(sqrt((double)want)), plate = side / 2 + 1;
  size_t np = (plate + 1) * (plate + 1), n = np + side * side;
  double *x = calloc(3 * n, sizeof *x), *v = calloc(3 * n, sizeof *v);
  double *f = calloc(3 * n, sizeof *f), *m = malloc(n * sizeof *m);
  uint32_t *quads = malloc(4 * plate * plate * sizeof *quads);
  uint32_t *slaves = malloc(side * side * sizeof *slaves);
  size_t k = 0;
  for (size_t j = 0; j <= plate; j++)
    for (size_t i = 0; i <= plate; i++, k++) {
      x[3 * k] = 2.0 * (double)i - 1.0, x[3 * k + 1] = 2.0 * (double)j - 1.0;
      x[3 * k + 2] = 0.0;
    }
  for (size_t j = 0; j < plate; j++)
    for (size_t i = 0; i < plate; i++) {
      uint32_t a = (uint32_t)(j * (plate + 1) + i), *q = quads + 4 * (j * plate + i);
      q[0] = a, q[1] = a + 1, q[2] = a + (uint32_t)plate + 2, q[3] = a + (uint32_t)plate + 1;
    }
  for (size_t j = 0; j < side; j++)
    for (size_t i = 0; i < side; i++, k++) {
      x[3 * k] = (double)i, x[3 * k + 1] = (double)j, x[3 * k + 2] = -0.01;
      slaves[k - np] = (uint32_t)k;
    }
  for (k = 0; k < n; k++) m[k] = 1.0;

  AbutDevice *device;
  if (!strcmp(which, "vulkan"))
    check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_VULKAN, NULL, &device), "device");
  else if (!strcmp(which, "gl"))
    check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_GL, NULL, &device), "device");
  else
    check(abut_device_new(ABUT_DEVICE_KIND_CPU, 0, NULL, &device), "device");
  AbutModel *model;
  uint32_t surface, set, pair;
  check(abut_model_new(3, &model), "model");
  check(abut_model_add_nodes(model, x, m, n, NULL), "nodes");
  check(abut_model_add_surface(model, ABUT_FACET_KIND_QUADS, quads, plate * plate, &surface),
        "plate");
  check(abut_model_add_node_set(model, slaves, side * side, NULL, &set), "slaves");
  AbutPairOptions o;
  check(abut_pair_options_default(&o), "options");
  o.friction = 1, o.mu = 0.3;
  check(abut_model_add_pair(model, set, surface, &o, &pair), "pair");
  AbutContact *contact;
  check(abut_contact_new(device, model, &contact), "contact");
  double first = 0, rest = 0;
  for (int r = 0; r <= reps; r++) {
    double t = now();
    check(abut_contact_penalty_step(contact, x, v, n, 1e-3, f, ABUT_FORCE_MODE_WRITE), "step");
    t = now() - t;
    if (r == 0) first = t;
    else rest += t;
  }
  printf("c %zu %.6e %.6e\n", side * side, first, rest / reps);
  abut_contact_free(contact);
  abut_model_free(model);
  abut_device_free(device);
  free(x), free(v), free(f), free(m), free(quads), free(slaves);
  return 0;
}
