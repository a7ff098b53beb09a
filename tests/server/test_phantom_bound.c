/*
 * test_phantom_bound.c - one bound for phantom meshes (session 76, 2026-12-06): the catalogue check
 * the stations and palp-recorder use (palp_dds_phantom_check, idl/) takes the largest mesh a
 * palp-server can publish and not one vertex more. No DDS traffic.
 *  - A catalogue entry of 200,000 vertices is accepted, 200,001 refused (with triangles, as the
 *    stations check, and without, as palp-recorder may keep one), the reason naming the bound;
 *    triangles: 400,000 accepted, 400,001 refused. Before: the check's own bound was 1,000,000
 *    vertices, so 200,001 (and a million) passed.
 *  - The server's side: a scene may ask for 200,000 vertices and not 200,001 (palp_scene_parse),
 *    palp_mesh_create makes 200,000 and not 200,001, and the catalogue entry the server builds from
 *    that mesh (palp_srv_catalogue_mesh, what publish_catalogue writes) passes the check: no station
 *    refuses its server's catalogue.
 * The numbers are written out here, not taken from PALP_MESH_MAX_VERTICES: the test states the bound.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp.h"
#include "palp_dds.h"
#include "server.h"

#define BOUND 200000

/* A catalogue entry of nv vertices on a 40 mm sphere-ish cloud and nt triangles naming vertices
 * (i, i + 1, i + 2) mod nv; the first is the dome's, the pole vertex 0 its top. */
static int entry(palp_Phantom *ph, uint32_t nv, uint32_t nt) {
  memset(ph, 0, sizeof *ph);
  palp_Vec3 *rest = malloc((size_t)nv * sizeof *rest);
  int32_t *tri = nt ? malloc((size_t)nt * 3 * sizeof *tri) : NULL;
  if (!rest || (nt && !tri)) {
    free(rest);
    free(tri);
    return -1;
  }
  for (uint32_t i = 0; i < nv; i++) {
    const double a = 6.283185307179586 * i / nv; /* [rad] */
    rest[i] = (palp_Vec3){0.04 * cos(a), 0.04 * sin(a), 0.001 * (i % 7)};
  }
  for (uint32_t t = 0; t < nt; t++)
    for (uint32_t k = 0; k < 3; k++) tri[3 * t + k] = (int32_t)((t + k) % nv);
  ph->phantom_id = 7;
  ph->radius = 0.04;
  ph->top_vertex = 0;
  ph->dome_triangle_count = nt ? 1 : 0;
  ph->rest = (dds_sequence_palp_Vec3){nv, nv, rest, false};
  ph->triangles = (dds_sequence_long){3 * nt, 3 * nt, tri, false};
  return 0;
}

static void entry_free(palp_Phantom *ph) {
  free(ph->rest._buffer);
  free(ph->triangles._buffer);
}

static void check_counts(void) {
  static const struct {
    uint32_t nv, nt;
    int ok;
  } c[] = {{BOUND, 1, 1}, {BOUND + 1, 1, 0}, {1000000, 1, 0}, {BOUND, 0, 1} /* recorder: triangles optional */,
           {BOUND + 1, 0, 0}, {BOUND, 2 * BOUND, 1}, {BOUND, 2 * BOUND + 1, 0}};
  for (size_t i = 0; i < sizeof c / sizeof c[0]; i++) {
    palp_Phantom ph;
    if (entry(&ph, c[i].nv, c[i].nt) != 0) {
      CHECK(0, "memory for %u vertices", c[i].nv);
      return;
    }
    char why[256] = "";
    const int rc = palp_dds_phantom_check(&ph, c[i].nt == 0, why, sizeof why);
    CHECK((rc == 0) == c[i].ok && (c[i].ok || rc == PALP_EINVAL), "%u vertices, %u triangles%s: %s (%s)", c[i].nv,
          c[i].nt, c[i].nt ? "" : " (triangles optional)", c[i].ok ? "accepted" : "refused", rc ? why : "ok");
    if (c[i].nt == 1 && !c[i].ok)
      CHECK(strstr(why, "want 4..200000, the largest mesh a palp-server publishes") != NULL,
            "  the reason names the bound: \"%s\"", why);
    /* (session 83 review "wire" #8: 1,200,003 indices, a positive multiple of 3, were refused as "want a
     * positive multiple of 3") */
    if (c[i].nt > 2 * BOUND)
      CHECK(strstr(why, "400001 triangles (at most 400000, twice the largest mesh a palp-server publishes)") != NULL,
            "  the reason names the triangle bound: \"%s\"", why);
    entry_free(&ph);
  }
}

static void check_server_side(void) {
  /* a scene asks for at most the bound */
  char scene[512], err[256];
  palp_scene s;
  for (int k = 0; k < 2; k++) {
    snprintf(scene, sizeof scene,
             "{\"name\": \"big\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": %d},"
             " \"time\": {\"dt_s\": 0.01, \"frames\": 10, \"frame_period_s\": 0.01},"
             " \"effects\": [\"membrane_elasticity\"], \"membrane\": {\"thickness_m\": 0.002, \"density_kg_m3\": 950,"
             " \"E1_Pa\": 1e5, \"eta1_Pa_s\": 1e9, \"E2_Pa\": 1e5, \"eta2_Pa_s\": 1e4},"
             " \"gel\": {\"law\": \"polytropic\", \"pressure_Pa\": 101325, \"a1\": 10, \"a2_Pa_s_m3\": 0},"
             " \"contacts\": []}",
             BOUND + k);
    err[0] = 0;
    const int rc = palp_scene_parse(scene, &s, err, sizeof err);
    CHECK(k == 0 ? rc == 0 : rc < 0 && strstr(err, "mesh.vertex_count") != NULL,
          "a scene's mesh.vertex_count %d: %s (%s)", BOUND + k, k ? "refused" : "accepted", rc ? err : "ok");
  }
  /* the mesh it makes, and the catalogue entry the server builds from it */
  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh none;
  md.vertex_count = BOUND + 1;
  CHECK(palp_mesh_create(&md, &none) == PALP_EINVAL, "palp_mesh_create refuses %d vertices", BOUND + 1);
  md.vertex_count = BOUND;
  palp_mesh m;
  const int rc = palp_mesh_create(&md, &m);
  CHECK(rc == 0 && m.vertex_count == BOUND && m.triangle_count == 2 * BOUND - 4,
        "palp_mesh_create makes %d vertices, %d triangles (a closed surface: 2V - 4 = %d)", m.vertex_count,
        m.triangle_count, 2 * BOUND - 4);
  if (rc != 0) return;
  palp_Vec3 *rest = malloc((size_t)m.vertex_count * sizeof *rest);
  int32_t *tri = malloc((size_t)m.triangle_count * 3 * sizeof *tri);
  if (rest && tri) {
    palp_Phantom ph;
    memset(&ph, 0, sizeof ph);
    ph.phantom_id = 1;
    ph.radius = md.radius;
    palp_srv_catalogue_mesh(&m, rest, tri, &ph);
    char why[256] = "";
    const int a = palp_dds_phantom_check(&ph, 0, why, sizeof why), b = palp_dds_phantom_check(&ph, 1, why, sizeof why);
    CHECK(ph.rest._length == (uint32_t)BOUND && a == 0 && b == 0,
          "the server's catalogue entry of that mesh (%u vertices, %u triangle indices) passes the stations' and the "
          "recorder's check (%d, %d: %s)",
          ph.rest._length, ph.triangles._length, a, b, why[0] ? why : "ok");
  } else {
    CHECK(0, "memory for the largest mesh's entry");
  }
  free(rest);
  free(tri);
  palp_mesh_destroy(&m);
}

int main(void) {
  check_counts();
  check_server_side();
  return failures != 0;
}
