/*
 * An explicit host loop in C calling abut once per increment through libabut.
 *
 * The model and loop of examples/host_loop.rs (the Rust reference): a sheet of 8 x 8 point
 * masses joined by springs, thrown onto a fixed plate of 4 x 4 quads; penalty contact with
 * Coulomb friction 0.3 and half of critical damping; 600 increments of 1e-4. The host sums
 * its own forces (springs, then gravity), abut adds the contact forces into the same array
 * (ABUT_FORCE_MODE_ADD), and the host takes a central-difference step. Every increment's
 * forces go to forces.bin when it is given (the Rust example's bytes, bit for bit).
 *
 *   cargo build --release -p abut-capi
 *   cc -std=c11 -O2 -ffp-contract=off -Iinclude examples/c/host_loop.c -Ltarget/release -labut -lm -o host_loop_c
 *   LD_LIBRARY_PATH=target/release ./host_loop_c [cpu|vulkan|gl|auto] [forces.bin]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "abut.h"

enum { PLATE = 4, SHEET = 8, STEPS = 600 };
static const double H = 0.1, KS = 200.0, G = 9.81, DT = 1e-4;

/* Prints the thread's last abut error and stops. */
static void check(AbutStatus s, const char *what) {
  if (s != ABUT_STATUS_OK) {
    char msg[1024];
    abut_last_error((uint8_t *)msg, sizeof msg, NULL);
    fprintf(stderr, "%s failed (status %d): %s\n", what, (int)s, msg);
    exit(1);
  }
}

int main(int argc, char **argv) {
  const char *which = argc > 1 ? argv[1] : "cpu";
  FILE *out = NULL;
  if (argc > 2 && !(out = fopen(argv[2], "wb"))) {
    perror(argv[2]);
    return 1;
  }

  enum { NP = (PLATE + 1) * (PLATE + 1), NS = SHEET * SHEET, N = NP + NS };
  enum { NSPRING = 2 * SHEET * (SHEET - 1) };
  static double x[N][3], v[N][3], f[N][3], fs[NSPRING][3], m[N];
  static uint32_t quads[PLATE * PLATE][4], sheet[NS], si[NSPRING], sj[NSPRING];
  int k = 0;
  for (int j = 0; j <= PLATE; j++)
    for (int i = 0; i <= PLATE; i++, k++) {
      x[k][0] = -1.0 + 0.5 * i;
      x[k][1] = -1.0 + 0.5 * j;
      x[k][2] = 0.0;
      m[k] = 1.0;
    }
  for (int j = 0; j < PLATE; j++)
    for (int i = 0; i < PLATE; i++) {
      uint32_t a = (uint32_t)(j * (PLATE + 1) + i);
      uint32_t *q = quads[j * PLATE + i];
      q[0] = a, q[1] = a + 1, q[2] = a + PLATE + 2, q[3] = a + PLATE + 1;
    }
  for (int j = 0; j < SHEET; j++)
    for (int i = 0; i < SHEET; i++, k++) {
      x[k][0] = H * i - 0.35;
      x[k][1] = H * j - 0.35;
      x[k][2] = 0.001;
      m[k] = 0.01;
      sheet[k - NP] = (uint32_t)k;
    }
  int s = 0;
  for (int j = 0; j < SHEET; j++)
    for (int i = 0; i < SHEET - 1; i++, s++)
      si[s] = NP + j * SHEET + i, sj[s] = NP + j * SHEET + i + 1;
  for (int j = 0; j < SHEET - 1; j++)
    for (int i = 0; i < SHEET; i++, s++)
      si[s] = NP + j * SHEET + i, sj[s] = NP + (j + 1) * SHEET + i;

  AbutDevice *device = NULL;
  if (!strcmp(which, "cpu"))
    check(abut_device_new(ABUT_DEVICE_KIND_CPU, 0, NULL, &device), "device");
  else if (!strcmp(which, "vulkan"))
    check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_VULKAN, NULL, &device), "device");
  else if (!strcmp(which, "gl"))
    check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_GL, NULL, &device), "device");
  else
    check(abut_device_new(ABUT_DEVICE_KIND_AUTO, 0, NULL, &device), "device");

  AbutModel *model = NULL;
  uint32_t plate, slaves, pair;
  check(abut_model_new(3, &model), "model");
  check(abut_model_add_nodes(model, &x[0][0], m, N, NULL), "nodes");
  check(abut_model_add_surface(model, ABUT_FACET_KIND_QUADS, &quads[0][0], PLATE * PLATE, &plate),
        "plate");
  check(abut_model_add_node_set(model, sheet, NS, NULL, &slaves), "sheet");
  AbutPairOptions options;
  check(abut_pair_options_default(&options), "options");
  options.friction = 1;
  options.mu = 0.3;
  options.damping = 0.5;
  check(abut_model_add_pair(model, slaves, plate, &options, &pair), "pair");
  AbutContact *contact = NULL;
  check(abut_contact_new(device, model, &contact), "contact");
  check(abut_model_free(model), "free model");

  for (k = NP; k < N; k++)
    v[k][0] = 1.0, v[k][1] = 0.25, v[k][2] = -0.2;
  int touching = 0;
  uint64_t most = 0;
  for (int step = 0; step < STEPS; step++) {
    memset(f, 0, sizeof f);
    for (s = 0; s < NSPRING; s++) {
      const double *a = x[si[s]], *b = x[sj[s]];
      double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      double c = KS * (l - H) / l;
      fs[s][0] = c * d[0], fs[s][1] = c * d[1], fs[s][2] = c * d[2];
    }
    for (s = 0; s < NSPRING; s++)
      for (int a = 0; a < 3; a++) f[si[s]][a] += fs[s][a];
    for (s = 0; s < NSPRING; s++)
      for (int a = 0; a < 3; a++) f[sj[s]][a] -= fs[s][a];
    for (k = NP; k < N; k++) f[k][2] -= m[k] * G;

    check(abut_contact_penalty_step(contact, &x[0][0], &v[0][0], N, DT, &f[0][0],
                                    ABUT_FORCE_MODE_ADD),
          "penalty step");
    AbutReport report;
    check(abut_contact_report(contact, &report), "report");
    touching += report.active > 0;
    if (report.active > most) most = report.active;
    if (out) fwrite(f, sizeof f, 1, out);

    for (k = NP; k < N; k++)
      for (int a = 0; a < 3; a++) {
        v[k][a] += DT * f[k][a] / m[k];
        x[k][a] += DT * v[k][a];
      }
  }
  double c[3] = {0, 0, 0};
  for (k = NP; k < N; k++)
    for (int a = 0; a < 3; a++) c[a] += x[k][a];
  char name[256];
  check(abut_device_describe(device, (uint8_t *)name, sizeof name, NULL), "describe");
  printf("c on %s: %d increments, in contact in %d, at most %llu nodes; sheet centre (%.6f, %.6f, %.6f)\n",
         name, STEPS, touching, (unsigned long long)most, c[0] / NS, c[1] / NS, c[2] / NS);
  check(abut_contact_free(contact), "free contact");
  check(abut_device_free(device), "free device");
  if (out) fclose(out);
  return 0;
}
