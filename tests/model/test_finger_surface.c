/*
 * test_finger_surface.c - the fingertip's smooth contact surface (docs/haptics.md,
 * "The smooth contact surface"): the Phong patches lie on the dome's sphere at rest,
 * neighbouring patches meet along their edges deformed or not, and a fingertip sliding
 * at light touch no longer feels the flat facets.
 *
 * Expected values come from geometry (the sphere, the chords' sag) and from what a hand
 * can feel (the force JND), never from the code under test.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "finger.h"
#include "palp.h"

#define PI 3.14159265358979323846

static palp_vec3 v(double x, double y, double z) { return (palp_vec3){x, y, z}; }
static palp_vec3 add(palp_vec3 a, palp_vec3 b) { return v(a.x + b.x, a.y + b.y, a.z + b.z); }
static palp_vec3 sub(palp_vec3 a, palp_vec3 b) { return v(a.x - b.x, a.y - b.y, a.z - b.z); }
static palp_vec3 scl(palp_vec3 a, double s) { return v(a.x * s, a.y * s, a.z * s); }
static double dot(palp_vec3 a, palp_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static double len(palp_vec3 a) { return sqrt(dot(a, a)); }
static palp_vec3 cross(palp_vec3 a, palp_vec3 b) {
  return v(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* Unit area-weighted normal of vertex i's ring of dome triangles at positions x. */
static palp_vec3 ring(const palp_mesh *m, const palp_vec3 *x, int i) {
  palp_vec3 s = v(0, 0, 0);
  for (int t = 0; t < m->dome_triangle_count; ++t)
    for (int e = 0; e < 3; ++e)
      if (m->tri[t][e] == i) s = add(s, cross(sub(x[m->tri[t][1]], x[m->tri[t][0]]), sub(x[m->tri[t][2]], x[m->tri[t][0]])));
  return scl(s, 1.0 / len(s));
}

/* At rest, on the 338-vertex dome: the flat facets sag up to ~0.27 mm inside the
 * sphere (R (1 - cos(theta / 2)) for ~7 mm edges at R = 40 mm, more at the facets'
 * centres); the patches must lie on it to a small fraction of that, and their normals
 * follow the sphere's where the facets tilt by half their angular size (~5 deg). Bounds:
 * 10 um (4% of the sag) and 0.5 deg. Then under a deformation (a 6 mm Gaussian dent,
 * with each vertex normal carried by its ring), the two triangles on each interior edge
 * give the same patch points along it (the offset there depends on the edge's two
 * vertices only), to round-off: 1e-12 m. */
static void test_geometry(void) {
  palp_mesh m;
  palp_mesh_def md = palp_mesh_default_def();
  CHECK(palp_mesh_create(&md, &m) == 0, "mesh");
  const int nv = m.vertex_count;
  palp_vec3 *N = calloc((size_t)nv, sizeof *N), *x = calloc((size_t)nv, sizeof *x), *Nx = calloc((size_t)nv, sizeof *Nx);
  palp_rest_normals(&m, N);
  const double R = md.radius;
  double sag = 0.0, emin = 0.0, emax = 0.0, tilt = 0.0;
  for (int t = 0; t < m.dome_triangle_count; ++t) {
    const int *T = m.tri[t];
    const palp_vec3 X[3] = {m.rest[T[0]], m.rest[T[1]], m.rest[T[2]]}, Nt[3] = {N[T[0]], N[T[1]], N[T[2]]};
    palp_smooth_patch sp;
    CHECK(palp_smooth_patch_init(&sp, X, Nt) == 0, "patch %d", t);
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; i + j <= 16; ++j) {
        const double b[3] = {(16 - i - j) / 16.0, i / 16.0, j / 16.0};
        palp_vec3 t1, t2;
        const palp_vec3 S = palp_smooth_point(&sp, X[0], X[1], X[2], Nt, b, &t1, &t2);
        const palp_vec3 P = add(add(scl(X[0], b[0]), scl(X[1], b[1])), scl(X[2], b[2]));
        sag = fmax(sag, R - len(P));
        emin = fmin(emin, len(S) - R), emax = fmax(emax, len(S) - R);
        const palp_vec3 n = cross(t1, t2);
        tilt = fmax(tilt, acos(fmin(1.0, dot(n, S) / (len(n) * len(S)))));
      }
  }
  printf("rest: the facets sag up to %.4f mm inside the sphere; the patches lie %.4f .. %.4f mm from it, their "
         "normals within %.3f deg of the sphere's\n", sag * 1e3, emin * 1e3, emax * 1e3, tilt * 180 / PI);
  CHECK(sag > 0.1e-3, "the facets sag (%.4f mm): the test measures something", sag * 1e3);
  CHECK(fmax(-emin, emax) < 10e-6, "the patches on the sphere within 10 um (%.4f .. %.4f mm)", emin * 1e3, emax * 1e3);
  CHECK(tilt < 0.5 * PI / 180, "patch normals within 0.5 deg of the sphere's (%.3f deg)", tilt * 180 / PI);

  /* deformed: a dent of 3 mm depth, 6 mm wide, at polar 40 deg, plus a lateral shear */
  const palp_vec3 c = v(R * sin(0.7), 0, R * cos(0.7));
  for (int i = 0; i < nv; ++i) {
    const palp_vec3 X = m.rest[i];
    const double g = m.fixed[i] ? 0.0 : exp(-dot(sub(X, c), sub(X, c)) / (0.006 * 0.006));
    x[i] = add(X, add(scl(N[i], -0.003 * g), v(0, 0.001 * g, 0)));
  }
  for (int i = 0; i < nv; ++i) Nx[i] = palp_normal_carry(N[i], ring(&m, m.rest, i), ring(&m, x, i));
  double gap = 0.0;
  int edges = 0;
  for (int t = 0; t < m.dome_triangle_count; ++t)
    for (int u = t + 1; u < m.dome_triangle_count; ++u)
      for (int e = 0; e < 3; ++e)
        for (int f = 0; f < 3; ++f) {
          const int a = m.tri[t][e], b = m.tri[t][(e + 1) % 3];
          if (!(m.tri[u][f] == b && m.tri[u][(f + 1) % 3] == a)) continue; /* shared edge, opposite order */
          edges++;
          palp_smooth_patch st, su;
          const int *T = m.tri[t], *U = m.tri[u];
          const palp_vec3 XT[3] = {m.rest[T[0]], m.rest[T[1]], m.rest[T[2]]}, NT[3] = {N[T[0]], N[T[1]], N[T[2]]};
          const palp_vec3 XU[3] = {m.rest[U[0]], m.rest[U[1]], m.rest[U[2]]}, NU[3] = {N[U[0]], N[U[1]], N[U[2]]};
          palp_smooth_patch_init(&st, XT, NT);
          palp_smooth_patch_init(&su, XU, NU);
          const palp_vec3 xt[3] = {x[T[0]], x[T[1]], x[T[2]]}, nt[3] = {Nx[T[0]], Nx[T[1]], Nx[T[2]]};
          const palp_vec3 xu[3] = {x[U[0]], x[U[1]], x[U[2]]}, nu[3] = {Nx[U[0]], Nx[U[1]], Nx[U[2]]};
          for (int k = 1; k < 8; ++k) {
            const double s = k / 8.0;
            double bt[3] = {0, 0, 0}, bu[3] = {0, 0, 0};
            bt[e] = 1 - s, bt[(e + 1) % 3] = s;   /* a -> b on t */
            bu[(f + 1) % 3] = 1 - s, bu[f] = s;   /* the same point on u */
            palp_vec3 t1, t2;
            const palp_vec3 St = palp_smooth_point(&st, xt[0], xt[1], xt[2], nt, bt, &t1, &t2);
            const palp_vec3 Su = palp_smooth_point(&su, xu[0], xu[1], xu[2], nu, bu, &t1, &t2);
            gap = fmax(gap, len(sub(St, Su)));
          }
        }
  printf("deformed (3 mm dent): neighbouring patches meet along %d interior edges within %.3g m\n", edges, gap);
  /* the dome is a disc: each triangle has 3 edges, interior ones shared by two, the rim's
   * (one per rim vertex) by one */
  int rim = 0;
  for (int i = 0; i < nv; ++i) rim += m.fixed[i] != 0;
  CHECK(2 * edges == 3 * m.dome_triangle_count - rim, "every interior edge checked (%d of %d)", edges,
        (3 * m.dome_triangle_count - rim) / 2);
  CHECK(gap < 1e-12, "neighbouring patches meet along their edges (gap %.3g m, bound 1e-12)", gap);
  free(N), free(x), free(Nx);
  palp_mesh_destroy(&m);
}

/* A fingertip slid at constant depth below the dome's sphere along a latitude (scene's dome,
 * its own contacts removed; 1 kHz, 5 mm/s over 20 mm after a press at 1 mm/s from 0.2 mm
 * above the sphere and 0.3 s of hold): (max - min) / mean of the force over the slide after
 * its first 2 mm [-]. The press started 1 mm above until 2026-12-07: 800 more ticks in the
 * air per slide (the world steps at full cost while its dome settles), which changed none
 * of the 13 slides' printed figures (the variations to 0.1%, the tick steps to 1e-5 N) and
 * cost ~20% of the test's CPU (33.1 -> 26.2 s, this machine under load). */
static double slide_on(const char *scene, int surface, double polar_deg, double depth, double *worst_step) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(scene, &sc, err, sizeof err)) {
    fprintf(stderr, "%s\n", err);
    exit(2);
  }
  sc.world.dt = 0.001;
  sc.world.finger_surface = surface;
  int e = 0;
  palp_world *w = palp_scene_create_world(&sc, &e);
  if (!w) exit(2);
  for (int k = 0; k < sc.contact_count; ++k) palp_world_remove_contact(w, k);
  const double R = sc.world.mesh.radius, r = 0.008, th = polar_deg * PI / 180;
  const palp_finger_def fd = palp_finger_default_def();
#define AT(rho, az) v((rho) * sin(th) * cos(az), (rho) * sin(th) * sin(az), (rho) * cos(th))
  const double above = 0.2e-3; /* the tip's start above the sphere [m] */
  const int f = palp_world_add_finger_def(w, &fd, AT(R + r + above, 0.0));
  const int npress = (int)lround((above + depth) / 1e-6);
  for (int k = 1; k <= npress + 300; ++k) {
    palp_world_set_finger_device(w, f, AT(R + r + above - 1e-6 * (k < npress ? k : npress), 0.0));
    CHECK(palp_world_step(w) == 0, "step");
  }
  const double rho = R + r - depth, daz = 5e-6 / (rho * sin(th)); /* 5 mm/s at 1 kHz */
  double fmin_ = INFINITY, fmax_ = 0.0, sum = 0.0, F1 = 0.0, F2 = 0.0;
  int n = 0, lost = 0;
  *worst_step = 0.0;
  for (int k = 1; k <= 4000; ++k) {
    palp_world_set_finger_device(w, f, AT(rho, daz * k));
    CHECK(palp_world_step(w) == 0, "step");
    palp_local_model lm;
    palp_world_finger_local_model(w, f, &lm);
    const double F = len(lm.force);
    lost += !lm.contact;
    if (k > 400) {
      fmin_ = fmin(fmin_, F), fmax_ = fmax(fmax_, F), sum += F, n++;
      *worst_step = fmax(*worst_step, fabs(F - 2 * F1 + F2));
    }
    F2 = F1, F1 = F;
  }
#undef AT
  CHECK(lost == 0, "contact kept while sliding (%d ticks lost)", lost);
  palp_world_destroy(w);
  return (fmax_ - fmin_) / (sum / n);
}

/* the same on the long-term dome */
static double slide(int surface, double polar_deg, double depth, double *worst_step) {
  return slide_on(PALP_CONFIG_DIR "/paper_step_long_term.json", surface, polar_deg, depth, worst_step);
}

/* At 0.5 mm below the sphere the flat facets' sag (0.13-0.19 mm under the path) is a
 * third of the depth, so on the facets the force swings by ~25% as the tip passes
 * vertices and facet centres ~7 mm apart: ridges the tissue does not have. With the
 * sag gone what is left is the net's own stiffness under a point load, which differs
 * between a vertex and a face (with a rigid pad 5% at 0.25-1 mm). Bound: 7%, the force
 * discrimination threshold of the hand (Weber fraction ~7%, Jones 1989; 5-10%, Pang,
 * Tan & Durlach 1991): below it the facets are not felt. The facets must exceed it, or
 * this test would not see them. */
static void test_slide(void) {
  double st = 0.0;
  const double s30 = slide(PALP_FINGER_SURFACE_SMOOTH, 30.0, 0.5e-3, &st);
  printf("slide 0.5 mm below the sphere, 5 mm/s: smooth surface at polar 30 deg (max - min) / mean %.1f%% (worst tick "
         "step off the trend %.5f N)\n", 100 * s30, st);
  const double s70 = slide(PALP_FINGER_SURFACE_SMOOTH, 70.0, 0.5e-3, &st);
  printf("  smooth at polar 70 deg %.1f%% (%.5f N)\n", 100 * s70, st);
  const double f70 = slide(PALP_FINGER_SURFACE_FACETS, 70.0, 0.5e-3, &st);
  printf("  facets at polar 70 deg %.1f%% (%.5f N)\n", 100 * f70, st);
  CHECK(s30 < 0.07, "smooth, 30 deg: the force varies by %.1f%% (bound 7%%)", 100 * s30);
  CHECK(s70 < 0.07, "smooth, 70 deg: the force varies by %.1f%% (bound 7%%)", 100 * s70);
  CHECK(f70 > 0.07, "facets, 70 deg: the facets are felt (%.1f%%, over 7%%)", 100 * f70);
}

/* A smooth-surface fingertip slid along the latitudes 30 and 70 deg of a scene's dome at each of n
 * depths below the sphere (slide_on), each slide's (max - min) / mean asserted under bound[k]
 * (labelled "bound" when it is the hand's 7%, else "regression bound"). */
static void slide_table(const char *scene, const char *label, int n, const double *depth, const double *bound) {
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 2; ++a) {
      double st = 0.0;
      const double r = slide_on(scene, PALP_FINGER_SURFACE_SMOOTH, a ? 70.0 : 30.0, depth[k], &st);
      printf("%s, smooth, polar %d deg, %.1f mm below the sphere: (max - min) / mean %.1f%% (worst tick step %.5f N)\n",
             label, a ? 70 : 30, 1e3 * depth[k], 100 * r, st);
      CHECK(r < bound[k], "%s, %.1f mm deep at %d deg: the force varies by %.1f%% (%s %.0f%%)", label, 1e3 * depth[k],
            a ? 70 : 30, 100 * r, bound[k] == 0.07 ? "bound" : "regression bound", 100 * bound[k]);
    }
}

/* The exercise phantom (the breast-tissue dome, config/phantoms/dome.json) slid the same way. Its
 * support is stiff against its bending (D 1.75x its skin's own since the refit of 2026-11-30), so the
 * net's stiffness under a fingertip differs between a vertex and a face more than on the long-term
 * dome: measured 2026-12-02, 5 mm deep (~1.7 N at the pole, the exercises' medium pressure) 5.4% at
 * 30 deg and 2.7% at 70 deg, under the hand's 7%: asserted. 2 mm deep (~0.5 N, light pressure) 18.9%
 * and 8.5% (16.0% and 7.5% with the set before that refit): over it, so a light touch feels the net as
 * much as the hard exercise's 1 cm lump (+9-16%); held here in a REGRESSION BOUND (22%), not a pass
 * (docs/haptics.md, "The net under a light touch"). */
static void test_slide_breast_tissue(void) {
  static const double depth[2] = {5e-3, 2e-3}, bound[2] = {0.07, 0.22};
  slide_table(PALP_CONFIG_DIR "/phantoms/dome.json", "breast tissue", 2, depth, bound);
}

/* The long-term dome on a 1,300-vertex net (config/paper_step_long_term_fine.json, its own
 * parameters fitted against the fingertip FE graded where the finger presses): the net's vertices
 * are half as far apart, so a light touch spans more of them. Slid as test_slide: under the
 * hand's 7% at 30 and 70 deg (measured 2026-12-02: 4.6% and 3.9%). The same set on the 338-vertex
 * net varies by 13.9% and 6.4%: its bending is 0.32x the shipped 338-vertex set's (docs/haptics.md,
 * "The net under a light touch"). */
static void test_slide_fine(void) {
  static const double depth[1] = {0.5e-3}, bound[1] = {0.07};
  slide_table(PALP_CONFIG_DIR "/paper_step_long_term_fine.json", "long-term, 1,300 vertices", 1, depth, bound);
}

/* The exercise phantom's set on a 1,300-vertex net (config/phantoms/dome_fine.json: the breast-tissue
 * set with the bonded base cutting the support's column, support_base_reach 0.93, fitted for the rim):
 * slid as test_slide_breast_tissue. 2 mm deep (~0.5 N at the pole), under the hand's 7% at 30 and
 * 70 deg (measured 2026-12-02: 6.2 / 2.6%; the 338-vertex dome 18.9 / 8.5%; 5 mm deep, not run here,
 * 3.6 / 1.1% against 5.4 / 2.7%). 1 mm deep (~0.2 N, under the MammaCare light band's 0.23 N) 9.0 / 8.0%, over it but a
 * third of the 338-vertex dome's 28.1 / 15.1%: a REGRESSION BOUND (10%) there (docs/haptics.md, "The
 * net under a light touch"). */
static void test_slide_breast_tissue_fine(void) {
  static const double depth[2] = {1e-3, 2e-3}, bound[2] = {0.10, 0.07};
  slide_table(PALP_CONFIG_DIR "/phantoms/dome_fine.json", "breast tissue, 1,300 vertices", 2, depth, bound);
}

int main(void) {
  test_geometry();
  test_slide();
  test_slide_breast_tissue();
  test_slide_fine();
  test_slide_breast_tissue_fine();
  CHECK_DONE();
}
