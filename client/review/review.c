/* palp-review: list, show, export, annotate, replay and report logged palpation sessions.
 *
 *   palp-review [--db FILE] COMMAND [ARGS]
 *
 * The database defaults to $PALP_DB, then ./palp-sessions.db. The tool opens the file with a WAL
 * reader, so it works while the server is writing the same file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "review.h"
#include "palp_app.h"

#define PI 3.14159265358979323846

/* replay --verbose has its own meaning, so only --log-level/--log-file. */
#define REVIEW_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG)

static void usage(FILE *f) {
  fputs("usage: palp-review [--db FILE] COMMAND [ARGS]\n"
        "  list     [--trainee NAME] [--phantom ID|NAME] [--since DATE] [--until DATE]\n"
        "  show     SESSION\n"
        "  export   SESSION --format csv|json [--table frames|contacts|feedback|events|notes] [--out FILE]\n"
        "  annotate SESSION --author NAME --note TEXT [--grade GRADE]\n"
        "  replay   SESSION [--verbose]\n"
        "  report   SESSION --out FILE.html\n"
        "SESSION is a session uid or a unique prefix of one. DATE is YYYY-MM-DD[THH:MM[:SS]] local time.\n"
        "The database is --db, else $PALP_DB, else ./palp-sessions.db.\n"
        "Errors are log lines (timestamp, level); tables and reports go to stdout.\n",
        f);
  palp_app_common_usage(f, REVIEW_OPTS);
}

void review_fmt_time(double unix_s, char *buf, size_t len) {
  if (!(unix_s > 0)) {
    snprintf(buf, len, "-");
    return;
  }
  time_t t = (time_t)unix_s;
  struct tm tm;
  localtime_r(&t, &tm);
  strftime(buf, len, "%Y-%m-%d %H:%M:%S %z", &tm);
}

void json_str(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p == '\n') fputs("\\n", f);
    else if (*p == '\t') fputs("\\t", f);
    else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
    else fputc(*p, f);
  }
  fputc('"', f);
}

void html_str(FILE *f, const char *s) {
  for (const char *p = s ? s : ""; *p; p++) {
    switch (*p) {
    case '<': fputs("&lt;", f); break;
    case '>': fputs("&gt;", f); break;
    case '&': fputs("&amp;", f); break;
    case '"': fputs("&quot;", f); break;
    case '\'': fputs("&#39;", f); break;
    default: fputc(*p, f);
    }
  }
}

/* Parses YYYY-MM-DD[THH:MM[:SS]] (or a space instead of T) as local time. */
static int parse_date(const char *s, double *out) {
  struct tm tm;
  memset(&tm, 0, sizeof tm);
  int y, mo, d, h = 0, mi = 0, se = 0;
  char sep = 0;
  int n = sscanf(s, "%4d-%2d-%2d%c%2d:%2d:%2d", &y, &mo, &d, &sep, &h, &mi, &se);
  if (n != 3 && n < 6) return -1;
  if (n >= 4 && sep != 'T' && sep != ' ') return -1;
  if (mo < 1 || mo > 12 || d < 1 || d > 31 || h < 0 || h > 23 || mi < 0 || mi > 59 || se < 0 || se > 60)
    return -1;
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  tm.tm_sec = se;
  tm.tm_isdst = -1;
  time_t t = mktime(&tm);
  if (t == (time_t)-1) return -1;
  *out = (double)t;
  return 0;
}

static int contact_cb(void *u, const palp_db_contact *c) {
  review_contacts *v = u;
  if (v->n == v->cap) {
    int ncap = v->cap ? 2 * v->cap : 64;
    palp_db_contact *nv = realloc(v->v, (size_t)ncap * sizeof *nv);
    if (!nv) return PALP_ENOMEM;
    v->v = nv;
    v->cap = ncap;
  }
  v->v[v->n++] = *c;
  return 0;
}

int review_load_contacts(palp_db *db, int64_t sid, review_contacts *out) {
  memset(out, 0, sizeof *out);
  return palp_db_each_contact(db, sid, contact_cb, out);
}

double review_clock_hours(palp_vec3 p) {
  /* Angle clockwise from +y seen from above (+z towards the viewer), in hours of a clock face. */
  double a = atan2(p.x, p.y); /* 0 at +y, +pi/2 at +x */
  double h = a / (2.0 * PI) * 12.0;
  if (h <= 0.0) h += 12.0;
  return h;
}

typedef struct press_acc {
  review_press *v;
  int n;
} press_acc;

static int fb_peak_cb(void *u, int64_t frame, int slot, palp_vec3 f) {
  press_acc *a = u;
  const double m = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
  /* Slots are reused after removal: the press on this slot live at that frame owns the sample
   * (feedback carries the frame after the step, so the live range is (on, off]). */
  for (int i = a->n - 1; i >= 0; i--)
    if (a->v[i].slot == slot && frame > a->v[i].frame_on && (a->v[i].frame_off < 0 || frame <= a->v[i].frame_off)) {
      if (a->v[i].kind == PALP_DB_KIND_FINGER && m > a->v[i].peak_force_n) a->v[i].peak_force_n = m;
      break;
    }
  return 0;
}

int review_presses(palp_db *db, int64_t sid, const review_contacts *c, review_press **out, int *n) {
  review_press *v = calloc((size_t)(c->n > 0 ? c->n : 1), sizeof *v);
  if (!v) return PALP_ENOMEM;
  int k = 0;
  for (int i = 0; i < c->n; i++) {
    const palp_db_contact *x = &c->v[i];
    if (x->op == PALP_DB_OP_ADD) {
      review_press *p = &v[k++];
      p->slot = x->slot;
      p->kind = x->kind;
      p->distribution = x->def.distribution;
      p->first_center_m = p->last_center_m = x->center_m;
      p->t_on_s = x->sim_time_s;
      p->t_off_s = -1;
      p->frame_on = x->frame;
      p->frame_off = -1;
      if (x->kind == PALP_DB_KIND_FORCE)
        p->peak_force_n = sqrt(x->force_n.x * x->force_n.x + x->force_n.y * x->force_n.y + x->force_n.z * x->force_n.z);
      continue;
    }
    for (int j = k - 1; j >= 0; j--) {
      review_press *p = &v[j];
      if (p->slot != x->slot || p->t_off_s >= 0) continue;
      if (x->op == PALP_DB_OP_REMOVE) {
        p->t_off_s = x->sim_time_s;
        p->frame_off = x->frame;
      } else {
        p->updates++;
        if (x->kind == PALP_DB_KIND_FINGER) p->last_center_m = x->center_m;
        else {
          double m = sqrt(x->force_n.x * x->force_n.x + x->force_n.y * x->force_n.y + x->force_n.z * x->force_n.z);
          if (m > p->peak_force_n) p->peak_force_n = m;
        }
      }
      break;
    }
  }
  press_acc a = {v, k};
  int rc = palp_db_each_feedback(db, sid, fb_peak_cb, &a);
  if (rc) {
    free(v);
    return rc;
  }
  *out = v;
  *n = k;
  return 0;
}

/* ---- list ------------------------------------------------------------------------------ */
static int cmd_list(palp_log *log, palp_db *db, int argc, char **argv) {
  palp_db_filter f = {0};
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review list: %s needs a value\n", a);
      return REVIEW_ERROR;
    }
    if (!strcmp(a, "--trainee")) f.trainee = argv[++i];
    else if (!strcmp(a, "--phantom")) f.phantom = argv[++i];
    else if (!strcmp(a, "--since") || !strcmp(a, "--until")) {
      double t;
      if (parse_date(argv[++i], &t)) {
        fprintf(stderr, "palp-review list: %s: expected YYYY-MM-DD[THH:MM[:SS]], got '%s'\n", a, argv[i]);
        return REVIEW_ERROR;
      }
      if (!strcmp(a, "--since")) f.since_unix_s = t;
      else f.until_unix_s = t;
    } else {
      fprintf(stderr, "palp-review list: unknown option %s\n", a);
      return REVIEW_ERROR;
    }
  }
  palp_db_session_info *v;
  int n;
  if (palp_db_list_sessions(db, &f, &v, &n)) {
    palp_log_error(log, "list: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  printf("%-36s %-14s %-12s %-25s %9s %-16s %s\n", "SESSION", "TRAINEE", "PHANTOM", "STARTED", "SIM [s]",
         "ENDED", "NOTES");
  for (int i = 0; i < n; i++) {
    char t[64];
    review_fmt_time(v[i].start_unix_s, t, sizeof t);
    palp_db_log_health h;
    int known = palp_db_log_health_get(db, &v[i], &h) == 0;
    printf("%-36s %-14s %-12s %-25s %9.3f %-16s %lld%s%s\n", v[i].uid, v[i].trainee, v[i].phantom_id, t,
           v[i].sim_duration_s, v[i].end_reason[0] ? v[i].end_reason : "(no end logged)", (long long)v[i].notes,
           known && h.damaged ? "  (log damaged)" : "", !known ? "  (log unreadable)" : "");
  }
  printf("%d session%s\n", n, n == 1 ? "" : "s");
  free(v);
  return REVIEW_OK;
}

/* ---- show ------------------------------------------------------------------------------ */
typedef struct peaks {
  double f, f_t, top, top_t, max, max_t;
  double p_min, p_max, v_min, v_max;
  int64_t n, ngel;
} peaks;

static int peaks_cb(void *u, const palp_db_frame *f) {
  peaks *p = u;
  p->n++;
  if (f->contact_force_n > p->f) p->f = f->contact_force_n, p->f_t = f->sim_time_s;
  if (f->top_disp_m > p->top) p->top = f->top_disp_m, p->top_t = f->sim_time_s;
  if (f->max_disp_m > p->max) p->max = f->max_disp_m, p->max_t = f->sim_time_s;
  /* Volume 0 marks a frame without gel data (palp-recorder before its first deformation sample). */
  if (!(f->volume_m3 > 0)) return 0;
  if (p->ngel++ == 0) {
    p->p_min = p->p_max = f->pressure_pa;
    p->v_min = p->v_max = f->volume_m3;
  }
  if (f->pressure_pa < p->p_min) p->p_min = f->pressure_pa;
  if (f->pressure_pa > p->p_max) p->p_max = f->pressure_pa;
  if (f->volume_m3 < p->v_min) p->v_min = f->volume_m3;
  if (f->volume_m3 > p->v_max) p->v_max = f->volume_m3;
  return 0;
}

typedef struct ev_tally {
  char kind[16][24];
  int64_t count[16];
  int n;
  int listed;
} ev_tally;

static int ev_cb(void *u, double wall, int64_t frame, const char *kind, const char *detail, int64_t count) {
  ev_tally *t = u;
  int i = 0;
  while (i < t->n && strcmp(t->kind[i], kind)) i++;
  if (i == t->n && t->n < 16) snprintf(t->kind[t->n++], sizeof t->kind[0], "%s", kind);
  if (i < 16) t->count[i] += count;
  /* The unusual ones are worth reading in full; joins and leaves are in the summary line. */
  if (strcmp(kind, "join") && strcmp(kind, "leave") && t->listed < 20) {
    char ts[64];
    review_fmt_time(wall, ts, sizeof ts);
    printf("    %s  frame %-8lld %-10s x%-4lld %s\n", ts, (long long)frame, kind, (long long)count, detail);
    t->listed++;
  }
  return 0;
}

static int note_cb(void *u, double wall, const char *author, const char *text, const char *grade) {
  (void)u;
  char ts[64];
  review_fmt_time(wall, ts, sizeof ts);
  printf("    %s  %s%s%s%s: %s\n", ts, author, grade ? " [grade " : "", grade ? grade : "", grade ? "]" : "", text);
  return 0;
}

static const char *dist_name(palp_distribution d) {
  switch (d) {
  case PALP_DIST_SINGLE: return "single";
  case PALP_DIST_UNIFORM: return "uniform";
  case PALP_DIST_GAUSSIAN: return "gaussian";
  case PALP_DIST_GAUSSIAN_OFFSET: return "gauss-off";
  }
  return "-";
}

static int cmd_show(palp_log *log, palp_db *db, const palp_db_session_info *s) {
  char t0[64], t1[64];
  review_fmt_time(s->start_unix_s, t0, sizeof t0);
  review_fmt_time(s->end_unix_s, t1, sizeof t1);
  printf("session    %s\n", s->uid);
  printf("trainee    %s   station %s\n", s->trainee, s->station);
  printf("phantom    %s (%s)\n", s->phantom_id, s->phantom_name);
  char *params = NULL;
  if (palp_db_session_json(db, s->id, NULL, &params) == 0 && params && strstr(params, "\"recorded_by\""))
    printf("source     recorded over DDS by palp-recorder (inputs as received; not replayable)\n");
  free(params);
  printf("started    %s\n", t0);
  if (s->end_reason[0])
    printf("ended      %s  (%s%s%s)\n", t1, s->end_reason, s->end_detail[0] ? ": " : "", s->end_detail);
  else printf("ended      - (still running, or the end was never logged)\n");
  peaks p = {0};
  palp_db_each_frame(db, s->id, peaks_cb, &p);
  printf("duration   wall %.3f s, simulated %.3f s (%lld frames logged at %.0f Hz, dt %.6g s)\n",
         s->end_unix_s > 0 ? s->end_unix_s - s->start_unix_s : 0.0, s->sim_duration_s, (long long)s->frames,
         s->tick_hz, s->dt_s);
  printf("peak force           %.4f N at t = %.3f s\n", p.f, p.f_t);
  printf("peak displacement    top vertex %.3f mm at t = %.3f s; any vertex %.3f mm at t = %.3f s\n",
         p.top * 1e3, p.top_t, p.max * 1e3, p.max_t);
  if (p.ngel)
    printf("gel                  pressure %.3f .. %.3f Pa, volume %.4f .. %.4f cm^3\n", p.p_min, p.p_max,
           p.v_min * 1e6, p.v_max * 1e6);

  review_contacts c;
  if (review_load_contacts(db, s->id, &c)) {
    palp_log_error(log, "show: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  review_press *pr = NULL;
  int np = 0;
  review_presses(db, s->id, &c, &pr, &np);
  int nforce = 0, nfinger = 0;
  for (int i = 0; i < np; i++) {
    if (pr[i].kind == PALP_DB_KIND_FORCE) nforce++;
    else nfinger++;
  }
  printf("contacts   %d inputs: %d force contact%s, %d finger%s\n", c.n, nforce, nforce == 1 ? "" : "s", nfinger,
         nfinger == 1 ? "" : "s");
  if (np) {
    printf("where pressed (seen from above; 12 o'clock = +y, 3 o'clock = +x; arc from the pole):\n");
    printf("    %-4s %-6s %-9s %-26s %-8s %-9s %-17s %s\n", "slot", "kind", "dist", "centre x,y,z [mm]", "clock",
           "arc [mm]", "on .. off [s]", "peak [N]");
    for (int i = 0; i < np; i++) {
      const review_press *q = &pr[i];
      const palp_vec3 x = q->first_center_m;
      const double r = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
      const double arc = r > 0 ? r * acos(fmax(-1.0, fmin(1.0, x.z / r))) : 0.0;
      char off[24];
      if (q->t_off_s >= 0) snprintf(off, sizeof off, "%.3f", q->t_off_s);
      else snprintf(off, sizeof off, "end");
      char ctr[40];
      snprintf(ctr, sizeof ctr, "%.1f,%.1f,%.1f", x.x * 1e3, x.y * 1e3, x.z * 1e3);
      printf("    %-4d %-6s %-9s %-26s %5.1f h  %-9.1f %7.3f .. %-7s %.3f%s\n", q->slot,
             q->kind == PALP_DB_KIND_FORCE ? "force" : "finger", q->kind == PALP_DB_KIND_FORCE ? dist_name(q->distribution) : "-",
             ctr, review_clock_hours(x), arc * 1e3, q->t_on_s, off, q->peak_force_n,
             q->updates ? "" : "");
    }
  }
  free(pr);
  free(c.v);
  printf("events     %lld\n", (long long)s->events);
  ev_tally t = {0};
  palp_db_each_event(db, s->id, ev_cb, &t);
  if (t.n) {
    printf("    totals:");
    for (int i = 0; i < t.n; i++) printf(" %s %lld%s", t.kind[i], (long long)t.count[i], i + 1 < t.n ? "," : "");
    printf("\n");
  }
  printf("notes      %lld\n", (long long)s->notes);
  palp_db_each_note(db, s->id, note_cb, NULL);
  palp_db_log_health h;
  char line[600];
  if (palp_db_log_health_get(db, s, &h) == 0) {
    palp_db_log_health_describe(&h, line, sizeof line);
    printf("log        %s\n", line);
    if (h.cut_short && h.last_event_unix_s > 0) {
      char t[64];
      review_fmt_time(h.last_event_unix_s, t, sizeof t);
      printf("           last event logged at %s\n", t);
    }
  } else {
    printf("log        UNKNOWN: %s\n", palp_db_errmsg(db));
  }
  return REVIEW_OK;
}

/* ---- annotate -------------------------------------------------------------------------- */
static int cmd_annotate(palp_log *log, palp_db *db, const palp_db_session_info *s, int argc, char **argv) {
  const char *author = NULL, *note = NULL, *grade = NULL;
  for (int i = 0; i < argc; i++) {
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review annotate: %s needs a value\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (!strcmp(argv[i], "--author")) author = argv[++i];
    else if (!strcmp(argv[i], "--note")) note = argv[++i];
    else if (!strcmp(argv[i], "--grade")) grade = argv[++i];
    else {
      fprintf(stderr, "palp-review annotate: unknown option %s\n", argv[i]);
      return REVIEW_ERROR;
    }
  }
  if (!author || !*author || !note) {
    fprintf(stderr, "palp-review annotate: --author and --note are required\n");
    return REVIEW_ERROR;
  }
  if (palp_db_add_note(db, s->id, author, note, grade)) {
    palp_log_error(log, "annotate: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  printf("note added to %s by %s%s%s\n", s->uid, author, grade ? ", grade " : "", grade ? grade : "");
  return REVIEW_OK;
}

int main(int argc, char **argv) {
  if (palp_app_handle_version(argc, argv, "palp-review")) return 0;
  const char *path = getenv("PALP_DB");
  if (!path || !*path) path = "palp-sessions.db";
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-review");
  /* --db and the log options may come anywhere: take them out before the
   * command's own options are parsed. */
  for (int k = 1; k < argc; k++) {
    int c = k;
    const int common = palp_app_common_opt(&ao, REVIEW_OPTS, argc, argv, &c);
    if (common < 0) return REVIEW_ERROR;
    if (common) {
      const int n = c - k + 1;
      for (int j = k; j + n <= argc; j++) argv[j] = argv[j + n];
      argc -= n;
      k--;
      continue;
    }
    if (strcmp(argv[k], "--db")) continue;
    if (k + 1 >= argc) {
      fprintf(stderr, "palp-review: --db needs a file\n");
      return REVIEW_ERROR;
    }
    path = argv[k + 1];
    for (int j = k; j + 2 <= argc; j++) argv[j] = argv[j + 2];
    argc -= 2;
    k--;
  }
  int i = 1;
  while (i < argc && argv[i][0] == '-') {
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
      usage(stdout);
      return REVIEW_OK;
    } else {
      fprintf(stderr, "palp-review: unknown option %s\n", argv[i]);
      usage(stderr);
      return REVIEW_ERROR;
    }
  }
  if (i >= argc) {
    usage(stderr);
    return REVIEW_ERROR;
  }
  const char *cmd = argv[i++];
  static const char *const cmds[] = {"list", "show", "export", "annotate", "replay", "report"};
  int known = 0;
  for (size_t k = 0; k < sizeof cmds / sizeof cmds[0]; k++) known |= !strcmp(cmd, cmds[k]);
  if (!known) {
    fprintf(stderr, "palp-review: unknown command '%s'\n", cmd);
    usage(stderr);
    return REVIEW_ERROR;
  }
  palp_log log;
  if (palp_log_init(&log, "palp-review", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-review: --log-file %s: cannot open it\n", ao.log_file);
    return REVIEW_ERROR;
  }
  char err[512] = "";
  palp_db *db;
  if (palp_db_open(path, 0, &db, err, sizeof err)) {
    palp_log_error(&log, "%s", err);
    return REVIEW_ERROR;
  }
  int rc;
  if (!strcmp(cmd, "list")) {
    rc = cmd_list(&log, db, argc - i, argv + i);
    palp_db_close(db);
    return rc;
  }
  if (i >= argc || argv[i][0] == '-') {
    fprintf(stderr, "palp-review %s: which SESSION?\n", cmd);
    palp_db_close(db);
    return REVIEW_ERROR;
  }
  palp_db_session_info s;
  const char *uid = argv[i++];
  rc = palp_db_find_session(db, uid, &s);
  if (rc) {
    palp_log_error(&log, "%s: session '%s': %s", cmd, uid,
            rc == PALP_DB_ESQL ? palp_db_errmsg(db) : palp_db_strerror(rc));
    palp_db_close(db);
    return REVIEW_ERROR;
  }
  const char *format = NULL, *table = "frames", *out = NULL;
  int verbose = 0;
  if (!strcmp(cmd, "annotate")) {
    rc = cmd_annotate(&log, db, &s, argc - i, argv + i);
    palp_db_close(db);
    return rc;
  }
  for (; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--verbose")) {
      verbose = 1;
      continue;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review %s: %s needs a value\n", cmd, a);
      palp_db_close(db);
      return REVIEW_ERROR;
    }
    if (!strcmp(a, "--format")) format = argv[++i];
    else if (!strcmp(a, "--table")) table = argv[++i];
    else if (!strcmp(a, "--out")) out = argv[++i];
    else {
      fprintf(stderr, "palp-review %s: unknown option %s\n", cmd, a);
      palp_db_close(db);
      return REVIEW_ERROR;
    }
  }
  if (!strcmp(cmd, "show")) rc = cmd_show(&log, db, &s);
  else if (!strcmp(cmd, "export")) rc = review_export(&log, db, &s, format, table, out);
  else if (!strcmp(cmd, "replay")) rc = review_replay(&log, db, &s, verbose);
  else {
    if (!out) {
      fprintf(stderr, "palp-review report: --out FILE.html is required\n");
      rc = REVIEW_ERROR;
    } else rc = review_report(&log, db, &s, out);
  }
  palp_db_close(db);
  return rc;
}
