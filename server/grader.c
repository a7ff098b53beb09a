/* grader.c - a closed exercise session's automatic score from the server's own log (grader.h). */
#include "grader.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "assess_log.h" /* review_assess: palp-review's own reading of a log */
#include "palp_assess.h"

#define QUEUE 32            /* sessions waiting to be graded, scores waiting to be taken */
#define WRITER_WAIT_S 30.0  /* the log's writer must have written the session's end by then */
#define STOPPING_WAIT_S 2.0 /* ... and stopping: a server whose disk hangs must still stop */
#define WAIT_SLICE_S 0.1    /* the writer is waited for in slices, so that a stop is seen */

typedef struct job {
  uint32_t session_id;
  int64_t mark; /* the log writer's mark as it was submitted: the session's end was enqueued before */
  char uid[96];
  char exercise[64];
} job;

struct palp_srv_grader {
  char *path;
  palp_db_writer *w;
  palp_log *log;
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t wake;
  int stop;
  job jobs[QUEUE];
  int job_head, job_n;
  palp_srv_score done[QUEUE];
  int done_head, done_n;
  palp_db *db; /* the grader thread's read connection, opened at its first job */
};

void palp_srv_score_of(const review_assessment *a, uint32_t session_id, const char *uid, const char *exercise,
                       const char *reason, palp_srv_score *out) {
  memset(out, 0, sizeof *out);
  out->session_id = session_id;
  snprintf(out->log_uid, sizeof out->log_uid, "%s", uid ? uid : "");
  snprintf(out->exercise, sizeof out->exercise, "%s", exercise ? exercise : "");
  if (!a) {
    snprintf(out->reason, sizeof out->reason, "%s", reason && reason[0] ? reason : "not graded");
    return;
  }
  const palp_assess_result *r = &a->r;
  out->graded = 1;
  out->score = r->score;
  out->pass = r->pass != 0;
  for (int m = 0; m < PALP_METRIC_COUNT && m < 6; m++) {
    out->credit[m] = r->component[m];
    out->passed[m] = r->pass_metric[m] != 0;
  }
  out->lesions = (uint32_t)r->lesion_count;
  out->found = (uint32_t)r->found;
  out->false_marks = (uint32_t)r->false_positives;
  for (int b = 0; b < PALP_BAND_COUNT; b++) out->coverage[b] = r->coverage[b];
  out->pattern = (int)r->pattern;
  out->duration = r->duration;
  out->peak_force = r->peak_force;
  out->out_of_range = (uint32_t)r->out_of_range;
  out->samples = (uint32_t)a->samples;
}

void palp_srv_health_fit(const char *line, char *out, size_t len) {
  if (!len) return;
  if (strlen(line) < len) {
    snprintf(out, len, "%s", line);
    return;
  }
  /* Too long for the wire's string<127> (a damaged and cut-short log's line runs to ~200): first
   * without its explanations in parentheses, which the review prints; then, if still too long, cut
   * after its last whole phrase (", " or "; ") that leaves room for " ...", never inside a count. */
  char bare[512];
  size_t n = 0;
  for (const char *c = line; *c && n + 1 < sizeof bare; c++) {
    const char *close = c[0] == ' ' && c[1] == '(' ? strchr(c, ')') : NULL;
    if (close) {
      c = close;
      continue;
    }
    bare[n++] = *c;
  }
  bare[n] = 0;
  if (n < len) {
    memcpy(out, bare, n + 1);
    return;
  }
  static const char more[] = " ...";
  size_t cut = 0;
  for (size_t i = 0; i + sizeof more <= len && i < n; i++)
    if ((bare[i] == ',' || bare[i] == ';') && bare[i + 1] == ' ') cut = i;
  if (!cut) cut = len - sizeof more;
  snprintf(out, len, "%.*s%s", (int)cut, bare, more);
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Waits for the log's writer to have written every record enqueued before the job (the session's end
 * among them), in slices: at most WRITER_WAIT_S, and once the server is stopping at most
 * STOPPING_WAIT_S more, even when the wait began before the stop. 0, or -1 and *waited [s]. */
static int wait_writer(palp_srv_grader *g, int64_t mark, double *waited) {
  const double t0 = now_s();
  double stop_t = -1;
  for (;;) {
    if (palp_db_writer_wait(g->w, mark, WAIT_SLICE_S) == 0) return 0;
    const double t = now_s();
    pthread_mutex_lock(&g->mu);
    if (g->stop && stop_t < 0) stop_t = t;
    pthread_mutex_unlock(&g->mu);
    *waited = t - t0;
    if (*waited >= WRITER_WAIT_S || (stop_t >= 0 && t - stop_t >= STOPPING_WAIT_S)) return -1;
  }
}

/* Why records were lost, in SQLite's words where there are some: a queue that overflowed sheds (no
 * error), a full file or disk fails with one, a record the database refused fails without. */
static const char *loss_cause(const palp_db_writer_stats *st, int failed) {
  if (!failed) return "its queue was full";
  return st->last_error_code ? palp_db_error_text(st->last_error_code) : "records refused by the database";
}

/* Grades one session: waits for the writer to have written the session's end, then reads the session
 * back as palp-review does. -1 when the writer did not catch up. */
static int grade(palp_srv_grader *g, const job *j, palp_srv_score *out) {
  char err[512] = "";
  double waited = 0;
  if (wait_writer(g, j->mark, &waited) != 0) {
    snprintf(err, sizeof err, "the session log's writer did not catch up within %.0f s", waited);
    palp_srv_score_of(NULL, j->session_id, j->uid, j->exercise, err, out);
    return -1;
  }
  if (!g->db && palp_db_open(g->path, 0, &g->db, err, sizeof err) != 0) {
    g->db = NULL;
    char why[160];
    snprintf(why, sizeof why, "the session log could not be read: %.120s", err);
    palp_srv_score_of(NULL, j->session_id, j->uid, j->exercise, why, out);
    return 0;
  }
  palp_db_session_info info;
  /* Exactly this uid: palp_db_find_session also takes a unique prefix, and "...-1" is one of "...-10". */
  if (palp_db_find_session(g->db, j->uid, &info) != 0 || strcmp(info.uid, j->uid) != 0) {
    /* A log that is losing records (a full disk, or its cap: session_log_max_mb), or lost some since
     * the server started, lost the session's opening: the trainee is told that, not left to think the
     * server forgot her (docs/server.md, "A full session log"). */
    palp_db_writer_stats st;
    palp_db_writer_stats_get(g->w, &st);
    char why[128] = "the session is not in the log";
    if (st.failed > 0 || st.shed > 0) {
      snprintf(why, sizeof why, "not in the session log, which %s records (%.48s); tell your instructor",
               st.in_error ? "is losing" : "lost", loss_cause(&st, st.failed > 0));
    }
    palp_srv_score_of(NULL, j->session_id, j->uid, j->exercise, why, out);
    return 0;
  }
  review_assessment *a = calloc(1, sizeof *a);
  if (!a) {
    palp_srv_score_of(NULL, j->session_id, j->uid, j->exercise, "out of memory", out);
    return 0;
  }
  /* On an error review_assess has freed what it made. */
  const int assessed = review_assess(g->db, &info, a, err, sizeof err) == 0;
  if (assessed && !a->has_exercise) snprintf(err, sizeof err, "the log holds no exercise for the session");
  if (!(assessed && a->has_exercise) && (info.records_failed > 0 || info.records_shed > 0)) {
    /* The session's row got in (a small batch found room in a full file) but what scoring needs (its
     * exercise, its fingertip's samples) did not: the loss is the reason, and what to do about it is
     * the instructor's; the row's counts are this session's own, up to date once the wait returns. */
    palp_db_writer_stats st;
    palp_db_writer_stats_get(g->w, &st);
    palp_log_info(g->log, "session %u (%s): %s, after the session log lost %lld of its records", j->session_id,
                  j->uid, err, (long long)(info.records_failed + info.records_shed));
    snprintf(err, sizeof err, "the session log lost %lld of its records (%.40s); tell your instructor",
             (long long)(info.records_failed + info.records_shed), loss_cause(&st, info.records_failed > 0));
  }
  palp_srv_score_of(assessed && a->has_exercise ? a : NULL, j->session_id, j->uid, j->exercise, err, out);
  /* How far the log can be trusted for it: a score from a log that lost records may be low. */
  palp_db_log_health health;
  if (out->graded && palp_db_log_health_get(g->db, &info, &health) == 0) {
    out->log_complete = health.complete != 0;
    char line[512];
    palp_db_log_health_describe(&health, line, sizeof line);
    palp_srv_health_fit(line, out->log_health, sizeof out->log_health);
  } else if (out->graded) {
    snprintf(out->log_health, sizeof out->log_health, "unknown: %s", palp_db_errmsg(g->db));
  }
  if (assessed) review_assessment_free(a);
  free(a);
  return 0;
}

static void *grader_main(void *arg) {
  palp_srv_grader *g = arg;
  int writer_stuck = 0; /* stopping, the writer did not catch up: the rest are not graded */
  pthread_mutex_lock(&g->mu);
  for (;;) {
    while (!g->stop && g->job_n == 0) pthread_cond_wait(&g->wake, &g->mu);
    /* Stopping, the sessions already waiting are still graded (at most QUEUE, each well under a
     * second): the log then says each one's score, as the review will; unless the writer is stuck. */
    if (g->job_n == 0 || writer_stuck) break;
    job j = g->jobs[g->job_head];
    pthread_mutex_unlock(&g->mu);
    palp_srv_score s;
    const int caught_up = grade(g, &j, &s) == 0;
    if (s.graded)
      /* shown as the station and palp-web show it (palp_shown_tenths: a score not passed floored to 0.1) */
      palp_log_info(g->log, "session %u (%s): scored %.1f, %s, from the session log", s.session_id, s.log_uid,
                    palp_shown_tenths(s.score, NAN, s.pass), s.pass ? "pass" : "fail");
    else
      /* info: the common case is a session without a fingertip, nothing to mend; a disk's trouble
       * is the writer's warning already */
      palp_log_info(g->log, "session %u (%s): not scored: %s (palp-review show grades it from the log)",
                    s.session_id, s.log_uid, s.reason);
    pthread_mutex_lock(&g->mu);
    if (!caught_up && g->stop) writer_stuck = 1;
    g->job_head = (g->job_head + 1) % QUEUE;
    g->job_n--;
    if (g->done_n == QUEUE) {
      palp_log_warn(g->log, "session %u: its score was not sent: %d scores are waiting for the server", s.session_id,
                    QUEUE);
      continue;
    }
    g->done[(g->done_head + g->done_n++) % QUEUE] = s;
  }
  pthread_mutex_unlock(&g->mu);
  return NULL;
}

int palp_srv_grader_open(const char *db_path, palp_db_writer *w, palp_log *log, palp_srv_grader **out) {
  *out = NULL;
  if (!db_path || !w) return PALP_EINVAL;
  palp_srv_grader *g = calloc(1, sizeof *g);
  if (!g) return PALP_ENOMEM;
  g->path = strdup(db_path);
  g->w = w;
  g->log = log;
  if (!g->path) {
    free(g);
    return PALP_ENOMEM;
  }
  pthread_mutex_init(&g->mu, NULL);
  pthread_cond_init(&g->wake, NULL);
  if (pthread_create(&g->thread, NULL, grader_main, g) != 0) {
    pthread_cond_destroy(&g->wake);
    pthread_mutex_destroy(&g->mu);
    free(g->path);
    free(g);
    return PALP_ENOMEM;
  }
  *out = g;
  return 0;
}

int palp_srv_grader_submit(palp_srv_grader *g, uint32_t session_id, const char *uid, const char *exercise) {
  const int64_t mark = palp_db_writer_mark(g->w); /* taken outside g->mu: no lock order to keep */
  pthread_mutex_lock(&g->mu);
  if (g->job_n == QUEUE) {
    /* Answered at once as not graded, where there is room for the answer: the dashboard and her
     * station then say why rather than wait for a score that will not come. */
    const int told = g->done_n < QUEUE;
    if (told) {
      char why[128];
      snprintf(why, sizeof why, "%d sessions were waiting to be graded as it closed; palp-review show grades it from "
                                "the log", QUEUE);
      palp_srv_score_of(NULL, session_id, uid, exercise, why, &g->done[(g->done_head + g->done_n++) % QUEUE]);
    }
    pthread_mutex_unlock(&g->mu);
    palp_log_warn(g->log, "session %u (%s): not scored live: %d sessions are waiting to be graded (palp-review show "
                          "grades it from the log)%s",
                  session_id, uid, QUEUE, told ? "" : "; not even that could be sent");
    return PALP_EFULL;
  }
  job *j = &g->jobs[(g->job_head + g->job_n++) % QUEUE];
  j->session_id = session_id;
  j->mark = mark;
  snprintf(j->uid, sizeof j->uid, "%s", uid);
  snprintf(j->exercise, sizeof j->exercise, "%s", exercise ? exercise : "");
  pthread_cond_signal(&g->wake);
  pthread_mutex_unlock(&g->mu);
  return 0;
}

int palp_srv_grader_take(palp_srv_grader *g, palp_srv_score *out) {
  pthread_mutex_lock(&g->mu);
  const int got = g->done_n > 0;
  if (got) {
    *out = g->done[g->done_head];
    g->done_head = (g->done_head + 1) % QUEUE;
    g->done_n--;
  }
  pthread_mutex_unlock(&g->mu);
  return got;
}

void palp_srv_grader_close(palp_srv_grader *g) {
  if (!g) return;
  pthread_mutex_lock(&g->mu);
  g->stop = 1;
  pthread_cond_signal(&g->wake);
  pthread_mutex_unlock(&g->mu);
  pthread_join(g->thread, NULL);
  if (g->job_n)
    palp_log_warn(g->log, "session log: %d closed session(s) not scored: the log's writer is behind as the server "
                          "stops (palp-review show grades them from the log)",
                  g->job_n);
  if (g->done_n)
    palp_log_info(g->log, "session log: %d score(s) not sent: the server stopped (palp-review show gives them)",
                  g->done_n);
  if (g->db) palp_db_close(g->db);
  pthread_cond_destroy(&g->wake);
  pthread_mutex_destroy(&g->mu);
  free(g->path);
  free(g);
}
