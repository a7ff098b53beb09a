/* Opening a session log: connection settings, schema versioning and migrations.
 *
 * The version lives in PRAGMA user_version (one integer in the file header, readable without a
 * table) and, for people reading the file with sqlite3, in the meta table along with the palp
 * version that created or last upgraded it. Migrations run in one IMMEDIATE transaction, so a
 * crash or a concurrent opener sees either the old schema or the new one, never a mix. */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "db_internal.h"
#include "migrations.h"
#include "palp_db.h"

#include "palp_version.h" /* PALP_VERSION_STRING, written at each build (cmake/PalpVersion.cmake) */

int palp_db_schema_version(void) { return palp_db_migration_count; }

double palp_db__now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void palp_db__fmt(char *buf, size_t len, const char *fmt, ...) {
  if (!buf || len == 0) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(buf, len, fmt, ap);
  va_end(ap);
}

const char *palp_db_strerror(int err) {
  switch (err) {
  case PALP_DB_ENEWER: return "database schema is newer than this palp";
  case PALP_DB_ENOTFOUND: return "no such session";
  case PALP_DB_ESQL: return "SQLite error";
  case PALP_DB_EAMBIGUOUS: return "session prefix is ambiguous";
  case PALP_DB_EOLDER: return "database schema is older than this palp, and reading it would need an upgrade";
  case PALP_DB_ECOPY: return "reading the file needs a copy in memory larger than allowed";
  case PALP_OK: return "ok";
  case PALP_EINVAL: return "invalid argument";
  case PALP_ENOMEM: return "out of memory";
  case PALP_EIO: return "I/O error";
  case PALP_EFULL: return "queue full";
  default: return "unknown error";
  }
}

static int exec_fmt(sqlite3 *db, char *err, size_t errlen, const char *what, const char *sql) {
  char *msg = NULL;
  int rc = sqlite3_exec(db, sql, NULL, NULL, &msg);
  if (rc != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: %s", what, msg ? msg : sqlite3_errstr(rc));
    sqlite3_free(msg);
    return PALP_DB_ESQL;
  }
  return 0;
}

static int user_version(sqlite3 *db, int *out) {
  sqlite3_stmt *st;
  int rc = sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &st, NULL);
  if (rc != SQLITE_OK) return rc;
  rc = sqlite3_step(st);
  if (rc == SQLITE_ROW) {
    *out = sqlite3_column_int(st, 0);
    rc = SQLITE_OK;
  }
  sqlite3_finalize(st);
  return rc;
}

static int has_tables(sqlite3 *db) {
  sqlite3_stmt *st;
  int n = 0;
  if (sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master WHERE name NOT LIKE 'sqlite_%'", -1, &st, NULL) !=
      SQLITE_OK)
    return 0;
  if (sqlite3_step(st) == SQLITE_ROW) n = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  return n > 0;
}

/* palp's own tables, as every schema version since 1 has them (the reader's check_palp_file asks the same) */
static int has_palp_tables(sqlite3 *db) {
  sqlite3_stmt *st;
  int n = 0;
  if (sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN ('session', 'meta')",
                         -1, &st, NULL) != SQLITE_OK)
    return 0;
  if (sqlite3_step(st) == SQLITE_ROW) n = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  return n == 2;
}

static int set_meta(sqlite3 *db, const char *key, const char *value) {
  sqlite3_stmt *st;
  int rc = sqlite3_prepare_v2(db,
                              "INSERT INTO meta(key, value) VALUES(?1, ?2) "
                              "ON CONFLICT(key) DO UPDATE SET value = excluded.value",
                              -1, &st, NULL);
  if (rc != SQLITE_OK) return rc;
  sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
  sqlite3_bind_text(st, 2, value, -1, SQLITE_STATIC);
  rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? SQLITE_OK : rc;
}

/* Brings the schema from its version to palp_db_migration_count inside one transaction. */
int palp_db__migrate(sqlite3 *db, const char *path, const char *app_version, char *err, size_t errlen) {
  if (!app_version) app_version = PALP_VERSION_STRING;
  int v = 0;
  if (user_version(db, &v) != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: cannot read the schema version: %s", path, sqlite3_errmsg(db));
    return PALP_DB_ESQL;
  }
  const int current = palp_db_migration_count;
  if (v > current) {
    palp_db__fmt(err, errlen, "%s: database schema version %d is newer than this palp (%d); upgrade palp",
                 path, v, current);
    return PALP_DB_ENEWER;
  }
  if (v == current) return 0;

  /* IMMEDIATE takes the write lock now, so two openers cannot both migrate; re-read inside. */
  int rc = exec_fmt(db, err, errlen, path, "BEGIN IMMEDIATE");
  if (rc) return rc;
  if (user_version(db, &v) != SQLITE_OK) goto sqlfail;
  if (v > current) {
    sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
    palp_db__fmt(err, errlen, "%s: database schema version %d is newer than this palp (%d); upgrade palp",
                 path, v, current);
    return PALP_DB_ENEWER;
  }
  const int was = v;
  for (int i = 0; i < palp_db_migration_count; i++) {
    const palp_db_migration *m = &palp_db_migrations[i];
    if (m->version <= v) continue;
    char *msg = NULL;
    if (sqlite3_exec(db, m->sql, NULL, NULL, &msg) != SQLITE_OK) {
      palp_db__fmt(err, errlen, "%s: migration %s failed: %s", path, m->name, msg ? msg : "?");
      sqlite3_free(msg);
      sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
      return PALP_DB_ESQL;
    }
    v = m->version;
  }
  char sql[64], now[32];
  snprintf(sql, sizeof sql, "PRAGMA user_version = %d", current);
  snprintf(now, sizeof now, "%.3f", palp_db__now());
  if (sqlite3_exec(db, sql, NULL, NULL, NULL) != SQLITE_OK) goto sqlfail;
  if (was == 0 && set_meta(db, "created_unix_s", now) != SQLITE_OK) goto sqlfail;
  if (was != 0 && set_meta(db, "upgraded_unix_s", now) != SQLITE_OK) goto sqlfail;
  if (set_meta(db, "app_version", app_version) != SQLITE_OK) goto sqlfail;
  snprintf(sql, sizeof sql, "%d", current);
  if (set_meta(db, "schema_version", sql) != SQLITE_OK) goto sqlfail;
  return exec_fmt(db, err, errlen, path, "COMMIT");
sqlfail:
  palp_db__fmt(err, errlen, "%s: schema upgrade failed: %s", path, sqlite3_errmsg(db));
  sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
  return PALP_DB_ESQL;
}

int palp_db__connect(const char *path, int create, const char *app_version, sqlite3 **out,
                     char *err, size_t errlen) {
  *out = NULL;
  if (!path || !*path) {
    palp_db__fmt(err, errlen, "no database path given");
    return PALP_EINVAL;
  }
  if (!app_version) app_version = PALP_VERSION_STRING;
  /* A new session log is made readable by its owner only (0600): it holds trainees' names, what
   * they did and their grades. SQLite would make it 0644 (less the umask), and its -wal and -shm
   * files take the database's own mode, so making the empty file first is enough (an empty file is
   * an empty database to SQLite). O_EXCL: an existing file is never touched here. */
  if (create) {
    const int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd >= 0) close(fd);
  }
  sqlite3 *db = NULL;
  int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_FULLMUTEX | (create ? SQLITE_OPEN_CREATE : 0);
  int rc = sqlite3_open_v2(path, &db, flags, NULL);
  if (rc != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: cannot open: %s", path, db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
    sqlite3_close(db);
    return PALP_EIO;
  }
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, PALP_DB_BUSY_TIMEOUT_MS);
  /* Refuse a newer schema before touching anything else in the file. */
  int v = 0;
  if (user_version(db, &v) != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: not a palp session log: %s", path, sqlite3_errmsg(db));
    sqlite3_close(db);
    return PALP_EIO;
  }
  if (v > palp_db_migration_count) {
    palp_db__fmt(err, errlen, "%s: database schema version %d is newer than this palp (%d); upgrade palp",
                 path, v, palp_db_migration_count);
    sqlite3_close(db);
    return PALP_DB_ENEWER;
  }
  if (v == 0 && has_tables(db)) {
    /* Version 0 with tables: somebody else's database. Never add our schema to it. */
    palp_db__fmt(err, errlen, "%s: not a palp session log (it holds tables but no palp schema version)", path);
    sqlite3_close(db);
    return PALP_EINVAL;
  }
  if (v < 0 || (v > 0 && !has_palp_tables(db))) {
    /* Another program's version number (palp's run 1..N): migrating from it would add palp's schema to
     * that database, and the WAL pragma below would change its journal for good (session 75, found by
     * review). Checked before anything is written. */
    palp_db__fmt(err, errlen, "%s: not a palp session log (schema version %d without palp's tables; left untouched)",
                 path, v);
    sqlite3_close(db);
    return PALP_EINVAL;
  }
  /* WAL: readers (palp-review) never block the server's writer and vice versa. synchronous=NORMAL
   * in WAL mode survives a process crash with every commit; only power loss can roll back the
   * commits made since the last checkpoint. */
  /* SQLite says a refused change (no shared memory on the file system, an in-memory database) by
   * answering the mode it kept, not by an error: read the answer (session 82). In a rollback journal
   * the writer and palp-review would block each other, and the durability docs/db.md states would not
   * hold: refused, naming the mode, rather than run so without a word. */
  sqlite3_stmt *jm = NULL;
  char mode[32] = "";
  rc = sqlite3_prepare_v2(db, "PRAGMA journal_mode=WAL", -1, &jm, NULL);
  if (rc == SQLITE_OK && (rc = sqlite3_step(jm)) == SQLITE_ROW) {
    const unsigned char *m = sqlite3_column_text(jm, 0);
    snprintf(mode, sizeof mode, "%s", m ? (const char *)m : "");
    rc = SQLITE_OK;
  }
  sqlite3_finalize(jm);
  if (rc != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: setting WAL mode: %s", path, sqlite3_errmsg(db));
    sqlite3_close(db);
    return PALP_DB_ESQL;
  }
  if (strcmp(mode, "wal") != 0) {
    palp_db__fmt(err, errlen, "%s: SQLite kept journal mode \"%s\" where WAL was asked (a file system without "
                 "shared memory?); a session log needs WAL", path, mode);
    sqlite3_close(db);
    return PALP_EIO;
  }
  if ((rc = exec_fmt(db, err, errlen, path, "PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON")) != 0 ||
      (rc = palp_db__migrate(db, path, app_version, err, errlen)) != 0) {
    sqlite3_close(db);
    return rc;
  }
  *out = db;
  return 0;
}
