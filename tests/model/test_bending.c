/* Linearised hinge bending (src/bending.c), against hand calculations:
 * - the gradient of the dihedral angle agrees with central differences of the angle
 *   itself (relative 1e-6) on random hinges, and sums to zero (1e-12 of its size);
 * - on an equilateral lattice, cylindrical bending w = kappa x^2 / 2 in any direction
 *   stores the thin plate's energy D kappa^2 / 2 per unit area (relative 1e-9: exact
 *   for a quadratic field), and spherical bending w = kappa r^2 / 2 stores
 *   D (1 + nu) kappa^2 with nu = -1/3, the Poisson ratio this hinge model implies
 *   (it only weighs the Gaussian curvature, which a plate's interior deflection
 *   D laplacian^2 w = p does not see);
 * - the linearised angle's energy equals that of the angle itself (palp_hinge_angle,
 *   independent of the gradient) at a small field, relative 1e-5;
 * - in the world, a skin of bending stiffness D on a support of modulus k (the
 *   membrane's stretching made negligible) carries a point load F at the pole like a
 *   thin plate on a Winkler foundation, w = F / (8 sqrt(D k)) (Timoshenko &
 *   Woinowsky-Krieger, Theory of Plates and Shells, ch. 8), within 20%, and w scales
 *   as D^(-1/2) within 10% (4 D gives half the depth; measured 0.525, the (l/R)^2 part below). Measured 2026-11-26 on the
 *   5,000-vertex dome: 1.15x the plate at l = (D / k)^(1/4) = 5 mm, 1.20x at 7 mm,
 *   1.34x at 10 mm, 1.11x at 2 mm (20,000 vertices): not a discretisation error
 *   (the same at 5,000 and 20,000 vertices), but ~10% from the hinge model on the
 *   dome's irregular triangles and a part growing as (l/R)^2: a hinge's angle does
 *   not change when a patch shrinks towards the centre, which a curved shell's
 *   change of curvature (~ laplacian w + 2 w / R^2) does; stretching, stiff in every
 *   real parameter set, resists that mode, here made negligible on purpose;
 * - without bending the same load sinks the pole vertex through its own support
 *   (over 10x deeper): what the paper's membrane does under a fingertip;
 * - the rotation is reported (health.max_bend); with stretching negligible the net
 *   slides in its plane under the point load and its hinges leave the linear range
 *   (below), which the world counts;
 * - the valid range is the linearisation's own error, |true - linear| turn <= 0.1 rad
 *   (PALP_HINGE_LINEAR_ERR_MAX), or the miss the set's validated fingertip presses
 *   reached where larger (palp_world_def.validated_hinge_error: 0.352 rad for the
 *   breast-tissue set, test_validated), checked against the test's own hinges (every edge
 *   of two triangles, enumerated here, true angles by palp_hinge_angle) at every step
 *   of a fingertip pressed at the pole of the breast-tissue dome (the exercises')
 *   from 2 to 30 mm: the world never counts a step before the test sees an error
 *   beyond that range, counts within one sweep (0.2 s) of it, stops counting within a
 *   sweep of the error falling back as the finger lifts, and at 8 mm, where the
 *   hinges turn past 0.35 rad (the former limit by the turn alone) with errors of
 *   ~0.05 rad, counts none;
 * - the shipped long-term scene, written by palp_scene_to_json (what a session log
 *   stores) and parsed back, keeps its bending stiffness bit for bit, and two worlds
 *   built from the two scenes step to the same state hash over 300 frames of a
 *   pressing finger (a logged session replays; tolerance 0). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bending.h"
#include "check.h"
#include "vec3.h"

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double urand(void) { /* [-1, 1) */
  rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
  return (double)(rng >> 11) / 4503599627370496.0 - 1.0;
}

static void check_gradient(void) {
  int worst_ok = 1;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    palp_vec3 x[4];
    x[0] = v3(0, 0, 0);
    x[1] = v3(1.0 + 0.3 * urand(), 0.2 * urand(), 0.2 * urand());
    x[2] = v3(0.5 + 0.4 * urand(), 0.8 + 0.3 * urand(), 0.5 * urand());  /* wing c */
    x[3] = v3(0.5 + 0.4 * urand(), -0.8 + 0.3 * urand(), 0.5 * urand()); /* wing d */
    for (int k = 0; k < 4; ++k) x[k] = v3_scale(x[k], 0.01); /* centimetre hinges, as on the dome */
    palp_vec3 g[4];
    if (palp_hinge_gradient(x[0], x[1], x[2], x[3], g)) {
      worst_ok = 0;
      continue;
    }
    double gmax = 0.0;
    for (int k = 0; k < 4; ++k) gmax = fmax(gmax, v3_len(g[k]));
    const palp_vec3 sum = v3_add(v3_add(g[0], g[1]), v3_add(g[2], g[3]));
    CHECK(v3_len(sum) <= 1e-12 * gmax, "gradients sum to %.3g (of %.3g)", v3_len(sum), gmax);
    const double step = 1e-7; /* [m] */
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 3; ++c) {
        palp_vec3 p[4] = {x[0], x[1], x[2], x[3]}, m[4] = {x[0], x[1], x[2], x[3]};
        double *pc = &p[k].x, *mc = &m[k].x;
        pc[c] += step, mc[c] -= step;
        const double fd = (palp_hinge_angle(p[0], p[1], p[2], p[3]) - palp_hinge_angle(m[0], m[1], m[2], m[3])) / (2 * step);
        const double an = (&g[k].x)[c];
        worst = fmax(worst, fabs(fd - an) / gmax);
      }
  }
  CHECK(worst_ok, "no random hinge is degenerate");
  CHECK(worst <= 1e-6, "gradient vs central differences: worst %.3g of the largest (tolerance 1e-6)", worst);
  printf("hinge gradient: worst relative difference to central differences %.2e\n", worst);
}

/* Equilateral lattice of edge L turned by phi; the energy of w(x, y) over the
 * hinges whose four vertices lie in the lattice, against the plate's over the
 * edges' share of the area (A_e / 3 each). */
#define NL 24
static double lattice_ratio(double phi, int spherical) {
  const double L = 0.005, D = 3.7e-3, kappa = 2.0; /* [m], [N m], [1/m] */
  palp_vec3 p[NL][NL], u[NL][NL];
  const double c = cos(phi), s = sin(phi);
  for (int j = 0; j < NL; ++j)
    for (int i = 0; i < NL; ++i) {
      const double x0 = L * (i + 0.5 * j), y0 = L * j * sqrt(3.0) / 2.0;
      p[j][i] = v3(c * x0 - s * y0, s * x0 + c * y0, 0.0);
      const double X = p[j][i].x, Y = p[j][i].y;
      u[j][i] = v3(0, 0, spherical ? 0.5 * kappa * (X * X + Y * Y) : 0.5 * kappa * X * X);
    }
  double energy = 0.0, area = 0.0, nl_energy = 0.0;
  /* Each interior edge once: its two triangles are (a, b, c) and (b, a, d). */
  for (int j = 1; j < NL - 1; ++j)
    for (int i = 1; i < NL - 1; ++i) {
      /* three edge directions from (i, j): +i, +j, and +j-i */
      const int e[3][2] = {{1, 0}, {0, 1}, {-1, 1}};
      const int wc[3][2] = {{0, 1}, {-1, 1}, {-1, 0}}, wd[3][2] = {{1, -1}, {1, 0}, {0, 1}};
      for (int q = 0; q < 3; ++q) {
        const int ai = i, aj = j, bi = i + e[q][0], bj = j + e[q][1];
        const int ci = i + wc[q][0], cj = j + wc[q][1], di = i + wd[q][0], dj = j + wd[q][1];
        if (bi < 0 || bi >= NL || bj >= NL || ci < 0 || cj >= NL || di >= NL || dj < 0 || dj >= NL) continue;
        palp_vec3 g[4];
        if (palp_hinge_gradient(p[aj][ai], p[bj][bi], p[cj][ci], p[dj][di], g)) return NAN;
        const double dth = v3_dot(g[0], u[aj][ai]) + v3_dot(g[1], u[bj][bi]) + v3_dot(g[2], u[cj][ci]) + v3_dot(g[3], u[dj][di]);
        {
          const double t = 1e-3; /* the angle itself, at a small multiple of the field */
          const double th = palp_hinge_angle(v3_add(p[aj][ai], v3_scale(u[aj][ai], t)), v3_add(p[bj][bi], v3_scale(u[bj][bi], t)),
                                             v3_add(p[cj][ci], v3_scale(u[cj][ci], t)), v3_add(p[dj][di], v3_scale(u[dj][di], t)));
          nl_energy += 0.5 * palp_hinge_stiffness(D, L * L, 2.0 * sqrt(3.0) / 4.0 * L * L) * th * th / (t * t);
        }
        const double tri = sqrt(3.0) / 4.0 * L * L;
        energy += 0.5 * palp_hinge_stiffness(D, L * L, 2.0 * tri) * dth * dth;
        area += 2.0 * tri / 3.0;
      }
    }
  const double plate = spherical ? D * (1.0 - 1.0 / 3.0) * kappa * kappa : 0.5 * D * kappa * kappa; /* [J/m^2] */
  CHECK_NEAR(nl_energy / energy, 1.0, 1e-5, "energy from the angle itself / from the linearised angle");
  return energy / area / plate;
}

/* The test's own hinges: every edge shared by two triangles with a dome triangle
 * among them and a free vertex among the four (the rim's against the base only when
 * they carry a moment, release < 1), with their rest angles and gradients. */
typedef struct {
  int v[4];
  palp_vec3 g[4];
  double th0; /* [rad] */
} test_hinge;

static int test_hinges(const palp_mesh *m, double release, test_hinge *out, int cap) {
  int n = 0;
  for (int a = 0; a < m->triangle_count; ++a)
    for (int ea = 0; ea < 3; ++ea) {
      const int i = m->tri[a][ea], j = m->tri[a][(ea + 1) % 3], c = m->tri[a][(ea + 2) % 3];
      for (int b = a + 1; b < m->triangle_count; ++b)
        for (int eb = 0; eb < 3; ++eb) {
          const int p = m->tri[b][eb], q = m->tri[b][(eb + 1) % 3], d = m->tri[b][(eb + 2) % 3];
          if (p != j || q != i) continue;
          const int dome_a = a < m->dome_triangle_count, dome_b = b < m->dome_triangle_count;
          if (!dome_a && !dome_b) continue;
          if (!(dome_a && dome_b) && release >= 1.0) continue;
          if (m->fixed[i] && m->fixed[j] && m->fixed[c] && m->fixed[d]) continue;
          if (n == cap) return -1;
          test_hinge *h = &out[n++];
          h->v[0] = i, h->v[1] = j, h->v[2] = c, h->v[3] = d;
          palp_hinge_gradient(m->rest[i], m->rest[j], m->rest[c], m->rest[d], h->g);
          h->th0 = palp_hinge_angle(m->rest[i], m->rest[j], m->rest[c], m->rest[d]);
        }
    }
  return n;
}

/* Largest |true - linear| turn over the hinges at positions x [rad], and the largest
 * linear turn in *lin_max. */
static double hinge_error(const test_hinge *hs, int n, const palp_mesh *m, const palp_vec3 *x, double *lin_max) {
  double worst = 0.0;
  *lin_max = 0.0;
  for (int e = 0; e < n; ++e) {
    const test_hinge *h = &hs[e];
    double lin = 0.0;
    for (int k = 0; k < 4; ++k) lin += v3_dot(h->g[k], v3_sub(x[h->v[k]], m->rest[h->v[k]]));
    const double tr = palp_hinge_angle(x[h->v[0]], x[h->v[1]], x[h->v[2]], x[h->v[3]]) - h->th0;
    worst = fmax(worst, fabs(tr - lin));
    *lin_max = fmax(*lin_max, fabs(lin));
  }
  return worst;
}

/* The pole's settled depth [m] under 0.5 N on its vertex, on a skin of bending
 * stiffness D whose stretching is negligible; the world's health, and the test's own
 * largest |true - linear| hinge turn at the end [rad] in *err. */
static double pole_static(double D, palp_world_health *health, double *err) {
  palp_world_def d = palp_world_default_def();
  d.mesh.vertex_count = 5000;
  d.effects = PALP_EFFECT_MEMBRANE_ELASTICITY | PALP_EFFECT_GEL_SUPPORT | PALP_EFFECT_GEL_DAMPING;
  d.membrane.E1 = d.membrane.E2 = 1.0;       /* [Pa]: stretching negligible (E t / R^2 ~ 1 Pa/m) */
  d.membrane.bending_stiffness = D;           /* [N m] */
  d.gel.support_modulus = 1e6;                /* [Pa/m] */
  d.gel.support_viscosity = 2e4;              /* [Pa s/m]: settles in ~0.1 s */
  d.gel.support_bulk_fraction = 0.0;
  d.max_contacts = 1;
  int e;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) return NAN;
  const palp_contact_def cd = palp_contact_default_def(PALP_DIST_SINGLE, v3(0, 0, d.mesh.radius));
  const int c = palp_world_add_contact(w, &cd);
  palp_world_set_contact_force(w, c, v3(0, 0, -0.5));
  double z = 0.0, zprev = 1.0;
  for (int k = 0; k < 400 && fabs(z - zprev) > 1e-9; ++k) {
    palp_world_step(w);
    zprev = z;
    z = d.mesh.radius - palp_world_positions(w)[palp_world_mesh(w)->top_vertex].z;
  }
  palp_world_get_health(w, health);
  *err = NAN;
  test_hinge *hs = malloc(sizeof *hs * 20000);
  const int nh = hs ? test_hinges(palp_world_mesh(w), 0.0, hs, 20000) : -1;
  double lin;
  if (nh > 0) *err = hinge_error(hs, nh, palp_world_mesh(w), palp_world_positions(w), &lin);
  free(hs);
  palp_world_destroy(w);
  return z;
}

static void check_replay(void) {
  palp_scene a, b;
  char err[256];
  if (palp_scene_load(PALP_CONFIG_DIR "/paper_step_long_term.json", &a, err, sizeof err)) {
    CHECK(0, "long-term scene: %s", err);
    return;
  }
  char *json = palp_scene_to_json(&a);
  const int rc = json ? palp_scene_parse(json, &b, err, sizeof err) : -1;
  free(json);
  CHECK(rc == 0, "the written scene parses back: %s", rc ? err : "");
  if (rc) return;
  CHECK(a.world.membrane.bending_stiffness > 0 && memcmp(&a.world.membrane.bending_stiffness, &b.world.membrane.bending_stiffness,
                                                         sizeof(double)) == 0,
        "bending stiffness %.17g written and read back as %.17g", a.world.membrane.bending_stiffness,
        b.world.membrane.bending_stiffness);
  CHECK(a.world.membrane.rim_hinge_release > 0 &&
            memcmp(&a.world.membrane.rim_hinge_release, &b.world.membrane.rim_hinge_release, sizeof(double)) == 0,
        "rim hinge release %.17g written and read back as %.17g", a.world.membrane.rim_hinge_release,
        b.world.membrane.rim_hinge_release);
  CHECK(a.world.membrane.skin_bending_stiffness > 0 &&
            memcmp(&a.world.membrane.skin_bending_stiffness, &b.world.membrane.skin_bending_stiffness, sizeof(double)) == 0,
        "skin bending stiffness %.17g written and read back as %.17g", a.world.membrane.skin_bending_stiffness,
        b.world.membrane.skin_bending_stiffness);
  palp_world *wa = palp_scene_create_world(&a, NULL), *wb = palp_scene_create_world(&b, NULL);
  CHECK(wa && wb, "worlds from both scenes");
  if (!wa || !wb) return;
  for (int i = 0; i < a.contact_count; i++) palp_world_remove_contact(wa, i), palp_world_remove_contact(wb, i);
  const int fa = palp_world_add_finger(wa, v3(0, 0, 0.05), 0.008), fb = palp_world_add_finger(wb, v3(0, 0, 0.05), 0.008);
  int same = 1;
  for (int k = 0; k < 300; ++k) {
    const palp_vec3 dev = v3(0.002 * sin(0.05 * k), 0, 0.048 - 0.004 * sin(0.02 * k)); /* up to 4 mm deep */
    palp_world_set_finger(wa, fa, dev, 0.008), palp_world_set_finger(wb, fb, dev, 0.008);
    palp_world_step(wa), palp_world_step(wb);
    same &= palp_world_hash(wa) == palp_world_hash(wb);
  }
  palp_world_health h;
  palp_world_get_health(wa, &h);
  printf("long-term scene through JSON: D %.9g N m both ways; 300 frames of a finger: hashes %s; max hinge turn %.3f rad\n",
         b.world.membrane.bending_stiffness, same ? "equal" : "DIFFER", h.max_bend);
  CHECK(same, "equal state hashes every frame (tolerance 0)");
  CHECK(h.max_bend > 0.0, "the finger bent the skin");
  palp_world_destroy(wa), palp_world_destroy(wb);
}

static void check_valid_range(void) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome.json", &sc, err, sizeof err)) {
    CHECK(0, "breast-tissue dome: %s", err);
    return;
  }
  sc.contact_count = 0;
  palp_world *w = palp_scene_create_world(&sc, NULL);
  CHECK(w != NULL, "breast-tissue dome's world");
  if (!w) return;
  const palp_mesh *m = palp_world_mesh(w);
  enum { CAP = 4096 };
  test_hinge *hs = malloc(sizeof *hs * CAP);
  const int nh = hs ? test_hinges(m, sc.world.membrane.rim_hinge_release, hs, CAP) : -1;
  CHECK(nh > 900, "the test's hinges (%d)", nh);
  if (nh <= 900) {
    free(hs), palp_world_destroy(w);
    return;
  }
  const double R = sc.world.mesh.radius, r = 0.008, dt = sc.world.dt;
  /* the set's range: 0.1 rad, or the miss its validated presses reached where larger */
  const double limit = palp_world_hinge_range(&sc.world);
  CHECK_NEAR(limit, fmax(PALP_HINGE_LINEAR_ERR_MAX, sc.world.validated_hinge_error), 0.0, "the world's hinge range");
  const palp_vec3 start = v3(0, 0, R + r);
  const int f = palp_world_add_finger(w, start, r);
  const int per_level = (int)lround(0.5 / dt), sweep = (int)ceil(PALP_HINGE_CHECK_PERIOD / dt);
  double depth = 0.0, worst = 0.0;
  long first_seen = -1, first_counted = -1, k = 0;
  palp_world_health h8 = {0};
  double err8 = 0.0, lin8 = 0.0, lin = 0.0;
  for (int level = 1; level <= 15; ++level)
    for (int t = 0; t < per_level; ++t, ++k) {
      if (depth < 0.002 * level) depth = fmin(0.002 * level, depth + 0.01 * dt); /* 10 mm/s */
      palp_world_set_finger_device(w, f, v3(0, 0, start.z - depth));
      palp_world_step(w);
      const double e = hinge_error(hs, nh, m, palp_world_positions(w), &lin);
      worst = fmax(worst, e);
      if (first_seen < 0 && e > limit) first_seen = k;
      palp_world_health h;
      palp_world_get_health(w, &h);
      if (first_counted < 0 && h.large_bend_steps > 0) first_counted = k;
      if (level == 4 && t == per_level - 1) h8 = h, err8 = e, lin8 = lin;
    }
  /* and back up at 10 mm/s, then 0.5 s off the surface */
  palp_world_health h;
  palp_world_get_health(w, &h);
  const long pressed = k;
  const int64_t counted_pressed = h.large_bend_steps;
  long last_seen = -1, last_counted = -1;
  int64_t prev = h.large_bend_steps;
  for (int t = 0; t < (int)lround(3.2 / dt); ++t, ++k) {
    depth = fmax(0.0, depth - 0.01 * dt);
    palp_world_set_finger_device(w, f, v3(0, 0, start.z - depth));
    palp_world_step(w);
    const double e = hinge_error(hs, nh, m, palp_world_positions(w), &lin);
    worst = fmax(worst, e);
    if (e > limit) last_seen = k;
    palp_world_get_health(w, &h);
    if (h.large_bend_steps > prev) last_counted = k;
    prev = h.large_bend_steps;
  }
  printf("breast-tissue dome, fingertip at the pole: at 8 mm the largest linear turn %.3f rad, its error %.3f rad "
         "(world %.3f), %lld steps counted; to 30 mm and back the error reached %.3f rad (world %.3f), first beyond %.3f rad "
         "at step %ld, counted from step %ld (a sweep is %d steps), %lld steps counted\n",
         lin8, err8, h8.max_bend_error, (long long)h8.large_bend_steps, worst, h.max_bend_error, limit, first_seen,
         first_counted, sweep, (long long)counted_pressed);
  printf("  lifted: the error last beyond the range at step %ld, last counted at step %ld (the press ended at step %ld); "
         "%lld steps counted pressing, %lld lifting\n",
         last_seen, last_counted, pressed, (long long)counted_pressed, (long long)(h.large_bend_steps - counted_pressed));
  CHECK(last_counted <= last_seen + sweep && last_seen < k - sweep,
        "lifting: counting stops within a sweep (%d steps) of the error falling back (step %ld; last counted %ld)",
        sweep, last_seen, last_counted);
  CHECK(lin8 > 0.35 && err8 < PALP_HINGE_LINEAR_ERR_MAX && h8.large_bend_steps == 0,
        "8 mm: turned %.3f rad (past the former 0.35), off by %.3f rad, no step counted (%lld)", lin8, err8,
        (long long)h8.large_bend_steps);
  CHECK(first_seen >= 0 && first_counted >= first_seen && first_counted <= first_seen + sweep,
        "counted from step %ld, not before the error passed %.3f rad (step %ld) and within a sweep (%d steps)",
        first_counted, limit, first_seen, sweep);
  CHECK(h.max_bend_error <= worst + 1e-12 && h.max_bend_error >= 0.9 * worst,
        "the world's largest error %.4f rad within 10%% below the test's %.4f rad (it checks a share per step)",
        h.max_bend_error, worst);
  free(hs);
  palp_world_destroy(w);
}

int main(void) {
  check_gradient();
  check_replay();
  check_valid_range();
  {
    const double k = 1e6, F = 0.5, D = k * pow(0.005, 4); /* [Pa/m], [N], [N m]: l = 5 mm */
    palp_world_health hb, h4, h0;
    double eb, e4, e0;
    const double wb = pole_static(D, &hb, &eb), w4 = pole_static(4.0 * D, &h4, &e4), w0 = pole_static(0.0, &h0, &e0);
    const double plate = F / (8.0 * sqrt(D * k)); /* [m] */
    printf("point load %.1f N at the pole: %.4f mm with bending (plate on foundation %.4f mm, ratio %.3f), "
           "%.4f mm with 4 D (ratio to D %.3f, plate 0.5), %.3f mm without; largest hinge rotation %.3f rad\n",
           F, 1e3 * wb, 1e3 * plate, wb / plate, 1e3 * w4, w4 / wb, 1e3 * w0, hb.max_bend);
    CHECK(fabs(wb / plate - 1.0) <= 0.20, "pole under a point load %.4f mm vs the plate's %.4f mm (tolerance 20%%)",
          1e3 * wb, 1e3 * plate);
    CHECK(fabs(w4 / wb - 0.5) <= 0.05, "4 D gives %.3f of the depth (plate 0.5, tolerance 0.05)", w4 / wb);
    CHECK(w0 > 10.0 * wb, "without bending the pole sinks %.3f mm (> 10x %.4f mm)", 1e3 * w0, 1e3 * wb);
    /* With stretching negligible nothing holds the net in its plane: the triangles
     * around the loaded vertex slide by up to an edge (1.4 mm), and their true angles
     * leave the linear ones (0.83 rad off at a 0.04 rad linear turn). The turn alone
     * (0.19 rad) said the hinges were in range; the range check says they are not. */
    printf("  its linearisation: off by %.3f rad at the end (the test's hinges), %.3f rad (world), %lld steps counted\n",
           eb, hb.max_bend_error, (long long)hb.large_bend_steps);
    CHECK(hb.max_bend > 0.0, "hinge rotation %.4f rad reported", hb.max_bend);
    CHECK(eb > PALP_HINGE_LINEAR_ERR_MAX && hb.max_bend_error >= 0.9 * eb && hb.large_bend_steps > 0,
          "the distorted net counted beyond the range: test %.3f rad, world %.3f rad (at least 90%% of it)", eb,
          hb.max_bend_error);
  }
  for (int k = 0; k < 4; ++k) {
    const double phi = 0.37 * k;
    const double rc = lattice_ratio(phi, 0), rs = lattice_ratio(phi, 1);
    printf("lattice turned %.2f rad: cylindrical %.12f, spherical (nu = -1/3) %.12f of the plate's energy\n", phi, rc, rs);
    CHECK_NEAR(rc, 1.0, 1e-9, "cylindrical bending energy / plate");
    CHECK_NEAR(rs, 1.0, 1e-9, "spherical bending energy / plate with nu = -1/3");
  }
  CHECK_DONE();
}
