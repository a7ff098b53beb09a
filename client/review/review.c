/* palp-review: list, show, export, annotate, replay and report logged palpation sessions.
 *
 *   palp-review [--db FILE] COMMAND [ARGS]
 *
 * The database defaults to $PALP_DB, then ./palp-sessions.db. The tool opens the file with a WAL
 * reader, so it works while the server is writing the same file. The commands that only read (list,
 * show, export, replay, report, class, trainee) open it read-only (palp_db_open_readonly): reading a
 * log never changes it, be it a copy from an older palp (read through an upgraded copy in memory),
 * on read-only media, or live. annotate, delete, prune and migrate write, and upgrade an older file. */
#include <limits.h>
#include <math.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "review.h"
#include "review_util.h"
#include "assess_log.h"
#include "grades.h"
#include "retention.h"
#include <sqlite3.h>
#include "palp_app.h"

/* replay --verbose has its own meaning, so only --log-level/--log-file. */
#define REVIEW_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG)

/* How large a log from an older palp the read-only commands copy into memory to read it unchanged
 * (PALP_REVIEW_COPY_MB overrides): a class's term is tens of MB; a machine running palp-review has
 * this much to spare, and a larger file is better upgraded once (migrate) than copied at every read. */
#define REVIEW_COPY_MB_DEFAULT 256

static void usage(FILE *f) {
  fprintf(f, "usage: palp-review [--db FILE] COMMAND [ARGS]\n"
        "  list     [--trainee NAME] [--phantom ID|NAME] [--since DATE] [--until DATE] [--ungraded]\n"
        "  show     SESSION\n"
        "  export   SESSION --format csv|json [--table frames|contacts|feedback|events|notes|metrics] [--out FILE]\n"
        "  annotate SESSION --author NAME --note TEXT [--score 0-100] [--level LEVEL]\n"
        "           LEVEL is insufficient|developing|competent|proficient; --grade takes either\n"
        "  replay   SESSION [--verbose]\n"
        "  report   SESSION --out FILE.html\n"
        "  class    --exercise NAME [--since DATE] --out FILE.html [--csv FILE]\n"
        "  trainee  NAME [--since DATE] [--until DATE] [--csv FILE] [--out FILE.html]\n"
        "           (her sessions oldest first, each exercise's scores, what to work on)\n"
        "           DATE is YYYY-MM-DD[THH:MM[:SS]], local time; --until a day alone takes in that whole day\n"
        "  delete   SESSION...                  (the sessions and all their data)\n"
        "  prune    --older-than DAYS [--keep-graded] [--dry-run]\n"
        "           (ended sessions: frames, feedback, contacts, meshes, finger samples go; the session,\n"
        "            exercise, findings, events, notes/grades and a metrics summary stay)\n"
        "  migrate  (upgrades a log from an older palp to this palp's schema, in the file)\n"
        "list, show, export, replay, report, class and trainee only read: the file is opened read-only and\n"
        "never changed. A log from an older palp is read through an upgraded copy in memory, if it is at\n"
        "most PALP_REVIEW_COPY_MB megabytes (default %d; 0: never copy); a larger one is refused, naming\n"
        "migrate. annotate, delete, prune and migrate write to the file, and upgrade an older one in it.\n"
        "SESSION is a session uid; else the number a station showed (\"session 3\", up to 9 digits) when one\n"
        "logged session has it; else a unique prefix of a uid (otherwise the candidates are listed). A number\n"
        "is a station's session number before it is a prefix. delete takes a whole uid or a station's\n"
        "number, never a prefix, and prints the uid it deleted.\n"
        "DATE is YYYY-MM-DD[THH:MM[:SS]] local time.\n"
        "The database is --db, else $PALP_DB, else ./palp-sessions.db. --database is the same option\n"
        "(palp-server's name for it).\n"
        "A command-line mistake is one plain line (\"palp-review list: unknown option --x\"); other\n"
        "errors are log lines (timestamp, level); tables and reports go to stdout.\n",
        REVIEW_COPY_MB_DEFAULT);
  palp_app_common_usage(f, REVIEW_OPTS);
}

/* ---- list ------------------------------------------------------------------------------ */
/* A phantom column as wide as its longest name, at most 40 characters: cut at 20 the demo's
 * "dome C (long-term, haptic 250 Hz)" read "dome C (long-term, h". */
static int phantom_width(const palp_db_session_info *v, int n) {
  int pw = 7;
  for (int i = 0; i < n; i++) {
    const int len = (int)strnlen(v[i].phantom_name, 40);
    if (len > pw) pw = len;
  }
  return pw;
}

static int cmd_list(palp_log *log, palp_db *db, int argc, char **argv) {
  palp_db_filter f = {0};
  int ungraded = 0; /* only the sessions no note grades yet: what is left to grade */
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--ungraded")) {
      ungraded = 1;
      continue;
    }
    static const char *const takes_value[] = {"--trainee", "--phantom", "--since", "--until", NULL};
    if (!review_option_known(a, takes_value)) {
      fprintf(stderr, "palp-review list: unknown option %s\n", a);
      return REVIEW_ERROR;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review list: %s needs a value\n", a);
      return REVIEW_ERROR;
    }
    if (!strcmp(a, "--trainee")) f.trainee = argv[++i];
    else if (!strcmp(a, "--phantom")) f.phantom = argv[++i];
    else { /* --since, --until */
      double t;
      const int until = !strcmp(a, "--until");
      if ((until ? review_parse_until : review_parse_date)(argv[++i], &t)) {
        fprintf(stderr, "palp-review list: %s: expected YYYY-MM-DD[THH:MM[:SS]], got '%s'\n", a, argv[i]);
        return REVIEW_ERROR;
      }
      if (!strcmp(a, "--since")) f.since_unix_s = t, f.has_since = 1;
      else f.until_unix_s = t, f.has_until = 1;
    }
  }
  palp_db_session_info *v;
  int n;
  if (palp_db_list_sessions(db, &f, &v, &n)) {
    palp_log_error(log, "list: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  const int pw = phantom_width(v, n);
  printf("%-36s %-14s %-*s %-16s %-25s %9s %-16s %-5s %s\n", "SESSION", "TRAINEE", pw, "PHANTOM", "EXERCISE", "STARTED",
         "SIM [s]", "ENDED", "NOTES", "GRADE");
  int shown = 0;
  for (int i = 0; i < n; i++) {
    char t[64], exname[64] = "-", grade[160];
    /* --ungraded lists the sessions not known to be graded: an unreadable grade ("unreadable") too */
    if (review_latest_grade(db, v[i].id, grade, sizeof grade) > 0 && ungraded) continue;
    shown++;
    review_fmt_time(v[i].start_unix_s, t, sizeof t);
    palp_db_log_health h;
    int known = palp_db_log_health_get(db, &v[i], &h) == 0;
    if (palp_db_session_exercise(db, v[i].id, exname, sizeof exname, NULL) != 0) snprintf(exname, sizeof exname, "-");
    char sim[32], pruned[64] = "";
    if (v[i].pruned_unix_s > 0) { /* no frames left: its simulated time is not known, not 0 */
      char tp[64];
      review_fmt_time(v[i].pruned_unix_s, tp, sizeof tp);
      snprintf(sim, sizeof sim, "-");
      snprintf(pruned, sizeof pruned, "  (PRUNED on %.10s)", tp);
    } else snprintf(sim, sizeof sim, "%.2f", v[i].sim_duration_s);
    printf("%-36s %-14s %-*.*s %-16.16s %-25s %9s %-16s %-5lld %s%s%s%s\n", v[i].uid, v[i].trainee, pw, pw,
           v[i].phantom_name, exname, t, sim, v[i].end_reason[0] ? v[i].end_reason : "(no end logged)",
           (long long)v[i].notes, grade, pruned, known && h.damaged ? "  (log damaged)" : "",
           !known ? "  (log unreadable)" : "");
  }
  printf("%d session%s%s\n", shown, shown == 1 ? "" : "s", ungraded ? " not graded yet" : "");
  free(v);
  /* Who could not join at all: no session, so nowhere above (palp-server logs them as
   * server-wide events; docs/security.md). Listed for the same time range. */
  palp_db_filter rf = {.since_unix_s = f.since_unix_s, .until_unix_s = f.until_unix_s, .has_since = f.has_since,
                       .has_until = f.has_until};
  palp_db_refused *rv;
  int rn;
  if (!f.trainee && !f.phantom && !ungraded && palp_db_list_refused(db, &rf, &rv, &rn) == 0) {
    for (int i = 0; i < rn; i++) { /* the first row is written at the first refusal; later ones when said */
      char a[64];
      review_fmt_time(rv[i].first_unix_s, a, sizeof a);
      printf("refused by DDS Security: %s, %lld time(s), the first at %s\n", rv[i].detail, (long long)rv[i].count, a);
    }
    free(rv);
  }
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
  /* The unusual ones are worth reading in full; joins and leaves are in the summary line, and
   * the valid-range events (one a second while outside) in the "valid range" line above, the
   * debrief in the "debrief" line. A
   * trainee's own leave and join are unusual: its station was lost and its session held
   * (docs/server.md, station_grace), which the instructor should see. */
  const int member = !strcmp(kind, "join") || !strcmp(kind, "leave");
  if ((member ? strstr(detail ? detail : "", "(trainee") != NULL
              : strcmp(kind, palp_db_event_kind_name(PALP_DB_EVENT_VALID_RANGE)) != 0 &&
                    strcmp(kind, palp_db_event_kind_name(PALP_DB_EVENT_DEBRIEF)) != 0) &&
      t->listed < 20) {
    char ts[64], k[64], d[1024];
    review_fmt_time(wall, ts, sizeof ts);
    snprintf(k, sizeof k, "%s", kind);
    snprintf(d, sizeof d, "%s", detail ? detail : "");
    review_tty(k);
    review_tty(d);
    printf("    %s  frame %-8lld %-10s x%-4lld %s\n", ts, (long long)frame, k, (long long)count, d);
    t->listed++;
  }
  return 0;
}

static int note_cb(void *u, double wall, const char *author, const char *text, const char *grade) {
  (void)u;
  char ts[64], a[256], t[4096];
  review_fmt_time(wall, ts, sizeof ts);
  snprintf(a, sizeof a, "%s", author);
  snprintf(t, sizeof t, "%s", text);
  review_tty(a);
  review_tty(t);
  printf("    %s  %s%s%s%s: %s\n", ts, a, grade ? " [grade " : "", grade ? grade : "", grade ? "]" : "", t);
  return 0;
}

/* A table of the log show could not read to its end (a damaged page): said in its place, and the first
 * such kept in why for the exit status (2026-12-06: the notes and events ended silently, stored metrics
 * that could not be read were "none"). */
static void show_unreadable(palp_db *db, const char *label, const char *table, char *why, size_t len) {
  printf("%-10s UNREADABLE: the %s table could not be read: %s\n", label, table, palp_db_errmsg(db));
  if (!why[0]) snprintf(why, len, "the %s table could not be read: %s", table, palp_db_errmsg(db));
}

static int cmd_show(palp_log *log, palp_db *db, const palp_db_session_info *s) {
  char why[400] = "";
  char t0[64], t1[64];
  review_fmt_time(s->start_unix_s, t0, sizeof t0);
  review_fmt_time(s->end_unix_s, t1, sizeof t1);
  /* One name for a session (docs/naming.md): the stations print "session N", the number
   * the server gave it on the wire; the log's uid is "<server run>-N". */
  const char *dash = strrchr(s->uid, '-');
  char *endp = NULL;
  const unsigned long wire = dash ? strtoul(dash + 1, &endp, 10) : 0;
  unsigned rec_phantom = 0, rec_session = 0;
  int rec_n = 0;
  /* palp-recorder's uid is "dds-PHANTOM-SESSION-START_MS" (db/recorder): no server run in it */
  if (sscanf(s->uid, "dds-%u-%u-%*[0-9]%n", &rec_phantom, &rec_session, &rec_n) == 2 && s->uid[rec_n] == '\0')
    printf("session    %s  (\"session %u\" on the stations; recorded over DDS)\n", s->uid, rec_session);
  else if (dash && endp && *endp == '\0' && endp != dash + 1 && dash != s->uid)
    printf("session    %s  (\"session %lu\" on the stations; server run %.*s)\n", s->uid, wire, (int)(dash - s->uid),
           s->uid);
  else printf("session    %s\n", s->uid);
  printf("trainee    %s   station %s\n", s->trainee, s->station);
  printf("phantom    %s (%s)\n", s->phantom_id, s->phantom_name);
  char *params = NULL;
  if (palp_db_session_json(db, s->id, NULL, &params) == 0 && params && strstr(params, "\"recorded_by\"")) {
    printf("source     recorded over DDS by palp-recorder (inputs as received; not replayable)\n");
    /* a recorder started after the session opened holds only its rest (db/recorder) */
    double from = 0;
    if (review_params_number(db, s->id, "recorded_from_s", &from) && from > 0)
      printf("           FROM %.1f s INTO THE SESSION: the recorder joined late; what came before (marks, touches) "
             "is not in this log, its metrics are of the rest\n", from);
  }
  free(params);
  printf("started    %s\n", t0);
  if (s->end_reason[0])
    printf("ended      %s  (%s%s%s)\n", t1, s->end_reason, s->end_detail[0] ? ": " : "", s->end_detail);
  else printf("ended      - (still running, or the end was never logged)\n");
  char tp[64];
  review_fmt_time(s->pruned_unix_s, tp, sizeof tp);
  if (s->pruned_unix_s > 0)
    printf("PRUNED     on %s: its frames, feedback, contact inputs, meshes and finger samples were deleted "
           "(palp-review prune); what follows is what was kept: its row, events, notes, findings, stored metrics\n", tp);
  peaks p = {0};
  /* A table that cannot be read is said where its figures go, and the exit status says the show is
   * incomplete (until session 90 the frames' and the presses' reads were unchecked: "0 force contacts, 0
   * fingers" and exit 0 over an unreadable feedback table; found by review). */
  const int frames_rc = palp_db_each_frame(db, s->id, peaks_cb, &p);
  char frames_err[256] = "";
  if (frames_rc) snprintf(frames_err, sizeof frames_err, "%s", palp_db_errmsg(db));
  palp_db_log_health health;
  const int health_rc = palp_db_log_health_get(db, s, &health);
  char health_err[256] = ""; /* said below, after other reads have replaced SQLite's message */
  if (health_rc) snprintf(health_err, sizeof health_err, "%s", palp_db_errmsg(db));
  char logging[200];
  review_fmt_logging(s, health_rc == 0 ? &health : NULL, logging, sizeof logging);
  if (s->pruned_unix_s > 0)
    printf("duration   wall %.3f s, simulated: not known (its frames were pruned on %s)\n",
           s->end_unix_s > 0 ? s->end_unix_s - s->start_unix_s : 0.0, tp);
  else
    printf("duration   wall %.3f s, simulated %.3f s (%s)\n", s->end_unix_s > 0 ? s->end_unix_s - s->start_unix_s : 0.0,
           s->sim_duration_s, logging);
  if (frames_rc) {
    printf("peaks      UNREADABLE: the frame table could not be read: %s\n", frames_err);
    if (!why[0]) snprintf(why, sizeof why, "the frame table could not be read: %s", frames_err);
  } else {
    printf("peak force           %.2f N at t = %.2f s (the phantom's force on the load, from the logged frames)\n", p.f,
           p.f_t);
    printf("peak displacement    top vertex %.2f mm at t = %.2f s; any vertex %.2f mm at t = %.2f s\n",
           p.top * 1e3, p.top_t, p.max * 1e3, p.max_t);
  }
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
  const int presses_rc = review_presses(db, s->id, &c, &pr, &np);
  int nforce = 0, nfinger = 0;
  for (int i = 0; i < np; i++) {
    if (pr[i].kind == PALP_DB_KIND_FORCE) nforce++;
    else nfinger++;
  }
  if (presses_rc == PALP_ENOMEM) {
    printf("contacts   %d inputs: their presses not counted (out of memory)\n", c.n);
    if (!why[0]) snprintf(why, sizeof why, "out of memory counting the presses");
  } else if (presses_rc) {
    printf("contacts   %d inputs; their presses UNREADABLE: the feedback table could not be read: %s\n", c.n,
           palp_db_errmsg(db));
    if (!why[0]) snprintf(why, sizeof why, "the feedback table could not be read: %s", palp_db_errmsg(db));
  } else
    printf("contacts   %d inputs: %d force contact%s, %d finger%s\n", c.n, nforce, nforce == 1 ? "" : "s", nfinger,
           nfinger == 1 ? "" : "s");
  /* The finger's touches come from its logged samples (the assessment's reading of them): a
   * finger slot lives for the whole session, and its input is the device point above the
   * surface, so the slot alone says neither where nor how often the trainee touched. */
  review_assessment a;
  char aerr[512];
  const int arc = review_assess(db, s, &a, aerr, sizeof aerr);
  const int touches = arc == 0 && a.touch_n > 0;
  if (np && (nforce || !touches)) {
    printf("where pressed (seen from above; 12 o'clock = +y, 3 o'clock = +x; arc from the pole):\n");
    printf("    %-4s %-6s %-18s %-26s %-8s %-9s %-15s %s\n", "slot", "kind", "distribution", "centre x,y,z [mm]", "clock",
           "arc [mm]", "on .. off [s]", "peak [N]");
    for (int i = 0; i < np; i++) {
      const review_press *q = &pr[i];
      if (q->kind != PALP_DB_KIND_FORCE && touches) continue; /* listed by its touches below */
      const palp_vec3 x = q->first_center_m;
      char off[24];
      if (q->t_off_s >= 0) snprintf(off, sizeof off, "%.2f", q->t_off_s);
      else snprintf(off, sizeof off, "end");
      char ctr[40];
      snprintf(ctr, sizeof ctr, "%.1f,%.1f,%.1f", x.x * 1e3, x.y * 1e3, x.z * 1e3);
      char clk[24];
      printf("    %-4d %-6s %-18s %-26s %s  %-9.1f %6.2f .. %-6s %.2f%s\n", q->slot,
             q->kind == PALP_DB_KIND_FORCE ? "force" : "finger", q->kind == PALP_DB_KIND_FORCE ? review_dist_name(q->distribution) : "-",
             ctr, review_clock_cell(x, 7, clk, sizeof clk), review_arc_m(x) * 1e3, q->t_on_s, off, q->peak_force_n,
             q->kind == PALP_DB_KIND_FORCE ? "" : "  (a finger: its device point at the start, above the surface)");
    }
  }
  if (touches) review_touches_print(stdout, &a, REVIEW_TOUCHES_LISTED);
  free(pr);
  free(c.v);
  /* what the trainee was told as the session closed (docs/assessment.md, "Debrief") */
  char exname[64], debrief[1024] = "";
  char *exjson = NULL;
  if (arc == 0 ? a.has_exercise : palp_db_session_exercise(db, s->id, exname, sizeof exname, &exjson) == 0) {
    palp_db_debrief d;
    review_debrief_text(review_debrief(db, s, &d), &d, arc == 0 ? &a : NULL, debrief, sizeof debrief);
  }
  free(exjson);
  if (arc == 0) {
    review_metrics_print(stdout, &a);
    /* an attempt after a debrief on the same lesions is not blind (docs/assessment.md, "Debrief") */
    review_told told;
    if (review_told_before(db, s, &a, &told) == 1) {
      char t[512];
      review_told_text(s, &told, t, sizeof t);
      printf("told       %s\n", t);
    }
    review_assessment_free(&a);
  } else if (arc == PALP_DB_ENOTFOUND) {
    const int stored = review_stored_metrics_print(db, s->id, stdout);
    if (stored == PALP_DB_ENOTFOUND) printf("metrics    none: %s\n", aerr);
    else if (stored) show_unreadable(db, "metrics", "session_metrics", why, sizeof why);
  } else {
    printf("metrics    UNKNOWN: %s\n", aerr);
    /* the log could not be read (a damaged page under the finger samples or findings): not a success
     * (since session 81: exit 0), as export, trainee and class say it. A logged scene or exercise that
     * does not parse stays said in the line alone, as before. */
    if ((arc == PALP_DB_ESQL || arc == PALP_ENOMEM) && !why[0])
      snprintf(why, sizeof why, "the metrics could not be computed: %.300s", aerr);
  }
  if (debrief[0]) printf("debrief    %s\n", debrief);
  /* Where the phantom's model answered outside its valid range: the forces (and so the pressure
   * bands the metrics above count) there are extrapolations (docs/model.md, "Valid range"). */
  char range[640];
  review_valid_range_text(db, s, range, sizeof range);
  printf("valid range %s\n", range);
  printf("events     %lld\n", (long long)s->events);
  ev_tally t = {0};
  if (palp_db_each_event(db, s->id, ev_cb, &t)) show_unreadable(db, "events", "event", why, sizeof why);
  if (t.n) {
    printf("    totals:");
    for (int i = 0; i < t.n; i++) {
      char k[sizeof t.kind[0]];
      snprintf(k, sizeof k, "%s", t.kind[i]);
      review_tty(k);
      printf(" %s %lld%s", k, (long long)t.count[i], i + 1 < t.n ? "," : "");
    }
    printf("\n");
  }
  printf("notes      %lld\n", (long long)s->notes);
  if (review_each_note(db, s->id, note_cb, NULL)) show_unreadable(db, "notes", "note", why, sizeof why);
  char line[600];
  if (health_rc == 0) {
    palp_db_log_health_describe(&health, line, sizeof line);
    printf("log        %s\n", line);
    if (health.cut_short && health.last_event_unix_s > 0) {
      char t[64];
      review_fmt_time(health.last_event_unix_s, t, sizeof t);
      printf("           last event logged at %s\n", t);
    }
  } else {
    printf("log        UNKNOWN: %s\n", health_err);
    if (!why[0]) snprintf(why, sizeof why, "the log's frames and events could not be read: %s", health_err);
  }
  if (why[0]) {
    palp_log_error(log, "show: %s: %s (what is shown is incomplete)", s->uid, why);
    return REVIEW_ERROR;
  }
  return REVIEW_OK;
}

/* ---- annotate -------------------------------------------------------------------------- */
static int cmd_annotate(palp_log *log, palp_db *db, const palp_db_session_info *s, int argc, char **argv) {
  const char *author = NULL, *note = NULL, *score_s = NULL, *level = NULL, *grade = NULL;
  static const char *const takes_value[] = {"--author", "--note", "--score", "--level", "--grade", NULL};
  for (int i = 0; i < argc; i++) {
    if (!review_option_known(argv[i], takes_value)) {
      fprintf(stderr, "palp-review annotate: unknown option %s\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review annotate: %s needs a value\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (!strcmp(argv[i], "--author")) author = argv[++i];
    else if (!strcmp(argv[i], "--note")) note = argv[++i];
    else if (!strcmp(argv[i], "--score")) score_s = argv[++i];
    else if (!strcmp(argv[i], "--level")) level = argv[++i];
    else grade = argv[++i]; /* --grade */
  }
  if (!author || !*author || !note) {
    fprintf(stderr, "palp-review annotate: --author and --note are required\n");
    return REVIEW_ERROR;
  }
  char msg[256];
  int li;
  /* The old free-text --grade maps onto the structured grade: a level name, or a score. */
  if (grade) {
    if (review_parse_level(grade, &li, msg, sizeof msg) == 0) {
      if (level) {
        fprintf(stderr, "palp-review annotate: --grade %s and --level both give a level\n", grade);
        return REVIEW_ERROR;
      }
      level = grade;
    } else if (!score_s) score_s = grade;
    else {
      fprintf(stderr, "palp-review annotate: --grade %s and --score both give a score\n", grade);
      return REVIEW_ERROR;
    }
  }
  double score = -1;
  if (score_s && review_parse_score(score_s, &score, msg, sizeof msg)) {
    fprintf(stderr, "palp-review annotate: %s%s\n", msg, grade ? " (--grade takes a score 0-100 or a level)" : "");
    return REVIEW_ERROR;
  }
  if (level && review_parse_level(level, &li, msg, sizeof msg)) {
    fprintf(stderr, "palp-review annotate: %s\n", msg);
    return REVIEW_ERROR;
  }
  if (review_add_graded_note(db, s->id, author, note, score, level)) {
    palp_log_error(log, "annotate: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  char g[160];
  review_grade_text(score >= 0, score, level, NULL, g, sizeof g);
  printf("note added to %s by %s%s%s\n", s->uid, author, strcmp(g, "-") ? ", grade " : "", strcmp(g, "-") ? g : "");
  return REVIEW_OK;
}

/* PALP_REVIEW_COPY_MB, else REVIEW_COPY_MB_DEFAULT, in bytes; a value that is not a whole number of
 * megabytes >= 0 is said and the default taken. */
static long long copy_max_bytes(palp_log *log) {
  const char *e = getenv("PALP_REVIEW_COPY_MB");
  long long mb = REVIEW_COPY_MB_DEFAULT;
  if (e && *e) {
    char *end;
    const long long v = strtoll(e, &end, 10);
    if (*end || v < 0 || v > LLONG_MAX / 1048576)
      palp_log_warn(log, "PALP_REVIEW_COPY_MB=%s: not a number of megabytes >= 0; %d taken", e, REVIEW_COPY_MB_DEFAULT);
    else mb = v;
  }
  return mb * 1048576;
}

/* ---- migrate --------------------------------------------------------------------------- */
/* The one command that only upgrades: what the read-only commands name for a log too large to copy.
 * palp_db_open upgrades in one transaction (a crash leaves the old schema or the new one). */
static int cmd_migrate(palp_log *log, const char *path, int nargs) {
  if (nargs > 0) {
    fprintf(stderr, "palp-review migrate: no arguments (the file is --db, $PALP_DB or ./palp-sessions.db)\n");
    return REVIEW_ERROR;
  }
  char err[1200] = "";
  int was = 0;
  if (palp_db_peek_version(path, &was, err, sizeof err)) {
    palp_log_error(log, "migrate: %s", err);
    return REVIEW_ERROR;
  }
  palp_db *db;
  if (palp_db_open(path, 0, &db, err, sizeof err)) {
    palp_log_error(log, "migrate: %s", err);
    return REVIEW_ERROR;
  }
  const int now = palp_db_file_version(db);
  palp_db_close(db);
  if (was == now) printf("%s: schema version %d, this palp's: nothing to upgrade\n", path, now);
  else printf("%s: upgraded from schema version %d to %d\n", path, was, now);
  return REVIEW_OK;
}

/* Every command option that takes a value (usage() above; each command's parser takes the word after
 * it as its value, whatever it looks like): the pre-scan in review_main skips that word. */
static int review_opt_takes_value(const char *a) {
  static const char *const with_value[] = {"--trainee", "--phantom", "--since",  "--until", "--format",
                                           "--table",   "--out",     "--author", "--note",  "--score",
                                           "--level",   "--grade",   "--exercise", "--csv", "--older-than"};
  for (size_t k = 0; k < sizeof with_value / sizeof with_value[0]; k++)
    if (!strcmp(a, with_value[k])) return 1;
  return 0;
}

static int review_main(int argc, char **argv) {
  if (palp_app_handle_version(argc, argv, "palp-review")) return 0;
  const char *path = getenv("PALP_DB");
  if (!path || !*path) path = "palp-sessions.db";
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-review");
  /* --db (or --database) and the log options may come anywhere: take them out before the
   * command's own options are parsed. The value of a command's option is skipped, never read as one
   * of these (`annotate --note "--version"` printed the version, exit 0, the note not stored; `--note
   * --log-file` opened a log file; until session 82). */
  for (int k = 1; k < argc; k++) {
    if (review_opt_takes_value(argv[k])) {
      k++;
      continue;
    }
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
    /* --database: palp-server's name for the same file (docs/naming.md) */
    if (strcmp(argv[k], "--db") && strcmp(argv[k], "--database")) continue;
    if (k + 1 >= argc) {
      fprintf(stderr, "palp-review: %s needs a file\n", argv[k]);
      return REVIEW_ERROR;
    }
    path = argv[k + 1];
    for (int j = k; j + 2 <= argc; j++) argv[j] = argv[j + 2];
    argc -= 2;
    k--;
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-review");
    return REVIEW_OK;
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
  static const char *const cmds[] = {"list", "show", "export", "annotate", "replay", "report", "class", "trainee", "delete",
                                     "prune", "migrate"};
  int known = 0;
  for (size_t k = 0; k < sizeof cmds / sizeof cmds[0]; k++) known |= !strcmp(cmd, cmds[k]);
  if (!known) {
    fprintf(stderr, "palp-review: unknown command '%s'\n", cmd);
    usage(stderr);
    return REVIEW_ERROR;
  }
  palp_log log;
  if (palp_log_init(&log, "palp-review", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-review: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return REVIEW_ERROR;
  }
  if (!strcmp(cmd, "migrate")) return cmd_migrate(&log, path, argc - i);
  review_out_protect(path);
  /* Only these write to the log (and so may upgrade it in place); the rest read it read-only, and so
   * does a prune's dry run (since session 81: it upgraded an older palp's log in place). */
  int dry_run = 0;
  for (int k = i; k < argc; k++) dry_run |= !strcmp(argv[k], "--dry-run");
  const int writes = !strcmp(cmd, "annotate") || !strcmp(cmd, "delete") || (!strcmp(cmd, "prune") && !dry_run);
  char err[1200] = "";
  palp_db *db;
  if (writes ? palp_db_open(path, 0, &db, err, sizeof err)
             : palp_db_open_readonly(path, copy_max_bytes(&log), &db, err, sizeof err)) {
    palp_log_error(&log, "%s", err);
    return REVIEW_ERROR;
  }
  if (palp_db_copied_from_version(db))
    palp_log_info(&log, "%s: a log of schema version %d (an older palp's), read through a copy upgraded to version %d "
                  "in memory; the file is left as it is (palp-review migrate upgrades it)",
                  path, palp_db_copied_from_version(db), palp_db_schema_version());
  if (palp_db_copied_unlocked(db))
    palp_log_info(&log, "%s: no -wal beside it, and this user cannot write the file or its directory: read from a "
                  "copy in memory taken at once, without the -wal and -shm SQLite would need beside it; the file is "
                  "left as it is", path);
  int rc;
  if (!strcmp(cmd, "list") || !strcmp(cmd, "class") || !strcmp(cmd, "trainee") || !strcmp(cmd, "delete") ||
      !strcmp(cmd, "prune")) {
    if (!strcmp(cmd, "list")) rc = cmd_list(&log, db, argc - i, argv + i);
    else if (!strcmp(cmd, "class")) rc = review_class(&log, db, argc - i, argv + i);
    else if (!strcmp(cmd, "trainee")) rc = review_trainee(&log, db, argc - i, argv + i);
    else if (!strcmp(cmd, "delete")) rc = review_delete(&log, db, path, argc - i, argv + i);
    else rc = review_prune(&log, db, path, argc - i, argv + i);
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
  /* a prefix names a session for the commands that only read (delete takes none: retention.c), nor does
   * annotate: a grade put on the wrong session cannot be taken back ("annotate run-1" graded run-10 once
   * run-1 was deleted, until session 90; found by review) */
  if (review_find_session(&log, db, cmd, uid, strcmp(cmd, "annotate") != 0, &s)) {
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
    static const char *const takes_value[] = {"--format", "--table", "--out", NULL};
    if (!review_option_known(a, takes_value)) {
      fprintf(stderr, "palp-review %s: unknown option %s\n", cmd, a);
      palp_db_close(db);
      return REVIEW_ERROR;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review %s: %s needs a value\n", cmd, a);
      palp_db_close(db);
      return REVIEW_ERROR;
    }
    if (!strcmp(a, "--format")) format = argv[++i];
    else if (!strcmp(a, "--table")) table = argv[++i];
    else out = argv[++i]; /* --out */
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

/* What a command printed on a full disk or a closed pipe was written to nothing: said, and not a
 * success (exit 2), as palp-stats does; the commands check only the files they open themselves. */
int main(int argc, char **argv) {
  int rc = review_main(argc, argv);
  if (review_finish_output(stdout) != 0) {
    fprintf(stderr, "palp-review: stdout: %s (what was printed is incomplete)\n", strerror(errno));
    rc = REVIEW_ERROR;
  }
  return rc;
}
