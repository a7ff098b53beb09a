/*
 * contact.c - the paper's four force distributions as per-vertex weights.
 *
 * A distribution turns one force vector into vertex forces f_i = w_i F with
 * sum w_i = 1, so the total load is the same for every distribution. Patches are
 * the free dome vertices within the patch radius r = sqrt(A / pi) of the centre
 * vertex; weights carry the vertex's lumped area so that "uniform" means uniform
 * pressure and not uniform force per vertex, which would depend on the mesh.
 * Fixed (rim) vertices never carry load: it would go straight into the ground.
 */
#include <math.h>
#include <stdlib.h>

#include "palp.h"
#include "vec3.h"

palp_contact_def palp_contact_default_def(palp_distribution d, palp_vec3 center) {
  palp_contact_def c = {.distribution = d,
                        .center = center,
                        .patch_area = 5.2e-4,
                        .sigma_fraction = 0.5,
                        .offset_fraction = 0.5,
                        .offset_dir = {1.0, 0.0, 0.0}};
  return c;
}

static int nearest_free(const palp_mesh *m, const palp_vec3 *pos, palp_vec3 p) {
  int best = -1;
  double bd = INFINITY;
  for (int i = 0; i < m->vertex_count; ++i) {
    if (m->fixed[i]) continue;
    palp_vec3 d = v3_sub(pos[i], p);
    const double dd = v3_dot(d, d);
    if (dd < bd) bd = dd, best = i;
  }
  return best;
}

int palp_contact_weights(const palp_mesh *m, const palp_vec3 *pos, const palp_contact_def *def, int *vertices,
                         double *weights, int cap) {
  if (!m || !pos || !def || !vertices || !weights || cap < 1) return PALP_EINVAL;
  if (!v3_isfinite(def->center)) return PALP_EINVAL;
  const int c = nearest_free(m, pos, def->center);
  if (c < 0) return PALP_EINVAL;
  if (def->distribution == PALP_DIST_SINGLE) {
    vertices[0] = c;
    weights[0] = 1.0;
    return 1;
  }
  if (def->distribution < PALP_DIST_SINGLE || def->distribution > PALP_DIST_GAUSSIAN_OFFSET) return PALP_EINVAL;
  if (!(def->patch_area > 0.0) || !isfinite(def->patch_area)) return PALP_EINVAL;
  const double r = sqrt(def->patch_area / PALP_PI); /* patch radius [m] */
  const palp_vec3 pc = pos[c];

  /* Gaussian peak: the centre vertex (III) or the patch vertex nearest to a point
   * offset along the tangent plane (IV, the distal pad of an inclined finger). */
  palp_vec3 peak = pc;
  if (def->distribution == PALP_DIST_GAUSSIAN_OFFSET) {
    palp_vec3 nrm = v3_scale(pc, 1.0 / fmax(v3_len(pc), 1e-300));
    palp_vec3 t = v3_sub(def->offset_dir, v3_scale(nrm, v3_dot(def->offset_dir, nrm)));
    if (v3_len(t) < 1e-9) { /* offset along the normal: fall back to the x then y axis */
      t = v3_sub(v3(1, 0, 0), v3_scale(nrm, nrm.x));
      if (v3_len(t) < 1e-9) t = v3_sub(v3(0, 1, 0), v3_scale(nrm, nrm.y));
    }
    t = v3_scale(t, 1.0 / v3_len(t));
    palp_vec3 target = v3_add(pc, v3_scale(t, def->offset_fraction * r));
    int best = c;
    double bd = INFINITY;
    for (int i = 0; i < m->vertex_count; ++i) {
      if (m->fixed[i]) continue;
      if (v3_len(v3_sub(pos[i], pc)) > r) continue;
      const double d = v3_len(v3_sub(pos[i], target));
      if (d < bd) bd = d, best = i;
    }
    peak = pos[best];
  }
  const double sigma = def->sigma_fraction * r; /* Gaussian width [m] */
  if (def->distribution != PALP_DIST_UNIFORM && !(sigma > 0.0)) return PALP_EINVAL;

  int n = 0;
  double sum = 0.0;
  for (int i = 0; i < m->vertex_count; ++i) {
    if (m->fixed[i]) continue;
    if (v3_len(v3_sub(pos[i], pc)) > r) continue;
    if (n >= cap) return PALP_ERANGE;
    double w = m->vertex_area[i];
    if (def->distribution != PALP_DIST_UNIFORM) {
      const double d = v3_len(v3_sub(pos[i], peak));
      w *= exp(-0.5 * d * d / (sigma * sigma));
    }
    vertices[n] = i;
    weights[n] = w;
    sum += w;
    ++n;
  }
  if (n == 0 || !(sum > 0.0)) return PALP_EINVAL;
  for (int k = 0; k < n; ++k) weights[k] /= sum;
  return n;
}
