/*
 * eval_fem.c - the FEM reference (src/fem, palp_fem_run with its cache) as a
 * palp_eval_record, so both models are compared through one type.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval_fem.h"

int palp_eval_record_from_fem(const palp_fem_result *r, const palp_scene *s, palp_eval_record *out, char *err,
                              size_t errlen) {
  memset(out, 0, sizeof *out);
  palp_mesh mesh;
  int rc = palp_mesh_create(&s->world.mesh, &mesh);
  if (rc) {
    snprintf(err, errlen, "cannot build the real-time mesh: %s", palp_strerror(rc));
    return rc;
  }
  if (mesh.vertex_count != r->vertex_count) {
    snprintf(err, errlen, "the FEM result maps %d vertices, the scene's mesh has %d", r->vertex_count,
             mesh.vertex_count);
    palp_mesh_destroy(&mesh);
    return PALP_EINVAL;
  }
  const size_t nf = (size_t)r->frames, nv = (size_t)r->vertex_count, nc = (size_t)r->contact_vertex_count;
  out->frames = r->frames;
  out->vertex_count = r->vertex_count;
  out->top_vertex = r->top_vertex;
  out->contact_vertex_count = r->contact_vertex_count;
  out->wall_seconds = r->wall_seconds;
  out->time = malloc(sizeof(double) * nf);
  out->disp = malloc(sizeof(palp_vec3) * nf * nv);
  out->fixed = malloc(nv);
  out->contact_vertex = malloc(sizeof(int) * (nc + 1));
  out->contact_of = malloc(sizeof(int) * (nc + 1));
  out->feedback = malloc(sizeof(palp_vec3) * (nf * nc + 1));
  if (!out->time || !out->disp || !out->fixed || !out->contact_vertex || !out->contact_of || !out->feedback) {
    palp_mesh_destroy(&mesh);
    palp_eval_record_destroy(out);
    return PALP_ENOMEM;
  }
  memcpy(out->time, r->time, sizeof(double) * nf);
  memcpy(out->disp, r->disp, sizeof(palp_vec3) * nf * nv);
  memcpy(out->fixed, mesh.fixed, nv);
  if (nc) {
    memcpy(out->contact_vertex, r->contact_vertex, sizeof(int) * nc);
    memcpy(out->contact_of, r->contact_of, sizeof(int) * nc);
    memcpy(out->feedback, r->feedback, sizeof(palp_vec3) * nf * nc);
  }
  palp_mesh_destroy(&mesh);
  return PALP_OK;
}
