/*
 * lesion.c - a lesion's effect on the gel support (palp.h, docs/haptics.md).
 *
 * Why a weighted column: the real-time model has no interior, so a stiff inclusion
 * can only act through the gel support under the surface. Under a fingertip the
 * gel's strain is concentrated near the surface and falls off with depth as the
 * vertical stress of a uniformly loaded circle on a half-space (Boussinesq):
 *   sigma_z(z) / p = 1 - z^3 / (c^2 + z^2)^{3/2},
 * so a layer at depth z contributes compliance in proportion to sigma_z(z) / E(z).
 * Integrating along the column from the surface towards the centre, a lesion of
 * stiffness ratio s cutting the column over [z1, z2] scales the support stiffness by
 *   k_i / k = C0 / (C0 - (1 - q) C(z1, z2)),
 * q the chord's compliance relative to the gel's. A stiff lesion under the fingertip is
 * pushed into by the column above it: in series, q = 1/s (against the level-3 FE, with
 * the hinges' share, within 2.4 points of its gain; docs/haptics.md). A soft cyst is not:
 * the gel around it carries the load, and it strains as Eshelby's sphere in an
 * incompressible matrix does, q = 1 / (1 + beta (s - 1)), beta = 0.4 (not fitted). The
 * series sum (q = 5 for a 0.2x cyst) softened the breast-tissue fingertip over a cyst
 * 15-21% where the level-3 FE softens it 4.0-5.5%; Eshelby's q (1.47), with the hinges'
 * gel part seeing the cyst too (world.c build_hinges), gives 4.5-5.9%.
 * The primitive is closed form: S(z) = int_0^z sigma_z / p dz
 *   = z - sqrt(c^2 + z^2) - c^2 / sqrt(c^2 + z^2) + 2 c   [m],  S(inf) = 2 c.
 */
#include <math.h>

#include "palp.h"
#include "vec3.h"

static double S(double z, double c) {
  const double q = sqrt(c * c + z * z);
  return z - q - c * c / q + 2.0 * c;
}

double palp_lesion_support_scale(const palp_lesion *les, int count, palp_vec3 x, palp_vec3 n, double length) {
  return palp_support_column_scale(les, count, x, n, length, length);
}

double palp_support_column_scale(const palp_lesion *les, int count, palp_vec3 x, palp_vec3 n, double length,
                                 double full) {
  const double c = PALP_LESION_CONTACT_SCALE;
  if (!(length > 0.0) || !(full > 0.0)) return 1.0;
  const double C0 = S(length, c);
  double C = C0;
  /* Each lesion's chord [z1, z2] on the column and its compliance ratio q. */
  double z1s[PALP_MAX_LESIONS], z2s[PALP_MAX_LESIONS], qs[PALP_MAX_LESIONS];
  int nc = 0, overlap = 0;
  for (int l = 0; l < count && l < PALP_MAX_LESIONS; ++l) {
    /* column p(z) = x - z n, z in [0, length]; chord inside |p - centre| <= a */
    const palp_vec3 d = v3_sub(x, les[l].center);
    const double a = les[l].radius;
    const double b = -v3_dot(d, n), cc = v3_dot(d, d) - a * a; /* z^2 + 2 b z + cc = 0 */
    const double disc = b * b - cc;
    if (!(disc > 0.0)) continue;
    double z1 = -b - sqrt(disc), z2 = -b + sqrt(disc);
    z1 = fmax(z1, 0.0), z2 = fmin(z2, length);
    if (!(z2 > z1)) continue;
    const double s = les[l].stiffness_ratio;
    for (int k = 0; k < nc; ++k) overlap |= z1 < z2s[k] && z1s[k] < z2;
    z1s[nc] = z1, z2s[nc] = z2, qs[nc] = s >= 1.0 ? 1.0 / s : 1.0 / (1.0 + PALP_LESION_SOFT_BETA * (s - 1.0));
    nc++;
  }
  if (!overlap) {
    for (int k = 0; k < nc; ++k) C -= (1.0 - qs[k]) * (S(z2s[k], c) - S(z1s[k], c));
  } else {
    /* Overlapping chords (a harder core inside a mass, a lesion listed twice) are one piece of
     * tissue: each was subtracted in full, so the overlap counted twice, C went negative and the
     * floor below made the support 1000x stiffer (session 82's review: 2.382 for one lesion,
     * 1000 for the same listed twice). On each stretch between the chords' ends the stiffest
     * lesion covering it (the smallest q) stands for the tissue there. */
    double zb[2 * PALP_MAX_LESIONS];
    int nb = 0;
    for (int k = 0; k < nc; ++k) zb[nb++] = z1s[k], zb[nb++] = z2s[k];
    for (int i = 1; i < nb; ++i) /* insertion sort: at most 16 ends */
      for (int j = i; j > 0 && zb[j] < zb[j - 1]; --j) {
        const double t = zb[j];
        zb[j] = zb[j - 1], zb[j - 1] = t;
      }
    for (int i = 0; i + 1 < nb; ++i) {
      const double lo = zb[i], hi = zb[i + 1];
      if (!(hi > lo)) continue;
      double q = -1.0;
      for (int k = 0; k < nc; ++k)
        if (z1s[k] <= lo && z2s[k] >= hi && (q < 0.0 || qs[k] < q)) q = qs[k];
      if (q >= 0.0) C -= (1.0 - q) * (S(hi, c) - S(lo, c));
    }
  }
  /* With the chords merged C >= q C0 > 0 for the smallest q (>= 1e-6: the scene's bound on
   * stiffness_ratio); q < 1 / (1 - beta) = 1.67 for any cyst. The floor only acts for a lesion
   * over 1000x the gel's stiffness covering nearly the whole column.
   * A shorter column than the full one (the base cuts it, world.c) is stiffer by
   * S(full) / S(length); with equal lengths that factor is exactly 1, as before. */
  const double base = full == length ? 1.0 : S(full, c) / C0;
  return base * (C0 / fmax(C, 1e-3 * C0));
}
