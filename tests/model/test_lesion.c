/*
 * test_lesion.c - lesions in the real-time model (docs/haptics.md, "Lesions"): the
 * support scale against an independent numerical integration, the force a fingertip
 * feels over a lesion, and the scene format.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "palp.h"

#define PI 3.14159265358979323846
static const double R = 0.04, r = 0.008;

/* Trapezoid integration of the Boussinesq weight along the column (independent of the closed
 * forms in src/lesion.c): at each z the chord's compliance is the smallest q[l] of the lesions
 * containing the point (the stiffest), or the gel's (1). Written from the rule, not from
 * src/lesion.c's chord merging. */
static double column_scale_numeric_qs(const palp_lesion *L, const double *q, int count, palp_vec3 x, palp_vec3 n,
                                      double length) {
  const double c = PALP_LESION_CONTACT_SCALE;
  const int N = 200000;
  double C0 = 0.0, C = 0.0;
  for (int k = 0; k < N; ++k) {
    const double z = (k + 0.5) * length / N;
    const double s = 1.0 - z * z * z / pow(c * c + z * z, 1.5);
    double qz = 1.0;
    int in = 0;
    for (int l = 0; l < count; ++l) {
      const palp_vec3 p = {x.x - z * n.x - L[l].center.x, x.y - z * n.y - L[l].center.y, x.z - z * n.z - L[l].center.z};
      if (p.x * p.x + p.y * p.y + p.z * p.z <= L[l].radius * L[l].radius) qz = in++ ? fmin(qz, q[l]) : q[l];
    }
    C0 += s;
    C += s * qz;
  }
  return C0 / C;
}

/* One lesion of chord compliance q (a cyst's may exceed 1). */
static double column_scale_numeric_q(const palp_lesion *L, palp_vec3 x, palp_vec3 n, double length, double q) {
  return column_scale_numeric_qs(L, &q, 1, x, n, length);
}

/* A stiff lesion in series with the column: q = 1 / ratio. */
static double column_scale_numeric(const palp_lesion *L, palp_vec3 x, palp_vec3 n, double length) {
  return column_scale_numeric_q(L, x, n, length, 1.0 / L->stiffness_ratio);
}

/* Several stiff lesions, each q = 1 / its ratio (count <= 8). */
static double column_scale_numeric_many(const palp_lesion *L, int count, palp_vec3 x, palp_vec3 n, double length) {
  double q[8];
  for (int l = 0; l < count && l < 8; ++l) q[l] = 1.0 / L[l].stiffness_ratio;
  return column_scale_numeric_qs(L, q, count < 8 ? count : 8, x, n, length);
}

/* Overlapping lesions (session 82's review): each chord was subtracted in full, so a lesion listed
 * twice made the column's compliance negative and the 1e-3 floor a 1000x stiffer support (2.382
 * for one stiff lesion 2..14 mm deep, 1000 for the same twice). Now: listed twice = once (to
 * 1e-12), and a harder core inside a mass, or two lesions that overlap in part, match the
 * numerical integration of the stiffest-lesion rule to 1e-4. */
static void test_overlap(void) {
  const palp_vec3 pole = {0, 0, R}, up = {0, 0, 1};
  const palp_lesion one = {.center = {0, 0, R - 0.008}, .radius = 0.006, .stiffness_ratio = 5.0};
  const double ratios[2] = {5.0, 20.0}; /* before: 13.96 and 1000 (the floor) listed twice */
  for (int i = 0; i < 2; ++i) {
    palp_lesion l1 = one;
    l1.stiffness_ratio = ratios[i];
    const palp_lesion twice[2] = {l1, l1};
    const double s1 = palp_lesion_support_scale(&l1, 1, pole, up, R), s2 = palp_lesion_support_scale(twice, 2, pole, up, R);
    printf("a %gx lesion 2..14 mm deep at the pole: support scale %.6f once, %.6f listed twice\n", ratios[i], s1, s2);
    CHECK(fabs(s2 - s1) < 1e-12 * s1, "a %gx lesion listed twice: support scale %.6f, once %.6f", ratios[i], s2, s1);
  }
  const palp_lesion core[2] = {one, {.center = {0, 0, R - 0.009}, .radius = 0.002, .stiffness_ratio = 20.0}};
  const palp_lesion part[2] = {one, {.center = {0.002, 0, R - 0.015}, .radius = 0.005, .stiffness_ratio = 3.0}};
  for (int k = 0; k < 3; ++k) {
    const double th = k * 3.0 * PI / 180.0;
    const palp_vec3 n = {sin(th), 0, cos(th)}, x = {R * n.x, 0, R * n.z};
    const double a = palp_lesion_support_scale(core, 2, x, n, R), b = column_scale_numeric_many(core, 2, x, n, R);
    const double c = palp_lesion_support_scale(part, 2, x, n, R), d = column_scale_numeric_many(part, 2, x, n, R);
    printf("overlapping lesions %d deg off the pole: core in a mass %.6f (numerical %.6f), in part %.6f (%.6f)\n",
           3 * k, a, b, c, d);
    CHECK_NEAR(a, b, 1e-4 * b, "a 20x core inside a 5x mass: closed form vs numerical integration");
    CHECK_NEAR(c, d, 1e-4 * d, "two lesions overlapping in part: closed form vs numerical integration");
  }
}

/* The fingertip pressed at the pole to depth and held; the force's magnitude [N], and
 * the world's state hash then (when hash is not NULL). */
static double press_def(palp_world_def d, const palp_lesion *les, int count, double depth, uint64_t *hash) {
  d.dt = 0.001;
  d.lesion_count = count;
  for (int i = 0; i < count; ++i) d.lesion[i] = les[i];
  int err = 0;
  palp_world *w = palp_world_create(&d, &err);
  CHECK(w != NULL, "world with %d lesions: %s", count, palp_strerror(err));
  if (!w) return NAN;
  palp_vec3 dev = {0, 0, R + r + 0.001};
  const int f = palp_world_add_finger(w, dev, r);
  double z = -0.001;
  for (int k = 0; k < 4000; ++k) {
    if (z < depth) z += 1e-5; /* 10 mm/s, then hold */
    dev.z = R + r - z;
    palp_world_set_finger_device(w, f, dev);
    palp_world_step(w);
  }
  palp_local_model lm;
  palp_world_finger_local_model(w, f, &lm);
  if (hash) *hash = palp_world_hash(w);
  palp_world_destroy(w);
  return sqrt(lm.force.x * lm.force.x + lm.force.y * lm.force.y + lm.force.z * lm.force.z);
}

static double press_force(const palp_lesion *les, int count, double depth) {
  return press_def(palp_world_default_def(), les, count, depth, NULL);
}

/* 4. The hinges' gel part sees a stiff lesion (membrane.skin_bending_stiffness_N_m,
 * docs/haptics.md "The hinges see the lesion"), on the shipped breast-tissue set. Exact
 * properties: without lesions the world is bit for bit the one without the split (the
 * same state hash after the press); over the 10 mm 5x lesion 10 mm deep the gain with the
 * device 5 mm in grows, and over a 0.2x cyst there the loss deepens (since 2026-11-29), by
 * more than 0.5 and 0.2 points. The split's share is the gel's part of D, D - D_skin: since
 * the refit against the refined fingertip FE (2026-11-30) D is 1.75x the skin's own, not
 * 3.6x, and the split moves the gain +12.99% -> +14.02% and the loss -5.34% -> -5.76%
 * (before: +8.4% -> +11.6% and -3.4% -> -4.8%, asserted as 2 and 1 points). The gain
 * against the refined FE and the loss against the level-4 FE are checked by
 * eval_finger_refined and eval_finger_breast_tissue. */
static void test_hinges_see_lesion(void) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome.json", &sc, err, sizeof err) != 0) {
    CHECK(0, "breast-tissue dome: %s", err);
    return;
  }
  palp_world_def split = sc.world, plain = sc.world;
  CHECK(split.membrane.skin_bending_stiffness > 0.0 && split.membrane.skin_bending_stiffness < split.membrane.bending_stiffness,
        "the shipped set names the skin's share of D (%g of %g N m)", split.membrane.skin_bending_stiffness,
        split.membrane.bending_stiffness);
  plain.membrane.skin_bending_stiffness = 0.0;
  const palp_lesion lump = {.center = {0, 0, R - 0.010}, .radius = 0.005, .stiffness_ratio = 5.0};
  const palp_lesion cyst = {.center = {0, 0, R - 0.010}, .radius = 0.005, .stiffness_ratio = 0.2};
  uint64_t ha = 0, hb = 1;
  const double F0s = press_def(split, NULL, 0, 0.005, &ha), F0p = press_def(plain, NULL, 0, 0.005, &hb);
  CHECK(ha == hb && F0s == F0p, "no lesion: the same world with and without the split (hash %016llx / %016llx)",
        (unsigned long long)ha, (unsigned long long)hb);
  const double Fcs = press_def(split, &cyst, 1, 0.005, NULL), Fcp = press_def(plain, &cyst, 1, 0.005, NULL);
  const double cs = Fcs / F0s - 1.0, cp = Fcp / F0p - 1.0;
  printf("breast-tissue dome, 5 mm at the pole over a 0.2x cyst there: loss %+.2f%% with the split, %+.2f%% support "
         "only\n", 100 * cs, 100 * cp);
  CHECK(cp < 0.0 && cs < cp - 0.002, "a soft cyst: the split deepens its loss by more than 0.2 points (%+.2f%% against "
        "%+.2f%%)", 100 * cs, 100 * cp);
  const double Fls = press_def(split, &lump, 1, 0.005, NULL), Flp = press_def(plain, &lump, 1, 0.005, NULL);
  const double gs = Fls / F0s - 1.0, gp = Flp / F0p - 1.0;
  printf("breast-tissue dome, 5 mm at the pole over the 10 mm 5x lesion 10 mm deep: gain %+.2f%% with the split, "
         "%+.2f%% support only\n", 100 * gs, 100 * gp);
  CHECK(gs > gp + 0.005, "the split raises the lesion's gain by more than 0.5 points (%+.2f%% against %+.2f%%)", 100 * gs,
        100 * gp);
}

/* The base cuts the support's column (gel.support_base_reach, palp.h): the scale of a column
 * of length l against the full one, S(R) / S(l), against trapezoid integration of the weight
 * over both (independent of the closed form); 1 at the pole; the world's per-vertex scale follows
 * R - f (R - z); the parameter round-trips through a scene. (f = 0 takes the code path of before,
 * whose bits bench_model_step --hash showed unchanged.) */
static double column_numeric(double length) {
  const double c = PALP_LESION_CONTACT_SCALE;
  const int N = 200000;
  double C = 0.0;
  for (int k = 0; k < N; ++k) {
    const double z = (k + 0.5) * length / N;
    C += (1.0 - z * z * z / pow(c * c + z * z, 1.5)) * length / N;
  }
  return C;
}

static void test_base_column(void) {
  const palp_vec3 pole = {0, 0, R}, up = {0, 0, 1};
  CHECK(palp_support_column_scale(NULL, 0, pole, up, R, R) == 1.0, "a full column: exactly 1");
  /* 70 deg: the base lies R cos 70 = 13.7 mm under the surface */
  const double th = 70.0 * PI / 180.0, z = R * cos(th);
  const palp_vec3 n = {sin(th), 0, cos(th)}, x = {R * n.x, 0, R * n.z};
  const double a = palp_support_column_scale(NULL, 0, x, n, z, R), b = column_numeric(R) / column_numeric(z);
  printf("base column at 70 deg (%.1f mm): support x%.4f (numerical %.4f)\n", 1e3 * z, a, b);
  CHECK_NEAR(a, b, 1e-4 * b, "base column: closed form vs numerical integration");
  CHECK(a > 1.3 && a < 1.5, "the base stiffens the support at 70 deg by 30-50%% (x%.3f)", a);
  /* with a lesion the chord is cut by the shorter column too: equal to the lesion scale of the
   * short column times S(R) / S(l) */
  const palp_lesion L = {.center = {0, 0, R - 0.010}, .radius = 0.005, .stiffness_ratio = 5.0};
  const double l = 0.012, cut = palp_support_column_scale(&L, 1, pole, up, l, R);
  const double cutn = column_scale_numeric(&L, pole, up, l) * column_numeric(R) / column_numeric(l);
  CHECK_NEAR(cut, cutn, 1e-4 * cutn, "lesion in a cut column: closed form vs numerical");
  /* the world: vertex scales against the formula at each vertex's height, f = 0.6 */
  palp_scene sc;
  char err[256];
  CHECK(palp_scene_load(PALP_CONFIG_DIR "/paper_step_long_term.json", &sc, err, sizeof err) == 0, "scene: %s", err);
  palp_world_def d = sc.world;
  CHECK(d.gel.support_base_reach == 0.0, "absent from a parameter file: 0");
  const double F0 = press_def(d, NULL, 0, 2e-3, NULL);
  d.gel.support_base_reach = 0.6;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w != NULL, "world with support_base_reach 0.6: %s", palp_strerror(e));
  if (w) {
    const palp_mesh *m = palp_world_mesh(w);
    double worst = 0.0, top = 0.0;
    for (int i = 0; i < m->vertex_count; ++i) {
      if (m->fixed[i]) continue;
      const palp_vec3 p = m->rest[i];
      const double rl = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      const double want = column_numeric(rl) / column_numeric(fmax(rl - 0.6 * (rl - p.z), 1e-3));
      worst = fmax(worst, fabs(palp_world_support_scale(w, i) / want - 1.0));
      top = fmax(top, palp_world_support_scale(w, i));
    }
    printf("support_base_reach 0.6: per-vertex scales up to x%.3f, worst against the numerical %.2e\n", top, worst);
    CHECK(worst < 1e-4, "per-vertex scale vs numerical integration (worst %.2e, bound 1e-4)", worst);
    palp_world_destroy(w);
  }
  const double F6 = press_def(d, NULL, 0, 2e-3, NULL);
  CHECK(F6 >= F0 && F6 < 1.05 * F0, "at the pole the cut barely matters: %.4f N against %.4f N (within 0-5%%)", F6, F0);
  /* the scene format round-trips it and refuses it out of range */
  sc.world.gel.support_base_reach = 0.6;
  char *out = palp_scene_to_json(&sc);
  palp_scene s2;
  CHECK(out && palp_scene_parse(out, &s2, err, sizeof err) == 0 && s2.world.gel.support_base_reach == 0.6,
        "support_base_reach round-trips: %s", err);
  /* out of range: refused, naming the field */
  char *at = out ? strstr(out, "\"support_base_reach\"") : NULL;
  if (at) {
    at = strchr(at, '0'); /* the value's leading digit: 0.6 -> 2.6 */
    if (at) *at = '2';
  }
  if (at) {
    CHECK(palp_scene_parse(out, &s2, err, sizeof err) != 0 && strstr(err, "support_base_reach"),
          "support_base_reach 2.6 is refused, naming the field (%s)", err);
  }
  CHECK(at != NULL, "the printed scene holds support_base_reach");
  free(out);
}

int main(void) {
  test_overlap();
  /* 1. The closed form against numerical integration, on and off the lesion's axis. */
  const palp_lesion L = {.center = {0, 0, R - 0.010}, .radius = 0.005, .stiffness_ratio = 5.0};
  for (int k = 0; k < 4; ++k) {
    const double th = k * 4.0 * PI / 180.0;
    const palp_vec3 n = {sin(th), 0, cos(th)}, x = {R * n.x, 0, R * n.z};
    const double a = palp_lesion_support_scale(&L, 1, x, n, R), b = column_scale_numeric(&L, x, n, R);
    printf("support scale %2d deg from the lesion's axis: %.6f (numerical %.6f)\n", 4 * k, a, b);
    CHECK_NEAR(a, b, 1e-4 * b, "closed form vs numerical integration");
  }
  const palp_vec3 pole = {0, 0, R}, up = {0, 0, 1};
  CHECK(palp_lesion_support_scale(&L, 0, pole, up, R) == 1.0, "no lesion: exactly 1");
  const palp_lesion cyst = {.center = L.center, .radius = L.radius, .stiffness_ratio = 0.2};
  CHECK(palp_lesion_support_scale(&cyst, 1, pole, up, R) < 1.0, "a soft cyst softens the support");
  /* A soft cyst strains as Eshelby's sphere in an incompressible matrix, not as a chord in
   * series: its strain over the matrix's is 1 / (1 + beta (ratio - 1)), beta = 2 (4 - 5 nu) /
   * (15 (1 - nu)) at nu = 0.5 (Eshelby 1957; Mura, "Micromechanics of Defects in Solids",
   * Sec. 22), i.e. 1 / 0.68 = 1.47 for 0.2x, not 5. */
  const double nu = 0.5, beta = 2.0 * (4.0 - 5.0 * nu) / (15.0 * (1.0 - nu));
  const double q_cyst = 1.0 / (1.0 + beta * (0.2 - 1.0));
  CHECK_NEAR(q_cyst, 1.0 / 0.68, 1e-12, "Eshelby's strain ratio of a 0.2x sphere");
  for (int k = 0; k < 4; ++k) {
    const double th = k * 4.0 * PI / 180.0;
    const palp_vec3 n = {sin(th), 0, cos(th)}, x = {R * n.x, 0, R * n.z};
    const double a = palp_lesion_support_scale(&cyst, 1, x, n, R), b = column_scale_numeric_q(&cyst, x, n, R, q_cyst);
    const double series = column_scale_numeric(&cyst, x, n, R);
    printf("cyst (0.2x) support scale %2d deg from its axis: %.6f (numerical %.6f; in series it would be %.6f)\n", 4 * k,
           a, b, series);
    CHECK_NEAR(a, b, 1e-4 * b, "cyst: closed form vs numerical integration with Eshelby's strain ratio");
    if (k == 0) CHECK(a > 0.8 && series < 0.4, "load goes round a cyst: support x%.3f (in series x%.3f)", a, series);
  }

  /* 2. What a fingertip feels 10 mm deep at the pole over a 10 mm lesion. */
  const double F0 = press_force(NULL, 0, 0.010);
  const double Fh = press_force(&L, 1, 0.010);
  palp_lesion deep = L;
  deep.center.z = R - 0.020;
  const double Fd = press_force(&deep, 1, 0.010);
  const double Fc = press_force(&cyst, 1, 0.010);
  printf("fingertip 10 mm deep at the pole: %.4f N without a lesion; over a 10 mm lesion (5x) 10 mm deep %.4f N "
         "(%+.1f%%), 20 mm deep %.4f N (%+.1f%%); over a soft cyst (0.2x) %.4f N (%+.1f%%)\n",
         F0, Fh, 100 * (Fh / F0 - 1), Fd, 100 * (Fd / F0 - 1), Fc, 100 * (Fc / F0 - 1));
  /* Measured +4.9% on the shipped phantom, whose support carries under half the force
   * at this depth (docs/haptics.md: the 20% needs the material rework). */
  CHECK(Fh > F0 * 1.03, "a hard lesion raises the force by more than 3%% (%+.2f%%)", 100 * (Fh / F0 - 1));
  /* The FE reference's figure for the same lesion (src/fem, level 2, long-term paper
   * material, rigid 8 mm sphere at the pole): +4.7% to +5.3% from 0.25 to 2 mm deep,
   * +5.0% at 1 mm (regenerate: palp-fem finger --scene config/paper_step.json
   * --reading long_term --site pole,pole_lesion; docs/fem.md). Not at equal depth:
   * today's real-time parameters are ~1000x softer than the long-term FEM, so at the
   * FE's 1 mm the real-time force is 2 mN and its gain is noise; the check says the
   * two models give the lesion the same weight, within 15% of the FE's gain. */
  const double fem_gain = 0.050;
  CHECK(fabs((Fh / F0 - 1) / fem_gain - 1) <= 0.15, "real-time lesion gain %+.2f%% within 15%% of the FE's %+.1f%%",
        100 * (Fh / F0 - 1), 100 * fem_gain);
  CHECK(Fd > F0 && Fd < Fh, "a deeper lesion is felt less (%.4f N between %.4f and %.4f N)", Fd, F0, Fh);
  CHECK(Fc < F0, "a soft cyst lowers the force (%.4f < %.4f N)", Fc, F0);

  /* 3. The scene format: lesions round-trip; a lesion outside the dome is refused by name. */
  palp_scene s;
  char err[256];
  const char *json = "{\"name\": \"lump\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 338},"
                     " \"parameters\": \"" PALP_CONFIG_DIR "/params/calibrated.json\","
                     " \"time\": {\"dt_s\": 0.01, \"frames\": 1}, \"effects\": [\"gel_support\"],"
                     " \"lesions\": [{\"center_m\": [0.0, 0.0, 0.03], \"radius_m\": 0.005, \"stiffness_ratio\": 5}],"
                     " \"contacts\": []}";
  CHECK(palp_scene_parse_in(json, NULL, &s, err, sizeof err) == 0, "scene with a lesion: %s", err);
  CHECK(s.world.lesion_count == 1 && s.world.lesion[0].stiffness_ratio == 5.0, "lesion parsed");
  char *out = palp_scene_to_json(&s);
  palp_scene s2;
  CHECK(out && palp_scene_parse(out, &s2, err, sizeof err) == 0, "round trip: %s", err);
  CHECK(s2.world.lesion_count == 1 && s2.world.lesion[0].center.z == 0.03 && s2.world.lesion[0].radius == 0.005,
        "round trip keeps the lesion");
  free(out);
  const char *bad = "{\"name\": \"lump\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 338},"
                    " \"parameters\": \"" PALP_CONFIG_DIR "/params/calibrated.json\","
                    " \"time\": {\"dt_s\": 0.01, \"frames\": 1}, \"effects\": [],"
                    " \"lesions\": [{\"center_m\": [0.0, 0.0, 0.038], \"radius_m\": 0.005, \"stiffness_ratio\": 5}],"
                    " \"contacts\": []}";
  CHECK(palp_scene_parse_in(bad, NULL, &s, err, sizeof err) != 0 && strstr(err, "lesions[0]"),
        "a lesion through the surface is refused, naming lesions[0] (%s)", err);
  test_hinges_see_lesion();
  test_base_column();
  CHECK_DONE();
}
