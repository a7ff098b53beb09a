/* fuzz_playout.c - a finger's device samples as the network and the session hand them to the
 * server's playout (server/playout.h): stamps, arrivals and times asked for anywhere in int64
 * (the clock's ends, a station clock that leaps either way, gaps of any length), points anywhere
 * in a 6.5 m cube, fingers started below the surface (palp_srv_playout_start) and lifted
 * (palp_srv_playout_clear), under a world step from none to a day.
 *
 * Whatever comes, each point played is finite and no farther from the dome's centre than the
 * farthest sample taken or started, or the reach (a late turn is bridged within it): the world
 * is never handed a device the station did not send, however its stamps lie (session 86 added
 * the catch-up of gaps, whose arithmetic meets these stamps first). Built with
 * -fsanitize=undefined in a scratch tree, any overflow is a finding too.
 *
 * Input: byte 0 picks the world's step (0: none; else b x 0.1 ms, 255: a day); then records,
 * each a tag byte: tag % 4 = 0 a push (source, arrival: int64 each; the point: 3 x int16 [0.1
 * mm]), 1 a time asked for (int64), 2 a start (source int64, point), 3 a clear. The int64s are
 * little-endian; a record cut short ends the input. */
#include <math.h>

#include "fuzz_util.h"
#include "playout.h"

static int64_t i64(const uint8_t *p) {
  uint64_t v = 0;
  for (int k = 7; k >= 0; k--) v = v << 8 | p[k];
  return (int64_t)v;
}
static double i16(const uint8_t *p) { return (double)(int16_t)(p[0] | p[1] << 8) * 1e-4; } /* [m] */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  const double reach = 0.4; /* [m]: 10 radii of the dome, as the session's */
  const double step = data[0] == 255 ? 86400.0 : data[0] * 1e-4;
  palp_srv_playout p;
  palp_srv_playout_init(&p, reach, step);
  double farthest = 0; /* |x| of the farthest point taken or started [m] */
  const uint8_t *q = data + 1;
  size_t left = size - 1;
  for (int records = 0; left > 0 && records < 4096; records++) {
    const int tag = *q++ % 4;
    left--;
    if (tag == 0 || tag == 2) {
      const size_t need = tag == 0 ? 22 : 14;
      if (left < need) break;
      const int64_t src = i64(q), recv = tag == 0 ? i64(q + 8) : 0;
      const uint8_t *xp = q + (tag == 0 ? 16 : 8);
      const palp_vec3 x = {i16(xp), i16(xp + 2), i16(xp + 4)};
      q += need, left -= need;
      const int rc = tag == 0 ? palp_srv_playout_push(&p, src, recv, x, (uint64_t)records)
                              : palp_srv_playout_start(&p, src, x, (uint64_t)records);
      if (rc == 1 || (tag == 2 && rc == PALP_OK)) farthest = fmax(farthest, sqrt(x.x * x.x + x.y * x.y + x.z * x.z));
    } else if (tag == 1) {
      if (left < 8) break;
      const int64_t now = i64(q);
      q += 8, left -= 8;
      palp_vec3 x = {NAN, NAN, NAN};
      int64_t src = 0;
      uint64_t seq = 0;
      if (palp_srv_playout_at(&p, now, &x, &src, &seq) == 1) {
        const double r = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
        if (!isfinite(r) || r > fmax(farthest, reach) * (1 + 1e-12)) abort();
      }
    } else {
      palp_srv_playout_clear(&p);
    }
  }
  return 0;
}
