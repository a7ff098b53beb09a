/* fuzz_local_model.c - what a station's hand feels: local contact models off the network
 * (any bytes in every field: NaN, infinities, 1e300, a stiffness that pushes the hand on, a
 * normal against the force, times from the past or far ahead, a period of 0) through the
 * station's check (palp_cli_local_model_from_wire) and, when accepted, into its 1 kHz core
 * (palp_cli_haptic_core_tick: latency compensation, hold, crossfade, passivity controller),
 * between device ticks whose position, lift and clock the input also chooses.
 *
 * Whatever arrives, every tick's force is finite and within the safe force (issue 11: "never
 * exceeds a safe force"), and the renderer says so when it limited it: the property the
 * station's hardware relies on when a server is buggy or, on a plain domain, a peer is not.
 *
 * Input: byte 0 picks the safe force (0.5-20.5 N) and byte 1 the core's switches (latency
 * compensation, passivity controller); then records, each a tag byte: tag & 1 a model (the
 * next sizeof(palp_LocalModel) bytes, raw, into the wire struct: it has no pointers; its boolean
 * takes the byte's low bit, as the wire allows only 0 and 1), else a
 * device tick: 3 x int16 position [0.05 mm], 1 byte lift / touch, 1 byte clock step [0.1 ms],
 * and the age the model arrived with. */
#include <math.h>
#include <stddef.h>

#include "fuzz_util.h"
#include "haptic_loop.h"

static int16_t i16(const uint8_t *p) { return (int16_t)(p[0] | p[1] << 8); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 2) return 0;
  palp_haptic_def render = palp_haptic_default_def();
  render.max_force = 0.5 + data[0] * (20.0 / 255.0); /* [N] */
  palp_cli_haptic_core core;
  if (palp_cli_haptic_core_init(&core, &render, 250.0, data[1] & 1, 0.0, 0.2) != 0) abort();
  core.passivity = (data[1] >> 1) & 1 ? 0 : 1;
  const uint8_t *p = data + 2;
  size_t left = size - 2;
  double t = 0.0;     /* station time [s] */
  palp_local_model pending;
  int have_pending = 0;
  double pending_age = -1.0;
  for (int ticks = 0; left > 0 && ticks < 4096;) {
    const uint8_t tag = *p++;
    left--;
    if (tag & 1) {
      palp_LocalModel w;
      if (left < sizeof w) break;
      memcpy(&w, p, sizeof w);
      /* a boolean on the wire is one byte, 0 or 1 (Cyclone's deserializer refuses any other
       * value before a reader sees the sample): any other bit pattern in a C bool is not a
       * sample a station can get, and reading it is undefined */
      uint8_t b;
      memcpy(&b, p + offsetof(palp_LocalModel, in_contact), 1);
      w.in_contact = b & 1;
      p += sizeof w, left -= sizeof w;
      palp_local_model m;
      if (palp_cli_local_model_from_wire(&w, &m) == 0) {
        pending = m;
        have_pending = 1;
        pending_age = (tag >> 1) * 1e-3 - 0.01; /* -10 ms (unknown) .. 117 ms */
      }
      continue;
    }
    if (left < 8) break;
    const palp_vec3 x = {i16(p) * 5e-5, i16(p + 2) * 5e-5, i16(p + 4) * 5e-5}; /* +-1.6 m */
    const int on = p[6] & 1;
    t += p[7] * 1e-4; /* 0 .. 25.5 ms, 0 included: two ticks at one time */
    p += 8, left -= 8;
    palp_haptic_out out;
    palp_vec3 xr;
    palp_cli_haptic_core_tick(&core, on, x, t, have_pending ? &pending : NULL, pending_age, &out, &xr);
    have_pending = 0;
    ticks++;
    const double f = sqrt(out.force.x * out.force.x + out.force.y * out.force.y + out.force.z * out.force.z);
    if (!isfinite(f) || f > render.max_force * (1.0 + 1e-9)) {
      fprintf(stderr, "tick %d: |F| = %g N against a safe force of %g N\n", ticks, f, render.max_force);
      abort();
    }
    /* a force the renderer had to cut is said (the station shows FORCE LIMITED) */
    if (out.requested > render.max_force * (1.0 + 1e-9) && !(out.flags & PALP_HAPTIC_LIMITED)) abort();
    if (!on && f != 0.0) abort(); /* a lifted finger feels nothing */
  }
  return 0;
}
