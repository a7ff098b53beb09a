/*
 * test_support_stiffening.c - the support that stiffens as the gel column under a vertex
 * is strained (gel.support_stiffening beta, gel.support_stiffening_power p; docs/model.md,
 * "The support stiffens near the base"): a free vertex displaced by u, over the gel's
 * height H above the base at its rest position, meets -k A (1 + beta (|u| / H)^p) u.
 *
 * - Closed form: with the support alone (no membrane, no gel pressure, no bulk shift) a
 *   vertex under a held force F comes to rest where k A u (1 + beta (u / H)^p) = F, solved
 *   here by bisection; the model must agree within 0.5% once settled, for a vertical load
 *   at the pole (H = 40 mm) and a sideways one near the rim (H ~ 8 mm), and its force
 *   feedback must balance the load within 0.5%.
 * - beta = 0 is the linear support bit for bit (the same positions after a finger press).
 * - On the shipped breast-tissue dome, a fingertip at the pole feels the same force at
 *   1 mm with and without the stiffening (within 1%: (1/40)^3 beta is 2e-4), and more at
 *   16 mm (at least 8% more: the FE asked for +22% there, docs/model.md); a press at
 *   70 deg to 12 mm of device depth stays in contact, its force monotone in depth (to
 *   0.5% of the largest), at 250 Hz and at 1 kHz.
 * - The two fields parse, serialise and are refused out of range, naming the field.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common.h"
#include "vec3.h"

static const double PI = 3.14159265358979323846;

/* u with k A u (1 + beta (u / H)^p) = F, by bisection (the left side rises with u). */
static double closed_form(double kA, double beta, double p, double H, double F) {
  double lo = 0.0, hi = F / kA;
  for (int i = 0; i < 200; ++i) {
    const double u = 0.5 * (lo + hi);
    if (kA * u * (1.0 + beta * pow(u / H, p)) > F) hi = u;
    else lo = u;
  }
  return 0.5 * (lo + hi);
}

/* Loads vertex v with F along dir for 0.4 s (the vertex settles in ~20 ms); returns the
 * displacement along dir and, in *fb, the feedback's component against dir. */
static double settle(const palp_world_def *d, int v, palp_vec3 dir, double F, double *fb) {
  int e = 0;
  palp_world *w = palp_world_create(d, &e);
  CHECK(w != NULL, "world: %s", palp_strerror(e));
  if (!w) return NAN;
  const palp_mesh *mesh = palp_world_mesh(w);
  palp_contact_def c = palp_contact_default_def(PALP_DIST_SINGLE, mesh->rest[v]);
  const int id = palp_world_add_contact(w, &c);
  palp_world_set_contact_force(w, id, v3_scale(dir, F));
  for (int s = 0; s < 400; ++s) palp_world_step(w);
  const double u = v3_dot(v3_sub(palp_world_positions(w)[v], mesh->rest[v]), dir);
  palp_vec3 total;
  palp_world_contact_feedback(w, id, &total);
  *fb = -v3_dot(total, dir);
  palp_world_destroy(w);
  return u;
}

static void test_closed_form(void) {
  const double k = 2.0e6, beta = 10.0, p = 3.0; /* Pa/m, -, - */
  palp_world_def d = handset_def();
  d.effects = PALP_EFFECT_GEL_SUPPORT | PALP_EFFECT_GEL_DAMPING | PALP_EFFECT_FORCE_FEEDBACK;
  d.dt = 1e-3;
  d.gel.support_modulus = k;
  d.gel.support_viscosity = 2e4; /* [Pa s/m] */
  d.gel.support_bulk_fraction = 0.0;
  d.gel.support_stiffening = beta;
  d.gel.support_stiffening_power = p;
  d.sleep_time = 0.0;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w != NULL, "world with a stiffening support: %s", palp_strerror(e));
  if (!w) return;
  const palp_mesh *mesh = palp_world_mesh(w);
  /* the pole, pushed down; and the free vertex nearest 75 deg, pushed sideways (along +y,
   * across its meridian: the gel column under it is sheared, not compressed) */
  const int top = mesh->top_vertex;
  int side = -1;
  double best = 1e9;
  for (int i = 0; i < mesh->vertex_count; ++i) {
    if (mesh->fixed[i]) continue;
    const palp_vec3 q = mesh->rest[i];
    const double th = atan2(sqrt(q.x * q.x + q.y * q.y), q.z), az = atan2(q.y, q.x);
    const double miss = fabs(th - 75.0 * PI / 180.0) + fabs(az);
    if (q.z > 0.0 && miss < best) best = miss, side = i;
  }
  const palp_vec3 qs = mesh->rest[side];
  const struct {
    int v;
    palp_vec3 dir;
    double H, F;
    const char *name;
  } load[2] = {{top, {0, 0, -1}, mesh->rest[top].z, 0.0, "pole, downward"},
               {side, {-sin(atan2(qs.y, qs.x)), cos(atan2(qs.y, qs.x)), 0}, qs.z, 0.0, "75 deg, sideways"}};
  for (int q = 0; q < 2; ++q) {
    const double kA = k * mesh->vertex_area[load[q].v]; /* [N/m] */
    /* a force that strains the column by ~0.6 of its height (the stiffening ~3x the spring) */
    const double u_want = 0.6 * load[q].H;
    const double F = kA * u_want * (1.0 + beta * pow(0.6, p));
    double fb = 0.0;
    const double u = settle(&d, load[q].v, load[q].dir, F, &fb);
    const double want = closed_form(kA, beta, p, load[q].H, F), lin = F / kA;
    printf("%s: H %.2f mm, F %.4f N: u %.4f mm, closed form %.4f mm (linear support %.4f mm); feedback %.5f N\n",
           load[q].name, 1e3 * load[q].H, F, 1e3 * u, 1e3 * want, 1e3 * lin, fb);
    CHECK(fabs(u - want) <= 0.005 * want, "%s: u %.4f mm against the closed form %.4f mm (tolerance 0.5%%)", load[q].name,
          1e3 * u, 1e3 * want);
    CHECK(fabs(fb - F) <= 0.005 * F, "%s: feedback %.5f N balances the load %.5f N (tolerance 0.5%%)", load[q].name, fb, F);
  }
  palp_world_destroy(w);
}

static int load_dome(palp_world_def *d) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome.json", &sc, err, sizeof err)) {
    CHECK(0, "dome.json: %s", err);
    return -1;
  }
  *d = sc.world;
  return 0;
}

/* A fingertip pressed along the inward normal at polar th, device from -1 mm to dev_mm over
 * 1 s, then held 0.3 s; forces [N] at each step into f (n entries), proxy depths into dp. */
static int press(const palp_world_def *d, double th, double dev_mm, double *f, double *dp, int cap, const palp_vec3 **pos_out,
                 palp_world **keep) {
  int e = 0;
  palp_world *w = palp_world_create(d, &e);
  CHECK(w != NULL, "world: %s", palp_strerror(e));
  if (!w) return 0;
  const double R = d->mesh.radius, r = 0.008;
  const palp_vec3 n = {sin(th), 0.0, cos(th)};
  const int fi = palp_world_add_finger(w, v3_scale(n, R + r + 0.001), r);
  const int ramp = (int)lround(1.0 / d->dt), hold = (int)lround(0.3 / d->dt);
  int k = 0;
  for (; k < ramp + hold && k < cap; ++k) {
    const double dd = 1e-3 * (-1.0 + (dev_mm + 1.0) * fmin(1.0, (double)(k + 1) / ramp));
    palp_world_set_finger_device(w, fi, v3_scale(n, R + r - dd));
    palp_world_step(w);
    palp_local_model lm;
    palp_world_finger_local_model(w, fi, &lm);
    f[k] = v3_len(lm.force);
    dp[k] = lm.contact ? R + r - v3_len(lm.proxy) : -1.0;
  }
  if (pos_out) *pos_out = palp_world_positions(w);
  if (keep) *keep = w;
  else palp_world_destroy(w);
  return k;
}

static void test_dome(void) {
  palp_world_def lin, stf;
  if (load_dome(&stf)) return;
  CHECK(stf.gel.support_stiffening > 0.0, "the shipped breast-tissue set stiffens (beta %g, p %g)",
        stf.gel.support_stiffening, stf.gel.support_stiffening_power);
  lin = stf;
  lin.gel.support_stiffening = 0.0;
  enum { CAP = 2000 };
  static double f0[CAP], d0[CAP], f1[CAP], d1[CAP];
  /* beta = 0 is the linear support bit for bit: the same press, the same positions. */
  palp_world_def lin2 = lin;
  lin2.gel.support_stiffening_power = 5.0; /* irrelevant without beta */
  palp_world *wa = NULL, *wb = NULL;
  const palp_vec3 *pa, *pb;
  const int na = press(&lin, 0.0, 8.0, f0, d0, CAP, &pa, &wa), nb = press(&lin2, 0.0, 8.0, f1, d1, CAP, &pb, &wb);
  if (wa && wb) {
    const int nv = palp_world_mesh(wa)->vertex_count;
    CHECK(na == nb && !memcmp(pa, pb, sizeof *pa * (size_t)nv), "beta 0: the same positions, bit for bit, whatever p");
  }
  palp_world_destroy(wa), palp_world_destroy(wb);
  /* The pole at 1 mm and at 16 mm of indentation: the force at the step that first reaches it. */
  const int n0 = press(&lin, 0.0, 24.0, f0, d0, CAP, NULL, NULL), n1 = press(&stf, 0.0, 24.0, f1, d1, CAP, NULL, NULL);
  const double at[2] = {0.001, 0.016};
  for (int q = 0; q < 2; ++q) {
    double fl = NAN, fs = NAN;
    for (int k = 0; k + 1 < n0; ++k)
      if (d0[k] <= at[q] && d0[k + 1] > at[q]) fl = f0[k] + (f0[k + 1] - f0[k]) * (at[q] - d0[k]) / (d0[k + 1] - d0[k]);
    for (int k = 0; k + 1 < n1; ++k)
      if (d1[k] <= at[q] && d1[k + 1] > at[q]) fs = f1[k] + (f1[k + 1] - f1[k]) * (at[q] - d1[k]) / (d1[k + 1] - d1[k]);
    printf("pole at %.0f mm: %.4f N linear, %.4f N stiffening (x%.4f)\n", 1e3 * at[q], fl, fs, fs / fl);
    if (q == 0) CHECK(fabs(fs / fl - 1.0) <= 0.01, "1 mm: the stiffening leaves the force alone (x%.4f, tolerance 1%%)", fs / fl);
    else CHECK(fs / fl >= 1.08, "16 mm: the stiffening adds at least 8%% (x%.4f)", fs / fl);
  }
  /* 70 deg to 12 mm of device depth, at 250 Hz and 1 kHz: in contact, monotone. */
  for (int rate = 0; rate < 2; ++rate) {
    palp_world_def d = stf;
    d.dt = rate ? 0.001 : 0.004;
    static double f[5000], dp[5000];
    const int n = press(&d, 70.0 * PI / 180.0, 12.0, f, dp, 5000, NULL, NULL);
    const int ramp = (int)lround(1.0 / d.dt);
    double fmaxv = 0.0, drop = 0.0, dmax = 0.0;
    int lost = 0;
    for (int k = 0; k < n; ++k) {
      if (f[k] > fmaxv) fmaxv = f[k];
      if (dp[k] > dmax) dmax = dp[k];
      if (k < ramp && fmaxv - f[k] > drop) drop = fmaxv - f[k];
    }
    int first = 0;
    while (first < n && dp[first] < 0.0) first++;
    for (int k = first + 1; k < n; ++k)
      if (dp[k] < 0.0) lost++;
    printf("70 deg at %s: %.2f mm deep, %.3f N, largest drop on the way in %.2g N, steps out of contact after touching %d\n",
           rate ? "1 kHz" : "250 Hz", 1e3 * dmax, fmaxv, drop, lost);
    CHECK(lost == 0, "70 deg at %s: contact kept after touching (%d steps lost)", rate ? "1 kHz" : "250 Hz", lost);
    CHECK(drop <= 0.005 * fmaxv, "70 deg at %s: force monotone in depth within 0.5%% of %.3f N (drop %.2g N)",
          rate ? "1 kHz" : "250 Hz", fmaxv, drop);
    CHECK(dmax > 0.008 && isfinite(fmaxv), "70 deg at %s: pressed beyond 8 mm (%.2f mm)", rate ? "1 kHz" : "250 Hz", 1e3 * dmax);
  }
}

static void test_parse(void) {
  const char *json = SUPPORT_SCENE_FMT;
  char buf[2048], err[256] = "";
  palp_scene s, back;
  snprintf(buf, sizeof buf, json, ",\"support_stiffening\":10,\"support_stiffening_power\":3");
  CHECK(palp_scene_parse(buf, &s, err, sizeof err) == 0 && s.world.gel.support_stiffening == 10.0 &&
            s.world.gel.support_stiffening_power == 3.0,
        "stiffening fields parse: %s", err);
  char *out = palp_scene_to_json(&s);
  CHECK(out && palp_scene_parse(out, &back, err, sizeof err) == 0 &&
            back.world.gel.support_stiffening == s.world.gel.support_stiffening &&
            back.world.gel.support_stiffening_power == s.world.gel.support_stiffening_power,
        "stiffening fields serialise and come back: %s", err);
  free(out);
  snprintf(buf, sizeof buf, json, "");
  CHECK(palp_scene_parse(buf, &s, err, sizeof err) == 0 && s.world.gel.support_stiffening == 0.0, "absent: a linear support");
  out = palp_scene_to_json(&s);
  CHECK(out && !strstr(out, "support_stiffening"), "a linear support's scene prints as before (no stiffening fields)");
  free(out);
  const struct {
    const char *v, *want;
  } bad[] = {{",\"support_stiffening\":-1", "gel.support_stiffening: must be in [0, 1000]"},
             {",\"support_stiffening\":2,\"support_stiffening_power\":0.5", "gel.support_stiffening_power: must be in [1, 8]"},
             {",\"support_stiffening\":2,\"support_stiffening_power\":9", "gel.support_stiffening_power: must be in [1, 8]"},
             {",\"support_stiffening\":\"x\"", "gel.support_stiffening: expected a number"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
    snprintf(buf, sizeof buf, json, bad[i].v);
    err[0] = 0;
    CHECK(palp_scene_parse(buf, &s, err, sizeof err) < 0 && strstr(err, bad[i].want), "refused with \"%s\" (got \"%s\")",
          bad[i].want, err);
  }
  palp_world_def d = handset_def();
  d.gel.support_stiffening = 2.0;
  d.gel.support_stiffening_power = 0.0;
  int e = 0;
  CHECK(palp_world_create(&d, &e) == NULL && e == PALP_EINVAL, "the world refuses a power outside [1, 8]");
}

int main(void) {
  test_closed_form();
  test_dome();
  test_parse();
  CHECK_DONE();
}
