/* export: a session as CSV (one table) or JSON (everything but the meshes).
 * Numbers are printed with 17 significant digits, which round-trips every IEEE double exactly,
 * so an export gives back the logged values bit for bit. The 64-bit state hash is written as a
 * hexadecimal string: JSON readers commonly hold numbers as doubles and would round it. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "assess_log.h"
#include "grades.h"
#include "palp_app.h"
#include "review.h"

/* A number as JSON: 17 significant digits, or null for one not finite (a damaged log's +Inf or NaN
 * was written "inf"/"nan", and the export was not JSON; session 81). Returned by value: its text
 * lives to the end of the full expression that calls it (C11 6.2.4), so several fit one fprintf. */
typedef struct jnum {
  char s[32];
} jnum;
static jnum jn(double v) {
  jnum j;
  if (isfinite(v)) snprintf(j.s, sizeof j.s, "%.17g", v);
  else snprintf(j.s, sizeof j.s, "null");
  return j;
}

typedef struct exp_ctx {
  FILE *f;
  int first;
  int csv;
} exp_ctx;

static void sep(exp_ctx *x) {
  if (!x->csv) fputs(x->first ? "\n    " : ",\n    ", x->f);
  x->first = 0;
}

static const char *op_name(palp_db_contact_op op) {
  return op == PALP_DB_OP_ADD ? "add" : op == PALP_DB_OP_UPDATE ? "update" : "remove";
}

static int frame_cb(void *u, const palp_db_frame *f) {
  exp_ctx *x = u;
  sep(x);
  if (x->csv)
    fprintf(x->f, "%" PRId64 ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0x%016" PRIx64 "\n", f->frame, f->sim_time_s,
            f->top_disp_m, f->max_disp_m, f->volume_m3, f->pressure_pa, f->contact_force_n, f->state_hash);
  else
    fprintf(x->f,
            "{\"frame\": %" PRId64 ", \"sim_time_s\": %s, \"top_disp_m\": %s, \"max_disp_m\": %s, "
            "\"volume_m3\": %s, \"pressure_pa\": %s, \"contact_force_n\": %s, "
            "\"state_hash\": \"0x%016" PRIx64 "\"}",
            f->frame, jn(f->sim_time_s).s, jn(f->top_disp_m).s, jn(f->max_disp_m).s, jn(f->volume_m3).s,
            jn(f->pressure_pa).s, jn(f->contact_force_n).s, f->state_hash);
  return 0;
}

static int contact_cb(void *u, const palp_db_contact *c) {
  exp_ctx *x = u;
  sep(x);
  const int force = c->kind == PALP_DB_KIND_FORCE;
  if (x->csv) {
    fprintf(x->f, "%" PRId64 ",%.17g,%d,%s,%s,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                  "%.17g,%.17g,%.17g\n",
            c->frame, c->sim_time_s, c->slot, op_name(c->op), force ? "force" : "finger", (int)c->def.distribution,
            c->center_m.x, c->center_m.y, c->center_m.z, c->force_n.x, c->force_n.y, c->force_n.z, c->radius_m,
            c->def.patch_area, c->def.sigma_fraction, c->def.offset_fraction, c->def.offset_dir.x,
            c->def.offset_dir.y, c->def.offset_dir.z);
    return 0;
  }
  fprintf(x->f, "{\"frame\": %" PRId64 ", \"sim_time_s\": %s, \"slot\": %d, \"op\": \"%s\", \"kind\": \"%s\"",
          c->frame, jn(c->sim_time_s).s, c->slot, op_name(c->op), force ? "force" : "finger");
  if (c->op != PALP_DB_OP_REMOVE) {
    fprintf(x->f, ", \"center_m\": [%s, %s, %s]", jn(c->center_m.x).s, jn(c->center_m.y).s, jn(c->center_m.z).s);
    if (force)
      fprintf(x->f, ", \"force_n\": [%s, %s, %s]", jn(c->force_n.x).s, jn(c->force_n.y).s, jn(c->force_n.z).s);
    else fprintf(x->f, ", \"radius_m\": %s", jn(c->radius_m).s);
    if (force && c->def.distribution)
      fprintf(x->f,
              ", \"distribution\": %d, \"patch_area_m2\": %s, \"sigma_fraction\": %s, "
              "\"offset_fraction\": %s, \"offset_dir\": [%s, %s, %s]",
              (int)c->def.distribution, jn(c->def.patch_area).s, jn(c->def.sigma_fraction).s,
              jn(c->def.offset_fraction).s, jn(c->def.offset_dir.x).s, jn(c->def.offset_dir.y).s,
              jn(c->def.offset_dir.z).s);
  }
  fputc('}', x->f);
  return 0;
}

static int feedback_cb(void *u, int64_t frame, int slot, palp_vec3 f) {
  exp_ctx *x = u;
  sep(x);
  if (x->csv) fprintf(x->f, "%" PRId64 ",%d,%.17g,%.17g,%.17g\n", frame, slot, f.x, f.y, f.z);
  else
    fprintf(x->f, "{\"frame\": %" PRId64 ", \"slot\": %d, \"force_n\": [%s, %s, %s]}", frame, slot, jn(f.x).s,
            jn(f.y).s, jn(f.z).s);
  return 0;
}

static int event_cb(void *u, double wall, int64_t frame, const char *kind, const char *detail, int64_t count) {
  exp_ctx *x = u;
  sep(x);
  if (x->csv) {
    fprintf(x->f, "%.17g,%" PRId64 ",", wall, frame);
    csv_str(x->f, kind); /* text from the file: quoted like any other */
    fprintf(x->f, ",%" PRId64 ",", count);
    csv_str(x->f, detail);
    fputc('\n', x->f);
    return 0;
  }
  fprintf(x->f, "{\"wall_unix_s\": %s, \"frame\": %" PRId64 ", \"kind\": ", jn(wall).s, frame);
  json_str(x->f, kind);
  fprintf(x->f, ", \"count\": %" PRId64 ", \"detail\": ", count);
  json_str(x->f, detail);
  fputc('}', x->f);
  return 0;
}

static int note_cb(void *u, double wall, const char *author, const char *text, const char *grade) {
  exp_ctx *x = u;
  sep(x);
  if (x->csv) {
    fprintf(x->f, "%.17g,", wall);
    csv_str(x->f, author);
    fputc(',', x->f);
    csv_str(x->f, text);
    fputc(',', x->f);
    csv_str(x->f, grade);
    fputc('\n', x->f);
    return 0;
  }
  fprintf(x->f, "{\"wall_unix_s\": %s, \"author\": ", jn(wall).s);
  json_str(x->f, author);
  fputs(", \"text\": ", x->f);
  json_str(x->f, text);
  fputs(", \"grade\": ", x->f);
  if (grade) json_str(x->f, grade);
  else fputs("null", x->f);
  fputc('}', x->f);
  return 0;
}

enum { T_CONTACTS, T_FEEDBACK, T_FRAMES, T_EVENTS, T_NOTES };
static int json_array(palp_db *db, exp_ctx *x, const char *name, int last, int table, int64_t sid) {
  fprintf(x->f, "  \"%s\": [", name);
  x->first = 1;
  int rc;
  switch (table) {
  case T_CONTACTS: rc = palp_db_each_contact(db, sid, contact_cb, x); break;
  case T_FEEDBACK: rc = palp_db_each_feedback(db, sid, feedback_cb, x); break;
  case T_FRAMES: rc = palp_db_each_frame(db, sid, frame_cb, x); break;
  case T_EVENTS: rc = palp_db_each_event(db, sid, event_cb, x); break;
  default: rc = review_each_note(db, sid, note_cb, x); break; /* the grade with its score and level */
  }
  fprintf(x->f, "%s]%s\n", x->first ? "" : "\n  ", last ? "" : ",");
  return rc;
}

/* The logged JSON goes in as JSON when it parses whole, else as a string, so the export stays valid:
 * cJSON_Parse alone stops after the first value, and text after it ('{}, "frames": [...]') would
 * have gone out raw, as keys of the export's own. What goes in is cJSON's own printing of the parsed
 * value, not the stored text (since session 81: cJSON accepts what JSON does not, "01", "1.", a raw
 * line break or \x01 inside a string, and the text went out as stored); text that is not UTF-8 goes
 * in as a string, its bad bytes as U+FFFD (cJSON would print them raw). */
static void json_embed(FILE *f, const char *s) {
  cJSON *j = s && *s && review_utf8_valid(s) ? cJSON_ParseWithOpts(s, NULL, 1) : NULL;
  char *printed = j ? cJSON_PrintUnformatted(j) : NULL;
  if (printed) fputs(printed, f);
  else if (s && *s) json_str(f, s);
  else fputs("null", f);
  cJSON_free(printed);
  cJSON_Delete(j);
}

int review_export(palp_log *log, palp_db *db, const palp_db_session_info *s, const char *format, const char *table,
                  const char *out_path) {
  if (!format || (strcmp(format, "csv") && strcmp(format, "json"))) {
    fprintf(stderr, "palp-review export: --format csv|json is required\n");
    return REVIEW_ERROR;
  }
  const int csv = !strcmp(format, "csv");
  /* JSON holds every table; a --table it is given must still be one (since session 81 "bogus" is refused
   * there too: it was taken without a word) */
  if (strcmp(table, "frames") && strcmp(table, "contacts") && strcmp(table, "feedback") &&
      strcmp(table, "events") && strcmp(table, "notes") && strcmp(table, "metrics")) {
    fprintf(stderr, "palp-review export: --table must be frames, contacts, feedback, events, notes or metrics\n");
    return REVIEW_ERROR;
  }
  FILE *f = stdout;
  /* whether --out names a file already there: an export cut short never replaces it (below) */
  const int had_file = out_path && strcmp(out_path, "-") && access(out_path, F_OK) == 0;
  if (out_path && strcmp(out_path, "-") && !(f = review_fopen_out(log, out_path))) {
    perror(out_path);
    return REVIEW_ERROR;
  }
  exp_ctx x = {f, 1, csv};
  int rc = 0;
  if (csv) {
    if (!strcmp(table, "frames")) {
      fputs("frame,sim_time_s,top_disp_m,max_disp_m,volume_m3,pressure_pa,contact_force_n,state_hash\n", f);
      rc = palp_db_each_frame(db, s->id, frame_cb, &x);
    } else if (!strcmp(table, "contacts")) {
      fputs("frame,sim_time_s,slot,op,kind,distribution,center_x_m,center_y_m,center_z_m,force_x_n,force_y_n,"
            "force_z_n,radius_m,patch_area_m2,sigma_fraction,offset_fraction,offset_dir_x,offset_dir_y,"
            "offset_dir_z\n",
            f);
      rc = palp_db_each_contact(db, s->id, contact_cb, &x);
    } else if (!strcmp(table, "feedback")) {
      fputs("frame,slot,force_x_n,force_y_n,force_z_n\n", f);
      rc = palp_db_each_feedback(db, s->id, feedback_cb, &x);
    } else if (!strcmp(table, "events")) {
      fputs("wall_unix_s,frame,kind,count,detail\n", f);
      rc = palp_db_each_event(db, s->id, event_cb, &x);
    } else if (!strcmp(table, "notes")) {
      fputs("wall_unix_s,author,text,grade\n", f);
      rc = review_each_note(db, s->id, note_cb, &x);
    } else {
      /* One row: the session's metrics (as palp-review show and the class CSV give them). */
      review_assessment a;
      char err[512];
      rc = review_assess(db, s, &a, err, sizeof err);
      int stored = PALP_DB_ENOTFOUND;
      if (rc == PALP_DB_ENOTFOUND && (stored = review_stored_metrics(db, s->id, &a)) == 0) rc = 0;
      else if (rc) {
        /* no samples, and the metrics a prune kept cannot be read: that is why */
        if (stored != PALP_DB_ENOTFOUND)
          snprintf(err, sizeof err, "the session_metrics table could not be read: %s", palp_db_errmsg(db));
        palp_log_error(log, "export metrics: %s", err);
        review_abandon_out(f);
        return REVIEW_ERROR;
      } else rc = 1; /* computed: free it below */
      review_metrics_csv_header(f);
      review_metrics_csv_row(f, db, s, &a, review_valid_range_seconds(db, s));
      if (rc == 1) review_assessment_free(&a);
      rc = 0;
    }
  } else {
    char *scene = NULL, *params = NULL;
    palp_db_session_json(db, s->id, &scene, &params);
    fputs("{\n  \"session\": {\"uid\": ", f);
    json_str(f, s->uid);
    fputs(", \"trainee\": ", f);
    json_str(f, s->trainee);
    fputs(", \"station\": ", f);
    json_str(f, s->station);
    fputs(", \"phantom_id\": ", f);
    json_str(f, s->phantom_id);
    fputs(", \"phantom_name\": ", f);
    json_str(f, s->phantom_name);
    fprintf(f, ", \"tick_hz\": %s, \"dt_s\": %s, \"start_unix_s\": %s, \"end_unix_s\": ", jn(s->tick_hz).s,
            jn(s->dt_s).s, jn(s->start_unix_s).s);
    if (s->end_reason[0]) fprintf(f, "%s, \"end_reason\": ", jn(s->end_unix_s).s), json_str(f, s->end_reason);
    else fputs("null, \"end_reason\": null", f);
    fputs(", \"end_detail\": ", f);
    json_str(f, s->end_detail);
    fprintf(f, ", \"records_shed\": %lld, \"records_failed\": %lld,\n    \"scene\": ", (long long)s->records_shed,
            (long long)s->records_failed);
    json_embed(f, scene);
    fputs(",\n    \"params\": ", f);
    json_embed(f, params);
    fputs("},\n", f);
    free(scene);
    free(params);
    /* in the order of T_CONTACTS ... T_NOTES; the first that cannot be read ends the export */
    static const char *const arrays[] = {"contacts", "feedback", "frames", "events", "notes"};
    for (int k = 0; k <= T_NOTES && !rc; k++)
      if ((rc = json_array(db, &x, arrays[k], k == T_NOTES, k, s->id))) table = arrays[k];
    fputs("}\n", f);
  }
  const int to_stdout = f == stdout;
  if (rc) { /* which table, and why (2026-12-06: the notes ended there silently) */
    /* What came before the damage is written (the rows read), except over a file already there: the
     * cut export (invalid JSON, a CSV short of rows) replaced a whole one until session 90 (found by
     * review); that file is kept. */
    const char *what = !had_file ? "the export is incomplete: it holds what came before"
                                 : "not written; the file already there is kept";
    palp_log_error(log, "export: the %s could not be read: %s (%s)", table, palp_db_errmsg(db), what);
    if (had_file) review_abandon_out(f);
    else review_close_out(f);
    return REVIEW_ERROR;
  }
  const int werr = review_close_out(f) != 0 ? errno : 0;
  if (werr) {
    if (to_stdout) palp_log_error(log, "export: standard output: %s (the export is incomplete)", strerror(werr));
    else palp_log_error(log, "export: %s: %s (not written; a file already there is kept)", out_path, strerror(werr));
    return REVIEW_ERROR;
  }
  return REVIEW_OK;
}
