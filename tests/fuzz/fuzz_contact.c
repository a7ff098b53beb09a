/* fuzz_contact.c - what a station can send: a contact sample (any bytes in every field,
 * including NaN, infinities, 1e300 and out-of-range enums) through the server's
 * validation, and a catalogue entry (any counts and indices) through the client's check
 * and, when accepted, its rendering. Accepted contacts must be within the limits. */
#include <math.h>

#include "fuzz_util.h"
#include "validate.h"
#include "view.h"

static palp_vec3 rest[4] = {{0, 0, 0.04}, {0.04, 0, 0}, {0, 0.04, 0}, {-0.04, 0, 0}};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  palp_Contact c;
  memset(&c, 0, sizeof c);
  memcpy(&c, data, size < sizeof c ? size : sizeof c);
  const palp_srv_limits lim = {.session_id = c.session_id % 3, .max_force = 20, .absurd_force = 1000,
                               .force_policy = size % 2 ? PALP_SRV_FORCE_CLAMP : PALP_SRV_FORCE_REJECT,
                               .finger_radius_min = 0.002, .finger_radius_max = 0.03, .phantom_radius = 0.04,
                               .vertex_count = 4, .rest = rest};
  palp_srv_contact out;
  palp_srv_reject_reason why = PALP_SRV_REJ_COUNT;
  int v = palp_srv_validate_contact(&c, &lim, &out, &why);
  if (v == PALP_SRV_ACCEPT || v == PALP_SRV_CLAMPED) {
    const double f = sqrt(out.force.x * out.force.x + out.force.y * out.force.y + out.force.z * out.force.z);
    if (!(f <= lim.max_force * (1 + 1e-12)) || out.finger < 0 || out.finger >= PALP_SRV_MAX_FINGERS ||
        !isfinite(out.center.x) || !isfinite(out.center.y) || !isfinite(out.center.z))
      abort();
  } else if (v != PALP_SRV_REJECT || (unsigned)why >= PALP_SRV_REJ_COUNT) {
    abort();
  }

  /* The rest of the input as a catalogue entry: header fields, then vertices and indices. */
  if (size <= sizeof c + 16) return 0;
  const uint8_t *p = data + sizeof c;
  size_t left = size - sizeof c;
  palp_Phantom ph;
  memset(&ph, 0, sizeof ph);
  ph.radius = 0.04;
  ph.top_vertex = (int32_t)(p[0] | p[1] << 8) - 100;
  ph.dome_triangle_count = (int32_t)(p[2] | p[3] << 8) - 100;
  const uint32_t nv = p[4] % 64, nt = p[5] % 128;
  p += 16, left -= 16;
  palp_Vec3 *v3 = calloc(nv ? nv : 1, sizeof *v3);
  int32_t *tri = calloc(nt ? nt : 1, sizeof *tri);
  palp_Vec3 *pos = calloc(nv ? nv : 1, sizeof *pos);
  for (uint32_t i = 0; i < nv && left >= 2; i++, p += 2, left -= 2)
    v3[i] = pos[i] = (palp_Vec3){(p[0] - 128) * 3e-4, (p[1] - 128) * 3e-4, (p[0] ^ p[1]) * 1e-4};
  for (uint32_t i = 0; i < nt && left >= 1; i++, p++, left--) tri[i] = (int32_t)p[0] - 8;
  ph.rest = (dds_sequence_palp_Vec3){nv, nv, v3, false};
  ph.triangles = (dds_sequence_long){nt, nt, tri, false};
  char err[256];
  if (palp_cli_phantom_check(&ph, err, sizeof err) == 0) {
    palp_Deformation d;
    memset(&d, 0, sizeof d);
    d.positions = (dds_sequence_palp_Vec3){nv, nv, pos, false};
    if (palp_cli_deformation_check(&ph, &d) == 0) {
      palp_cli_view view;
      if (palp_cli_view_init(&view, &ph, 8, 4, 0) == 0) {
        FILE *devnull = fopen("/dev/null", "w");
        palp_cli_view_render(&view, &d, devnull, 1);
        fclose(devnull);
        palp_cli_view_free(&view);
      }
      palp_cli_view_svg(&ph, &d, "fuzz", "/dev/null");
    }
  }
  free(v3);
  free(tri);
  free(pos);
  return 0;
}
