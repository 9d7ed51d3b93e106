/*
 * Bad input across the C ABI, from C through libabut: each call fails with its status and a
 * message naming the item, nothing crashes, and nothing leaks (.ci/bindings runs this under
 * valgrind). Exits non-zero on the first surprise.
 *
 *   cc -std=c11 -Wall -Wextra -Werror -Iinclude capi/tests/bad_input.c -Ltarget/release -labut -o bad_input
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "abut.h"

static int failures = 0;

/* `s` must be `want` and the thread's last error must contain `word`. */
static void expect(AbutStatus s, AbutStatus want, const char *word, const char *what) {
  char msg[1024];
  abut_last_error((uint8_t *)msg, sizeof msg, NULL);
  if (s != want || !strstr(msg, word)) {
    fprintf(stderr, "FAIL %s: status %d (want %d), message '%s' (want '%s')\n", what, (int)s,
            (int)want, msg, word);
    failures++;
  } else {
    printf("ok   %-34s %s\n", what, msg);
  }
}

int main(void) {
  double x[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, 0.001}};
  double m[4] = {1, 1, 1, 0.1};
  uint32_t tri[3] = {0, 1, 2}, slave[1] = {3}, id = 0, surface = 0, set = 0, pair = 0;
  AbutModel *model = NULL, *freed = NULL;
  AbutDevice *device = NULL;
  AbutContact *contact = NULL;

  expect(abut_model_new(3, NULL), ABUT_STATUS_NULL_POINTER, "out", "null out");
  expect(abut_model_new(5, &model), ABUT_STATUS_BAD_VALUE, "dim = 5", "dimension");
  expect(abut_model_add_nodes(NULL, &x[0][0], m, 4, NULL), ABUT_STATUS_NULL_POINTER,
         "model handle is null", "null handle");
  abut_model_new(3, &freed);
  abut_model_free(freed);
  expect(abut_model_add_nodes(freed, &x[0][0], m, 4, NULL), ABUT_STATUS_BAD_HANDLE, "not live",
         "used after free");
  expect(abut_model_free(freed), ABUT_STATUS_BAD_HANDLE, "not live", "freed twice");

  abut_model_new(3, &model);
  double bad[3] = {0, NAN, 0}, bad_mass[1] = {1};
  expect(abut_model_add_nodes(model, bad, bad_mass, 1, NULL), ABUT_STATUS_BAD_VALUE,
         "coordinate 1 is not finite", "NaN coordinate");
  expect(abut_model_add_nodes(model, &x[0][0], NULL, 4, NULL), ABUT_STATUS_NULL_POINTER,
         "masses", "null masses");
  if (abut_model_add_nodes(model, &x[0][0], m, 4, NULL) != ABUT_STATUS_OK) return 1;
  uint32_t far[3] = {0, 1, 7};
  expect(abut_model_add_surface(model, ABUT_FACET_KIND_TRIANGLES, far, 1, &id),
         ABUT_STATUS_OUT_OF_RANGE, "index 7", "node id out of range");
  expect(abut_model_add_surface(model, 9, tri, 1, &id), ABUT_STATUS_BAD_VALUE, "AbutFacetKind",
         "unknown facet kind");
  abut_model_add_surface(model, ABUT_FACET_KIND_TRIANGLES, tri, 1, &surface);
  abut_model_add_node_set(model, slave, 1, NULL, &set);
  expect(abut_model_add_pair(model, set, 5, NULL, &pair), ABUT_STATUS_OUT_OF_RANGE, "5",
         "surface id out of range");
  AbutPairOptions o;
  abut_pair_options_default(&o);
  o.damping = -1;
  expect(abut_model_add_pair(model, set, surface, &o, &pair), ABUT_STATUS_BAD_VALUE, "damping",
         "negative damping");
  abut_model_add_pair(model, set, surface, NULL, &pair);

  abut_device_new(ABUT_DEVICE_KIND_CPU, 0, NULL, &device);
  expect(abut_contact_new(device, (AbutModel *)device, &contact), ABUT_STATUS_BAD_HANDLE,
         "not a model", "wrong kind of handle");
  abut_contact_new(device, model, &contact);
  double v[4][3] = {{0}}, f[4][3];
  expect(abut_contact_penalty_step(contact, &x[0][0], &v[0][0], 3, 1e-4, &f[0][0], 0),
         ABUT_STATUS_LENGTH, "expected 4 entries, got 3", "wrong length");
  v[2][1] = NAN;
  expect(abut_contact_penalty_step(contact, &x[0][0], &v[0][0], 4, 1e-4, &f[0][0], 0),
         ABUT_STATUS_BAD_VALUE, "NaN", "NaN velocity");
  v[2][1] = 0;
  expect(abut_contact_penalty_step(contact, &x[0][0], &v[0][0], 4, -1.0, &f[0][0], 0),
         ABUT_STATUS_BAD_VALUE, "dt", "negative increment");
  expect(abut_contact_penalty_step(contact, &x[0][0], &v[0][0], 4, 1e-4, NULL, 0),
         ABUT_STATUS_NULL_POINTER, "forces", "null forces");
  if (abut_contact_penalty_step(contact, &x[0][0], &v[0][0], 4, 1e-4, &f[0][0], 0)) return 1;
  size_t len = 0;
  expect(abut_contact_output_len(contact, ABUT_PAIR_KIND_MESHED, 3, 0, &len),
         ABUT_STATUS_OUT_OF_RANGE, "pair 3", "pair id out of range");
  char msg[256];
  abut_contact_error(contact, (uint8_t *)msg, sizeof msg, &len);
  if (!strstr(msg, "pair 3")) {
    fprintf(stderr, "FAIL per-handle error: '%s'\n", msg);
    failures++;
  }
  abut_contact_free(contact);
  expect(abut_contact_free(contact), ABUT_STATUS_BAD_HANDLE, "not live", "contact freed twice");
  abut_device_free(device);
  abut_model_free(model);
  if (failures) fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
