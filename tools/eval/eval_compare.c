/*
 * eval_compare.c - the paired data sets of Tables V and VI and their statistics.
 *
 * Displacement (Table V): the magnitude |u| = sqrt(ux^2 + uy^2 + uz^2) of every
 * free vertex at every frame. Magnitude rather than components because the paper
 * reports one displacement per vertex in cm, and because components of vertices
 * far from the load are mostly zero in both models, which would pad the data
 * with trivially agreeing pairs. The clamped rim is left out for the same reason:
 * it is a boundary condition both models share, not a result.
 * Force (Table VI): the magnitude of the feedback at each contact vertex present
 * in both records, every frame.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval.h"

const palp_eval_paper_row palp_eval_paper[2][4] = {
    /* Table V: vertex displacement, RMSE and SD in cm */
    {{0.17, 2.37, 0.12, 0.27, 95.2}, {0.21, 1.52, 0.36, 0.29, 95.0}, {0.26, 1.69, 0.32, 0.32, 95.3},
     {0.32, 0.96, 0.48, 0.33, 96.5}},
    /* Table VI: force feedback, RMSE and SD in N; Distr. II's F is printed "12"
     * (most likely 1.2 with the point lost; kept as printed). */
    {{0.05, 0.12, 0.86, 0.01, 98.6}, {0.12, 12.0, 0.31, 0.12, 96.1}, {0.15, 1.93, 0.29, 0.21, 95.2},
     {0.16, 2.02, 0.21, 0.25, 95.1}},
};

static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

void palp_eval_pairs_destroy(palp_eval_pairs *p) {
  if (!p) return;
  free(p->disp_rt);
  free(p->disp_ref);
  free(p->force_rt);
  free(p->force_ref);
  free(p->disp_frame);
  free(p->disp_vertex);
  free(p->force_frame);
  free(p->force_vertex);
  memset(p, 0, sizeof *p);
}

int palp_eval_pairs_build(const palp_eval_record *rt, const palp_eval_record *ref, palp_eval_pairs *out,
                          char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  if (rt->frames != ref->frames || rt->vertex_count != ref->vertex_count) {
    snprintf(err, errlen, "records differ in shape: real-time %d frames x %d vertices, reference %d x %d",
             rt->frames, rt->vertex_count, ref->frames, ref->vertex_count);
    return PALP_EINVAL;
  }
  for (int f = 0; f < rt->frames; ++f)
    if (fabs(rt->time[f] - ref->time[f]) > 1e-9 * fmax(1.0, fabs(rt->time[f]))) {
      snprintf(err, errlen, "frame %d is at %.9g s in the real-time record but %.9g s in the reference", f,
               rt->time[f], ref->time[f]);
      return PALP_EINVAL;
    }
  const int nv = rt->vertex_count, nf = rt->frames;
  int nfree = 0;
  for (int i = 0; i < nv; ++i) nfree += !rt->fixed[i];
  /* Pair contact vertices by (contact, vertex); both models load the points
   * palp_contact_weights picks on the real-time mesh, so the sets should agree. */
  int *match = malloc(sizeof(int) * (size_t)(rt->contact_vertex_count + 1));
  if (!match) return PALP_ENOMEM;
  int nmatch = 0;
  for (int i = 0; i < rt->contact_vertex_count; ++i) {
    match[i] = -1;
    for (int j = 0; j < ref->contact_vertex_count; ++j)
      if (ref->contact_vertex[j] == rt->contact_vertex[i] && ref->contact_of[j] == rt->contact_of[i]) {
        match[i] = j;
        ++nmatch;
        break;
      }
  }
  out->n_disp = (size_t)nfree * (size_t)nf;
  out->n_force = (size_t)nmatch * (size_t)nf;
  out->force_vertices = nmatch;
  out->disp_rt = malloc(sizeof(double) * (out->n_disp + 1));
  out->disp_ref = malloc(sizeof(double) * (out->n_disp + 1));
  out->force_rt = malloc(sizeof(double) * (out->n_force + 1));
  out->force_ref = malloc(sizeof(double) * (out->n_force + 1));
  out->disp_frame = malloc(sizeof(int) * (out->n_disp + 1));
  out->disp_vertex = malloc(sizeof(int) * (out->n_disp + 1));
  out->force_frame = malloc(sizeof(int) * (out->n_force + 1));
  out->force_vertex = malloc(sizeof(int) * (out->n_force + 1));
  if (!out->disp_rt || !out->disp_ref || !out->force_rt || !out->force_ref || !out->disp_frame || !out->disp_vertex ||
      !out->force_frame || !out->force_vertex) {
    free(match);
    palp_eval_pairs_destroy(out);
    return PALP_ENOMEM;
  }
  size_t k = 0, q = 0;
  for (int f = 0; f < nf; ++f) {
    const palp_vec3 *a = rt->disp + (size_t)f * (size_t)nv, *b = ref->disp + (size_t)f * (size_t)nv;
    for (int i = 0; i < nv; ++i)
      if (!rt->fixed[i]) {
        out->disp_rt[k] = norm3(a[i]);
        out->disp_ref[k] = norm3(b[i]);
        out->disp_frame[k] = f;
        out->disp_vertex[k] = i;
        ++k;
      }
    for (int i = 0; i < rt->contact_vertex_count; ++i)
      if (match[i] >= 0) {
        out->force_rt[q] = norm3(rt->feedback[(size_t)f * (size_t)rt->contact_vertex_count + (size_t)i]);
        out->force_ref[q] =
            norm3(ref->feedback[(size_t)f * (size_t)ref->contact_vertex_count + (size_t)match[i]]);
        out->force_frame[q] = f;
        out->force_vertex[q] = rt->contact_vertex[i];
        ++q;
      }
  }
  free(match);
  return PALP_OK;
}

int palp_eval_row_compute(const double *a, const double *b, size_t n, palp_eval_row *out) {
  palp_eval_row r;
  memset(&r, 0, sizeof r);
  r.n = n;
  int rc = palp_stats_rmse(a, b, n, &r.rmse);
  if (!rc) rc = palp_stats_anova_two(a, b, n, &r.anova);
  if (!rc) rc = palp_stats_bland_altman(a, b, n, &r.ba);
  if (rc) return rc;
  r.meets = palp_stats_meets_paper_criteria(&r.anova, &r.ba);
  for (size_t i = 0; i < n; ++i) {
    r.max_abs_diff = fmax(r.max_abs_diff, fabs(a[i] - b[i]));
    r.ref_peak = fmax(r.ref_peak, b[i]);
    r.rt_peak = fmax(r.rt_peak, a[i]);
  }
  *out = r;
  return PALP_OK;
}
