/*
 * device_variants.c - device drivers for test_inputs.c's loader checks (client/input_device.c),
 * as a shared object like a real driver. ARG chooses the entry points handed back:
 *   haptic     read_position + write_force + close, no poll (a haptic device: client/input.h)
 *   read-only  read_position + close: neither a haptic device nor a force-driven source
 * palp_test_driver_closed counts close() calls; the test reads it through a handle of its own.
 */
#include <stdlib.h>
#include <string.h>

#include "input.h"

int palp_test_driver_closed;

static int v_read(void *ctx, double t, palp_vec3 *x) {
  (void)ctx;
  *x = (palp_vec3){0, 0, 0.05 + 0.001 * t};
  return 1;
}

static void v_write(void *ctx, palp_vec3 f, unsigned flags) {
  (void)ctx, (void)f, (void)flags;
}

static void v_close(void *ctx) {
  free(ctx);
  palp_test_driver_closed++;
}

int palp_cli_device_driver(const char *arg, palp_cli_input *out);
int palp_cli_device_driver(const char *arg, palp_cli_input *out) {
  void *ctx = malloc(64);
  if (!ctx) return PALP_ENOMEM;
  if (!strcmp(arg, "haptic")) {
    *out = (palp_cli_input){.name = "haptic variant", .ctx = ctx, .read_position = v_read, .write_force = v_write,
                            .close = v_close, .finger_radius = 0.008};
    return 0;
  }
  if (!strcmp(arg, "read-only")) {
    *out = (palp_cli_input){.name = "read-only variant", .ctx = ctx, .read_position = v_read, .close = v_close};
    return 0;
  }
  free(ctx);
  return PALP_EINVAL;
}
