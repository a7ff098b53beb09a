/*
 * test_finger_drift.c - the drift of a finger's local contact model (palp.h,
 * palp_local_model.drift) is the surface's velocity at the contact: each touched
 * feature's vertices weighted by their own barycentric weights.
 *
 * The fingertip (8 mm, default coupling) touches the default phantom's flat facets
 * (def.finger_surface "facets", 1 kHz) for the first time, 0.2 mm deep, above a single
 * vertex (on the vertex's radial line: the sphere's tangent plane there supports the
 * inscribed dome, so every facet at the vertex has the vertex as its closest point) or
 * above the midpoint of an interior edge. A first touch has no last model, so the drift
 * observer adds nothing (palp_drift_observe: c = 0) and the drift must be
 *   d = sum_v b_v v_v,
 * v_v the vertex velocities after the step (palp_world_velocities), b_v the vertex's
 * barycentric weight in the one touched feature:
 *   - a vertex: b = 1, from the geometry alone;
 *   - an edge: b_v = |f_v| / lambda, with f_v the per-vertex feedback (the row's force
 *     lambda n b_v on that vertex, palp_world_contact_vertices) and lambda the row's force
 *     (palp_world_finger_contacts); the weights are checked to sum to 1 within 1e-9.
 * Steps where the finger touched more than one feature are skipped (their weights
 * cannot be told apart from the feedback) and counted. Tolerance: 1e-9 |d| + 1e-12 m/s
 * (the drift is lambda b v / lambda, a few roundings).
 *
 * Before the fix the drift read the weight of the row's e-th triangle corner for its
 * e-th free, non-zero-weight vertex: a vertex at corner 1 or 2 of its triangle got
 * weight 0 (the drift was 0 at any surface speed), and an edge not at corners 0 and 1
 * read the zero weight of its missing corner for one of its vertices.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "palp.h"

static palp_vec3 add(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static palp_vec3 sc(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
static double len(palp_vec3 a) { return sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }
static palp_vec3 unit(palp_vec3 a) { return sc(a, 1.0 / len(a)); }

enum { MAXV = 64 };

typedef struct tally {
  int checked, skipped, misread; /* single-feature first touches checked, multi-feature ones, features whose n
                                    vertices are not the triangle's corners 0 .. n-1 (the old index misread them) */
  double worst;                      /* largest |d - expected| / |expected| [-] */
  double speed_min;                  /* slowest expected surface speed checked [m/s] */
} tally;

/* One first touch: a fresh world, a finger with its device `depth` [m] inside the rest
 * surface at `point` along the unit outward `dir`, one step; compares the drift with
 * the weighted vertex velocities. */
static void touch(palp_vec3 point, palp_vec3 dir, double depth, const char *what, tally *t) {
  palp_world_def d = palp_world_default_def();
  d.dt = 0.001;
  d.finger_surface = PALP_FINGER_SURFACE_FACETS;
  int err = 0;
  palp_world *w = palp_world_create(&d, &err);
  if (!w) {
    CHECK(0, "world: %s", palp_strerror(err));
    return;
  }
  const palp_finger_def fd = palp_finger_default_def();
  const palp_vec3 device = add(point, sc(dir, fd.radius - depth));
  const int f = palp_world_add_finger_def(w, &fd, device);
  CHECK(f >= 0, "%s: add_finger %d", what, f);
  CHECK(palp_world_step(w) == 0, "%s: step", what);
  palp_local_model lm;
  palp_world_finger_local_model(w, f, &lm);
  int tri[8];
  double lam[8];
  const int rows = palp_world_finger_contacts(w, f, tri, lam, 8);
  int vert[MAXV];
  palp_vec3 fb[MAXV];
  const int nv = palp_world_contact_vertices(w, f, vert, fb, MAXV);
  CHECK(lm.contact, "%s: the finger touches", what);
  if (!lm.contact || rows < 1) {
    palp_world_destroy(w);
    return;
  }
  if (rows > 1) {
    t->skipped++;
    palp_world_destroy(w);
    return;
  }
  const palp_vec3 *vel = palp_world_velocities(w);
  const palp_mesh *m = palp_world_mesh(w);
  palp_vec3 expect = {0, 0, 0};
  double bsum = 0.0;
  for (int q = 0; q < nv; ++q) {
    const double b = len(fb[q]) / lam[0];
    bsum += b;
    expect = add(expect, sc(vel[vert[q]], b));
  }
  /* the feature's vertices at the triangle's corners 0 .. nv-1, where a packed index is the corner? */
  int misread = 0;
  for (int e = 0; e < 3; ++e)
    for (int q = 0; q < nv; ++q)
      if (m->tri[tri[0]][e] == vert[q] && e >= nv) misread = 1;
  t->misread += misread;
  CHECK(fabs(bsum - 1.0) <= 1e-9, "%s: the feature's weights sum to 1 (%.12f)", what, bsum);
  const double err_d = len(add(lm.drift, sc(expect, -1.0)));
  const double tol = 1e-9 * len(expect) + 1e-12;
  CHECK(err_d <= tol, "%s: drift (%.6g, %.6g, %.6g) m/s against the surface's (%.6g, %.6g, %.6g) m/s (%d vertices, "
        "triangle %d): off by %.3g m/s, tolerance %.3g", what, lm.drift.x, lm.drift.y, lm.drift.z, expect.x,
        expect.y, expect.z, nv, tri[0], err_d, tol);
  if (len(expect) > 0.0 && err_d / len(expect) > t->worst) t->worst = err_d / len(expect);
  if (len(expect) < t->speed_min) t->speed_min = len(expect);
  t->checked++;
  palp_world_destroy(w);
}

/* A finger added again in a slot a pressing finger left (palp_world_remove_contact, then
 * palp_world_add_finger_def): until its first step it touches nothing, so
 * palp_world_finger_contacts must report no rows. Until session 76 (review, 2026-12-06) the
 * slot's row count (nfinger) survived the re-add, and the new finger, 5 cm above the dome,
 * reported the old finger's triangles and forces. */
static void readded(void) {
  palp_world_def d = palp_world_default_def();
  d.dt = 0.001;
  int err = 0;
  palp_world *w = palp_world_create(&d, &err);
  if (!w) {
    CHECK(0, "world: %s", palp_strerror(err));
    return;
  }
  const palp_finger_def fd = palp_finger_default_def();
  const palp_vec3 pole = {0.0, 0.0, d.mesh.radius}; /* [m] the dome's top */
  const int f = palp_world_add_finger_def(w, &fd, (palp_vec3){0.0, 0.0, pole.z + fd.radius - 0.002}); /* 2 mm in */
  CHECK(f >= 0, "re-add: first finger %d", f);
  for (int i = 0; i < 20; ++i) CHECK(palp_world_step(w) == 0, "re-add: step %d", i);
  const int pressed = palp_world_finger_contacts(w, f, NULL, NULL, 0);
  CHECK(pressed >= 1, "re-add: the first finger, 2 mm in at the pole, touches (%d rows)", pressed);
  CHECK(palp_world_remove_contact(w, f) == 0, "re-add: remove");
  const int g = palp_world_add_finger_def(w, &fd, (palp_vec3){0.0, 0.0, pole.z + 0.05}); /* 5 cm above */
  CHECK(g == f, "re-add: the freed slot %d is taken again (%d)", f, g);
  const int rows = palp_world_finger_contacts(w, g, NULL, NULL, 0);
  CHECK(rows == 0, "re-add: a finger 5 cm above the dome, not yet stepped, touches nothing (%d rows; the old "
        "finger's were %d)", rows, pressed);
  CHECK(palp_world_step(w) == 0, "re-add: step");
  CHECK(palp_world_finger_contacts(w, g, NULL, NULL, 0) == 0, "re-add: nor after a step");
  palp_world_destroy(w);
}

int main(void) {
  const palp_mesh_def md = palp_mesh_default_def();
  palp_mesh m;
  if (palp_mesh_create(&md, &m)) {
    fprintf(stderr, "mesh\n");
    return 2;
  }
  const double depth = 0.0002; /* [m] */
  char what[96];
  /* Vertices: every fourth free vertex within 60 deg of the pole. */
  tally tv = {0, 0, 0, 0.0, INFINITY};
  for (int i = 0; i < m.vertex_count; i += 4) {
    const palp_vec3 x = m.rest[i];
    if (m.fixed[i] || x.z < 0.5 * len(x)) continue;
    snprintf(what, sizeof what, "vertex %d", i);
    touch(x, unit(x), depth, what, &tv);
  }
  /* Edges: the first edge of every fourth dome triangle within 60 deg, both ends free. */
  tally te = {0, 0, 0, 0.0, INFINITY};
  for (int tr = 0; tr < m.dome_triangle_count; tr += 4) {
    const int a = m.tri[tr][0], b = m.tri[tr][1];
    const palp_vec3 mid = sc(add(m.rest[a], m.rest[b]), 0.5);
    if (m.fixed[a] || m.fixed[b] || mid.z < 0.5 * len(mid)) continue;
    snprintf(what, sizeof what, "edge %d-%d", a, b);
    touch(mid, unit(mid), depth, what, &te);
  }
  printf("first touches 0.2 mm deep on the facets at 1 kHz: vertices %d checked (%d not at their triangle's corner 0), "
         "%d touching more than one feature skipped; edges %d checked (%d not at corners 0 and 1), %d skipped; drift "
         "against the weighted vertex velocities: worst %.3g relative (vertices), %.3g (edges); slowest surface %.3g / "
         "%.3g m/s\n",
         tv.checked, tv.misread, tv.skipped, te.checked, te.misread, te.skipped, tv.worst, te.worst, tv.speed_min,
         te.speed_min);
  /* the test measures something: contacts whose weights the packed index misread */
  CHECK(tv.checked >= 10 && tv.misread >= 3, "vertex touches checked %d, off corner 0 %d (want >= 10, >= 3)",
        tv.checked, tv.misread);
  CHECK(te.checked >= 10 && te.misread >= 3, "edge touches checked %d, off corners 0-1 %d (want >= 10, >= 3)",
        te.checked, te.misread);
  CHECK(tv.speed_min > 1e-4 && te.speed_min > 1e-4, "the touched surface moves (slowest %.3g / %.3g m/s)",
        tv.speed_min, te.speed_min);
  readded();
  palp_mesh_destroy(&m);
  CHECK_DONE();
}
