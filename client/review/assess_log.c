/* Metrics from the log: the session's exercise (its logged JSON, hidden lesions included), the
 * rest mesh (from the session's scene JSON), the finger samples and the findings go through
 * palp_assess, the same pure call the assessment tests make in process, so the review shows
 * exactly the definitions of docs/assessment.md. A session without an exercise is free practice:
 * it is assessed against FREE_PRACTICE below (no lesions, the shipped pressure bands), and the
 * review shows its coverage, pattern and forces but no sensitivity and no score. */
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include <sqlite3.h>

#include "assess_log.h"
#include "grades.h"
#include "palp_place.h"
#include "review_util.h"
#include "vec3.h" /* PALP_PI */

/* The shipped exercises' bands and force limit (config/exercises/easy.json). The phantom is not
 * loaded: the mesh comes from the session's own scene. */
static const char FREE_PRACTICE[] =
    "{\"name\":\"free-practice\",\"title\":\"Free practice\",\"phantom\":\"(session scene)\","
    "\"instructions\":\"Free practice: no hidden lesions.\",\"time_limit_s\":3600,\"lesions\":[],"
    "\"pressure_bands\":{\"light\":{\"depth_mm\":[1,4]},\"medium\":{\"depth_mm\":[4,9]},"
    "\"deep\":{\"depth_mm\":[9,18]}},\"max_force_N\":15,\"match_margin_mm\":10,"
    "\"rubric\":{\"weights\":{\"thoroughness\":1},\"pass\":{\"sensitivity\":0,"
    "\"coverage\":{\"light\":0,\"medium\":0,\"deep\":0},\"score\":0}}}";

typedef struct sample_acc {
  palp_assess_sample *s;
  int32_t *tri;
  size_t *tri_at;
  int n, cap;
  size_t ntri, tricap;
  double radius;
  int slot; /* the first finger's slot: one trainee's finger per session */
  int err;
} sample_acc;

static int sample_cb(void *u, const palp_db_finger_sample *fs) {
  sample_acc *a = u;
  if (a->n == 0 && a->slot < 0) a->slot = fs->slot;
  if (fs->slot != a->slot) return 0;
  if (a->n == a->cap) {
    int ncap = a->cap ? 2 * a->cap : 4096;
    palp_assess_sample *ns = realloc(a->s, sizeof *ns * (size_t)ncap);
    if (!ns) return a->err = PALP_ENOMEM;
    a->s = ns;
    size_t *nt = realloc(a->tri_at, sizeof *nt * (size_t)ncap);
    if (!nt) return a->err = PALP_ENOMEM;
    a->tri_at = nt;
    a->cap = ncap;
  }
  const int nt = fs->triangles ? fs->triangle_count : 0;
  if (a->ntri + (size_t)nt > a->tricap) {
    size_t ncap = a->tricap ? 2 * a->tricap + (size_t)nt : 65536;
    int32_t *ntri = realloc(a->tri, sizeof *ntri * ncap);
    if (!ntri) return a->err = PALP_ENOMEM;
    a->tri = ntri;
    a->tricap = ncap;
  }
  if (nt) memcpy(a->tri + a->ntri, fs->triangles, sizeof(int32_t) * (size_t)nt);
  a->tri_at[a->n] = a->ntri;
  a->ntri += (size_t)nt;
  a->radius = fs->radius_m;
  a->s[a->n++] = (palp_assess_sample){.t = fs->sim_time_s, .device = fs->device_m, .proxy = fs->proxy_m,
                                      .force = fs->force_n, .contact = fs->in_contact, .point = fs->point_m,
                                      .area = fs->area_m2, .triangle_count = nt};
  return 0;
}

/* A withdrawal names the station's mark: the latest mark with that id made before it goes. Withdrawals
 * are kept (the id, and how many marks there were then) and applied once all rows are read, by binary
 * search over the marks sorted by id (since session 81: each withdrawal scanned the marks back, and a
 * log of 100,000 marks and 100,000 withdrawals took 10 s to assess). */
typedef struct withdrawal {
  int64_t mark_id;
  int before; /* marks made before it: it names one of v[0 .. before - 1] */
} withdrawal;

typedef struct mark_acc {
  review_mark *v;
  int n, cap, err;
  withdrawal *w;
  int wn, wcap;
} mark_acc;

static int grow(void **v, int *cap, size_t elem) {
  const int ncap = *cap ? 2 * *cap : 16;
  if (*cap > INT_MAX / 2) return PALP_ENOMEM;
  void *nv = realloc(*v, elem * (size_t)ncap);
  if (!nv) return PALP_ENOMEM;
  *v = nv;
  *cap = ncap;
  return 0;
}

static int finding_cb(void *u, const palp_db_finding *f) {
  mark_acc *a = u;
  if (f->op == PALP_DB_FINDING_WITHDRAW) {
    if (a->wn == a->wcap && grow((void **)&a->w, &a->wcap, sizeof *a->w)) return a->err = PALP_ENOMEM;
    a->w[a->wn++] = (withdrawal){.mark_id = f->mark_id, .before = a->n};
    return 0;
  }
  if (a->n == a->cap && grow((void **)&a->v, &a->cap, sizeof *a->v)) return a->err = PALP_ENOMEM;
  a->v[a->n++] = (review_mark){.mark_id = f->mark_id,
                               .f = {.t = f->sim_time_s, .point = f->point_m, .withdrawn = 0},
                               .match = PALP_FINDING_FALSE};
  return 0;
}

/* The marks as (id, index) pairs, sorted: qsort's comparison has no context argument in C17, and a
 * static pointer to the marks would not do (palp-server grades on a thread of its own). */
typedef struct mark_key {
  int64_t id;
  int index;
} mark_key;

static int key_cmp(const void *x, const void *y) {
  const mark_key *a = x, *b = y;
  if (a->id != b->id) return a->id < b->id ? -1 : 1;
  return (a->index > b->index) - (a->index < b->index);
}

static int apply_withdrawals(mark_acc *a) {
  if (!a->wn || !a->n) return 0;
  mark_key *k = malloc(sizeof *k * (size_t)a->n);
  if (!k) return PALP_ENOMEM;
  for (int i = 0; i < a->n; i++) k[i] = (mark_key){a->v[i].mark_id, i};
  qsort(k, (size_t)a->n, sizeof *k, key_cmp);
  for (int j = 0; j < a->wn; j++) {
    /* the last key < (id, before): the latest mark with that id made before the withdrawal */
    int lo = 0, hi = a->n; /* first key >= (id, before) */
    const mark_key want = {a->w[j].mark_id, a->w[j].before};
    while (lo < hi) {
      const int mid = lo + (hi - lo) / 2;
      if (key_cmp(&k[mid], &want) < 0) lo = mid + 1;
      else hi = mid;
    }
    if (lo > 0 && k[lo - 1].id == want.id) a->v[k[lo - 1].index].f.withdrawn = 1;
  }
  free(k);
  return 0;
}

void review_assessment_free(review_assessment *a) {
  if (!a) return;
  palp_mesh_destroy(&a->mesh);
  free(a->coverage);
  free(a->path);
  free(a->marks);
  free(a->touches);
  memset(a, 0, sizeof *a);
}

/* The same lesions: as many, each at the same place, depth and size (to 1e-9 of the file's SI values). */
static int same_lesions(const palp_exercise *a, const palp_exercise *b) {
  if (a->lesion_count != b->lesion_count) return 0;
  for (int i = 0; i < a->lesion_count; i++) {
    const palp_exercise_lesion *x = &a->lesion[i], *y = &b->lesion[i];
    if (fabs(x->polar - y->polar) > 1e-9 || fabs(x->azimuth - y->azimuth) > 1e-9 || fabs(x->depth - y->depth) > 1e-9 ||
        fabs(x->diameter - y->diameter) > 1e-9)
      return 0;
  }
  return 1;
}

int review_debrief(palp_db *db, const palp_db_session_info *s, palp_db_debrief *d) {
  const int rc = palp_db_session_debrief(db, s->id, d);
  if (rc == 1) return REVIEW_DEBRIEF_LOGGED;
  if (rc == PALP_EINVAL) return REVIEW_DEBRIEF_UNREADABLE;
  if (rc < 0) return rc;
  if (!review_params_flag(db, s->id, "debrief_events")) return REVIEW_DEBRIEF_UNKNOWN;
  /* the server writes the debrief before it closes the session: a close without one lost it */
  return s->end_unix_s > 0 && s->end_reason[0] ? REVIEW_DEBRIEF_LOST : REVIEW_DEBRIEF_NONE;
}

/* appends to buf at *n, never past len */
static void cat(char *buf, size_t len, size_t *n, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void cat(char *buf, size_t len, size_t *n, const char *fmt, ...) {
  if (*n >= len) return;
  va_list ap;
  va_start(ap, fmt);
  const int k = vsnprintf(buf + *n, len - *n, fmt, ap);
  va_end(ap);
  if (k > 0) *n = *n + (size_t)k < len ? *n + (size_t)k : len;
}

void review_debrief_text(int status, const palp_db_debrief *d, const review_assessment *a, char *buf, size_t len) {
  size_t n = 0;
  if (len) buf[0] = 0;
  switch (status) {
  case REVIEW_DEBRIEF_UNKNOWN:
    cat(buf, len, &n, "not in this log (its writer logged no debriefs: a server before 2026-12-05's session 59, a "
                      "palp-recorder before session 60, or one that did not receive it)");
    return;
  case REVIEW_DEBRIEF_NONE:
    cat(buf, len, &n, "none sent: the session's close was not logged (its server stopped first), so its trainee was "
                      "told nothing");
    return;
  case REVIEW_DEBRIEF_UNREADABLE:
    cat(buf, len, &n, "UNREADABLE: the logged debrief does not parse (was the log altered?)");
    return;
  case REVIEW_DEBRIEF_LOST:
    cat(buf, len, &n, "LOST: the session closed but its debrief's record is not in the log (see the log's shed and "
                      "failed records): what the trainee was told is not known");
    return;
  case REVIEW_DEBRIEF_LOGGED: break;
  default:
    cat(buf, len, &n, "UNKNOWN: the log could not be read");
    return;
  }
  const char *lv = palp_db_debrief_level_name(d->level);
  if (!d->sent) {
    cat(buf, len, &n, "NOT SENT (the exercise's debrief: %s): %s; its trainee was told nothing", lv ? lv : "?", d->why);
    return;
  }
  if (d->level == PALP_DB_DEBRIEF_NONE) {
    cat(buf, len, &n, "told nothing of the lesions (the exercise's debrief: none); %d mark%s standing", d->marks,
        d->marks == 1 ? "" : "s");
    return;
  }
  if (d->lesions == 0) /* a draw that hid none (docs/assessment.md, "Lesions drawn for each session") */
    cat(buf, len, &n, "told there was no lump to find this time");
  else
    cat(buf, len, &n, "%s: found %d of %d lump%s",
        d->level == PALP_DB_DEBRIEF_LESIONS ? "told where each lump is" : "told the count only", d->found, d->lesions,
        d->lesions == 1 ? "" : "s");
  const int places = a && a->has_exercise && a->ex.lesion_count == d->listed;
  for (int l = 0; l < d->listed; l++) {
    cat(buf, len, &n, "%s lump %d ", l ? "," : ";", l + 1);
    if (d->found_by[l]) cat(buf, len, &n, "found by mark %u", (unsigned)d->found_by[l]);
    else cat(buf, len, &n, "MISSED");
    /* where, in the one phrase of every tool (palp_place_words: the station's debrief says the same) */
    char at[64];
    if (places) cat(buf, len, &n, " (%s)", palp_place_words(a->lesion_surface[l], at, sizeof at));
  }
  cat(buf, len, &n, "; %d mark%s standing, %d near no lump", d->marks, d->marks == 1 ? "" : "s", d->false_marks);
  if (d->duplicates) cat(buf, len, &n, ", %d on a lump already found", d->duplicates);
  /* The server matched with the review's own function (palp_assess_findings) on the same marks:
   * a difference means the log and the trainee's screen disagree, which the instructor must see. */
  if (a && a->has_exercise) {
    int differ = a->r.found != d->found || a->r.lesion_count != d->lesions;
    for (int l = 0; l < d->listed && l < a->r.lesion_count && !differ; l++)
      differ = (a->r.lesion_found[l] >= 0) != (d->found_by[l] != 0);
    if (differ)
      cat(buf, len, &n, " (DIFFERS from this review, which counts %d of %d found: the trainee was told otherwise)",
          a->r.found, a->r.lesion_count);
  }
}

int review_drawn_text(const palp_exercise *ex, char *buf, size_t len) {
  if (len) buf[0] = 0;
  if (ex->placement.kind != PALP_PLACEMENT_DRAWN) return 0;
  snprintf(buf, len, "drawn for this session (seed %u, polar %.0f-%.0f deg from the pole, at least %.0f mm apart)",
           (unsigned)ex->placement.seed, ex->placement.polar_min * 180.0 / PALP_PI,
           ex->placement.polar_max * 180.0 / PALP_PI, ex->placement.min_gap * 1e3);
  return 1;
}

int review_told_before(palp_db *db, const palp_db_session_info *s, const review_assessment *a, review_told *out) {
  memset(out, 0, sizeof *out);
  if (!a->has_exercise || !a->ex.lesion_count) return 0;
  palp_db_filter flt = {.trainee = s->trainee, .until_unix_s = s->start_unix_s, .has_until = 1};
  palp_db_session_info *v = NULL;
  int n = 0;
  const int rc = palp_db_list_sessions(db, &flt, &v, &n);
  if (rc < 0) return rc;
  int found = 0;
  for (int i = 0; i < n; i++) {
    /* ended before this one began: its debrief went out as it closed (a log cut short by a killed
     * server has no end, and its session sent none) */
    if (v[i].id == s->id || !(v[i].end_unix_s > 0) || v[i].end_unix_s > s->start_unix_s) continue;
    char name[64];
    char *json = NULL;
    if (palp_db_session_exercise(db, v[i].id, name, sizeof name, &json) != 0) continue;
    palp_exercise e;
    char perr[256];
    const int same = strcmp(name, a->exercise_name) == 0 && palp_exercise_parse(json, NULL, &e, perr, sizeof perr) == 0 &&
                     same_lesions(&e, &a->ex);
    free(json);
    if (!same || (found && v[i].end_unix_s <= out->end_unix_s)) continue;
    /* what its log says was sent; a log from before debriefs were logged, or a row that does not
     * parse, by what its exercise file allowed (inferred: the debrief may have failed to go out) */
    palp_db_debrief d;
    const int st = review_debrief(db, &v[i], &d);
    if (st < 0) {
      free(v);
      return st;
    }
    int inferred = 0;
    palp_debrief_level level;
    if (st == REVIEW_DEBRIEF_LOGGED) level = d.sent ? (palp_debrief_level)d.level : PALP_DEBRIEF_NONE;
    else if (st == REVIEW_DEBRIEF_NONE) level = PALP_DEBRIEF_NONE;
    else level = e.debrief, inferred = 1; /* unknown, unreadable or lost: what the file allowed */
    if (level == PALP_DEBRIEF_NONE) continue;
    snprintf(out->uid, sizeof out->uid, "%s", v[i].uid);
    out->end_unix_s = v[i].end_unix_s;
    out->level = level;
    out->inferred = inferred;
    found = 1;
  }
  free(v);
  return found;
}

void review_told_text(const palp_db_session_info *s, const review_told *t, char *buf, size_t len) {
  if (!t->uid[0]) {
    if (len) buf[0] = 0;
    return;
  }
  char when[64];
  review_fmt_time(t->end_unix_s, when, sizeof when);
  snprintf(buf, len, "%s had been told %s when session %s ended (%s): this attempt was not blind%s", s->trainee,
           t->level == PALP_DEBRIEF_LESIONS ? "where this exercise's lesions are" : "how many lesions this exercise hides",
           t->uid, when,
           t->inferred ? " (inferred from that session's exercise file: its log does not record what was sent)" : "");
}

int review_assess(palp_db *db, const palp_db_session_info *s, review_assessment *out, char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  if (errlen) err[0] = 0;
  char *exjson = NULL;
  int rc = palp_db_session_exercise(db, s->id, out->exercise_name, sizeof out->exercise_name, &exjson);
  if (rc == 0) out->has_exercise = 1;
  else if (rc != PALP_DB_ENOTFOUND) {
    snprintf(err, errlen, "exercise: %s", palp_db_errmsg(db));
    return rc;
  }
  char perr[512] = "";
  rc = palp_exercise_parse(out->has_exercise ? exjson : FREE_PRACTICE, NULL, &out->ex, perr, sizeof perr);
  free(exjson);
  if (rc) {
    snprintf(err, errlen, "the logged exercise '%s' does not parse: %s", out->exercise_name, perr);
    return rc;
  }
  if (!out->has_exercise) {
    snprintf(out->exercise_name, sizeof out->exercise_name, "%s", "");
    review_params_string(db, s->id, "exercise_name", out->exercise_unlogged, sizeof out->exercise_unlogged);
    review_tty(out->exercise_unlogged); /* from the recorder's params, off the wire: printed as every name is */
  }
  char footprint[16] = "";
  out->footprint_patch = review_params_string(db, s->id, "footprint", footprint, sizeof footprint) &&
                         !strcmp(footprint, "patch");

  char *scene = NULL;
  if ((rc = palp_db_session_json(db, s->id, &scene, NULL))) {
    snprintf(err, errlen, "scene: %s", palp_db_errmsg(db));
    return rc;
  }
  palp_scene *sc = malloc(sizeof *sc);
  if (!sc) {
    free(scene);
    return PALP_ENOMEM;
  }
  rc = palp_scene_parse(scene ? scene : "", sc, perr, sizeof perr);
  free(scene);
  if (rc) {
    free(sc);
    snprintf(err, errlen, "the logged scene does not parse: %s", perr);
    return rc;
  }
  out->dome_radius_m = sc->world.mesh.radius;
  rc = palp_mesh_create(&sc->world.mesh, &out->mesh);
  free(sc);
  if (rc) {
    snprintf(err, errlen, "the logged scene's mesh: %s", palp_strerror(rc));
    return rc;
  }
  for (int i = 0; i < out->ex.lesion_count; i++)
    out->lesion_surface[i] = palp_exercise_lesion_surface(&out->ex.lesion[i], out->dome_radius_m);

  sample_acc sa = {.slot = -1};
  rc = palp_db_each_finger_sample(db, s->id, sample_cb, &sa);
  mark_acc ma = {0};
  if (!rc) rc = palp_db_each_finding(db, s->id, finding_cb, &ma);
  if (!rc && (rc = apply_withdrawals(&ma))) ma.err = rc;
  free(ma.w);
  ma.w = NULL;
  if (rc) {
    snprintf(err, errlen, "%s", sa.err || ma.err ? "out of memory" : palp_db_errmsg(db));
    goto fail;
  }
  out->samples = sa.n;
  out->finger_radius_m = sa.radius;
  out->marks = ma.v;
  out->mark_n = ma.n;
  ma.v = NULL;
  if (sa.n == 0) {
    snprintf(err, errlen, "no finger samples logged (a session of force contacts only, or logged before schema 3)");
    rc = PALP_DB_ENOTFOUND;
    goto fail;
  }
  /* Withdrawn tail: samples own their triangles only once the pool stops moving. */
  for (int i = 0; i < sa.n; i++) sa.s[i].triangles = sa.s[i].triangle_count ? (const int *)(sa.tri + sa.tri_at[i]) : NULL;
  palp_finding *f = calloc((size_t)(out->mark_n ? out->mark_n : 1), sizeof *f);
  int *match = calloc((size_t)(out->mark_n ? out->mark_n : 1), sizeof *match);
  out->coverage = calloc((size_t)out->mesh.vertex_count, 1);
  out->path = malloc(sizeof *out->path * (size_t)sa.n);
  if (!f || !match || !out->coverage || !out->path) {
    free(f), free(match);
    rc = PALP_ENOMEM;
    snprintf(err, errlen, "out of memory");
    goto fail;
  }
  for (int i = 0; i < out->mark_n; i++) f[i] = out->marks[i].f;
  rc = palp_assess(&out->ex, &out->mesh, sa.radius, sa.s, sa.n, f, out->mark_n, &out->r, match, out->coverage);
  for (int i = 0; i < out->mark_n && !rc; i++) out->marks[i].match = match[i];
  free(f), free(match);
  if (rc) {
    snprintf(err, errlen, "palp_assess: %s", palp_strerror(rc));
    goto fail;
  }
  for (int i = 0; i < sa.n; i++)
    if (sa.s[i].contact) out->path[out->path_n++] = sa.s[i].point;
  const int nt = palp_assess_touches(sa.s, sa.n, out->dome_radius_m, sa.radius, NULL, 0);
  out->touches = malloc(sizeof *out->touches * (size_t)(nt ? nt : 1));
  if (!out->touches) {
    rc = PALP_ENOMEM;
    snprintf(err, errlen, "out of memory");
    goto fail;
  }
  out->touch_n = palp_assess_touches(sa.s, sa.n, out->dome_radius_m, sa.radius, out->touches, nt);
  free(sa.s), free(sa.tri), free(sa.tri_at);
  return 0;
fail:
  free(sa.s), free(sa.tri), free(sa.tri_at), free(ma.v);
  review_assessment_free(out);
  return rc;
}

void review_metrics_csv_header(FILE *f) {
  fputs("session,trainee,started_unix_s,exercise,samples,lesions,found,sensitivity,findings,withdrawn,"
        "false_positives,coverage_light,coverage_medium,coverage_deep,coverage_any,pattern,path_length_m,"
        "presses,overlap,gap_share,duration_s,peak_force_n,out_of_range,score,pass,outside_valid_range_s,strips,"
        "strip_order,grade_score,grade_level,debrief,not_blind_after\n",
        f);
}

void review_metrics_csv_row(FILE *f, palp_db *db, const palp_db_session_info *s, const review_assessment *a,
                            double outside_s) {
  const palp_assess_result *r = &a->r;
  csv_str(f, s->uid);
  fputc(',', f);
  csv_str(f, s->trainee);
  fprintf(f, ",%.3f,", s->start_unix_s);
  csv_str(f, a->has_exercise ? a->exercise_name : "");
  /* Free practice has no lesions: its sensitivity and score are empty fields, not 1 or 0. */
  if (a->has_exercise)
    fprintf(f, ",%d,%d,%d,%.4f,", a->samples, r->lesion_count, r->found, r->sensitivity);
  else fprintf(f, ",%d,0,0,,", a->samples);
  fprintf(f, "%d,%d,%d,%.4f,%.4f,%.4f,%.4f,%s,%.4f,%d,", r->findings, r->withdrawn, r->false_positives,
          r->coverage[0], r->coverage[1], r->coverage[2], r->coverage_any, palp_pattern_name(r->pattern),
          r->evidence.path_length, r->evidence.presses);
  /* a pruned session's stored metrics do not keep them (review_stored_metrics): unknown, empty
   * fields, not 0 overlap and 0 area left unpalpated */
  if (r->evidence.overlap >= 0) fprintf(f, "%.3f,%.4f,", r->evidence.overlap, r->evidence.gap_share);
  else fputs(",,", f);
  fprintf(f, "%.3f,%.2f,%d,", r->duration, r->peak_force, r->out_of_range);
  if (a->has_exercise) fprintf(f, "%.1f,%d,", palp_shown_tenths(r->score, NAN, r->pass), r->pass);
  else fputs(",,", f);
  /* out_of_range above is the force's (episodes above the exercise's limit); this is the model's */
  if (outside_s >= 0) fprintf(f, "%.2f", outside_s);
  /* added after the rest (2026-12-04), so a reader of the older columns reads them where they were */
  if (r->evidence.strips >= 0) fprintf(f, ",%d,%.4f", r->evidence.strips, r->evidence.sweep_monotony);
  else fputs(",,", f); /* metrics a prune stored before schema 5 do not keep them */
  /* the instructor's latest grade (2026-12-05), so that a class's spreadsheet carries it beside the
   * metrics; empty fields when the session is not graded */
  double gs;
  char gl[32];
  review_latest_grade_parts(db, s->id, &gs, gl, sizeof gl);
  if (gs >= 0) fprintf(f, ",%g,", gs);
  else fputs(",,", f);
  csv_str(f, gl);
  /* since session 59: what the trainee was told as this session closed (the level sent, or
   * "not_sent"; empty when the log does not say or there is no exercise), and the earlier session
   * whose debrief told her these lesions or their count (empty: a blind attempt) */
  const char *told_now = "";
  review_told t = {0};
  if (a->has_exercise) {
    palp_db_debrief d;
    const int st = review_debrief(db, s, &d);
    if (st == REVIEW_DEBRIEF_LOGGED) told_now = d.sent ? palp_db_debrief_level_name(d.level) : "not_sent";
    else if (st == REVIEW_DEBRIEF_UNREADABLE) told_now = "unreadable";
    if (review_told_before(db, s, a, &t) != 1) t.uid[0] = 0;
  }
  fputc(',', f);
  csv_str(f, told_now ? told_now : "");
  fputc(',', f);
  csv_str(f, t.uid);
  fputc('\n', f);
}

void review_touches_print(FILE *f, const review_assessment *a, int listed) {
  fprintf(f, "where touched (the finger's %d touch%s, a lift being > %.2f s off the surface; contact points on the "
             "phantom's surface seen from above: 12 o'clock = +y, 3 o'clock = +x; arc from the pole):\n",
          a->touch_n, a->touch_n == 1 ? "" : "es", PALP_ASSESS_LIFT_GAP_S);
  fprintf(f, "    %-4s %-17s %-22s %-8s %-9s %-8s %-9s %-10s %-13s %s\n", "#", "on .. off [s]", "down at x,y,z [mm]", "clock",
          "arc [mm]", "lift at", "arc [mm]", "path [mm]", "deepest [mm]", "peak [N]");
  for (int i = 0; i < a->touch_n && i < listed; i++) {
    const palp_touch *t = &a->touches[i];
    char at[40], on[24];
    snprintf(at, sizeof at, "%.1f,%.1f,%.1f", t->first_point.x * 1e3, t->first_point.y * 1e3, t->first_point.z * 1e3);
    snprintf(on, sizeof on, "%.2f .. %.2f", t->t_on, t->t_off);
    char down[24], lift[24];
    fprintf(f, "    %-4d %-17s %-22s %s  %-9.1f %s  %-9.1f %-10.1f %-13.1f %.2f\n", i + 1, on, at,
            review_clock_cell(t->first_point, 7, down, sizeof down), review_arc_m(t->first_point) * 1e3,
            review_clock_cell(t->last_point, 7, lift, sizeof lift),
            review_arc_m(t->last_point) * 1e3, t->path_length * 1e3, t->peak_indentation * 1e3, t->peak_force);
  }
  if (a->touch_n > listed)
    fprintf(f, "    ... and %d more (palp-review report lists every touch)\n", a->touch_n - listed);
}

int review_strips_shown(const palp_assess_result *r) {
  return r->pattern == PALP_PATTERN_VERTICAL_STRIP && r->evidence.strips >= 3;
}

void review_pattern_mark(const palp_rubric *rb, char *buf, size_t len) {
  const char *what = rb->pass_any_systematic                        ? "systematic"
                     : rb->pass_pattern == PALP_PATTERN_UNSYSTEMATIC ? "any"
                                                                     : palp_pattern_name(rb->pass_pattern);
  if (rb->pass_strip_order > 0.0) snprintf(buf, len, "%s; strips in order >= %.2f", what, rb->pass_strip_order);
  else snprintf(buf, len, "%s", what);
}

void review_metrics_print(FILE *f, const review_assessment *a) {
  const palp_assess_result *r = &a->r;
  const palp_rubric *rb = &a->ex.rubric;
  if (a->has_exercise) {
    char title[sizeof a->ex.title];
    snprintf(title, sizeof title, "%s", a->ex.title); /* the exercise file's, from the log: no escape (session 81) */
    review_tty(title);
    fprintf(f, "exercise   %s: %s (time limit %.0f s)\n", a->exercise_name, title, a->ex.time_limit);
    /* a random exercise's lesions were drawn for this session (docs/assessment.md): say so, and which
     * draw, so that the instructor reads the places below as this attempt's own */
    char drawn[160];
    if (review_drawn_text(&a->ex, drawn, sizeof drawn)) fprintf(f, "           its lesions %s\n", drawn);
  } else if (a->exercise_unlogged[0])
    fprintf(f, "exercise   %s, WITHOUT ITS LESIONS: they did not reach palp-recorder (a server without DDS Security, "
               "or on permissions before palp_session_exercise, keeps them; its own log has them): assessed here as "
               "free practice (no sensitivity, no score)\n", a->exercise_unlogged);
  else
    fprintf(f, "exercise   none: free practice (no hidden lesions; no sensitivity, no score)\n");
  fprintf(f, "metrics    from %d finger samples (definitions: docs/assessment.md)\n", a->samples);
  if (a->has_exercise) {
    if (r->lesion_count == 0) /* a random exercise's draw that hid none: only false marks count */
      fprintf(f, "  sensitivity      no lesion hidden in this session (nothing to find: 100%%)%s\n",
              r->pass_metric[PALP_METRIC_SENSITIVITY] ? "   pass" : "   FAIL");
    else
      fprintf(f, "  sensitivity      %d of %d lesions found (%.0f%%)%s\n", r->found, r->lesion_count,
              100.0 * r->sensitivity, r->pass_metric[PALP_METRIC_SENSITIVITY] ? "   pass" : "   FAIL");
    fprintf(f, "  false positives  %d (of %d marks, %d withdrawn)%s\n", r->false_positives, r->findings,
            r->withdrawn, r->pass_metric[PALP_METRIC_FALSE_POSITIVES] ? "   pass" : "   FAIL");
  } else {
    fprintf(f, "  findings         %d marks, %d withdrawn (no lesions to match)\n", r->findings, r->withdrawn);
  }
  /* Each band's figure as judged against its pass mark (palp_shown_tenths): 89.96% short of 90 prints
   * 89.9, not 90.0 (session 81 review); the pass marks with %g, as many digits as they have. */
  double shown[PALP_BAND_COUNT];
  for (int b = 0; b < PALP_BAND_COUNT; b++)
    shown[b] = a->has_exercise ? palp_shown_tenths(100 * r->coverage[b], 100 * rb->pass_coverage[b],
                                                   r->coverage[b] >= rb->pass_coverage[b])
                               : round(1000 * r->coverage[b]) / 10;
  fprintf(f, "  thoroughness     light %.1f%%, medium %.1f%%, deep %.1f%%, any %.1f%% of the dome", shown[0], shown[1],
          shown[2], 100 * r->coverage_any);
  if (a->has_exercise)
    fprintf(f, " (pass at %g/%g/%g%%)%s", 100 * rb->pass_coverage[0], 100 * rb->pass_coverage[1],
            100 * rb->pass_coverage[2], r->pass_metric[PALP_METRIC_THOROUGHNESS] ? "   pass" : "   FAIL");
  fputc('\n', f);
  if (a->footprint_patch) /* docs/assessment.md, "Recorded over DDS" */
    fprintf(f, "                   (recorded over DDS: each press's skin taken as the patch of as many triangles as it "
               "touched, under the fingertip; the server's own log has the touched ones)\n");
  char mark[96] = "";
  if (a->has_exercise) {
    char m[80];
    review_pattern_mark(rb, m, sizeof m);
    snprintf(mark, sizeof mark, " (pass: %s)", m);
  }
  fprintf(f, "  search pattern   %s (path %.2f m, %d presses, overlap %.2f, never palpated %.1f%%, largest gap %.1f cm^2)%s%s\n",
          palp_pattern_name(r->pattern), r->evidence.path_length, r->evidence.presses, r->evidence.overlap,
          100 * r->evidence.gap_share, r->evidence.largest_gap * 1e4, mark,
          !a->has_exercise ? "" : r->pass_metric[PALP_METRIC_PATTERN] ? "   pass" : "   FAIL");
  if (review_strips_shown(r)) {
    fprintf(f, "  strips           %d, in order %.2f (share of the steps between strips that keep the direction of "
               "the step before; 1: one pass across the breast)",
            r->evidence.strips, r->evidence.sweep_monotony);
    if (a->has_exercise && rb->strip_order_share > 0.0)
      fprintf(f, "; the rubric rests %.0f%% of the pattern's credit on it: %.2f of 1", 100 * rb->strip_order_share,
              r->component[PALP_METRIC_PATTERN]);
    if (a->has_exercise && rb->pass_strip_order > 0.0)
      fprintf(f, "; pass at %.2f   %s", rb->pass_strip_order,
              r->evidence.sweep_monotony >= rb->pass_strip_order ? "pass" : "FAIL");
    fputc('\n', f);
  }
  else if (r->pattern == PALP_PATTERN_VERTICAL_STRIP)
    fprintf(f, "  strips           %d: too few to tell their order\n", r->evidence.strips);
  fprintf(f, "  time             %.2f s%s\n", r->duration,
          !a->has_exercise ? "" : r->pass_metric[PALP_METRIC_TIME] ? "   pass" : "   FAIL");
  fprintf(f, "  force            peak %.2f N, %d episode%s above %.2f N (%.2f s)%s\n", r->peak_force, r->out_of_range,
          r->out_of_range == 1 ? "" : "s", a->ex.max_force, r->out_of_range_time,
          !a->has_exercise ? "" : r->pass_metric[PALP_METRIC_FORCE] ? "   pass" : "   FAIL");
  if (a->has_exercise)
    fprintf(f, "  score            %.1f / 100 (pass at %g): %s\n",
            /* not passed: floored to 0.1, as her station and page print it (they do not know the mark) */
            palp_shown_tenths(r->score, r->pass ? rb->pass_score : NAN, r->pass), rb->pass_score,
            r->pass ? "PASS" : "FAIL");
}

int review_stored_metrics(palp_db *db, int64_t sid, review_assessment *out) {
  memset(out, 0, sizeof *out);
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(palp_db_handle(db),
                         "SELECT exercise_name, samples, lesions, found, findings, withdrawn, false_positives, "
                         "coverage_light, coverage_medium, coverage_deep, coverage_any, pattern, path_length_m, presses, "
                         "duration_s, peak_force_n, out_of_range, score, pass, strips, strip_order FROM session_metrics "
                         "WHERE session_id = ?1",
                         -1, &st, NULL) != SQLITE_OK)
    return PALP_DB_ESQL;
  sqlite3_bind_int64(st, 1, sid);
  int rc = PALP_DB_ENOTFOUND;
  const int step = sqlite3_step(st);
  if (step != SQLITE_ROW && step != SQLITE_DONE) rc = PALP_DB_ESQL; /* unreadable (a damaged page), not absent */
  if (step == SQLITE_ROW) {
    palp_assess_result *r = &out->r;
    /* not in the table (0004_retention.sql): unknown, which the CSV writes as empty fields */
    r->evidence.overlap = r->evidence.gap_share = r->evidence.largest_gap = -1.0;
    const char *ex = (const char *)sqlite3_column_text(st, 0);
    out->has_exercise = ex != NULL;
    snprintf(out->exercise_name, sizeof out->exercise_name, "%s", ex ? ex : "");
    review_tty(out->exercise_name); /* printed on the instructor's terminal: no control characters (review_tty) */
    out->samples = sqlite3_column_int(st, 1);
    r->lesion_count = sqlite3_column_int(st, 2);
    r->found = sqlite3_column_int(st, 3);
    r->sensitivity = r->lesion_count ? (double)r->found / r->lesion_count : 1.0;
    r->findings = sqlite3_column_int(st, 4);
    r->withdrawn = sqlite3_column_int(st, 5);
    r->false_positives = sqlite3_column_int(st, 6);
    for (int b = 0; b < 3; b++) r->coverage[b] = sqlite3_column_double(st, 7 + b);
    r->coverage_any = sqlite3_column_double(st, 10);
    const char *p = (const char *)sqlite3_column_text(st, 11);
    for (int k = 0; k < 4; k++)
      if (p && !strcmp(p, palp_pattern_name((palp_pattern)k))) r->pattern = (palp_pattern)k;
    r->evidence.path_length = sqlite3_column_double(st, 12);
    r->evidence.presses = sqlite3_column_int(st, 13);
    r->duration = sqlite3_column_double(st, 14);
    r->peak_force = sqlite3_column_double(st, 15);
    r->out_of_range = sqlite3_column_int(st, 16);
    r->score = sqlite3_column_double(st, 17);
    r->pass = sqlite3_column_int(st, 18);
    /* stored since schema 5; NULL in a row stored before: unknown, not none */
    const int has_strips = sqlite3_column_type(st, 19) != SQLITE_NULL;
    r->evidence.strips = has_strips ? sqlite3_column_int(st, 19) : -1;
    r->evidence.sweep_monotony = has_strips ? sqlite3_column_double(st, 20) : 0.0;
    rc = 0;
  }
  sqlite3_finalize(st);
  return rc;
}

int review_stored_metrics_print(palp_db *db, int64_t sid, FILE *f) {
  review_assessment a;
  int rc = review_stored_metrics(db, sid, &a);
  if (rc) return rc;
  const palp_assess_result *r = &a.r;
  fprintf(f, "metrics    stored when the session was pruned (its samples are gone; no rubric detail)\n");
  fprintf(f, "  exercise         %s\n", a.has_exercise ? a.exercise_name : "none: free practice");
  if (a.has_exercise)
    fprintf(f, "  sensitivity      %d of %d lesions found\n  false positives  %d (of %d marks, %d withdrawn)\n", r->found,
            r->lesion_count, r->false_positives, r->findings, r->withdrawn);
  fprintf(f, "  thoroughness     light %.1f%%, medium %.1f%%, deep %.1f%%, any %.1f%% of the dome\n", 100 * r->coverage[0],
          100 * r->coverage[1], 100 * r->coverage[2], 100 * r->coverage_any);
  fprintf(f, "  search pattern   %s (path %.2f m, %d presses)\n", palp_pattern_name(r->pattern), r->evidence.path_length,
          r->evidence.presses);
  if (review_strips_shown(r)) fprintf(f, "  strips           %d, in order %.2f\n", r->evidence.strips, r->evidence.sweep_monotony);
  else if (r->pattern == PALP_PATTERN_VERTICAL_STRIP && r->evidence.strips < 0)
    fprintf(f, "  strips           not stored (pruned before the log kept them)\n");
  fprintf(f, "  time             %.2f s\n  force            peak %.2f N, %d episodes out of range\n", r->duration,
          r->peak_force, r->out_of_range);
  if (a.has_exercise)
    fprintf(f, "  score            %.1f / 100: %s\n", palp_shown_tenths(r->score, NAN, r->pass), r->pass ? "PASS" : "FAIL");
  return 0;
}
