/*
 * exercise.c - exercise files (JSON, cJSON): phantom, hidden lesions, pressure bands,
 * time limit, instructions and rubric (palp_assess.h, docs/assessment.md). Keys carry
 * their unit (depth_mm, time_limit_s, ...); every error names its field, as
 * "lesions[1].depth_mm: must be > 0". Unknown keys are refused so that a misspelt
 * rubric entry cannot silently fall back to a default.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_assess.h"
#include "palp_input_file.h"
#include "parse_error.h"
#include "vec3.h"

typedef palp_parse_ctx ctx;

static const char *const band_names[PALP_BAND_COUNT] = {"light", "medium", "deep"};
static const char *const metric_names[PALP_METRIC_COUNT] = {"sensitivity", "false_positives", "thoroughness",
                                                            "pattern",     "time",            "force"};
static const char *const pattern_names[] = {"unsystematic", "vertical_strip", "circles", "radial"};

const char *palp_band_name(int b) { return b >= 0 && b < PALP_BAND_COUNT ? band_names[b] : "none"; }
const char *palp_metric_name(int m) { return m >= 0 && m < PALP_METRIC_COUNT ? metric_names[m] : "?"; }
const char *palp_metric_to_work_on(int m) {
  static const char *const words[PALP_METRIC_COUNT] = {
      "finding the lumps",           "marking only lumps",        "covering the whole dome at each pressure",
      "a systematic search pattern", "finishing within the time", "pressing within the force limit"};
  return m >= 0 && m < PALP_METRIC_COUNT ? words[m] : "?";
}
double palp_shown_tenths(double v, double mark, int reached) {
  const double r = round(v * 10.0) / 10.0;
  if (!reached && (isnan(mark) || r >= mark)) return floor(v * 10.0) / 10.0;
  if (reached && !isnan(mark) && r < mark) return ceil(v * 10.0) / 10.0;
  return r;
}
const char *palp_pattern_name(palp_pattern p) {
  return p >= PALP_PATTERN_UNSYSTEMATIC && p <= PALP_PATTERN_RADIAL ? pattern_names[p] : "?";
}

/* Refuses keys not in the list (NULL-terminated). */
static int only_keys(ctx *c, const cJSON *obj, const char *path, const char *const *keys) {
  for (const cJSON *it = obj->child; it; it = it->next) {
    int ok = 0;
    for (int k = 0; keys[k]; ++k)
      if (it->string && strcmp(it->string, keys[k]) == 0) ok = 1;
    if (!ok) return palp_parse_fail(c, PALP_EPARSE, "%s%s: unknown key", path, it->string ? it->string : "?");
  }
  return PALP_OK;
}

static int get_num(ctx *c, const cJSON *obj, const char *path, const char *key, int required, double lo, double hi,
                   double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? palp_parse_fail(c, PALP_EPARSE, "%s%s: missing (a number is required)", path, key) : PALP_OK;
  if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected a finite number", path, key);
  if (!(it->valuedouble >= lo && it->valuedouble <= hi))
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: must be within [%g, %g] (got %g)", path, key, lo, hi, it->valuedouble);
  *out = it->valuedouble;
  return PALP_OK;
}

static int get_int(ctx *c, const cJSON *obj, const char *path, const char *key, int lo, int hi, int *out) {
  double v = *out;
  int e = get_num(c, obj, path, key, 0, lo, hi, &v);
  if (e) return e;
  if (v != floor(v)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected an integer (got %g)", path, key, v);
  *out = (int)v;
  return PALP_OK;
}

static int get_str(ctx *c, const cJSON *obj, const char *path, const char *key, int required, char *out, size_t cap) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? palp_parse_fail(c, PALP_EPARSE, "%s%s: missing (a string is required)", path, key) : PALP_OK;
  if (!cJSON_IsString(it)) return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected a string", path, key);
  if (strlen(it->valuestring) >= cap)
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: longer than %zu characters", path, key, cap - 1);
  if (required && !it->valuestring[0]) return palp_parse_fail(c, PALP_EPARSE, "%s%s: must not be empty", path, key);
  snprintf(out, cap, "%s", it->valuestring);
  return PALP_OK;
}

/* One of names[0..n-1] (a NULL-terminated list), its index in *out; absent and not required: *out
 * untouched. The error lists the names, so a misspelt choice says what it could have been. */
static int get_choice(ctx *c, const cJSON *obj, const char *path, const char *key, int required,
                      const char *const *names, int *out) {
  char v[32] = "", list[160] = "";
  int e;
  if (!cJSON_GetObjectItemCaseSensitive(obj, key) && !required) return PALP_OK;
  if ((e = get_str(c, obj, path, key, 1, v, sizeof v))) return e;
  for (int i = 0; names[i]; i++) {
    if (strcmp(v, names[i]) == 0) {
      *out = i;
      return PALP_OK;
    }
    const size_t n = strlen(list);
    snprintf(list + n, sizeof list - n, "%s%s", i ? ", " : "", names[i]);
  }
  return palp_parse_fail(c, PALP_EPARSE, "%s%s: unknown \"%s\" (%s)", path, key, v, list);
}

/* [min, max] pair in the given unit, scaled to SI. */
static int get_range(ctx *c, const cJSON *obj, const char *path, const char *key, double scale, double hi, int *has,
                     double *lo_out, double *hi_out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return PALP_OK;
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 2)
    return palp_parse_fail(c, PALP_EPARSE, "%s%s: expected [min, max]", path, key);
  double v[2];
  for (int i = 0; i < 2; ++i) {
    const cJSON *x = cJSON_GetArrayItem(it, i);
    if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble) || x->valuedouble < 0.0 || x->valuedouble > hi)
      return palp_parse_fail(c, PALP_EPARSE, "%s%s[%d]: expected a number within [0, %g]", path, key, i, hi);
    v[i] = x->valuedouble;
  }
  if (!(v[1] > v[0])) return palp_parse_fail(c, PALP_EPARSE, "%s%s: max must be > min", path, key);
  *has = 1;
  *lo_out = v[0] * scale;
  *hi_out = v[1] * scale;
  return PALP_OK;
}

static int parse_lesion(ctx *c, const cJSON *o, int i, int drawn_here, palp_exercise_lesion *L) {
  char path[32];
  snprintf(path, sizeof path, "lesions[%d].", i);
  if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "lesions[%d]: expected an object", i);
  static const char *const keys[] = {"polar_deg", "azimuth_deg", "depth_mm", "diameter_mm", "stiffness_ratio",
                                     "comment",   NULL};
  int e;
  double polar = 0, az = 0, depth = 0, dia = 0;
  if ((e = only_keys(c, o, path, keys))) return e;
  if (drawn_here) { /* placement random: the server draws them; a place here would mislead a reader */
    if (cJSON_GetObjectItemCaseSensitive(o, "polar_deg") || cJSON_GetObjectItemCaseSensitive(o, "azimuth_deg"))
      return palp_parse_fail(c, PALP_EPARSE, "%spolar_deg, azimuth_deg: drawn for each session (placement random): leave "
                             "them out", path);
  } else {
    if ((e = get_num(c, o, path, "polar_deg", 1, 0.0, 90.0, &polar))) return e;
    if ((e = get_num(c, o, path, "azimuth_deg", 1, -360.0, 360.0, &az))) return e;
  }
  if ((e = get_num(c, o, path, "depth_mm", 1, 0.0, 1000.0, &depth))) return e;
  if ((e = get_num(c, o, path, "diameter_mm", 1, 0.0, 1000.0, &dia))) return e;
  if (!(dia > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "%sdiameter_mm: must be > 0", path);
  if (!(depth > dia / 2.0))
    return palp_parse_fail(c, PALP_EPARSE, "%sdepth_mm: the centre must lie deeper than the radius (%g mm) so the lesion is "
                "below the surface (got %g)", path, dia / 2.0, depth);
  L->stiffness_ratio = 0.0;
  if ((e = get_num(c, o, path, "stiffness_ratio", 1, 0.0, 1e6, &L->stiffness_ratio))) return e;
  if (!(L->stiffness_ratio > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "%sstiffness_ratio: must be > 0", path);
  L->polar = polar * PALP_PI / 180.0;
  L->azimuth = az * PALP_PI / 180.0;
  L->depth = depth * 1e-3;
  L->diameter = dia * 1e-3;
  return PALP_OK;
}

/* "placement": {"kind": "fixed" | "random" | "drawn", "polar_deg": [min, max], "min_gap_mm": g,
 * "count": [lo, hi], "per": "session" | "run", "seed": n (drawn only), "comment"}. Absent: fixed. */
static int parse_placement(ctx *c, const cJSON *o, palp_exercise_placement *P) {
  static const char *const keys[] = {"kind", "polar_deg", "min_gap_mm", "seed", "count", "per", "comment", NULL};
  memset(P, 0, sizeof *P);
  if (!o) return PALP_OK;
  if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "placement: expected an object");
  int e;
  if ((e = only_keys(c, o, "placement.", keys))) return e;
  static const char *const kinds[] = {"fixed", "random", "drawn", NULL}; /* palp_placement_kind's order */
  int kind = 0;
  if ((e = get_choice(c, o, "placement.", "kind", 1, kinds, &kind))) return e;
  P->kind = (palp_placement_kind)kind;
  const int band = P->kind != PALP_PLACEMENT_FIXED;
  if (!band) {
    if (cJSON_GetObjectItemCaseSensitive(o, "polar_deg") || cJSON_GetObjectItemCaseSensitive(o, "min_gap_mm") ||
        cJSON_GetObjectItemCaseSensitive(o, "seed") || cJSON_GetObjectItemCaseSensitive(o, "count") ||
        cJSON_GetObjectItemCaseSensitive(o, "per"))
      return palp_parse_fail(c, PALP_EPARSE,
                             "placement: polar_deg, min_gap_mm, seed, count and per belong to kind random or drawn");
    return PALP_OK;
  }
  int has = 0;
  /* up to 80 deg: the last 10 deg before the fixed rim are the model's stiffest and least like a breast */
  if ((e = get_range(c, o, "placement.", "polar_deg", PALP_PI / 180.0, 80.0, &has, &P->polar_min, &P->polar_max))) return e;
  if (!has) return palp_parse_fail(c, PALP_EPARSE, "placement.polar_deg: missing ([min, max] degrees from the pole)");
  double gap = 10.0;
  if ((e = get_num(c, o, "placement.", "min_gap_mm", 0, 0.0, 100.0, &gap))) return e;
  P->min_gap = gap * 1e-3;
  const cJSON *seed = cJSON_GetObjectItemCaseSensitive(o, "seed");
  if (P->kind == PALP_PLACEMENT_RANDOM && seed)
    return palp_parse_fail(c, PALP_EPARSE, "placement.seed: the server draws a seed for each session (only a drawn "
                           "exercise, as logged, carries one)");
  static const char *const pers[] = {"session", "run", NULL};
  if ((e = get_choice(c, o, "placement.", "per", 0, pers, &P->per_run))) return e;
  /* "count": [min, max] integers; checked against the lesions listed once they are read */
  P->count_min = P->count_max = -1;
  const cJSON *cnt = cJSON_GetObjectItemCaseSensitive(o, "count");
  if (cnt) {
    const cJSON *a = cJSON_IsArray(cnt) && cJSON_GetArraySize(cnt) == 2 ? cJSON_GetArrayItem(cnt, 0) : NULL;
    const cJSON *b = a ? cJSON_GetArrayItem(cnt, 1) : NULL;
    if (!cJSON_IsNumber(a) || !cJSON_IsNumber(b) || a->valuedouble != floor(a->valuedouble) ||
        b->valuedouble != floor(b->valuedouble) || !(a->valuedouble >= 0) || !(b->valuedouble >= a->valuedouble) ||
        !(b->valuedouble <= PALP_MAX_LESIONS))
      return palp_parse_fail(c, PALP_EPARSE, "placement.count: expected [min, max], whole numbers, 0 <= min <= max <= %d",
                             PALP_MAX_LESIONS);
    P->count_min = (int)a->valuedouble;
    P->count_max = (int)b->valuedouble;
  }
  if (P->kind == PALP_PLACEMENT_DRAWN) {
    double v = -1;
    if ((e = get_num(c, o, "placement.", "seed", 1, 0.0, 4294967295.0, &v))) return e;
    if (v != floor(v)) return palp_parse_fail(c, PALP_EPARSE, "placement.seed: expected an integer (got %g)", v);
    P->seed = (uint32_t)v;
  }
  return PALP_OK;
}

static int parse_bands(ctx *c, const cJSON *o, palp_exercise *ex) {
  static const char *const keys[] = {"light", "medium", "deep", "comment", NULL};
  static const char *const bkeys[] = {"depth_mm", "force_N", NULL};
  int e;
  if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "pressure_bands: expected an object");
  if ((e = only_keys(c, o, "pressure_bands.", keys))) return e;
  for (int b = 0; b < PALP_BAND_COUNT; ++b) {
    char path[48];
    snprintf(path, sizeof path, "pressure_bands.%s.", band_names[b]);
    const cJSON *bo = cJSON_GetObjectItemCaseSensitive(o, band_names[b]);
    if (!bo) return palp_parse_fail(c, PALP_EPARSE, "pressure_bands.%s: missing (an object is required)", band_names[b]);
    if (!cJSON_IsObject(bo)) return palp_parse_fail(c, PALP_EPARSE, "pressure_bands.%s: expected an object", band_names[b]);
    if ((e = only_keys(c, bo, path, bkeys))) return e;
    palp_band *B = &ex->band[b];
    if ((e = get_range(c, bo, path, "depth_mm", 1e-3, 1000.0, &B->has_depth, &B->depth_min, &B->depth_max))) return e;
    if ((e = get_range(c, bo, path, "force_N", 1.0, 1000.0, &B->has_force, &B->force_min, &B->force_max))) return e;
    if (!B->has_depth && !B->has_force)
      return palp_parse_fail(c, PALP_EPARSE, "pressure_bands.%s: needs depth_mm or force_N (or both)", band_names[b]);
    /* Bands go up: light below medium below deep, never overlapping, so a sample is in one band at most.
     * Against every band below, not only the one just below: with a medium band by force alone, a deep
     * band by depth inside light's was taken (session 90's review), and light credited for it. */
    for (int q = 0; q < b; ++q) {
      const palp_band *P = &ex->band[q];
      if (B->has_depth && P->has_depth && B->depth_min < P->depth_max)
        return palp_parse_fail(c, PALP_EPARSE, "%sdepth_mm: must start at or above %s's max", path, band_names[q]);
      if (B->has_force && P->has_force && B->force_min < P->force_max)
        return palp_parse_fail(c, PALP_EPARSE, "%sforce_N: must start at or above %s's max", path, band_names[q]);
    }
  }
  return PALP_OK;
}

static int parse_rubric(ctx *c, const cJSON *o, palp_rubric *r) {
  static const char *const keys[] = {"weights", "pass", "strip_order_share", "comment", NULL};
  static const char *const pkeys[] = {"sensitivity", "max_false_positives", "coverage", "pattern",
                                      "max_out_of_range", "score", "strip_order", NULL};
  int e;
  if (!cJSON_IsObject(o)) return palp_parse_fail(c, PALP_EPARSE, "rubric: expected an object");
  if ((e = only_keys(c, o, "rubric.", keys))) return e;
  const cJSON *w = cJSON_GetObjectItemCaseSensitive(o, "weights");
  if (!cJSON_IsObject(w)) return palp_parse_fail(c, PALP_EPARSE, "rubric.weights: missing or not an object");
  /* On the stack: a static table filled on every call was written by every thread that parses
   * an exercise, a data race even though each wrote the same pointers. */
  const char *wkeys[PALP_METRIC_COUNT + 1];
  for (int m = 0; m < PALP_METRIC_COUNT; ++m) wkeys[m] = metric_names[m];
  wkeys[PALP_METRIC_COUNT] = NULL;
  if ((e = only_keys(c, w, "rubric.weights.", wkeys))) return e;
  double sum = 0.0;
  for (int m = 0; m < PALP_METRIC_COUNT; ++m) {
    r->weight[m] = 0.0;
    if ((e = get_num(c, w, "rubric.weights.", metric_names[m], 0, 0.0, 1e6, &r->weight[m]))) return e;
    sum += r->weight[m];
  }
  if (!(sum > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "rubric.weights: at least one weight must be > 0");
  r->strip_order_share = 0.0;
  if ((e = get_num(c, o, "rubric.", "strip_order_share", 0, 0.0, 1.0, &r->strip_order_share))) return e;

  const cJSON *p = cJSON_GetObjectItemCaseSensitive(o, "pass");
  if (!cJSON_IsObject(p)) return palp_parse_fail(c, PALP_EPARSE, "rubric.pass: missing or not an object");
  if ((e = only_keys(c, p, "rubric.pass.", pkeys))) return e;
  r->pass_sensitivity = 0.0;
  if ((e = get_num(c, p, "rubric.pass.", "sensitivity", 1, 0.0, 1.0, &r->pass_sensitivity))) return e;
  r->pass_max_false_positives = 0;
  if ((e = get_int(c, p, "rubric.pass.", "max_false_positives", 0, 1000, &r->pass_max_false_positives))) return e;
  r->pass_max_out_of_range = 0;
  if ((e = get_int(c, p, "rubric.pass.", "max_out_of_range", 0, 1000000, &r->pass_max_out_of_range))) return e;
  r->pass_score = 0.0;
  if ((e = get_num(c, p, "rubric.pass.", "score", 1, 0.0, 100.0, &r->pass_score))) return e;
  r->pass_strip_order = 0.0;
  if ((e = get_num(c, p, "rubric.pass.", "strip_order", 0, 0.0, 1.0, &r->pass_strip_order))) return e;
  const cJSON *cov = cJSON_GetObjectItemCaseSensitive(p, "coverage");
  if (!cJSON_IsObject(cov)) return palp_parse_fail(c, PALP_EPARSE, "rubric.pass.coverage: missing or not an object");
  static const char *const ckeys[] = {"light", "medium", "deep", NULL};
  if ((e = only_keys(c, cov, "rubric.pass.coverage.", ckeys))) return e;
  for (int b = 0; b < PALP_BAND_COUNT; ++b)
    if ((e = get_num(c, cov, "rubric.pass.coverage.", band_names[b], 1, 0.0, 1.0, &r->pass_coverage[b]))) return e;
  const cJSON *pat = cJSON_GetObjectItemCaseSensitive(p, "pattern");
  r->pass_pattern = PALP_PATTERN_UNSYSTEMATIC;
  r->pass_any_systematic = 0;
  if (pat) {
    if (!cJSON_IsString(pat)) return palp_parse_fail(c, PALP_EPARSE, "rubric.pass.pattern: expected a string");
    const char *s = pat->valuestring;
    if (strcmp(s, "any") == 0) {
    } else if (strcmp(s, "systematic") == 0) {
      r->pass_any_systematic = 1;
    } else {
      int k = 0;
      for (int i = 1; i <= PALP_PATTERN_RADIAL; ++i)
        if (strcmp(s, pattern_names[i]) == 0) k = i;
      if (!k)
        return palp_parse_fail(c, PALP_EPARSE,
                    "rubric.pass.pattern: unknown \"%s\" (any, systematic, vertical_strip, circles, radial)", s);
      r->pass_pattern = (palp_pattern)k;
    }
  }
  return PALP_OK;
}

static int parse_root(ctx *c, const cJSON *root, const char *dir, palp_exercise *ex) {
  static const char *const keys[] = {"name", "title", "phantom", "instructions", "time_limit_s", "lesions",
                                     "decoys", "pressure_bands", "max_force_N", "match_margin_mm", "rubric",
                                     "debrief", "placement", "comment", NULL};
  memset(ex, 0, sizeof *ex);
  if (!cJSON_IsObject(root)) return palp_parse_fail(c, PALP_EPARSE, "exercise: expected a JSON object");
  int e;
  if ((e = only_keys(c, root, "", keys))) return e;
  if ((e = get_str(c, root, "", "name", 1, ex->name, sizeof ex->name))) return e;
  for (const char *p = ex->name; *p; ++p)
    if (!((*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' || *p == '-'))
      return palp_parse_fail(c, PALP_EPARSE, "name: use lower-case letters, digits, '_' and '-' only (got \"%s\")", ex->name);
  /* The phantom catalogue names an exercise's phantom by its title, in 63 bytes (palp_Phantom.name):
   * a longer one was cut there, and a station asking for it by its whole title found nothing (session
   * 81's review). "longer than 63 characters" (bytes, as get_str counts). */
  if ((e = get_str(c, root, "", "title", 1, ex->title, PALP_EXERCISE_TITLE_MAX + 1))) return e;
  if ((e = get_str(c, root, "", "phantom", 1, ex->phantom, sizeof ex->phantom))) return e;
  if (ex->phantom[0] == '/' || !dir || !dir[0]) snprintf(ex->phantom_path, sizeof ex->phantom_path, "%s", ex->phantom);
  else if ((size_t)snprintf(ex->phantom_path, sizeof ex->phantom_path, "%s/%s", dir, ex->phantom) >=
           sizeof ex->phantom_path)
    return palp_parse_fail(c, PALP_EPARSE, "phantom: path too long");
  if ((e = get_str(c, root, "", "instructions", 1, ex->instructions, sizeof ex->instructions))) return e;
  if ((e = get_num(c, root, "", "time_limit_s", 1, 1.0, 86400.0, &ex->time_limit))) return e;

  const cJSON *ls = cJSON_GetObjectItemCaseSensitive(root, "lesions");
  if (!ls) return palp_parse_fail(c, PALP_EPARSE, "lesions: missing (an array, possibly empty, is required)");
  if (!cJSON_IsArray(ls)) return palp_parse_fail(c, PALP_EPARSE, "lesions: expected an array");
  const int nl = cJSON_GetArraySize(ls);
  if (nl > PALP_MAX_LESIONS) return palp_parse_fail(c, PALP_EPARSE, "lesions: at most %d", PALP_MAX_LESIONS);
  if ((e = parse_placement(c, cJSON_GetObjectItemCaseSensitive(root, "placement"), &ex->placement))) return e;
  for (int i = 0; i < nl; ++i)
    if ((e = parse_lesion(c, cJSON_GetArrayItem(ls, i), i, ex->placement.kind == PALP_PLACEMENT_RANDOM, &ex->lesion[i])))
      return e;
  ex->lesion_count = nl;
  palp_exercise_placement *P = &ex->placement;
  if (P->kind == PALP_PLACEMENT_RANDOM && P->count_max > nl)
    return palp_parse_fail(c, PALP_EPARSE, "placement.count: at most the %d lesion%s listed (got [%d, %d])", nl,
                           nl == 1 ? "" : "s", P->count_min, P->count_max);
  if (P->kind == PALP_PLACEMENT_DRAWN && P->count_max >= 0 && !(nl >= P->count_min && nl <= P->count_max))
    return palp_parse_fail(c, PALP_EPARSE, "placement.count: this draw's %d lesion%s outside [%d, %d]", nl,
                           nl == 1 ? "" : "s", P->count_min, P->count_max);
  if (P->kind != PALP_PLACEMENT_FIXED && P->count_max < 0) P->count_min = P->count_max = nl; /* all of them */
  for (int i = 0; i < nl; ++i) P->source[i] = i;
  /* Normal nodularity (a decoy that feels lumpy but is not a lesion) needs a textured
   * material the model does not have yet: refuse rather than ignore it. */
  const cJSON *dec = cJSON_GetObjectItemCaseSensitive(root, "decoys");
  if (dec && !(cJSON_IsArray(dec) && cJSON_GetArraySize(dec) == 0))
    return palp_parse_fail(c, PALP_EPARSE, "decoys: normal nodularity is not modelled yet (only an empty array is accepted)");

  const cJSON *bands = cJSON_GetObjectItemCaseSensitive(root, "pressure_bands");
  if (!bands) return palp_parse_fail(c, PALP_EPARSE, "pressure_bands: missing (an object is required)");
  if ((e = parse_bands(c, bands, ex))) return e;
  if ((e = get_num(c, root, "", "max_force_N", 1, 0.0, 1000.0, &ex->max_force))) return e;
  if (!(ex->max_force > 0.0)) return palp_parse_fail(c, PALP_EPARSE, "max_force_N: must be > 0");
  double margin = 10.0;
  if ((e = get_num(c, root, "", "match_margin_mm", 0, 0.0, 100.0, &margin))) return e;
  ex->match_margin = margin * 1e-3;
  /* What the trainee is told at the session's end (docs/assessment.md, "Debrief"). Absent:
   * nothing, so that a file written before the key, or for an examination, never tells a
   * trainee where its lesions are. */
  static const char *const levels[] = {"none", "count", "lesions", NULL}; /* palp_debrief_level's order */
  int level = PALP_DEBRIEF_NONE;
  if ((e = get_choice(c, root, "", "debrief", 0, levels, &level))) return e;
  ex->debrief = (palp_debrief_level)level;
  const cJSON *rub = cJSON_GetObjectItemCaseSensitive(root, "rubric");
  if (!rub) return palp_parse_fail(c, PALP_EPARSE, "rubric: missing (an object is required)");
  return parse_rubric(c, rub, &ex->rubric);
}

int palp_exercise_parse(const char *json, const char *base_dir, palp_exercise *out, char *err, size_t errlen) {
  ctx c = {err, errlen};
  if (!json || !out) return palp_parse_fail(&c, PALP_EINVAL, "exercise: no input");
  char why[200];
  cJSON *root = palp_json_parse_strict(json, why, sizeof why);
  if (!root) return palp_parse_fail(&c, PALP_EPARSE, "exercise: %s", why);
  const int e = parse_root(&c, root, base_dir, out);
  cJSON_Delete(root);
  return e;
}

int palp_exercise_load(const char *path, palp_exercise *out, char *err, size_t errlen) {
  ctx c = {err, errlen};
  char *buf, why[200];
  /* Exercises are small: 1 MiB bounds what a bad file can make us hold. */
  const int rc = palp_input_file_read(path, (size_t)1 << 20, &buf, NULL, why, sizeof why);
  if (rc) return palp_parse_fail(&c, rc == PALP_ENOMEM ? rc : PALP_EIO, "exercise: cannot read \"%s\": %s", path, why);
  char dir[1024];
  snprintf(dir, sizeof dir, "%s", path);
  char *slash = strrchr(dir, '/');
  if (slash) *slash = 0;
  else dir[0] = 0;
  const int e = palp_exercise_parse(buf, dir, out, err, errlen);
  free(buf);
  return e;
}

static palp_vec3 dir_of(double polar, double az) {
  return v3(sin(polar) * cos(az), sin(polar) * sin(az), cos(polar));
}

palp_vec3 palp_exercise_lesion_surface(const palp_exercise_lesion *l, double R) {
  return v3_scale(dir_of(l->polar, l->azimuth), R);
}

double palp_exercise_lesion_gap(const palp_exercise_lesion *a, const palp_exercise_lesion *b, double R) {
  const double c = v3_dot(dir_of(a->polar, a->azimuth), dir_of(b->polar, b->azimuth));
  return R * acos(fmax(-1.0, fmin(1.0, c))) - (a->diameter + b->diameter) / 2.0;
}

int palp_exercise_lesions(const palp_exercise *ex, double R, palp_lesion *out, int cap, char *err, size_t errlen) {
  ctx c = {err, errlen};
  if (!ex || !(R > 0.0) || (cap > 0 && !out)) return palp_parse_fail(&c, PALP_EINVAL, "exercise lesions: bad arguments");
  int n = 0;
  for (int i = 0; i < ex->lesion_count && n < cap; ++i) {
    const palp_exercise_lesion *L = &ex->lesion[i];
    const double a = L->diameter / 2.0;
    const palp_vec3 centre = v3_scale(dir_of(L->polar, L->azimuth), R - L->depth);
    /* The same test the scene applies: inside the dome and clear of its base. */
    if (!(R - L->depth + a < R) || !(L->depth + a < 2.0 * R) || !(centre.z - a > 0.0))
      return palp_parse_fail(&c, PALP_EINVAL,
                  "lesions[%d]: a %g mm lesion %g mm deep at polar %g deg does not fit inside the dome (radius %g "
                  "mm) above its base",
                  i, L->diameter * 1e3, L->depth * 1e3, L->polar * 180.0 / PALP_PI, R * 1e3);
    /* Two lesions whose discs on the skin overlap are one lump to a fingertip and to a mark (a mark
     * on the overlap reaches both), yet count as two to find: a lesion listed twice asked the trainee
     * for a second mark on the one lump she felt ("found 1 of 2"; session 81 review). Only overlap is
     * refused, not the random draw's min_gap: a fixed exercise places its lesions by hand and has no
     * gap of its own, and a gap of 0 (discs touching) is still two lumps to mark. A random exercise
     * lists no places until drawn, and a draw keeps min_gap >= 0. */
    for (int j = 0; j < i && ex->placement.kind != PALP_PLACEMENT_RANDOM; ++j) {
      const double g = palp_exercise_lesion_gap(L, &ex->lesion[j], R);
      if (g < 0.0)
        return palp_parse_fail(&c, PALP_EINVAL,
                               "lesions[%d] and lesions[%d]: their discs on the skin overlap by %.1f mm (the %g and %g "
                               "mm lesions' centres %.1f mm apart along the skin): one lump to the finger; list it "
                               "once or move them apart",
                               j, i, -g * 1e3, ex->lesion[j].diameter * 1e3, L->diameter * 1e3,
                               (g + (L->diameter + ex->lesion[j].diameter) / 2.0) * 1e3);
    }
    out[n++] = (palp_lesion){.center = centre, .radius = a, .stiffness_ratio = L->stiffness_ratio};
  }
  return n;
}

int palp_exercise_scene(const palp_exercise *ex, palp_scene *out, char *err, size_t errlen) {
  ctx c = {err, errlen};
  int e = palp_scene_load(ex->phantom_path, out, err, errlen);
  if (e) {
    /* keep the scene's message, say which file */
    char inner[256];
    snprintf(inner, sizeof inner, "%s", err && errlen ? err : "");
    return palp_parse_fail(&c, e, "phantom \"%s\": %s", ex->phantom_path, inner);
  }
  /* The phantom's own lesions would be felt but never graded (only the exercise's are matched):
   * a mark on one counted as a false positive (session 81 review). */
  if (out->world.lesion_count > 0)
    return palp_parse_fail(&c, PALP_EINVAL,
                           "phantom \"%s\": declares %d lesion%s of its own, which the assessment would not grade (a "
                           "mark on one would count as false): put the lesions in the exercise",
                           ex->phantom_path, out->world.lesion_count, out->world.lesion_count == 1 ? "" : "s");
  /* A random exercise: the draws that prove its lesions can be placed. A session hides at most
   * hi = count_max of the n listed (placement.count; all by default), any hi of them, so every set
   * of hi, in the file's order, is drawn once (seed 0; a session tries 16 seeds, server/session.c):
   * C(n, hi) <= 70 draws, each of a few dozen tries when the band has room. The first set (the
   * first hi listed) is the phantom's scene; the sessions replace it with their own draws. Until
   * session 83 all n were placed at once: a pool (8 listed, "count": [1, 1]) whose 8 did not fit
   * together was refused at the server's start although every session's draw placed its one
   * lesion, and the message named 8 lesions. With hi = n this is that one draw, unchanged. */
  palp_exercise drawn;
  if (ex->placement.kind == PALP_PLACEMENT_RANDOM) {
    const int n = ex->lesion_count, cmax = ex->placement.count_max;
    const int hi = cmax >= 0 && cmax <= n ? cmax : n;
    int pick[PALP_MAX_LESIONS];
    for (int i = 0; i < hi; i++) pick[i] = i;
    for (int first = 1;; first = 0) {
      palp_exercise set = *ex, other;
      for (int i = 0; i < hi; i++) set.lesion[i] = ex->lesion[pick[i]];
      set.lesion_count = hi;
      set.placement.count_min = set.placement.count_max = hi;
      if ((e = palp_exercise_draw(&set, out->world.mesh.radius, 0u, first ? &drawn : &other, err, errlen))) {
        if (hi == n) return e;
        char inner[256], which[64] = "";
        snprintf(inner, sizeof inner, "%s", err && errlen ? err : "");
        for (int i = 0, k = 0; i < hi && k < (int)sizeof which; i++)
          k += snprintf(which + k, sizeof which - (size_t)k, "%s%d", i ? ", " : "", pick[i]);
        return palp_parse_fail(&c, e, "%s: lesions[%s] of the %d listed (a session hides up to %d of them, any %d)",
                               inner, which, n, hi, hi);
      }
      /* the next set of hi indices in lexicographic order */
      int i = hi - 1;
      while (i >= 0 && pick[i] == n - hi + i) i--;
      if (i < 0) break;
      pick[i]++;
      for (int j = i + 1; j < hi; j++) pick[j] = pick[j - 1] + 1;
    }
    ex = &drawn;
  }
  const int n = palp_exercise_lesions(ex, out->world.mesh.radius, out->world.lesion + out->world.lesion_count,
                                      PALP_MAX_LESIONS - out->world.lesion_count, err, errlen);
  if (n < 0) return n;
  out->world.lesion_count += n;
  return PALP_OK;
}

double palp_fingertip_depth(double dome_radius, double tip_radius, palp_vec3 proxy) {
  return dome_radius + tip_radius - v3_len(proxy); /* [m] */
}

int palp_band_of(const palp_band band[PALP_BAND_COUNT], double depth, double force) {
  for (int b = 0; b < PALP_BAND_COUNT; ++b) {
    const palp_band *B = &band[b];
    if (B->has_depth && !(depth >= B->depth_min && depth < B->depth_max)) continue;
    if (B->has_force && !(force >= B->force_min && force < B->force_max)) continue;
    return b;
  }
  return -1;
}

int palp_exercise_band(const palp_exercise *ex, double depth, double force) { return palp_band_of(ex->band, depth, force); }

char *palp_exercise_drawn_json(const char *file_json, const palp_exercise *d) {
  if (!file_json || !d) return NULL;
  cJSON *root = cJSON_Parse(file_json);
  cJSON *file_ls = root ? cJSON_GetObjectItemCaseSensitive(root, "lesions") : NULL;
  const int listed = cJSON_IsArray(file_ls) ? cJSON_GetArraySize(file_ls) : -1;
  int ok = listed >= d->lesion_count;
  /* the lesions drawn, each the file's object it came from (its size, depth, comment) */
  cJSON *ls = ok ? cJSON_CreateArray() : NULL;
  for (int i = 0; i < d->lesion_count && ok; ++i) {
    const int src = d->placement.kind == PALP_PLACEMENT_FIXED ? i : d->placement.source[i];
    cJSON *o = src >= 0 && src < listed ? cJSON_Duplicate(cJSON_GetArrayItem(file_ls, src), 1) : NULL;
    ok = o && cJSON_AddItemToArray(ls, o);
    if (!ok) {
      cJSON_Delete(o);
      break;
    }
    cJSON_DeleteItemFromObjectCaseSensitive(o, "polar_deg");
    cJSON_DeleteItemFromObjectCaseSensitive(o, "azimuth_deg");
    /* cJSON prints a number with up to 17 significant digits when 15 do not give it back:
     * the degrees parse back to the same radians the world was built from (to rounding of the
     * degree conversion, ~1e-16 rad) */
    ok = cJSON_AddNumberToObject(o, "polar_deg", d->lesion[i].polar * 180.0 / PALP_PI) &&
         cJSON_AddNumberToObject(o, "azimuth_deg", d->lesion[i].azimuth * 180.0 / PALP_PI);
  }
  if (ok) {
    ok = cJSON_ReplaceItemInObjectCaseSensitive(root, "lesions", ls);
    if (ok) ls = NULL; /* root's now */
  }
  cJSON_Delete(ls);
  cJSON_DeleteItemFromObjectCaseSensitive(root, "placement");
  cJSON *p = ok ? cJSON_AddObjectToObject(root, "placement") : NULL;
  /* the band and gap as the file said them (to 1e-9 deg / mm): the radians' round trip could put
   * an 80 deg band's end a bit past the parser's 80 */
  const double band[2] = {round(d->placement.polar_min * 180.0 / PALP_PI * 1e9) / 1e9,
                          round(d->placement.polar_max * 180.0 / PALP_PI * 1e9) / 1e9};
  ok = p && cJSON_AddStringToObject(p, "kind", d->placement.kind == PALP_PLACEMENT_FIXED ? "fixed" : "drawn") &&
       (d->placement.kind == PALP_PLACEMENT_FIXED ||
        (cJSON_AddNumberToObject(p, "seed", (double)d->placement.seed) &&
         cJSON_AddItemToObject(p, "polar_deg", cJSON_CreateDoubleArray(band, 2)) &&
         cJSON_AddNumberToObject(p, "min_gap_mm", round(d->placement.min_gap * 1e12) / 1e9) &&
         cJSON_AddStringToObject(p, "per", d->placement.per_run ? "run" : "session") &&
        cJSON_AddItemToObject(p, "count", cJSON_CreateIntArray((const int[2]){d->placement.count_min, d->placement.count_max}, 2))));
  char *text = ok ? cJSON_Print(root) : NULL;
  cJSON_Delete(root);
  return text;
}
