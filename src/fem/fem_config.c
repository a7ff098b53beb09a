/*
 * fem_config.c - defaults (paper Tables I-II and Eq. 4) and JSON overrides.
 *
 * Table I (membrane): thickness 2 mm, density 950 kg/m^3, C10 = 700.3 kPa,
 * D1 = 0.001 1/MPa. Table II (gel): density 950 kg/m^3, C10 = 10.3 kPa,
 * D1 = 0.001 1/MPa. The Prony constants printed beside the tables (g1 = 0.9,
 * tau1 = 0.002 s; g2 = 0.09, tau2 = 0.005 s) are applied to both materials: the
 * text says "Both materials use a two-term Prony series" and prints one set.
 *
 * JSON form (every key optional; unknown keys are errors):
 * { "mesh": {"level": 2, "radius": 0.04, "membrane_thickness": 0.002,
 *            "core_fraction": 0.5, "membrane_layers": 0,
 *            "grading": 1, "grading_polar_deg": 0},
 *   "inp": "phantom.inp",
 *   "membrane": {"density": 950, "c10": 700.3e3, "d1": 1e-9,
 *                "prony": [{"g": 0.9, "tau": 0.002}, {"g": 0.09, "tau": 0.005}]},
 *   "material": "paper_long_term" | "paper_instantaneous" | "breast_tissue",
 *   "gel": {...}, "c10_reading": "long_term" | "instantaneous",
 *   "dt": 0.01, "newmark_beta": 0.25, "newmark_gamma": 0.5, "max_newton": 12,
 *   "newton_rtol": 1e-4, "newton_atol": 1e-9, "max_cutbacks": 8, "cache_dir": "cache/fem",
 *   "full_newton": 0, "pcg_refactor": 0, "threads": 2, "factor_lag": 5,
 *   "load_map": "point" | "patch", "hht_alpha": 0 }
 * "hht_alpha" (in [-1/3, 0]) also sets newmark_beta = (1 - alpha)^2 / 4 and
 * newmark_gamma = 1/2 - alpha; giving either beside a nonzero alpha is an error.
 * Units: SI (m, kg/m^3, Pa, 1/Pa, s).
 *
 * "material" is applied first, so "membrane", "gel" and "c10_reading" given beside
 * it override single fields of the profile. "c10_reading" alone is kept as the
 * older spelling: with the paper's tables, "long_term" is paper_long_term and
 * "instantaneous" is paper_instantaneous (docs/materials.md).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "fem_internal.h"
#include "palp_input_file.h"

static palp_fem_material paper_material(double c10) {
  palp_fem_material m = {.density = 950.0, .c10 = c10, .d1 = 0.001e-6, .prony_count = 2};
  m.g[0] = 0.9;
  m.tau[0] = 0.002;
  m.g[1] = 0.09;
  m.tau[1] = 0.005;
  return m;
}

/* Breast tissue (docs/materials.md has the sources). Neo-Hookean, nearly
 * incompressible (nu = 0.499): mu = E / 3, K = 2 mu (1 + nu) / (3 (1 - 2 nu)),
 * D1 = 2 / K, C10 = mu / 2. */
static palp_fem_material tissue_material(double young, double nu) {
  const double mu = young / 3.0, k = 2.0 * mu * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu));
  palp_fem_material m = {.density = 950.0, .c10 = 0.5 * mu, .d1 = 2.0 / k, .prony_count = 1};
  /* Assumed, not from a source: a third of the shear stiffness relaxing over
   * 0.5 s, of the order of the ~1 s recovery the real-time model is fitted to. */
  m.g[0] = 0.3;
  m.tau[0] = 0.5;
  return m;
}

typedef struct material_profile {
  const char *name, *label;
} material_profile;

static const material_profile profiles[] = {
    {"paper_long_term", "paper Tables I-II, C10 read as the long-term (relaxed) modulus"},
    {"paper_instantaneous", "reproduction of the paper's literal reading (C10 instantaneous; relaxed ~1% of it)"},
    {"breast_tissue", "breast fat (secant modulus at fingertip strains) under 2 mm of skin, from the literature"},
};
#define PROFILE_COUNT ((int)(sizeof profiles / sizeof *profiles))

const char *const *palp_fem_material_names(void) {
  static const char *const names[] = {"paper_long_term", "paper_instantaneous", "breast_tissue", NULL};
  return names;
}

const char *palp_fem_material_label(const char *name) {
  for (int i = 0; name && i < PROFILE_COUNT; ++i)
    if (strcmp(name, profiles[i].name) == 0) return profiles[i].label;
  return "";
}

void palp_fem_config_set_hht(palp_fem_config *cfg, double alpha) {
  cfg->hht_alpha = alpha;
  cfg->newmark_beta = 0.25 * (1.0 - alpha) * (1.0 - alpha);
  cfg->newmark_gamma = 0.5 - alpha;
}

int palp_fem_config_set_material(palp_fem_config *cfg, const char *name, char *err, size_t errlen) {
  if (name && strcmp(name, "paper_long_term") == 0) {
    cfg->membrane = paper_material(700.3e3);
    cfg->gel = paper_material(10.3e3);
    cfg->c10_reading = PALP_FEM_C10_LONG_TERM;
    cfg->load_map = PALP_FEM_LOAD_PATCH;
    if (cfg->hht_alpha != 0.0) palp_fem_config_set_hht(cfg, 0.0); /* the trapezoidal rule; its Prony terms damp */
  } else if (name && strcmp(name, "paper_instantaneous") == 0) {
    cfg->membrane = paper_material(700.3e3);
    cfg->gel = paper_material(10.3e3);
    cfg->c10_reading = PALP_FEM_C10_INSTANTANEOUS;
    cfg->load_map = PALP_FEM_LOAD_POINT; /* the reproduction reads the loads literally too */
    if (cfg->hht_alpha != 0.0) palp_fem_config_set_hht(cfg, 0.0);
  } else if (name && strcmp(name, "breast_tissue") == 0) {
    cfg->membrane = tissue_material(334e3, 0.499); /* breast skin, Sutradhar & Miller 2013 */
    cfg->gel = tissue_material(15e3, 0.499);       /* fat secant modulus, Samani 2007 / Krouskop 1998 / Wellman 1999 */
    cfg->c10_reading = PALP_FEM_C10_LONG_TERM;
    cfg->load_map = PALP_FEM_LOAD_PATCH;
    /* HHT-alpha at Abaqus's default -0.05: this profile's one Prony term (tau 0.5 s)
     * leaves the modes a 10 ms step cannot resolve undamped, and under the trapezoidal
     * rule they rang without decay (the peak vertex jumping 3.6-5.6 mm from frame to
     * frame under a constant 3 N, 0.2-0.6 m/s of velocity in the mesh) until, with the
     * patch map, distribution IV's recovery blew up at t = 3.13 s (docs/fem.md,
     * "Time integration") */
    palp_fem_config_set_hht(cfg, -0.05);
  } else {
    snprintf(err, errlen, "material: unknown profile \"%.40s\" (expected paper_long_term, paper_instantaneous or "
             "breast_tissue)", name ? name : "");
    return PALP_EINVAL;
  }
  snprintf(cfg->material, sizeof cfg->material, "%s", name);
  return 0;
}

palp_fem_config palp_fem_default_config(void) {
  palp_fem_config c;
  memset(&c, 0, sizeof c);
  c.mesh = palp_fem_mesh_default_def();
  /* The physically sound reading, paper_long_term, is the default (issue 12): Mehrabian &
   * Samani's constants come from quasi-static fits, so they are relaxed moduli, and a
   * flat-punch hand calculation agrees with it; the instantaneous reading leaves the
   * relaxed gel softer than fat. A scene names the profile its real-time parameters were
   * fitted to ("material"), and the tools use that one (docs/materials.md). */
  char e[8];
  (void)palp_fem_config_set_material(&c, "paper_long_term", e, sizeof e);
  c.dt = 0.0;
  c.newmark_beta = 0.25;
  c.newmark_gamma = 0.5;
  c.max_newton = 12;
  /* 1e-4 of the force scale (3 N here) leaves a displacement error of ~1e-4 of
   * the response, far below the discretisation error (~10% between levels 2 and
   * 3), and saves the third Newton iteration of most steps. */
  c.newton_rtol = 1e-4;
  c.threads = 2;
  c.newton_atol = 1e-9;
  c.max_cutbacks = 8;
  c.full_newton = 0;
  c.pcg_refactor = 0;
  /* 5 attempts (2026-12-03, docs/fem.md "The lag again"): the factorisation runs
   * CHOLMOD's loops on one thread (fem_solver.c omp_serial: 0.87-0.99 s against
   * 1.56-1.80 s), so a renewal no longer needs 8 attempts, and a younger factor costs
   * fewer CG iterations (354 against 8's 415). 4 never waited until the preconditioner's
   * single-precision solve made the attempts ~20% shorter; then it waited 0-0.33 s a run
   * and 5 did not. 8 from 2026-12-02, when a renewal took ~1.4 s; 3 before. */
  c.factor_lag = 5;
  /* A real-time vertex's load as its hat-function traction, not a point force: a point
   * force on a solid has no converged displacement (distribution I's peak grew 0.83 ->
   * 1.19 -> 1.54 mm from level 2 to 4), the patch converges like a distributed load
   * (0.78 -> 1.06 -> 1.21 mm) and matches what a vertex of the 338-vertex net stands
   * for. The point map stays selectable, labelled as the literal nodal load. */
  c.load_map = PALP_FEM_LOAD_PATCH;
  snprintf(c.cache_dir, sizeof c.cache_dir, "cache/fem");
  return c;
}

int palp_fem_config_for_scene(const palp_scene *scene, palp_fem_config *out, char *err, size_t errlen) {
  *out = palp_fem_default_config();
  return scene && scene->material[0] ? palp_fem_config_set_material(out, scene->material, err, errlen) : PALP_OK;
}

static int number(const cJSON *o, const char *key, const char *ctx, double *out, char *err, size_t errlen) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  if (!v) return 0;
  if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
    snprintf(err, errlen, "%s%s: expected a number", ctx, key);
    return PALP_EPARSE;
  }
  *out = v->valuedouble;
  return 0;
}

static int integer(const cJSON *o, const char *key, const char *ctx, int *out, char *err, size_t errlen) {
  double d = *out;
  int rc = number(o, key, ctx, &d, err, errlen);
  if (rc) return rc;
  if (d != floor(d) || fabs(d) > 1e9) {
    snprintf(err, errlen, "%s%s: expected an integer", ctx, key);
    return PALP_EPARSE;
  }
  *out = (int)d;
  return 0;
}

static int string(const cJSON *o, const char *key, const char *ctx, char *out, size_t cap, char *err, size_t errlen) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  if (!v) return 0;
  if (!cJSON_IsString(v) || strlen(v->valuestring) >= cap) {
    snprintf(err, errlen, "%s%s: expected a string shorter than %zu bytes", ctx, key, cap);
    return PALP_EPARSE;
  }
  snprintf(out, cap, "%s", v->valuestring);
  return 0;
}

static int only_keys(const cJSON *o, const char *const *keys, const char *ctx, char *err, size_t errlen) {
  for (const cJSON *c = o->child; c; c = c->next) {
    int ok = 0;
    for (const char *const *k = keys; *k; ++k) ok |= strcmp(*k, c->string) == 0;
    if (!ok) {
      snprintf(err, errlen, "%s%s: unknown key", ctx, c->string);
      return PALP_EPARSE;
    }
  }
  return 0;
}

static int material(const cJSON *o, const char *ctx, palp_fem_material *m, char *err, size_t errlen) {
  if (!cJSON_IsObject(o)) {
    snprintf(err, errlen, "%s: expected an object", ctx);
    return PALP_EPARSE;
  }
  static const char *const keys[] = {"density", "c10", "d1", "prony", NULL};
  char c[64];
  snprintf(c, sizeof c, "%s.", ctx);
  int rc = only_keys(o, keys, c, err, errlen);
  if (!rc) rc = number(o, "density", c, &m->density, err, errlen);
  if (!rc) rc = number(o, "c10", c, &m->c10, err, errlen);
  if (!rc) rc = number(o, "d1", c, &m->d1, err, errlen);
  if (rc) return rc;
  const cJSON *p = cJSON_GetObjectItemCaseSensitive(o, "prony");
  if (!p) return 0;
  if (!cJSON_IsArray(p) || cJSON_GetArraySize(p) > PALP_FEM_MAX_PRONY) {
    snprintf(err, errlen, "%sprony: expected an array of at most %d {g, tau} objects", c, PALP_FEM_MAX_PRONY);
    return PALP_EPARSE;
  }
  m->prony_count = 0;
  const cJSON *t;
  cJSON_ArrayForEach(t, p) {
    char cc[96];
    snprintf(cc, sizeof cc, "%sprony[%d].", c, m->prony_count);
    static const char *const tk[] = {"g", "tau", NULL};
    if (!cJSON_IsObject(t)) {
      snprintf(err, errlen, "%sprony[%d]: expected an object", c, m->prony_count);
      return PALP_EPARSE;
    }
    double g = NAN, tau = NAN;
    rc = only_keys(t, tk, cc, err, errlen);
    if (!rc) rc = number(t, "g", cc, &g, err, errlen);
    if (!rc) rc = number(t, "tau", cc, &tau, err, errlen);
    if (rc) return rc;
    if (isnan(g) || isnan(tau)) {
      snprintf(err, errlen, "%s: needs both g and tau", cc);
      return PALP_EPARSE;
    }
    m->g[m->prony_count] = g;
    m->tau[m->prony_count] = tau;
    m->prony_count++;
  }
  return 0;
}

int palp_fem_config_parse(const char *json, palp_fem_config *cfg, char *err, size_t errlen) {
  char why[200];
  cJSON *root = palp_json_parse_strict(json, why, sizeof why);
  if (!root || !cJSON_IsObject(root)) {
    snprintf(err, errlen, "config: %s", root ? "not a JSON object" : why);
    cJSON_Delete(root);
    return PALP_EPARSE;
  }
  static const char *const keys[] = {"mesh",         "inp",        "material",   "membrane",    "gel",          "c10_reading",
                                     "dt",           "newmark_beta", "newmark_gamma", "max_newton", "newton_rtol",
                                     "newton_atol",  "max_cutbacks", "cache_dir",   "full_newton", "pcg_refactor", "threads", "factor_lag", "load_map", "hht_alpha", NULL};
  int rc = only_keys(root, keys, "", err, errlen);
  const cJSON *mesh = cJSON_GetObjectItemCaseSensitive(root, "mesh");
  if (!rc && mesh) {
    static const char *const mk[] = {"level",           "radius",  "membrane_thickness", "core_fraction",
                                     "membrane_layers", "grading", "grading_polar_deg",  NULL};
    if (!cJSON_IsObject(mesh)) {
      snprintf(err, errlen, "mesh: expected an object");
      rc = PALP_EPARSE;
    }
    if (!rc) rc = only_keys(mesh, mk, "mesh.", err, errlen);
    if (!rc) rc = integer(mesh, "level", "mesh.", &cfg->mesh.level, err, errlen);
    if (!rc) rc = number(mesh, "radius", "mesh.", &cfg->mesh.radius, err, errlen);
    if (!rc) rc = number(mesh, "membrane_thickness", "mesh.", &cfg->mesh.membrane_thickness, err, errlen);
    if (!rc) rc = number(mesh, "core_fraction", "mesh.", &cfg->mesh.core_fraction, err, errlen);
    if (!rc) rc = integer(mesh, "membrane_layers", "mesh.", &cfg->mesh.membrane_layers, err, errlen);
    if (!rc) rc = number(mesh, "grading", "mesh.", &cfg->mesh.grading, err, errlen);
    if (!rc) rc = number(mesh, "grading_polar_deg", "mesh.", &cfg->mesh.grading_polar_deg, err, errlen);
  }
  if (!rc) rc = string(root, "inp", "", cfg->inp_path, sizeof cfg->inp_path, err, errlen);
  const cJSON *o;
  if (!rc && (o = cJSON_GetObjectItemCaseSensitive(root, "material"))) {
    if (!cJSON_IsString(o)) {
      snprintf(err, errlen, "material: expected a profile name (a string)");
      rc = PALP_EPARSE;
    } else
      rc = palp_fem_config_set_material(cfg, o->valuestring, err, errlen) ? PALP_EPARSE : 0;
  }
  if (!rc && (o = cJSON_GetObjectItemCaseSensitive(root, "membrane"))) rc = material(o, "membrane", &cfg->membrane, err, errlen);
  if (!rc && (o = cJSON_GetObjectItemCaseSensitive(root, "gel"))) rc = material(o, "gel", &cfg->gel, err, errlen);
  if (!rc && (o = cJSON_GetObjectItemCaseSensitive(root, "c10_reading"))) {
    if (cJSON_IsString(o) && strcmp(o->valuestring, "long_term") == 0) cfg->c10_reading = PALP_FEM_C10_LONG_TERM;
    else if (cJSON_IsString(o) && strcmp(o->valuestring, "instantaneous") == 0)
      cfg->c10_reading = PALP_FEM_C10_INSTANTANEOUS;
    else {
      snprintf(err, errlen, "c10_reading: expected \"long_term\" or \"instantaneous\"");
      rc = PALP_EPARSE;
    }
  }
  /* The alias: c10_reading switches between the two paper profiles; material
   * fields given beside a profile make the materials custom (name cleared). */
  if (!rc && cJSON_GetObjectItemCaseSensitive(root, "c10_reading") && strncmp(cfg->material, "paper_", 6) == 0) {
    snprintf(cfg->material, sizeof cfg->material, "%s",
             cfg->c10_reading == PALP_FEM_C10_LONG_TERM ? "paper_long_term" : "paper_instantaneous");
    cfg->load_map = cfg->c10_reading == PALP_FEM_C10_LONG_TERM ? PALP_FEM_LOAD_PATCH : PALP_FEM_LOAD_POINT;
  }
  if (!rc && (cJSON_GetObjectItemCaseSensitive(root, "membrane") || cJSON_GetObjectItemCaseSensitive(root, "gel") ||
              (cfg->c10_reading == PALP_FEM_C10_INSTANTANEOUS && strcmp(cfg->material, "breast_tissue") == 0)))
    cfg->material[0] = 0;
  if (!rc) rc = number(root, "dt", "", &cfg->dt, err, errlen);
  if (!rc) rc = number(root, "newmark_beta", "", &cfg->newmark_beta, err, errlen);
  if (!rc) rc = number(root, "newmark_gamma", "", &cfg->newmark_gamma, err, errlen);
  if (!rc) rc = integer(root, "max_newton", "", &cfg->max_newton, err, errlen);
  if (!rc) rc = number(root, "newton_rtol", "", &cfg->newton_rtol, err, errlen);
  if (!rc) rc = number(root, "newton_atol", "", &cfg->newton_atol, err, errlen);
  if (!rc) rc = integer(root, "max_cutbacks", "", &cfg->max_cutbacks, err, errlen);
  if (!rc) rc = string(root, "cache_dir", "", cfg->cache_dir, sizeof cfg->cache_dir, err, errlen);
  if (!rc) rc = integer(root, "full_newton", "", &cfg->full_newton, err, errlen);
  if (!rc) rc = integer(root, "pcg_refactor", "", &cfg->pcg_refactor, err, errlen);
  if (!rc) rc = integer(root, "threads", "", &cfg->threads, err, errlen);
  if (!rc) rc = integer(root, "factor_lag", "", &cfg->factor_lag, err, errlen);
  if (!rc && (o = cJSON_GetObjectItemCaseSensitive(root, "load_map"))) {
    if (cJSON_IsString(o) && strcmp(o->valuestring, "point") == 0) cfg->load_map = PALP_FEM_LOAD_POINT;
    else if (cJSON_IsString(o) && strcmp(o->valuestring, "patch") == 0) cfg->load_map = PALP_FEM_LOAD_PATCH;
    else {
      snprintf(err, errlen, "load_map: expected \"point\" or \"patch\"");
      rc = PALP_EPARSE;
    }
  }
  if (!rc && cJSON_GetObjectItemCaseSensitive(root, "hht_alpha")) {
    rc = number(root, "hht_alpha", "", &cfg->hht_alpha, err, errlen);
    if (!rc && cfg->hht_alpha != 0.0 && (cJSON_GetObjectItemCaseSensitive(root, "newmark_beta") ||
                                         cJSON_GetObjectItemCaseSensitive(root, "newmark_gamma"))) {
      snprintf(err, errlen, "hht_alpha sets newmark_beta and newmark_gamma; give one or the other");
      rc = PALP_EINVAL;
    }
    if (!rc) palp_fem_config_set_hht(cfg, cfg->hht_alpha);
  }
  cJSON_Delete(root);
  if (!rc) rc = palp_fem_config_validate(cfg, err, errlen);
  return rc;
}

int palp_fem_config_load(const char *path, palp_fem_config *cfg, char *err, size_t errlen) {
  char *buf, why[200];
  const int rd = palp_input_file_read(path, (size_t)1 << 24, &buf, NULL, why, sizeof why);
  if (rd) {
    snprintf(err, errlen, "%s: %s", path, why);
    return rd == PALP_ENOMEM ? rd : PALP_EIO;
  }
  char e2[200];
  int rc = palp_fem_config_parse(buf, cfg, e2, sizeof e2);
  if (rc) snprintf(err, errlen, "%s: %s", path, e2);
  free(buf);
  /* "inp" is read from beside the configuration, as a scene's "parameters" and an exercise's
   * "phantom" are from beside theirs: until session 81 from the working directory, so a
   * configuration found its mesh only when run from its own folder ("m.inp: cannot open").
   * cache_dir stays the working directory's (a cache, not an input: docs/fem.md). */
  const char *slash = strrchr(path, '/');
  if (!rc && cfg->inp_path[0] && cfg->inp_path[0] != '/' && slash) {
    char full[sizeof cfg->inp_path];
    const int n = snprintf(full, sizeof full, "%.*s/%s", (int)(slash - path), path, cfg->inp_path);
    if (n < 0 || (size_t)n >= sizeof full) {
      snprintf(err, errlen, "%s: inp: \"%s\" beside the configuration makes a path longer than %zu bytes", path,
               cfg->inp_path, sizeof full - 1);
      return PALP_EINVAL;
    }
    memcpy(cfg->inp_path, full, (size_t)n + 1);
  }
  return rc;
}

static int check_material(const palp_fem_material *m, const char *name, char *err, size_t errlen) {
  if (!(m->density > 0.0) || !(m->c10 > 0.0) || !(m->d1 > 0.0)) {
    snprintf(err, errlen, "%s: density, c10 and d1 must be positive", name);
    return PALP_EINVAL;
  }
  if (m->prony_count < 0 || m->prony_count > PALP_FEM_MAX_PRONY) {
    snprintf(err, errlen, "%s: at most %d Prony terms", name, PALP_FEM_MAX_PRONY);
    return PALP_EINVAL;
  }
  double sum = 0.0;
  for (int k = 0; k < m->prony_count; ++k) {
    if (!(m->g[k] >= 0.0) || !(m->tau[k] > 0.0)) {
      snprintf(err, errlen, "%s.prony[%d]: need g >= 0 and tau > 0 s", name, k);
      return PALP_EINVAL;
    }
    sum += m->g[k];
  }
  if (!(sum < 1.0)) {
    snprintf(err, errlen, "%s.prony: the g_k must sum to less than 1 (got %g)", name, sum);
    return PALP_EINVAL;
  }
  return 0;
}

double palp_fem_memory_estimate_gb(double elements) {
  return 5.0 * pow(elements / 87040.0, 4.0 / 3.0);
}

int palp_fem_config_validate(const palp_fem_config *c, char *err, size_t errlen) {
  int rc = check_material(&c->membrane, "membrane", err, errlen);
  if (!rc) rc = check_material(&c->gel, "gel", err, errlen);
  if (rc) return rc;
  /* Level 8 (87,040 hexahedra, 5.0 GB peak) is the largest ever run. The elements grow as
   * level^3 and a 3D factor's fill as (elements)^(4/3), so memory as level^4: level 9
   * ~8 GB (ccx_crosscheck's own estimate), level 16, once accepted, ~80 GB. Refused up
   * front with the estimate (since session 82), instead of failing as a "singular"
   * factorisation or swapping for hours. (palp_fem_mesh_create keeps its own 1..16: the
   * sha256 of fem_mesh.c is held by the refined-mesh guard references.) */
  if (!c->inp_path[0] && (c->mesh.level < 1 || c->mesh.level > PALP_FEM_MAX_LEVEL)) {
    if (c->mesh.level > PALP_FEM_MAX_LEVEL)
      snprintf(err, errlen, "mesh.level: %d is above %d: it would need roughly %.0f GB (level 8 took 5 GB; memory "
               "grows as level^4)", c->mesh.level, PALP_FEM_MAX_LEVEL, palp_fem_memory_estimate_gb(
                   87040.0 * pow(c->mesh.level / 8.0, 3.0))); /* the elements: level 8's 87,040 x (level / 8)^3 */
    else
      snprintf(err, errlen, "mesh.level: expected 1..%d", PALP_FEM_MAX_LEVEL);
    return PALP_EINVAL;
  }
  /* the mesh's own fields, named (palp_fem_mesh_create's checks; its failure only said
   * "invalid mesh definition (level N)") */
  if (!c->inp_path[0]) {
    const palp_fem_mesh_def *d = &c->mesh;
    const char *bad = !(d->radius > 0.0 && d->radius <= 10.0)                         ? "mesh.radius: expected (0, 10] m"
                      : !(d->membrane_thickness > 0.0 && d->membrane_thickness < 0.5 * d->radius)
                          ? "mesh.membrane_thickness: expected (0, radius / 2) m"
                      : !(d->core_fraction > 0.05 && d->core_fraction < 0.9) ? "mesh.core_fraction: expected (0.05, 0.9)"
                      : d->membrane_layers < 0 || d->membrane_layers == 1 || d->membrane_layers > 32
                          ? "mesh.membrane_layers: expected 0 (automatic) or 2..32"
                      : !(d->grading >= 0.0 && d->grading <= 1.0) ? "mesh.grading: expected [0, 1]"
                      : !(d->grading_polar_deg >= 0.0 && d->grading_polar_deg <= 90.0)
                          ? "mesh.grading_polar_deg: expected [0, 90] deg"
                          : NULL;
    if (bad) {
      snprintf(err, errlen, "%s", bad);
      return PALP_EINVAL;
    }
  }
  if (!(c->dt >= 0.0) || c->dt > 1.0) {
    snprintf(err, errlen, "dt: expected 0 (one step per frame) or a step in (0, 1] s");
    return PALP_EINVAL;
  }
  if (!(c->newmark_beta > 0.0) || !(c->newmark_gamma >= 0.5) ||
      c->newmark_beta < 0.25 * (c->newmark_gamma + 0.5) * (c->newmark_gamma + 0.5) - 1e-12) {
    snprintf(err, errlen, "newmark: need gamma >= 1/2 and beta >= (gamma + 1/2)^2 / 4 (unconditional stability)");
    return PALP_EINVAL;
  }
  if (!(c->hht_alpha >= -1.0 / 3.0 - 1e-12 && c->hht_alpha <= 0.0) ||
      (c->hht_alpha != 0.0 && (fabs(c->newmark_beta - 0.25 * (1.0 - c->hht_alpha) * (1.0 - c->hht_alpha)) > 1e-12 ||
                               fabs(c->newmark_gamma - (0.5 - c->hht_alpha)) > 1e-12))) {
    snprintf(err, errlen, "hht_alpha: expected -1/3..0, with newmark_beta = (1 - alpha)^2 / 4 and newmark_gamma = 1/2 - alpha");
    return PALP_EINVAL;
  }
  if (c->max_newton < 1 || c->max_newton > 60 || c->max_cutbacks < 0 || c->max_cutbacks > 20 || c->pcg_refactor < 0 || c->threads < 1 || c->threads > 16 ||
      c->factor_lag < 0 || c->factor_lag > 64 ||
      !(c->newton_rtol > 0.0) || !(c->newton_atol >= 0.0)) {
    snprintf(err, errlen, "newton: max_newton 1..60, max_cutbacks 0..20, rtol > 0, atol >= 0, pcg_refactor >= 0, threads 1..16, factor_lag 0..64");
    return PALP_EINVAL;
  }
  /* Upper bounds (since session 82): with rtol >= 1, or atol above the load's norm, the
   * first residual (|f_ext| at rest) "converged" at iteration 0 and the run returned all
   * zeros as a valid, cached reference. rtol is relative to the force scale; the tools'
   * smallest loads are ~0.1 N, so atol <= 1e-3 N keeps it below 1% of any of them. */
  if (c->newton_rtol > PALP_FEM_MAX_RTOL) {
    snprintf(err, errlen, "newton_rtol: %g is above %g (a looser test accepts the unloaded state as converged)",
             c->newton_rtol, PALP_FEM_MAX_RTOL);
    return PALP_EINVAL;
  }
  if (c->newton_atol > PALP_FEM_MAX_ATOL) {
    snprintf(err, errlen, "newton_atol: %g N is above %g N (a looser test accepts the unloaded state as converged)",
             c->newton_atol, PALP_FEM_MAX_ATOL);
    return PALP_EINVAL;
  }
  return 0;
}
