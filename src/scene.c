/*
 * scene.c - scene files (JSON, cJSON): geometry, material, time step, effects,
 * contacts and force profiles. Keys carry their SI unit (radius_m, E1_Pa, ...).
 * Every error names the field it is about, as "contacts[1].profile.t_off_s: ...".
 * Unknown keys are refused (as exercise files and the server's config do): a misspelt
 * optional key ("bending_stifness_N_m") would otherwise silently leave its default.
 * Every object may carry a "comment".
 */
#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"
#include "palp_input_file.h"
#include "parse_error.h"
#include "vec3.h"

typedef palp_parse_ctx ctx;

/* Reads a required (or optional, keeping *out) finite number. */
static int get_num(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? palp_parse_fail(c, PALP_EPARSE, "%s%s: missing (a number is required)", path, key) : PALP_OK;
  if (!cJSON_IsNumber(it)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected a number", path, key);
  if (!isfinite(it->valuedouble)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be finite", path, key);
  *out = it->valuedouble;
  return PALP_OK;
}

static int get_pos(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double *out) {
  double v = *out;
  int e = get_num(c, obj, path, key, required, &v);
  if (e) return e;
  if (!(v > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be > 0 (got %g)", path, key, v);
  *out = v;
  return PALP_OK;
}

/* A number > 0 and <= hi: the physical upper bounds below keep absurd values (1e300,
 * a unit slip of 1000) from reaching the model, where they overflow or stall it. */
static int get_pos_max(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double hi,
                       double *out) {
  double v = *out;
  int e = get_pos(c, obj, path, key, required, &v);
  if (e) return e;
  if (!(v <= hi)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be <= %g (got %g)", path, key, hi, v);
  *out = v;
  return PALP_OK;
}

/* A number >= 0 and <= hi (a damping or a support that may be absent). */
static int get_nonneg_max(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double hi,
                          double *out) {
  double v = *out;
  int e = get_num(c, obj, path, key, required, &v);
  if (e) return e;
  if (!(v >= 0.0)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be >= 0 (got %g)", path, key, v);
  if (!(v <= hi)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be <= %g (got %g)", path, key, hi, v);
  *out = v;
  return PALP_OK;
}

/* |v| <= hi, for signed quantities (forces). */
static int get_abs_max(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double hi,
                       double *out) {
  double v = *out;
  int e = get_num(c, obj, path, key, required, &v);
  if (e) return e;
  if (!(fabs(v) <= hi)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be within [-%g, %g] (got %g)", path, key, hi, hi, v);
  *out = v;
  return PALP_OK;
}

/* Refuses keys not in the NULL-terminated list; "comment" is allowed everywhere. */
static int only_keys(ctx *c, const cJSON *obj, const char *path, const char *const *keys) {
  for (const cJSON *it = obj->child; it; it = it->next) {
    int ok = it->string && strcmp(it->string, "comment") == 0;
    for (int k = 0; !ok && keys[k]; ++k) ok = it->string && strcmp(it->string, keys[k]) == 0;
    if (!ok) return palp_parse_fail(c, PALP_EPARSE, "%s%s: unknown key", path, it->string ? it->string : "?");
  }
  return PALP_OK;
}

static int get_int(ctx *c, const cJSON *obj, const char *path, const char *key, int required, int lo, int hi,
                   int *out) {
  double v = *out;
  int e = get_num(c, obj, path, key, required, &v);
  if (e) return e;
  if (v != floor(v) || v < lo || v > hi)
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected an integer in [%d, %d] (got %g)", path, key, lo, hi, v);
  *out = (int)v;
  return PALP_OK;
}

/* Whether plain d / |d| is exact enough for d: d.d finite and well inside the doubles. */
static int well_scaled(palp_vec3 d) {
  const double d2 = v3_dot(d, d);
  return isfinite(d2) && d2 >= DBL_MIN / DBL_EPSILON;
}

/* The unit vector along a finite, non-zero d. Plain d / |d| while d.d is well inside the
 * doubles (>= DBL_MIN / DBL_EPSILON, so subnormal squares cost no precision, and finite): those
 * are the bits every logged session was stepped with, so replays keep them. Otherwise d is first
 * divided by its largest |component| (length then in [1, sqrt 3]): plainly, [1e200, 0, -1e200]
 * had length inf and a silently zero force, and [1e-170, 0, -1e-170] length 0, which read as
 * "no direction" and pushed along the default inward normal instead. */
static palp_vec3 unit_direction(palp_vec3 d) {
  if (well_scaled(d)) return v3_scale(d, 1.0 / sqrt(v3_dot(d, d)));
  const double m = fmax(fabs(d.x), fmax(fabs(d.y), fabs(d.z)));
  const palp_vec3 u = v3(d.x / m, d.y / m, d.z / m); /* divided, not times 1/m: 1/5e-324 is inf */
  return v3_scale(u, 1.0 / v3_len(u));
}

/* An exactly zero direction: the default inward normal (palp_scene_to_json writes [0, 0, 0] for it). */
static int is_zero(palp_vec3 d) { return d.x == 0.0 && d.y == 0.0 && d.z == 0.0; }

static int get_vec(ctx *c, const cJSON *obj, const char *path, const char *key, int required, palp_vec3 *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? palp_parse_fail(c, PALP_EPARSE, "%s%s: missing (an array of 3 numbers is required)", path, key) : 0;
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected an array of 3 numbers", path, key);
  double v[3];
  for (int i = 0; i < 3; ++i) {
    const cJSON *x = cJSON_GetArrayItem(it, i);
    if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
      return palp_parse_fail(c, PALP_EPARSE, "%s%s[%d]: expected a finite number", path, key, i);
    v[i] = x->valuedouble;
  }
  *out = v3(v[0], v[1], v[2]);
  return PALP_OK;
}

static const cJSON *get_obj(ctx *c, const cJSON *obj, const char *path, const char *key, int required, int *e) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  *e = PALP_OK;
  if (!it) {
    if (required) *e = palp_parse_fail(c, PALP_EPARSE, "%s%s: missing (an object is required)", path, key);
    return NULL;
  }
  if (!cJSON_IsObject(it)) {
    *e = palp_parse_fail(c, PALP_EPARSE, "%s%s: expected an object", path, key);
    return NULL;
  }
  return it;
}

/* Physical upper bounds (generous: each is far beyond any phantom, and below what makes
 * the model's arithmetic overflow):
 * - the dome's radius, 1 mm .. 1 m: a breast phantom is ~4 cm; a metre is a room's furniture;
 * - the membrane's moduli E1, E2 <= 1 GPa: silicone rubbers are 0.1-100 MPa, tissue kPa; a
 *   GPa is a rigid plastic, no longer a palpable skin;
 * - its viscosities eta1, eta2 <= 1e14 Pa s: with E <= 1 GPa a relaxation time eta / E of
 *   1e5 s (a day) is already a spring for any session (the shipped sets go to 1.7e10 Pa s);
 * - gravity |g| <= 100 m/s^2: ten times the Earth's; a phantom on a table sees 9.81;
 * - a scripted contact's force |F| <= 1e4 N: a tonne-force, ten times the server's
 *   absurd_force of 1 kN (no hand presses that); the shipped scenes press 3 N;
 * - a sine profile's frequency <= 1e4 Hz: the fastest physics rate the server runs
 *   (physics_rate_hz <= 10 kHz); above it the load only aliases;
 * - the membrane's thickness and density, the gel's pressure, a1, a2, density and the
 *   support's moduli, viscosity and relax time: palp.h's PALP_*_MAX, which the world
 *   checks too (session 81; they had none, and pressure_Pa 1e30 stepped "ok" to
 *   V/V0 = -1.8); the membrane's bending stiffness too (session 83: 1e30 made a dome
 *   that never moved). */
#define SCENE_RADIUS_MIN_M 1e-3
#define SCENE_RADIUS_MAX_M 1.0
#define SCENE_MODULUS_MAX_PA 1e9
#define SCENE_VISCOSITY_MAX_PA_S 1e14
#define SCENE_GRAVITY_MAX_M_S2 100.0
#define SCENE_FORCE_MAX_N 1e4
#define SCENE_FREQUENCY_MAX_HZ 1e4

static const char *const dist_names[] = {"single", "uniform", "gaussian", "gaussian_offset"};
static const char *const profile_names[] = {"step", "ramp", "sine", "keyframes"};

static int parse_membrane(ctx *c, const cJSON *m, palp_membrane_params *p) {
  static const char *const keys[] = {"thickness_m", "density_kg_m3", "E1_Pa", "eta1_Pa_s", "E2_Pa", "eta2_Pa_s",
                                     "bending_stiffness_N_m", "rim_hinge_release", "skin_bending_stiffness_N_m", NULL};
  int e;
  if ((e = only_keys(c, m, "membrane.", keys))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "thickness_m", 1, PALP_THICKNESS_MAX_M, &p->thickness))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "density_kg_m3", 1, PALP_DENSITY_MAX_KG_M3, &p->density))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "E1_Pa", 1, SCENE_MODULUS_MAX_PA, &p->E1))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "eta1_Pa_s", 1, SCENE_VISCOSITY_MAX_PA_S, &p->eta1))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "E2_Pa", 1, SCENE_MODULUS_MAX_PA, &p->E2))) return e;
  if ((e = get_pos_max(c, m, "membrane.", "eta2_Pa_s", 1, SCENE_VISCOSITY_MAX_PA_S, &p->eta2))) return e;
  /* optional: absent is the paper's membrane, without bending */
  if ((e = get_nonneg_max(c, m, "membrane.", "bending_stiffness_N_m", 0, PALP_BENDING_MAX_N_M, &p->bending_stiffness)))
    return e;
  if ((e = get_num(c, m, "membrane.", "rim_hinge_release", 0, &p->rim_hinge_release))) return e;
  if (!(p->rim_hinge_release >= 0.0 && p->rim_hinge_release <= 1.0))
    return palp_parse_fail(c, PALP_EPARSE, "membrane.rim_hinge_release: must be in [0, 1] (0 clamps the rim, 1 pins it; got %g)",
                           p->rim_hinge_release);
  if ((e = get_num(c, m, "membrane.", "skin_bending_stiffness_N_m", 0, &p->skin_bending_stiffness))) return e;
  if (!(p->skin_bending_stiffness >= 0.0 && p->skin_bending_stiffness <= p->bending_stiffness))
    return palp_parse_fail(c, PALP_EPARSE,
                           "membrane.skin_bending_stiffness_N_m: must be in [0, bending_stiffness_N_m] (the skin's own share "
                           "of the hinges' %g N m; got %g)",
                           p->bending_stiffness, p->skin_bending_stiffness);
  return PALP_OK;
}

static int parse_gel(ctx *c, const cJSON *g, palp_gel_params *p) {
  static const char *const keys[] = {"law", "pressure_Pa", "a1", "a2_Pa_s_m3", "a3_s2", "support_modulus_Pa_m",
                                     "support_viscosity_Pa_s_m", "support_bulk_fraction", "support_relax_modulus_Pa_m",
                                     "support_relax_time_s", "support_stiffening", "support_stiffening_power",
                                     "support_base_reach", "density_kg_m3", "added_mass_fraction", NULL};
  int e;
  if ((e = only_keys(c, g, "gel.", keys))) return e;
  const cJSON *law = cJSON_GetObjectItemCaseSensitive(g, "law");
  if (!law) return palp_parse_fail(c, PALP_EPARSE, "gel.law: missing (\"polytropic\" or \"paper_literal\")");
  if (!cJSON_IsString(law)) return palp_parse_fail(c, PALP_EPARSE, "gel.law: expected a string");
  if (strcmp(law->valuestring, "polytropic") == 0) p->law = PALP_GEL_POLYTROPIC;
  else if (strcmp(law->valuestring, "paper_literal") == 0) p->law = PALP_GEL_PAPER_LITERAL;
  else return palp_parse_fail(c, PALP_EPARSE, "gel.law: unknown law \"%s\" (polytropic, paper_literal)", law->valuestring);
  if ((e = get_pos_max(c, g, "gel.", "pressure_Pa", 1, PALP_GEL_PRESSURE_MAX_PA, &p->pressure))) return e;
  if ((e = get_pos_max(c, g, "gel.", "a1", 1, PALP_GEL_A1_MAX, &p->a1))) return e;
  if ((e = get_nonneg_max(c, g, "gel.", "a2_Pa_s_m3", 1, PALP_GEL_A2_MAX, &p->a2))) return e;
  p->a3 = 0.0;
  if ((e = get_num(c, g, "gel.", "a3_s2", 0, &p->a3))) return e;
  if ((e = get_nonneg_max(c, g, "gel.", "support_modulus_Pa_m", 0, PALP_SUPPORT_MODULUS_MAX, &p->support_modulus)))
    return e;
  if ((e = get_nonneg_max(c, g, "gel.", "support_viscosity_Pa_s_m", 0, PALP_SUPPORT_VISCOSITY_MAX,
                          &p->support_viscosity)))
    return e;
  if ((e = get_num(c, g, "gel.", "support_bulk_fraction", 0, &p->support_bulk_fraction))) return e;
  if (!(p->support_bulk_fraction >= 0.0 && p->support_bulk_fraction <= 1.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_bulk_fraction: must be in [0, 1] (the share of the gel's bulk shift the support follows)");
  if ((e = get_num(c, g, "gel.", "support_relax_modulus_Pa_m", 0, &p->support_relax_modulus))) return e;
  if (!(p->support_relax_modulus >= 0.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_relax_modulus_Pa_m: must be >= 0 (0: the support does not relax)");
  if (!(p->support_relax_modulus <= PALP_SUPPORT_MODULUS_MAX))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_relax_modulus_Pa_m: must be <= %g (got %g)",
                           PALP_SUPPORT_MODULUS_MAX, p->support_relax_modulus);
  if ((e = get_num(c, g, "gel.", "support_relax_time_s", 0, &p->support_relax_time))) return e;
  if (!(p->support_relax_time <= PALP_SUPPORT_RELAX_TIME_MAX))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_relax_time_s: must be <= %g (got %g)", PALP_SUPPORT_RELAX_TIME_MAX,
                           p->support_relax_time);
  if (p->support_relax_modulus > 0.0 && !(p->support_relax_time > 0.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_relax_time_s: must be > 0 with a relaxing support (got %g s)",
                           p->support_relax_time);
  p->support_stiffening = 0.0;
  p->support_stiffening_power = 2.0;
  if ((e = get_num(c, g, "gel.", "support_stiffening", 0, &p->support_stiffening))) return e;
  if (!(p->support_stiffening >= 0.0 && p->support_stiffening <= 1e3))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_stiffening: must be in [0, 1000] (0: a linear support; got %g)",
                           p->support_stiffening);
  if ((e = get_num(c, g, "gel.", "support_stiffening_power", 0, &p->support_stiffening_power))) return e;
  if (!(p->support_stiffening_power >= 1.0 && p->support_stiffening_power <= 8.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_stiffening_power: must be in [1, 8] (got %g)",
                           p->support_stiffening_power);
  p->support_base_reach = 0.0;
  if ((e = get_num(c, g, "gel.", "support_base_reach", 0, &p->support_base_reach))) return e;
  if (!(p->support_base_reach >= 0.0 && p->support_base_reach <= 1.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_base_reach: must be in [0, 1] (0: the base does not cut the "
                           "support's column; got %g)", p->support_base_reach);
  if ((e = get_num(c, g, "gel.", "density_kg_m3", 0, &p->density))) return e;
  if (!(p->density > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "gel.density_kg_m3: must be > 0");
  if (!(p->density <= PALP_DENSITY_MAX_KG_M3))
    return palp_parse_fail(c, PALP_EPARSE, "gel.density_kg_m3: must be <= %g (got %g)", PALP_DENSITY_MAX_KG_M3, p->density);
  if ((e = get_num(c, g, "gel.", "added_mass_fraction", 0, &p->added_mass_fraction))) return e;
  if (!(p->added_mass_fraction >= 0.0 && p->added_mass_fraction <= 1.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.added_mass_fraction: must be in [0, 1] (the share of the gel's mass the surface carries)");
  return PALP_OK;
}

static int parse_profile(ctx *c, const cJSON *o, const char *path, palp_profile *p) {
  memset(p, 0, sizeof *p);
  const cJSON *kind = cJSON_GetObjectItemCaseSensitive(o, "kind");
  if (!kind || !cJSON_IsString(kind)) return palp_parse_fail(c, PALP_EPARSE, "%skind: missing or not a string", path);
  int k = 0;
  for (int i = 0; i < 4; ++i)
    if (strcmp(kind->valuestring, profile_names[i]) == 0) k = i + 1;
  if (!k) return palp_parse_fail(c, PALP_EPARSE, "%skind: unknown profile \"%s\" (step, ramp, sine, keyframes)", path,
                      kind->valuestring);
  p->kind = (palp_profile_kind)k;
  /* only the kind's own keys: a "frequency_Hz" on a step would be silently unused */
  static const char *const key_keys[] = {"kind", "keyframes", NULL};
  static const char *const step_keys[] = {"kind", "magnitude_N", "t_on_s", "t_off_s", NULL};
  static const char *const sine_keys[] = {"kind", "magnitude_N", "t_on_s", "t_off_s", "frequency_Hz", "offset_N", NULL};
  int e;
  if ((e = only_keys(c, o, path,
                     p->kind == PALP_PROFILE_KEYFRAMES ? key_keys
                     : p->kind == PALP_PROFILE_SINE    ? sine_keys
                                                       : step_keys)))
    return e;
  if (p->kind == PALP_PROFILE_KEYFRAMES) {
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(o, "keyframes");
    if (!cJSON_IsArray(keys)) return palp_parse_fail(c, PALP_EPARSE, "%skeyframes: expected an array of [t_s, force_N]", path);
    const int n = cJSON_GetArraySize(keys);
    if (n < 1 || n > PALP_PROFILE_MAX_KEYS)
      return palp_parse_fail(c, PALP_EPARSE, "%skeyframes: needs 1 to %d entries", path, PALP_PROFILE_MAX_KEYS);
    for (int i = 0; i < n; ++i) {
      const cJSON *kf = cJSON_GetArrayItem(keys, i);
      const cJSON *t = cJSON_GetArrayItem(kf, 0), *f = cJSON_GetArrayItem(kf, 1);
      if (!cJSON_IsArray(kf) || cJSON_GetArraySize(kf) != 2 || !cJSON_IsNumber(t) || !cJSON_IsNumber(f) ||
          !isfinite(t->valuedouble) || !isfinite(f->valuedouble))
        return palp_parse_fail(c, PALP_EPARSE, "%skeyframes[%d]: expected [t_s, force_N]", path, i);
      if (!(fabs(f->valuedouble) <= SCENE_FORCE_MAX_N))
        return palp_parse_fail(c, PALP_EPARSE, "%skeyframes[%d]: force_N must be within [-%g, %g] (got %g)", path, i,
                               SCENE_FORCE_MAX_N, SCENE_FORCE_MAX_N, f->valuedouble);
      if (i > 0 && !(t->valuedouble > p->key_t[i - 1]))
        return palp_parse_fail(c, PALP_EPARSE, "%skeyframes[%d]: times must increase", path, i);
      p->key_t[i] = t->valuedouble;
      p->key_f[i] = f->valuedouble;
    }
    p->key_count = n;
    return PALP_OK;
  }
  if ((e = get_abs_max(c, o, path, "magnitude_N", 1, SCENE_FORCE_MAX_N, &p->magnitude))) return e;
  if ((e = get_num(c, o, path, "t_on_s", 1, &p->t_on))) return e;
  if ((e = get_num(c, o, path, "t_off_s", 1, &p->t_off))) return e;
  if (p->t_off < p->t_on) return palp_parse_fail(c, PALP_EPARSE, "%st_off_s: must be >= t_on_s", path);
  if (p->kind == PALP_PROFILE_SINE) {
    if ((e = get_pos_max(c, o, path, "frequency_Hz", 1, SCENE_FREQUENCY_MAX_HZ, &p->frequency))) return e;
    if ((e = get_abs_max(c, o, path, "offset_N", 0, SCENE_FORCE_MAX_N, &p->offset))) return e;
  }
  return PALP_OK;
}

static int parse_contact(ctx *c, const cJSON *o, int idx, double radius, palp_scene_contact *sc) {
  char path[48];
  snprintf(path, sizeof path, "contacts[%d].", idx);
  if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "contacts[%d]: expected an object", idx);
  static const char *const keys[] = {"distribution",    "center_deg", "center_m",  "patch_area_m2", "sigma_fraction",
                                     "offset_fraction", "offset_dir", "direction", "profile",       NULL};
  int e;
  if ((e = only_keys(c, o, path, keys))) return e;
  const cJSON *d = cJSON_GetObjectItemCaseSensitive(o, "distribution");
  int dist = 0;
  if (cJSON_IsString(d)) {
    for (int i = 0; i < 4; ++i)
      if (strcmp(d->valuestring, dist_names[i]) == 0) dist = i + 1;
  } else if (cJSON_IsNumber(d) && d->valuedouble >= 1 && d->valuedouble <= 4 && d->valuedouble == floor(d->valuedouble)) {
    dist = (int)d->valuedouble;
  }
  if (!d) return palp_parse_fail(c, PALP_EPARSE, "%sdistribution: missing", path);
  if (!dist)
    return palp_parse_fail(c, PALP_EPARSE, "%sdistribution: expected single, uniform, gaussian, gaussian_offset or 1-4", path);
  palp_vec3 center = v3(0, 0, radius);
  const cJSON *deg = cJSON_GetObjectItemCaseSensitive(o, "center_deg");
  if (deg && cJSON_GetObjectItemCaseSensitive(o, "center_m"))
    return palp_parse_fail(c, PALP_EPARSE, "%scenter_m: not with center_deg (one centre)", path);
  if (deg) {
    if (!cJSON_IsObject(deg)) return palp_parse_fail(c, PALP_EPARSE, "%scenter_deg: expected {\"polar\": .., \"azimuth\": ..}", path);
    char p2[64];
    snprintf(p2, sizeof p2, "%scenter_deg.", path);
    static const char *const deg_keys[] = {"polar", "azimuth", NULL};
    if ((e = only_keys(c, deg, p2, deg_keys))) return e;
    double polar = 0, az = 0;
    if ((e = get_num(c, deg, p2, "polar", 1, &polar)) || (e = get_num(c, deg, p2, "azimuth", 1, &az))) return e;
    if (polar < 0 || polar > 90) return palp_parse_fail(c, PALP_EPARSE, "%spolar: must be within [0, 90] degrees", p2);
    const double th = polar * PALP_PI / 180.0, ph = az * PALP_PI / 180.0;
    center = v3(radius * sin(th) * cos(ph), radius * sin(th) * sin(ph), radius * cos(th));
  } else if ((e = get_vec(c, o, path, "center_m", 1, &center))) {
    return palp_parse_fail(c, PALP_EPARSE, "%scenter_m or center_deg: missing or malformed", path);
  }
  sc->def = palp_contact_default_def((palp_distribution)dist, center);
  if ((e = get_pos(c, o, path, "patch_area_m2", 0, &sc->def.patch_area))) return e;
  if ((e = get_pos(c, o, path, "sigma_fraction", 0, &sc->def.sigma_fraction))) return e;
  if ((e = get_num(c, o, path, "offset_fraction", 0, &sc->def.offset_fraction))) return e;
  if ((e = get_vec(c, o, path, "offset_dir", 0, &sc->def.offset_dir))) return e;
  sc->direction = v3(0, 0, 0);
  if ((e = get_vec(c, o, path, "direction", 0, &sc->direction))) return e;
  /* Kept as given where plain normalisation is exact enough (the bits logged sessions were
   * replayed with), made unit where it over- or underflows (unit_direction); all zero is the
   * default inward normal, as palp_scene_to_json writes it and every log holds it. */
  if (!is_zero(sc->direction) && !well_scaled(sc->direction)) sc->direction = unit_direction(sc->direction);
  const cJSON *prof = get_obj(c, o, path, "profile", 1, &e);
  if (e) return e;
  char p3[64];
  snprintf(p3, sizeof p3, "%sprofile.", path);
  return parse_profile(c, prof, p3, &sc->profile);
}

/* A scene or its parameters: a few kB; 64 MiB bounds what a wrong path makes us hold. */
#define SCENE_FILE_MAX ((size_t)1 << 26)

/* A material profile's name: a short identifier, so that a hostile file cannot smuggle
 * text into the evaluation's messages; whether it names a known profile is the FEM's
 * business (palp_fem_config_set_material), not the model's. */
static int get_material(ctx *c, const cJSON *obj, const char *path, palp_scene *s) {
  const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, "material");
  if (!m) return PALP_OK;
  if (!cJSON_IsString(m)) return palp_parse_fail(c, PALP_EPARSE, "%smaterial: expected a profile name", path);
  const char *v = m->valuestring;
  const size_t n = strlen(v);
  int ok = n > 0 && n < sizeof s->material;
  for (size_t i = 0; ok && i < n; ++i) ok = (v[i] >= 'a' && v[i] <= 'z') || (v[i] >= '0' && v[i] <= '9') || v[i] == '_';
  if (!ok)
    return palp_parse_fail(c, PALP_EPARSE, "%smaterial: \"%.40s\" is not a profile name (lower case, digits, _; < %zu)",
                           path, v, sizeof s->material);
  snprintf(s->material, sizeof s->material, "%s", v);
  return PALP_OK;
}

/* Where the parameters were validated against the FE with a fingertip (palp_world_def.
 * validated_*; docs/model.md, "Valid range"): {"finger": [{"polar_deg": a, "depth_m": d},
 * ...], "hinge_error_rad": e}, polar angles ascending within [0, 90] deg (or "polar_rad",
 * exact, as a logged scene writes them), depths > 0 m; e, optional, the largest miss of a
 * linearised hinge those presses reached, in (0, 1] rad (absent: 0, none stated). The
 * object is optional; absent keeps what was there, present replaces all of it. */
static int get_validated(ctx *c, const cJSON *obj, const char *path, palp_world_def *w) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, "validated");
  if (!v) return PALP_OK;
  if (!cJSON_IsObject(v)) return palp_parse_fail(c, PALP_EPARSE, "%svalidated: expected an object {\"finger\": [...]}", path);
  {
    static const char *const keys[] = {"finger", "hinge_error_rad", NULL};
    char p1[48];
    snprintf(p1, sizeof p1, "%svalidated.", path);
    const int rc = only_keys(c, v, p1, keys);
    if (rc) return rc;
  }
  const cJSON *f = cJSON_GetObjectItemCaseSensitive(v, "finger");
  const int n = cJSON_IsArray(f) ? cJSON_GetArraySize(f) : -1;
  if (n < 1 || n > PALP_MAX_VALIDATED)
    return palp_parse_fail(c, PALP_EPARSE, "%svalidated.finger: expected an array of 1 to %d {\"polar_deg\", \"depth_m\"}",
                           path, PALP_MAX_VALIDATED);
  for (int i = 0; i < n; ++i) {
    const cJSON *o = cJSON_GetArrayItem(f, i);
    char p2[64];
    snprintf(p2, sizeof p2, "%svalidated.finger[%d].", path, i);
    if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "%.*s: expected an object", (int)strlen(p2) - 1, p2);
    static const char *const keys[] = {"polar_deg", "polar_rad", "depth_m", NULL};
    int e;
    if ((e = only_keys(c, o, p2, keys))) return e;
    if (cJSON_GetObjectItemCaseSensitive(o, "polar_rad") && cJSON_GetObjectItemCaseSensitive(o, "polar_deg"))
      return palp_parse_fail(c, PALP_EPARSE, "%spolar_deg: not with polar_rad (one angle)", p2);
    double a = NAN, d = 0.0;
    if (cJSON_GetObjectItemCaseSensitive(o, "polar_rad")) {
      if ((e = get_num(c, o, p2, "polar_rad", 1, &a))) return e;
    } else {
      if ((e = get_num(c, o, p2, "polar_deg", 1, &a))) return e;
      a *= PALP_PI / 180.0;
    }
    if ((e = get_pos(c, o, p2, "depth_m", 1, &d))) return e;
    if (!(a >= 0.0 && a <= 0.5 * PALP_PI + 1e-12))
      return palp_parse_fail(c, PALP_EPARSE, "%spolar_deg: must be within [0, 90] degrees", p2);
    if (i > 0 && !(a > w->validated_polar[i - 1]))
      return palp_parse_fail(c, PALP_EPARSE, "%spolar_deg: the polar angles must increase", p2);
    if (!(d < 1.0)) return palp_parse_fail(c, PALP_EPARSE, "%sdepth_m: %g m is not an indentation (< 1 m)", p2, d);
    w->validated_polar[i] = a;
    w->validated_depth[i] = d;
  }
  w->validated_count = n;
  double e = 0.0;
  if (cJSON_GetObjectItemCaseSensitive(v, "hinge_error_rad")) {
    int rc;
    char p2[64];
    snprintf(p2, sizeof p2, "%svalidated.", path);
    if ((rc = get_pos(c, v, p2, "hinge_error_rad", 1, &e))) return rc;
    if (!(e <= 1.0))
      return palp_parse_fail(c, PALP_EPARSE, "%shinge_error_rad: %g rad is not a hinge's miss (at most 1 rad)", p2, e);
  }
  w->validated_hinge_error = e;
  return PALP_OK;
}

/* The parameter file "name" (relative to dir, the scene's directory). Its errors are said
 * as "parameters \"<its path>\": membrane.E1_Pa: ...": the caller names the scene file, and
 * without the parameter file's own path one could not tell which of the two is wrong. */
static int parse_params_file(ctx *c, const char *dir, const char *name, palp_scene *s) {
  char path[1024];
  if (name[0] == '/' || !dir[0]) snprintf(path, sizeof path, "%s", name);
  else snprintf(path, sizeof path, "%s/%s", dir, name);
  char *txt, why[200];
  int rc = palp_input_file_read(path, SCENE_FILE_MAX, &txt, NULL, why, sizeof why);
  if (rc) return palp_parse_fail(c, rc == PALP_ENOMEM ? rc : PALP_EIO, "parameters: cannot read \"%s\": %s", path, why);
  cJSON *root = palp_json_parse_strict(txt, why, sizeof why);
  free(txt);
  if (!root) return palp_parse_fail(c, PALP_EPARSE, "parameters: \"%s\": %s", path, why);
  char inner[400] = "";
  ctx ic = {inner, sizeof inner};
  static const char *const keys[] = {"membrane", "gel", "material", "validated", NULL};
  int e = cJSON_IsObject(root) ? only_keys(&ic, root, "", keys)
                               : palp_parse_fail(&ic, PALP_EPARSE, "expected a JSON object");
  const cJSON *m = e ? NULL : get_obj(&ic, root, "", "membrane", 1, &e);
  if (!e) e = parse_membrane(&ic, m, &s->world.membrane);
  const cJSON *g = e ? NULL : get_obj(&ic, root, "", "gel", 1, &e);
  if (!e) e = parse_gel(&ic, g, &s->world.gel);
  if (!e) e = get_material(&ic, root, "", s);
  if (!e) e = get_validated(&ic, root, "", &s->world);
  cJSON_Delete(root);
  if (e) return palp_parse_fail(c, e, "parameters \"%s\": %s", path, inner);
  return PALP_OK;
}

/* dir: the scene file's directory, where "parameters" is looked for; NULL for text from
 * elsewhere (palp_scene_parse), which may not name a file. */
static int parse_root(ctx *c, const cJSON *root, const char *dir, palp_scene *s) {
  memset(s, 0, sizeof *s);
  s->world = palp_world_default_def();
  if (!cJSON_IsObject(root)) return palp_parse_fail(c, PALP_EPARSE, "scene: expected a JSON object");
  static const char *const keys[] = {"name",       "material",   "mesh",          "parameters",   "membrane",
                                     "gel",        "validated",  "time",          "effects",      "gravity_m_s2",
                                     "max_contacts", "finger_surface", "finger_linearise", "lesions", "contacts",
                                     NULL};
  int e;
  if ((e = only_keys(c, root, "", keys))) return e;
  const cJSON *name = cJSON_GetObjectItemCaseSensitive(root, "name");
  if (!cJSON_IsString(name)) return palp_parse_fail(c, PALP_EPARSE, "name: missing or not a string");
  snprintf(s->name, sizeof s->name, "%s", name->valuestring);

  const cJSON *mesh = get_obj(c, root, "", "mesh", 1, &e);
  if (e) return e;
  {
    static const char *const mkeys[] = {"radius_m", "vertex_count", NULL};
    if ((e = only_keys(c, mesh, "mesh.", mkeys))) return e;
  }
  if ((e = get_pos_max(c, mesh, "mesh.", "radius_m", 1, SCENE_RADIUS_MAX_M, &s->world.mesh.radius))) return e;
  if (s->world.mesh.radius < SCENE_RADIUS_MIN_M)
    return palp_parse_fail(c, PALP_EPARSE, "mesh.radius_m: must be >= %g m (got %g)", SCENE_RADIUS_MIN_M,
                           s->world.mesh.radius);
  if ((e = get_int(c, mesh, "mesh.", "vertex_count", 1, 19, PALP_MESH_MAX_VERTICES, &s->world.mesh.vertex_count))) return e;

  const cJSON *params = cJSON_GetObjectItemCaseSensitive(root, "parameters");
  if (params) {
    if (!cJSON_IsString(params)) return palp_parse_fail(c, PALP_EPARSE, "parameters: expected a file name");
    /* Text not read from a scene file (a session log's scene, palp_scene_parse) is not
     * trusted to name files: a handed-over database whose scene named a FIFO hung the
     * reviewer, and any path served as an "exists / is JSON" probe. Logs store the resolved
     * scene (palp_scene_to_json), never a reference. */
    if (!dir)
      return palp_parse_fail(c, PALP_EPARSE,
                             "parameters: a file reference is only read from a scene file (palp_scene_load); "
                             "this scene text must carry its \"membrane\" and \"gel\" itself");
    /* and not both: the file's would silently win over the scene's own */
    if (cJSON_GetObjectItemCaseSensitive(root, "membrane") || cJSON_GetObjectItemCaseSensitive(root, "gel"))
      return palp_parse_fail(c, PALP_EPARSE, "%s: not with parameters (the parameter file gives it)",
                             cJSON_GetObjectItemCaseSensitive(root, "membrane") ? "membrane" : "gel");
    if ((e = parse_params_file(c, dir, params->valuestring, s))) return e;
  } else {
    const cJSON *m = get_obj(c, root, "", "membrane", 1, &e);
    if (e || (e = parse_membrane(c, m, &s->world.membrane))) return e;
    const cJSON *g = get_obj(c, root, "", "gel", 1, &e);
    if (e || (e = parse_gel(c, g, &s->world.gel))) return e;
  }

  /* the scene's own "material" wins over its parameter file's, and so does its "validated" */
  if ((e = get_material(c, root, "", s))) return e;
  if ((e = get_validated(c, root, "", &s->world))) return e;

  const cJSON *t = get_obj(c, root, "", "time", 1, &e);
  if (e) return e;
  {
    static const char *const tkeys[] = {"dt_s", "frames", "refactor_lag_steps", "refactor_blend_steps",
                                        "frame_period_s", NULL};
    if ((e = only_keys(c, t, "time.", tkeys))) return e;
  }
  if ((e = get_pos(c, t, "time.", "dt_s", 1, &s->world.dt))) return e;
  if (s->world.dt > PALP_WORLD_MAX_DT)
    return palp_parse_fail(c, PALP_EPARSE, "time.dt_s: must be <= %g s", PALP_WORLD_MAX_DT);
  /* 1 us is a thousand times finer than the haptic rate; below it a step is no physics,
   * and 1e-300 made every frame period a "whole multiple" (1e298 rounds to itself). */
  if (s->world.dt < 1e-6) return palp_parse_fail(c, PALP_EPARSE, "time.dt_s: %g s is below 1e-6 s", s->world.dt);
  if ((e = get_int(c, t, "time.", "frames", 1, 1, 100000000, &s->frames))) return e;
  /* Deferred tangent rebuilds (docs/haptics.md): part of the physics a log replays, so a
   * session's scene carries it; absent = 0, how every log before it was stepped. */
  if ((e = get_int(c, t, "time.", "refactor_lag_steps", 0, 0, 1000, &s->world.refactor_lag))) return e;
  /* and the blend of a rebuilt tangent (absent = 0: at once, as every log before it) */
  if ((e = get_int(c, t, "time.", "refactor_blend_steps", 0, 0, 1000, &s->world.refactor_blend))) return e;
  s->frame_period = s->world.dt;
  if ((e = get_pos(c, t, "time.", "frame_period_s", 0, &s->frame_period))) return e;
  const double ratio = s->frame_period / s->world.dt;
  if (ratio < 1.0 - 1e-9 || fabs(ratio - round(ratio)) > 1e-6)
    return palp_parse_fail(c, PALP_EPARSE, "time.frame_period_s: must be a whole multiple of time.dt_s");
  if (ratio > 100000.5)
    return palp_parse_fail(c, PALP_EPARSE, "time.frame_period_s: %.0f steps per frame; at most 100000", ratio);

  const cJSON *fx = cJSON_GetObjectItemCaseSensitive(root, "effects");
  if (!fx) return palp_parse_fail(c, PALP_EPARSE, "effects: missing (an array of effect names is required)");
  if (!cJSON_IsArray(fx)) return palp_parse_fail(c, PALP_EPARSE, "effects: expected an array of effect names");
  s->world.effects = 0;
  for (int i = 0; i < cJSON_GetArraySize(fx); ++i) {
    const cJSON *it = cJSON_GetArrayItem(fx, i);
    palp_effect ef;
    if (!cJSON_IsString(it)) return palp_parse_fail(c, PALP_EPARSE, "effects[%d]: expected a string", i);
    if (palp_effect_from_name(it->valuestring, &ef))
      return palp_parse_fail(c, PALP_EPARSE,
                  "effects[%d]: unknown effect \"%s\" (membrane_elasticity, membrane_viscosity, gel_pressure, "
                  "gel_damping, gel_support, gravity, force_feedback)",
                  i, it->valuestring);
    s->world.effects |= (uint32_t)ef;
  }
  if ((s->world.effects & PALP_EFFECT_MEMBRANE_VISCOSITY) && !(s->world.effects & PALP_EFFECT_MEMBRANE_ELASTICITY))
    return palp_parse_fail(c, PALP_EPARSE, "effects: membrane_viscosity needs membrane_elasticity");
  if ((s->world.effects & PALP_EFFECT_GEL_DAMPING) &&
      !(s->world.effects & (PALP_EFFECT_GEL_PRESSURE | PALP_EFFECT_GEL_SUPPORT)))
    return palp_parse_fail(c, PALP_EPARSE, "effects: gel_damping needs gel_pressure or gel_support");
  if ((s->world.effects & PALP_EFFECT_GEL_SUPPORT) && !(s->world.gel.support_modulus > 0.0))
    return palp_parse_fail(c, PALP_EPARSE, "gel.support_modulus_Pa_m: must be > 0 when the gel_support effect is on");
  if ((e = get_vec(c, root, "", "gravity_m_s2", 0, &s->world.gravity))) return e;
  if (!(v3_len(s->world.gravity) <= SCENE_GRAVITY_MAX_M_S2))
    return palp_parse_fail(c, PALP_EPARSE, "gravity_m_s2: |g| must be <= %g m/s^2 (got %g)", SCENE_GRAVITY_MAX_M_S2,
                           v3_len(s->world.gravity));
  if ((e = get_int(c, root, "", "max_contacts", 0, 1, 64, &s->world.max_contacts))) return e;
  /* The surface a finger meets (docs/haptics.md): part of the physics a log replays, so
   * a session's scene carries it; absent = "facets", how every scene and log before
   * 2026-11-27 was stepped (the shipped scenes say "smooth"). */
  s->world.finger_surface = PALP_FINGER_SURFACE_FACETS;
  const cJSON *fsu = cJSON_GetObjectItemCaseSensitive(root, "finger_surface");
  if (fsu && (!cJSON_IsString(fsu) || palp_finger_surface_from_name(fsu->valuestring, &s->world.finger_surface)))
    return palp_parse_fail(c, PALP_EPARSE, "finger_surface: expected \"smooth\" or \"facets\"");
  /* Where the fingertip's contact is linearised (palp.h): absent = "free", how every
   * scene and log before 2026-11-29 was stepped. */
  s->world.finger_linearise = PALP_FINGER_LINEARISE_FREE;
  const cJSON *fli = cJSON_GetObjectItemCaseSensitive(root, "finger_linearise");
  if (fli && (!cJSON_IsString(fli) || palp_finger_linearise_from_name(fli->valuestring, &s->world.finger_linearise)))
    return palp_parse_fail(c, PALP_EPARSE, "finger_linearise: expected \"free\" or \"current\"");

  /* Lesions (optional): hidden inclusions; a trainee's station never sees the scene. */
  const cJSON *ls = cJSON_GetObjectItemCaseSensitive(root, "lesions");
  if (ls) {
    if (!cJSON_IsArray(ls)) return palp_parse_fail(c, PALP_EPARSE, "lesions: expected an array");
    const int nl = cJSON_GetArraySize(ls);
    if (nl > PALP_MAX_LESIONS) return palp_parse_fail(c, PALP_EPARSE, "lesions: at most %d", PALP_MAX_LESIONS);
    for (int i = 0; i < nl; ++i) {
      const cJSON *o = cJSON_GetArrayItem(ls, i);
      char path[32];
      snprintf(path, sizeof path, "lesions[%d].", i);
      if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "lesions[%d]: expected an object", i);
      static const char *const lkeys[] = {"center_m", "radius_m", "stiffness_ratio", NULL};
      if ((e = only_keys(c, o, path, lkeys))) return e;
      palp_lesion *L = &s->world.lesion[i];
      if ((e = get_vec(c, o, path, "center_m", 1, &L->center))) return e;
      if ((e = get_pos(c, o, path, "radius_m", 1, &L->radius))) return e;
      if ((e = get_pos(c, o, path, "stiffness_ratio", 1, &L->stiffness_ratio))) return e;
      const double R = s->world.mesh.radius;
      const double cr = sqrt(L->center.x * L->center.x + L->center.y * L->center.y + L->center.z * L->center.z);
      if (!(cr + L->radius < R) || !(L->center.z - L->radius > 0.0))
        return palp_parse_fail(c, PALP_EPARSE, "lesions[%d]: the sphere must lie inside the dome (radius %g m) and above its base", i, R);
      if (!(L->stiffness_ratio <= 1e6)) return palp_parse_fail(c, PALP_EPARSE, "lesions[%d].stiffness_ratio: must be <= 1e6", i);
    }
    s->world.lesion_count = nl;
  }

  const cJSON *cs = cJSON_GetObjectItemCaseSensitive(root, "contacts");
  if (!cs) return palp_parse_fail(c, PALP_EPARSE, "contacts: missing (an array, possibly empty, is required)");
  if (!cJSON_IsArray(cs)) return palp_parse_fail(c, PALP_EPARSE, "contacts: expected an array");
  const int nc = cJSON_GetArraySize(cs);
  if (nc > PALP_SCENE_MAX_CONTACTS) return palp_parse_fail(c, PALP_EPARSE, "contacts: at most %d", PALP_SCENE_MAX_CONTACTS);
  if (nc > s->world.max_contacts) s->world.max_contacts = nc;
  for (int i = 0; i < nc; ++i)
    if ((e = parse_contact(c, cJSON_GetArrayItem(cs, i), i, s->world.mesh.radius, &s->contact[i]))) return e;
  s->contact_count = nc;
  return PALP_OK;
}

static int parse_with_dir(const char *json, const char *dir, palp_scene *out, char *err, size_t errlen) {
  ctx c = {err, errlen};
  if (err && errlen) err[0] = 0;
  if (!json || !out) return palp_parse_fail(&c, PALP_EINVAL, "scene: no input");
  char why[200];
  cJSON *root = palp_json_parse_strict(json, why, sizeof why);
  if (!root) return palp_parse_fail(&c, PALP_EPARSE, "scene: %s", why);
  int e = parse_root(&c, root, dir, out);
  cJSON_Delete(root);
  return e;
}

int palp_scene_parse(const char *json, palp_scene *out, char *err, size_t errlen) {
  return parse_with_dir(json, NULL, out, err, errlen);
}

int palp_scene_parse_in(const char *json, const char *dir, palp_scene *out, char *err, size_t errlen) {
  return parse_with_dir(json, dir ? dir : ".", out, err, errlen);
}

int palp_scene_load(const char *path, palp_scene *out, char *err, size_t errlen) {
  char *txt, why[200];
  const int rc = palp_input_file_read(path, SCENE_FILE_MAX, &txt, NULL, why, sizeof why);
  if (rc) {
    if (err && errlen) snprintf(err, errlen, "%s: cannot read the scene file: %s", path, why);
    return rc == PALP_ENOMEM ? rc : PALP_EIO;
  }
  char dir[1024];
  snprintf(dir, sizeof dir, "%s", path);
  char *slash = strrchr(dir, '/');
  if (!slash) snprintf(dir, sizeof dir, "."); /* "parameters" from the working directory, as before */
  else if (slash == dir) dir[1] = 0;           /* "/x.json" lies in "/" */
  else *slash = 0;
  int e = parse_with_dir(txt, dir, out, err, errlen);
  free(txt);
  return e;
}

/* A number written so that it parses back to the same double. cJSON prints 15
 * significant digits whenever they read back within a relative DBL_EPSILON, which
 * is not always the same double (-0.018825206147913998 came back as ...914001), and
 * a replayed world built from that scene diverged from the session's after 66 frames.
 * 17 significant digits always round-trip an IEEE double. */
static cJSON *exact_number(double v) {
  char buf[40];
  if (!isfinite(v)) return cJSON_CreateNull();
  snprintf(buf, sizeof buf, "%.17g", v);
  return cJSON_CreateRaw(buf);
}

static cJSON *add_exact(cJSON *obj, const char *key, double v) {
  cJSON *n = exact_number(v);
  if (n) cJSON_AddItemToObject(obj, key, n);
  return n;
}

static cJSON *vec_json(palp_vec3 v) {
  cJSON *a = cJSON_CreateArray();
  if (!a) return NULL;
  cJSON_AddItemToArray(a, exact_number(v.x));
  cJSON_AddItemToArray(a, exact_number(v.y));
  cJSON_AddItemToArray(a, exact_number(v.z));
  return a;
}

char *palp_scene_to_json(const palp_scene *s) {
  cJSON *r = cJSON_CreateObject();
  if (!r) return NULL;
  cJSON_AddStringToObject(r, "name", s->name);
  /* only when declared, so that the scenes of earlier logs print as they did */
  if (s->material[0]) cJSON_AddStringToObject(r, "material", s->material);
  cJSON *m = cJSON_AddObjectToObject(r, "mesh");
  add_exact(m, "radius_m", s->world.mesh.radius);
  add_exact(m, "vertex_count", s->world.mesh.vertex_count);
  const palp_membrane_params *mp = &s->world.membrane;
  cJSON *mb = cJSON_AddObjectToObject(r, "membrane");
  add_exact(mb, "thickness_m", mp->thickness);
  add_exact(mb, "density_kg_m3", mp->density);
  add_exact(mb, "E1_Pa", mp->E1);
  add_exact(mb, "eta1_Pa_s", mp->eta1);
  add_exact(mb, "E2_Pa", mp->E2);
  add_exact(mb, "eta2_Pa_s", mp->eta2);
  /* only when set, so that the scenes of earlier logs print as they did */
  if (mp->bending_stiffness > 0.0) add_exact(mb, "bending_stiffness_N_m", mp->bending_stiffness);
  if (mp->rim_hinge_release > 0.0) add_exact(mb, "rim_hinge_release", mp->rim_hinge_release);
  if (mp->skin_bending_stiffness > 0.0) add_exact(mb, "skin_bending_stiffness_N_m", mp->skin_bending_stiffness);
  const palp_gel_params *gp = &s->world.gel;
  cJSON *g = cJSON_AddObjectToObject(r, "gel");
  cJSON_AddStringToObject(g, "law", gp->law == PALP_GEL_POLYTROPIC ? "polytropic" : "paper_literal");
  add_exact(g, "pressure_Pa", gp->pressure);
  add_exact(g, "a1", gp->a1);
  add_exact(g, "a2_Pa_s_m3", gp->a2);
  add_exact(g, "a3_s2", gp->a3);
  add_exact(g, "support_modulus_Pa_m", gp->support_modulus);
  add_exact(g, "support_viscosity_Pa_s_m", gp->support_viscosity);
  add_exact(g, "support_bulk_fraction", gp->support_bulk_fraction);
  if (gp->support_relax_modulus > 0.0) {
    add_exact(g, "support_relax_modulus_Pa_m", gp->support_relax_modulus);
    add_exact(g, "support_relax_time_s", gp->support_relax_time);
  }
  if (gp->support_stiffening > 0.0) {
    add_exact(g, "support_stiffening", gp->support_stiffening);
    add_exact(g, "support_stiffening_power", gp->support_stiffening_power);
  }
  if (gp->support_base_reach > 0.0) add_exact(g, "support_base_reach", gp->support_base_reach);
  add_exact(g, "density_kg_m3", gp->density);
  add_exact(g, "added_mass_fraction", gp->added_mass_fraction);
  if (s->world.lesion_count > 0) {
    cJSON *ls = cJSON_AddArrayToObject(r, "lesions");
    for (int i = 0; i < s->world.lesion_count; ++i) {
      const palp_lesion *L = &s->world.lesion[i];
      cJSON *o = cJSON_CreateObject();
      cJSON_AddItemToObject(o, "center_m", vec_json(L->center));
      add_exact(o, "radius_m", L->radius);
      add_exact(o, "stiffness_ratio", L->stiffness_ratio);
      cJSON_AddItemToArray(ls, o);
    }
  }
  /* only when stated, so that the scenes of earlier logs print as they did */
  if (s->world.validated_count > 0) {
    cJSON *va = cJSON_AddObjectToObject(r, "validated");
    cJSON *vf = va ? cJSON_AddArrayToObject(va, "finger") : NULL;
    for (int i = 0; vf && i < s->world.validated_count; ++i) {
      cJSON *o = cJSON_CreateObject();
      add_exact(o, "polar_rad", s->world.validated_polar[i]);
      add_exact(o, "depth_m", s->world.validated_depth[i]);
      cJSON_AddItemToArray(vf, o);
    }
    if (va && s->world.validated_hinge_error > 0.0) add_exact(va, "hinge_error_rad", s->world.validated_hinge_error);
  }
  cJSON *t = cJSON_AddObjectToObject(r, "time");
  add_exact(t, "dt_s", s->world.dt);
  add_exact(t, "frames", s->frames);
  add_exact(t, "frame_period_s", s->frame_period);
  if (s->world.refactor_lag > 0) add_exact(t, "refactor_lag_steps", s->world.refactor_lag);
  if (s->world.refactor_blend > 0) add_exact(t, "refactor_blend_steps", s->world.refactor_blend);
  cJSON *fx = cJSON_AddArrayToObject(r, "effects");
  for (int i = 0; i < 7; ++i)
    if (s->world.effects & (1u << i)) cJSON_AddItemToArray(fx, cJSON_CreateString(palp_effect_name((palp_effect)(1u << i))));
  cJSON_AddItemToObject(r, "gravity_m_s2", vec_json(s->world.gravity));
  add_exact(r, "max_contacts", s->world.max_contacts);
  /* only when smooth, so that the scenes of earlier logs print as they did */
  if (s->world.finger_surface != PALP_FINGER_SURFACE_FACETS)
    cJSON_AddStringToObject(r, "finger_surface", palp_finger_surface_name(s->world.finger_surface));
  if (s->world.finger_linearise != PALP_FINGER_LINEARISE_FREE)
    cJSON_AddStringToObject(r, "finger_linearise", palp_finger_linearise_name(s->world.finger_linearise));
  cJSON *cs = cJSON_AddArrayToObject(r, "contacts");
  for (int i = 0; i < s->contact_count; ++i) {
    const palp_scene_contact *sc = &s->contact[i];
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "distribution", dist_names[sc->def.distribution - 1]);
    cJSON_AddItemToObject(o, "center_m", vec_json(sc->def.center));
    add_exact(o, "patch_area_m2", sc->def.patch_area);
    add_exact(o, "sigma_fraction", sc->def.sigma_fraction);
    add_exact(o, "offset_fraction", sc->def.offset_fraction);
    cJSON_AddItemToObject(o, "offset_dir", vec_json(sc->def.offset_dir));
    cJSON_AddItemToObject(o, "direction", vec_json(sc->direction));
    cJSON *p = cJSON_AddObjectToObject(o, "profile");
    const palp_profile *pr = &sc->profile;
    cJSON_AddStringToObject(p, "kind", profile_names[pr->kind - 1]);
    if (pr->kind == PALP_PROFILE_KEYFRAMES) {
      cJSON *keys = cJSON_AddArrayToObject(p, "keyframes");
      /* exact_number, as every other number: cJSON_CreateDoubleArray prints 15 digits, and a
       * key at 0.30000000000000004 s came back as 0.29999999999999999 s (a replay's profile
       * then switches one step apart from the session's). */
      for (int k = 0; k < pr->key_count; ++k) {
        cJSON *kv = cJSON_CreateArray();
        if (!kv) continue;
        cJSON_AddItemToArray(kv, exact_number(pr->key_t[k]));
        cJSON_AddItemToArray(kv, exact_number(pr->key_f[k]));
        cJSON_AddItemToArray(keys, kv);
      }
    } else {
      add_exact(p, "magnitude_N", pr->magnitude);
      add_exact(p, "t_on_s", pr->t_on);
      add_exact(p, "t_off_s", pr->t_off);
      if (pr->kind == PALP_PROFILE_SINE) {
        add_exact(p, "frequency_Hz", pr->frequency);
        add_exact(p, "offset_N", pr->offset);
      }
    }
    cJSON_AddItemToArray(cs, o);
  }
  char *out = cJSON_Print(r);
  cJSON_Delete(r);
  return out;
}

palp_world *palp_scene_create_world(const palp_scene *s, int *err) {
  palp_world *w = palp_world_create(&s->world, err);
  if (!w) return NULL;
  for (int i = 0; i < s->contact_count; ++i) {
    const int id = palp_world_add_contact(w, &s->contact[i].def);
    if (id < 0) {
      palp_world_destroy(w);
      if (err) *err = id;
      return NULL;
    }
  }
  return w;
}

double palp_scene_step_time(const palp_scene *s, long f, int q) {
  return (double)f * s->frame_period + (double)q * s->world.dt;
}

int palp_scene_apply(const palp_scene *s, palp_world *w, double t) {
  const palp_mesh *m = palp_world_mesh(w);
  for (int i = 0; i < s->contact_count; ++i) {
    const palp_scene_contact *sc = &s->contact[i];
    palp_vec3 dir = sc->direction;
    if (!v3_isfinite(dir)) return PALP_EINVAL;
    if (is_zero(dir)) {
      /* Inward normal at the contact centre: the rest surface normal of a sphere. */
      const int v = palp_mesh_nearest_vertex(m, m->rest, sc->def.center);
      dir = v3_scale(m->rest[v], -1.0);
    }
    dir = unit_direction(dir);
    const int e = palp_world_set_contact_force(w, i, v3_scale(dir, palp_profile_eval(&sc->profile, t)));
    if (e) return e;
  }
  return PALP_OK;
}
