/* Retention: palp-review delete and prune (docs/db.md, "Retention").
 *
 *  - delete SESSION...: the session and everything logged for it go.
 *  - prune --older-than DAYS [--keep-graded] [--dry-run]: for each ENDED session started more
 *    than DAYS ago, its metrics are computed (assess_log.c) and stored in session_metrics, then
 *    its bulky data goes: frames, feedback, contact inputs, meshes, finger samples. Kept: the
 *    session row (scene, trainee, times, end), its exercise, findings, events, notes and grades,
 *    and the metrics summary. A session with no end logged is never pruned (a server may still
 *    be writing it). --keep-graded skips sessions with any grade.
 *
 * Both run in transactions of up to RETENTION_BATCH_SESSIONS sessions, each closed once it has run
 * RETENTION_BATCH_SECONDS, on the WAL connection with its busy timeout, so a server writing other
 * sessions at the same time only waits, briefly; a transaction is all or nothing (a crash or an error
 * leaves every session of it as it was), and one rolled back because a session of it failed is run
 * again without that session (delete then stops there; prune goes on). Then the freed pages go back to the file system with VACUUM
 * (or PRAGMA incremental_vacuum when the file is in that mode), which also waits on the busy timeout
 * and leaves the file untouched if it cannot get the lock.
 *
 * While a writer (palp-server, palp-recorder) has the file open (live_writer_pid), two things are
 * refused (since session 75, both found by review): deleting a session with no end logged, which that
 * writer may still be writing (session ids are rowids: the next session would be given the deleted
 * one's id, and the deleted session's later records would land in it), and the VACUUM, which
 * rewrites the whole file under the write lock for as long as that takes, seconds to minutes on a
 * class's log, while the writer gives a batch up after ~21 s of retries and the stations' records
 * are shed. The freed pages then stay in the file, where the writer reuses them. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <sqlite3.h>

#include "assess_log.h"
#include "grades.h"
#include "retention.h"
#include "review_util.h"

/* Until 2026-12-06 each session had a transaction of its own: pruning a term's 10,000 sessions was
 * 10,000 transactions, each taking the write lock and appending the session table's and its indexes'
 * pages to the WAL again (found by review). A live writer waits while one runs, and gives a batch up
 * after ~21 s of retries (5 s busy timeout each): half a second keeps its wait short, and a few
 * hundred small sessions fit in it. A session larger than that still goes whole in one. */
#define RETENTION_BATCH_SESSIONS 256
#define RETENTION_MAX_DAYS 100000 /* prune --older-than: 274 years at most (the cap before session 81) */
#define RETENTION_BATCH_SECONDS 0.5

static double mono_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Whether a transaction begun at t0 holding `taken` sessions takes another. */
static int batch_has_room(int taken, double t0) {
  return taken == 0 || (taken < RETENTION_BATCH_SESSIONS && mono_s() - t0 < RETENTION_BATCH_SECONDS);
}

static const char *const bulky[] = {"frame", "feedback", "contact_input", "mesh", "finger_sample"};
static const char *const small[] = {"session_exercise", "finding", "event", "note", "session_metrics"};

static int exec_sid(sqlite3 *h, const char *fmt, const char *table, int64_t sid) {
  char sql[256];
  snprintf(sql, sizeof sql, fmt, table);
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(h, sql, -1, &st, NULL) != SQLITE_OK) return -1;
  sqlite3_bind_int64(st, 1, sid);
  int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? 0 : -1;
}

/* A session to prune and the metrics stored for it, taken from its assessment (review_assess) before
 * its transaction: the assessment's mesh, coverage and path are freed at once, so a batch holds only
 * these. */
typedef struct prune_item {
  int index;    /* in the session list */
  int failed;   /* its own statements failed: kept, and left out when its transaction is run again */
  int assessed; /* 0: no finger samples (PALP_DB_ENOTFOUND), no metrics stored */
  int has_exercise;
  char exercise_name[64];
  int samples;
  palp_assess_result r;
} prune_item;

static int store_metrics(sqlite3 *h, int64_t sid, const prune_item *a) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(h,
                         "INSERT OR REPLACE INTO session_metrics(session_id, computed_unix_s, exercise_name, "
                         "samples, lesions, found, findings, withdrawn, false_positives, coverage_light, "
                         "coverage_medium, coverage_deep, coverage_any, pattern, path_length_m, presses, duration_s, "
                         "peak_force_n, out_of_range, score, pass, strips, strip_order) "
                         "VALUES(?1, (julianday('now') - 2440587.5) * 86400.0, "
                         "?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21, "
                         "?22)",
                         -1, &st, NULL) != SQLITE_OK)
    return -1;
  const palp_assess_result *r = &a->r;
  sqlite3_bind_int64(st, 1, sid);
  if (a->has_exercise) sqlite3_bind_text(st, 2, a->exercise_name, -1, SQLITE_TRANSIENT);
  sqlite3_bind_int(st, 3, a->samples);
  sqlite3_bind_int(st, 4, r->lesion_count);
  sqlite3_bind_int(st, 5, r->found);
  sqlite3_bind_int(st, 6, r->findings);
  sqlite3_bind_int(st, 7, r->withdrawn);
  sqlite3_bind_int(st, 8, r->false_positives);
  sqlite3_bind_double(st, 9, r->coverage[0]);
  sqlite3_bind_double(st, 10, r->coverage[1]);
  sqlite3_bind_double(st, 11, r->coverage[2]);
  sqlite3_bind_double(st, 12, r->coverage_any);
  sqlite3_bind_text(st, 13, palp_pattern_name(r->pattern), -1, SQLITE_STATIC);
  sqlite3_bind_double(st, 14, r->evidence.path_length);
  sqlite3_bind_int(st, 15, r->evidence.presses);
  sqlite3_bind_double(st, 16, r->duration);
  sqlite3_bind_double(st, 17, r->peak_force);
  sqlite3_bind_int(st, 18, r->out_of_range);
  if (a->has_exercise) {
    sqlite3_bind_double(st, 19, r->score);
    sqlite3_bind_int(st, 20, r->pass);
  }
  sqlite3_bind_int(st, 21, r->evidence.strips); /* schema 5 */
  sqlite3_bind_double(st, 22, r->evidence.sweep_monotony);
  int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? 0 : -1;
}

/* The pid of a writer that opened this file and has not closed it, and whose process is alive (a
 * WAL file is shared by processes of one host only, so the pid is this host's); 0 if none. A pid
 * reused by another process since a crash reads as alive: refused to the safe side, and said.
 * *opened (if not NULL): when the earliest such writer opened the file [unix s]; a session begun
 * before it is none of theirs. */
static long long live_writer_pid_since(sqlite3 *h, double *opened) {
  sqlite3_stmt *st;
  long long found = 0;
  if (opened) *opened = INFINITY;
  if (sqlite3_prepare_v2(h, "SELECT pid, opened_unix_s FROM writer_run WHERE closed_unix_s IS NULL ORDER BY id DESC",
                         -1, &st, NULL) != SQLITE_OK)
    return 0; /* no writer_run (schema 1): nothing known */
  while (sqlite3_step(st) == SQLITE_ROW) {
    const long long pid = sqlite3_column_int64(st, 0);
    if (pid > 0 && pid <= INT_MAX && (kill((pid_t)pid, 0) == 0 || errno == EPERM)) {
      found = pid;
      if (opened) *opened = fmin(*opened, sqlite3_column_double(st, 1));
    }
  }
  sqlite3_finalize(st);
  return found;
}
static long long live_writer_pid(sqlite3 *h) { return live_writer_pid_since(h, NULL); }

static long long freelist_pages(sqlite3 *h) {
  sqlite3_stmt *st;
  long long n = 0;
  if (sqlite3_prepare_v2(h, "PRAGMA freelist_count", -1, &st, NULL) == SQLITE_OK) {
    if (sqlite3_step(st) == SQLITE_ROW) n = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
  }
  return n;
}

static int reclaim(palp_log *log, sqlite3 *h) {
  const long long pid = live_writer_pid(h);
  if (pid) {
    printf("not compacted: a session log writer (pid %lld) has the file open, and compacting would hold its writes "
           "for as long as it takes; the freed pages stay in the file, where the log reuses them (prune again once "
           "it has stopped to give them back to the file system)\n", pid);
    return 0;
  }
  sqlite3_stmt *st;
  int mode = 0;
  if (sqlite3_prepare_v2(h, "PRAGMA auto_vacuum", -1, &st, NULL) == SQLITE_OK) {
    if (sqlite3_step(st) == SQLITE_ROW) mode = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
  }
  /* 2 = incremental: give the free pages back without rewriting the file. */
  const char *sql = mode == 2 ? "PRAGMA incremental_vacuum" : "VACUUM";
  char *msg = NULL;
  if (sqlite3_exec(h, sql, NULL, NULL, &msg) != SQLITE_OK) {
    palp_log_warn(log, "%s: %s (the space stays free inside the file and is reused)", sql, msg ? msg : "?");
    sqlite3_free(msg);
    return -1;
  }
  /* Truncate the WAL the vacuum wrote through, so the bytes really leave the disk. */
  sqlite3_exec(h, "PRAGMA wal_checkpoint(TRUNCATE)", NULL, NULL, NULL);
  return 0;
}

/* Rows of the given tables logged for a session, inside the caller's transaction. 0 or -1. */
static int delete_rows(sqlite3 *h, int64_t sid, const char *const *tables, size_t n) {
  for (size_t k = 0; k < n; k++)
    if (exec_sid(h, "DELETE FROM %s WHERE session_id = ?1", tables[k], sid)) return -1;
  return 0;
}

/* A session and everything logged for it, inside the caller's transaction. 0 or -1. */
static int delete_session(sqlite3 *h, int64_t sid) {
  if (delete_rows(h, sid, bulky, sizeof bulky / sizeof *bulky) || delete_rows(h, sid, small, sizeof small / sizeof *small))
    return -1;
  return exec_sid(h, "DELETE FROM %s WHERE id = ?1", "session", sid);
}

/* A session's bulky data, its metrics stored first, inside the caller's transaction. 0 or -1. */
static int prune_session(sqlite3 *h, int64_t sid, const prune_item *it) {
  if (it->assessed && store_metrics(h, sid, it)) return -1;
  if (delete_rows(h, sid, bulky, sizeof bulky / sizeof *bulky)) return -1;
  return exec_sid(h, "UPDATE %s SET pruned_unix_s = (julianday('now') - 2440587.5) * 86400.0 WHERE id = ?1", "session",
                  sid);
}

int review_delete(palp_log *log, palp_db *db, const char *path, int argc, char **argv) {
  if (argc < 1) {
    fprintf(stderr, "palp-review delete: which SESSION(s)?\n");
    return REVIEW_ERROR;
  }
  sqlite3 *h = palp_db_handle(db);
  /* Resolve every name first: a typo deletes nothing. */
  int64_t *ids = calloc((size_t)argc, sizeof *ids);
  char(*uids)[sizeof ((palp_db_session_info *)0)->uid] = calloc((size_t)argc, sizeof *uids);
  if (!ids || !uids) {
    free(ids);
    free(uids);
    return REVIEW_ERROR;
  }
  for (int i = 0; i < argc; i++) {
    palp_db_session_info s;
    /* a whole uid or a station's number, never a prefix: "run7-1" would delete run7-10 once run7-1 is gone */
    if (review_find_session(log, db, "delete", argv[i], 0, &s)) {
      palp_log_error(log, "delete: nothing deleted");
      free(ids);
      free(uids);
      return REVIEW_ERROR;
    }
    ids[i] = s.id;
    /* said as the uid deleted, not as typed: "3" is the station's number of one uid */
    snprintf(uids[i], sizeof uids[i], "%s", s.uid);
    long long pid;
    double since;
    /* A session with no end begun while a live writer had the file open may be that writer's, still
     * running; one begun before it opened is a dead writer's, cut short (a crash logs no end). */
    if (!s.end_reason[0] && (pid = live_writer_pid_since(h, &since)) && s.start_unix_s >= since - 1.0) {
      palp_log_error(log,
                     "delete: session '%s' has no end logged and a session log writer (pid %lld) has had the file "
                     "open since before it began: it may still be writing that session, and its records would go to "
                     "the next session given its id; nothing deleted (end the session or stop that server first)",
                     uids[i], pid);
      free(ids);
      free(uids);
      return REVIEW_ERROR;
    }
  }
  const long long before = palp_db_file_bytes(path);
  /* A session whose own statements fail stops the delete there, as one transaction per session did
   * before 2026-12-06: the sessions named before it are deleted (those of its transaction again, in
   * one of their own; found by review: they were rolled back with it and left), it and the later ones
   * not. end: where the transactions stop, the failed session once one has. */
  int i = 0, end = argc, rc = REVIEW_OK;
  while (i < end) {
    const int first = i;
    const double t0 = mono_s();
    int bad = sqlite3_exec(h, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK;
    const int began = !bad;
    while (!bad && i < end && batch_has_room(i - first, t0)) {
      bad = delete_session(h, ids[i]);
      if (!bad) i++;
    }
    if (bad && began && end == argc) {
      char msg[256];
      snprintf(msg, sizeof msg, "%s", sqlite3_errmsg(h));
      sqlite3_exec(h, "ROLLBACK", NULL, NULL, NULL);
      palp_log_error(log, "delete %s: %s (untouched%s%s)", uids[i], msg,
                     i > first ? "; the sessions named before it are deleted without it" : "",
                     i + 1 < argc ? "; the later ones not tried" : "");
      rc = REVIEW_ERROR;
      end = i;
      i = first;
      continue;
    }
    if (bad || sqlite3_exec(h, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
      /* the write lock not had, a COMMIT refused (the disk full), or a session failing where it had not:
       * the transaction's sessions are untouched, and nothing after them is tried */
      char msg[256];
      snprintf(msg, sizeof msg, "%s", sqlite3_errmsg(h));
      sqlite3_exec(h, "ROLLBACK", NULL, NULL, NULL);
      const int last = bad ? i : i - 1; /* the session that failed, or the transaction's last when COMMIT did */
      palp_log_error(log, "delete %s: %s (rolled back with its transaction: %s .. %s, %d session%s, untouched%s)",
                     uids[last], msg, uids[first], uids[last], last - first + 1, last > first ? "s" : "",
                     last + 1 < argc ? "; the later ones not tried" : "");
      free(ids);
      free(uids);
      return REVIEW_ERROR;
    }
    for (int k = first; k < i; k++) printf("deleted %s\n", uids[k]);
  }
  free(ids);
  free(uids);
  if (rc != REVIEW_OK) return rc; /* no compaction after a failure: the command stops where it failed */
  reclaim(log, h);
  printf("file %lld -> %lld bytes\n", before, palp_db_file_bytes(path));
  return REVIEW_OK;
}

int review_prune(palp_log *log, palp_db *db, const char *path, int argc, char **argv) {
  double days = -1;
  int keep_graded = 0, dry = 0;
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--keep-graded")) keep_graded = 1;
    else if (!strcmp(argv[i], "--dry-run")) dry = 1;
    else if (!strcmp(argv[i], "--older-than") && i + 1 < argc) {
      /* Digits, and a fraction after a point, nothing else (since session 81: strtod took "" as 0 days,
       * "prune everything ended", and " 5", "1e3", "0x10" as numbers). At most RETENTION_MAX_DAYS: the
       * cutoff, before 1970 for more than ~20,000 days, is a bound all the same (has_until), where a
       * cutoff <= 0 was taken for none and --older-than 30000 pruned every ended session. */
      const char *a = argv[++i];
      const size_t nd = strspn(a, "0123456789");
      const int whole = nd > 0 && (a[nd] == '\0' || (a[nd] == '.' && a[nd + 1 + strspn(a + nd + 1, "0123456789")] == '\0'));
      days = whole ? strtod(a, NULL) : -1;
      if (!whole || !(days <= RETENTION_MAX_DAYS)) {
        fprintf(stderr, "palp-review prune: --older-than DAYS: a number of days from 0 to %d (digits, a fraction "
                "after a point) is required, got '%s'\n", RETENTION_MAX_DAYS, a);
        return REVIEW_ERROR;
      }
    } else {
      fprintf(stderr, "palp-review prune: unknown option or missing value: %s\n", argv[i]);
      return REVIEW_ERROR;
    }
  }
  if (days < 0) {
    fprintf(stderr, "palp-review prune: --older-than DAYS is required\n");
    return REVIEW_ERROR;
  }
  sqlite3 *h = palp_db_handle(db);
  const double cutoff = (double)time(NULL) - days * 86400.0;
  palp_db_filter f = {.until_unix_s = cutoff, .has_until = 1};
  palp_db_session_info *v;
  int n;
  if (palp_db_list_sessions(db, &f, &v, &n)) {
    palp_log_error(log, "prune: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  const long long before = palp_db_file_bytes(path);
  int pruned = 0, already = 0, rc = REVIEW_OK;
  prune_item *batch = dry ? NULL : malloc(RETENTION_BATCH_SESSIONS * sizeof *batch);
  if (!dry && !batch) {
    palp_log_error(log, "prune: out of memory");
    free(v);
    return REVIEW_ERROR;
  }
  int i = 0, stop = 0;
  while (i < n && !stop) {
    /* The next sessions to prune, up to a batch, each assessed before any transaction: the
     * assessment reads a session's samples, which is no work to do while holding the write lock. */
    int nb = 0;
    for (; i < n && nb < RETENTION_BATCH_SESSIONS; i++) {
      const palp_db_session_info *s = &v[i];
      /* pruned before: nothing left to delete, and its stored metrics and stamp are not to be
       * overwritten (until session 81 each prune said it again and stamped it anew) */
      if (s->pruned_unix_s > 0) {
        already++;
        continue;
      }
      if (!s->end_reason[0]) {
        printf("kept   %s: no end logged (may still be running)\n", s->uid);
        continue;
      }
      if (keep_graded) {
        char g[160];
        const int graded = review_latest_grade(db, s->id, g, sizeof g);
        if (graded < 0) { /* whether it was graded is not known: kept (found by review, session 90) */
          printf("kept   %s: its grade could not be read (%s)\n", s->uid, palp_db_errmsg(db));
          continue;
        }
        if (graded > 0) {
          printf("kept   %s: graded (%s)\n", s->uid, g);
          continue;
        }
      }
      review_assessment a;
      char err[512];
      const int arc = review_assess(db, s, &a, err, sizeof err);
      if (arc && arc != PALP_DB_ENOTFOUND) {
        /* Do not lose what cannot be summarised. */
        printf("kept   %s: its metrics could not be computed (%s)\n", s->uid, err);
        continue;
      }
      if (dry) {
        printf("would prune %s\n", s->uid);
        pruned++;
      } else {
        prune_item *it = &batch[nb++];
        memset(it, 0, sizeof *it);
        it->index = i;
        if (!arc) {
          it->assessed = 1;
          it->has_exercise = a.has_exercise;
          snprintf(it->exercise_name, sizeof it->exercise_name, "%s", a.exercise_name);
          it->samples = a.samples;
          it->r = a.r;
        }
      }
      if (!arc) review_assessment_free(&a);
    }
    /* The batch, in as many transactions as the time allows each. A session whose own statements fail
     * is kept and its transaction run again without it: until 2026-12-06 the sessions before it in
     * that transaction were rolled back with it and not tried again in this run (found by review; the
     * one transaction per session before kept only the failing one). */
    int k = 0;
    while (k < nb) {
      if (batch[k].failed) {
        k++;
        continue;
      }
      const int first = k;
      const double t0 = mono_s();
      if (sqlite3_exec(h, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
        /* the write lock not had within the busy timeout (a writer holding it), or the file not writable:
         * every later transaction would wait as long, so the prune stops here */
        palp_log_error(log, "prune: %s; %s and the sessions after it not pruned (run prune again)", sqlite3_errmsg(h),
                       v[batch[k].index].uid);
        rc = REVIEW_ERROR;
        stop = 1;
        break;
      }
      int bad = 0;
      while (!bad && k < nb && !batch[k].failed && batch_has_room(k - first, t0)) {
        bad = prune_session(h, v[batch[k].index].id, &batch[k]);
        if (!bad) k++;
      }
      if (bad) {
        /* session k's own statements: it is kept; the ones before it in this transaction go again in
         * one of their own (which stops at k), the rest of the batch after it */
        char msg[256];
        snprintf(msg, sizeof msg, "%s", sqlite3_errmsg(h));
        sqlite3_exec(h, "ROLLBACK", NULL, NULL, NULL);
        palp_log_error(log, "prune %s: %s (kept, untouched%s)", v[batch[k].index].uid, msg,
                       k > first ? "; the sessions before it in its transaction are pruned again without it" : "");
        printf("kept   %s: %s\n", v[batch[k].index].uid, msg);
        batch[k].failed = 1;
        rc = REVIEW_ERROR;
        k = first;
        continue;
      }
      if (sqlite3_exec(h, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
        /* no one session's fault (the disk full, an I/O error): the transaction's sessions are kept, and
         * the prune goes on with the rest */
        char msg[256];
        snprintf(msg, sizeof msg, "%s", sqlite3_errmsg(h));
        sqlite3_exec(h, "ROLLBACK", NULL, NULL, NULL);
        palp_log_error(log, "prune: COMMIT: %s (rolled back: %s .. %s, %d session%s, untouched)", msg,
                       v[batch[first].index].uid, v[batch[k - 1].index].uid, k - first, k - first > 1 ? "s" : "");
        for (int j = first; j < k; j++) printf("kept   %s: rolled back (%s)\n", v[batch[j].index].uid, msg);
        rc = REVIEW_ERROR;
        continue;
      }
      for (int j = first; j < k; j++) printf("pruned %s\n", v[batch[j].index].uid);
      pruned += k - first;
    }
  }
  free(batch);
  free(v);
  /* also when nothing was pruned this time: what an earlier prune freed beside a running server */
  if (!dry && (pruned || (freelist_pages(h) > 0 && !live_writer_pid(h)))) reclaim(log, h);
  printf("%d session%s %s", pruned, pruned == 1 ? "" : "s", dry ? "would be pruned" : "pruned");
  if (already) printf(" (%d pruned before, left as they were)", already);
  printf("; file %lld -> %lld bytes\n", before, palp_db_file_bytes(path));
  return rc;
}
