/* Reading a session log: listing, finding and walking sessions, adding notes.
 * Readers run beside the server's writer: WAL gives them a consistent snapshot per statement
 * without blocking it, and busy_timeout covers the moments a checkpoint holds a lock. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "db_internal.h"
#include "migrations.h"
#include "palp_db.h"

struct palp_db {
  sqlite3 *db;
  int copied_from; /* > 0: db is an upgraded in-memory copy of a file at this schema version */
  int unlocked;    /* db is an in-memory copy of a file opened immutable (open_ro), taken at once */
  char *ro_path;   /* db is open_ro's connection to this file: tidy_wal after closing it */
  int wal_before;  /* ... and a -wal was beside the file when it was opened */
};

static int file_exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

/* Whether the -wal beside a log may hold commits: present and not empty. A zero-length -wal (left by a
 * reader or reset by a checkpoint) holds none: the committed data is all in the file. */
static int wal_has_frames(const char *wal) {
  struct stat st;
  return stat(wal, &st) == 0 && st.st_size > 0;
}

/* Whether the file's header says WAL mode (bytes 18 and 19, the read and write versions, are 2): the
 * immutable fallback below is for such files only. A rollback-journal file that SQLite cannot read
 * read-only may have a hot journal, which immutable would ignore. */
static int is_wal_file(const char *path) {
  unsigned char h[20];
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  const size_t n = fread(h, 1, sizeof h, f);
  fclose(f);
  return n == sizeof h && memcmp(h, "SQLite format 3", 16) == 0 && h[18] == 2 && h[19] == 2;
}

/* path as a "file:" URI with query (RFC 3986: everything but unreserved characters and '/' as %XX,
 * so that '?', '#' and '%' in a file name stay the name's; a leading "//" would read as an
 * authority, so the second '/' is encoded too). malloc'd, NULL when out of memory. */
static char *file_uri(const char *path, const char *query) {
  const size_t n = strlen(path);
  char *u = malloc(3 * n + strlen(query) + 8);
  if (!u) return NULL;
  char *o = u + sprintf(u, "file:");
  for (size_t i = 0; i < n; i++) {
    const unsigned char c = (unsigned char)path[i];
    const int plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                      c == '.' || c == '_' || c == '~' || (c == '/' && !(i == 1 && path[0] == '/'));
    o += plain ? sprintf(o, "%c", c) : sprintf(o, "%%%02X", c);
  }
  sprintf(o, "?%s", query);
  return u;
}

/* Whether this user may make and remove files in path's directory. */
static int dir_writable(const char *path) {
  char dir[4200];
  snprintf(dir, sizeof dir, "%s", path);
  char *slash = strrchr(dir, '/');
  if (!slash) snprintf(dir, sizeof dir, ".");
  else slash[slash == dir] = '\0'; /* "/x.db": "/" */
  return access(dir, W_OK | X_OK) == 0;
}

/* What a file opened immutable was just before (open_ro): the same file, unchanged since, when
 * these are (a write sets mtime and ctime; the kernel's timestamps are at worst a few ms coarse, so
 * a file last written within that of the first look and written again in the same tick could pass:
 * a window of a few ms, against a whole command's without the look). */
typedef struct file_id {
  dev_t dev;
  ino_t ino;
  off_t size;
  struct timespec mtime, ctime;
} file_id;

static int file_id_of(const char *path, file_id *id) {
  struct stat st;
  if (stat(path, &st) != 0) return -1;
  *id = (file_id){st.st_dev, st.st_ino, st.st_size, st.st_mtim, st.st_ctim};
  return 0;
}

static int file_id_same(const file_id *a, const file_id *b) {
  return a->dev == b->dev && a->ino == b->ino && a->size == b->size && a->mtime.tv_sec == b->mtime.tv_sec &&
         a->mtime.tv_nsec == b->mtime.tv_nsec && a->ctime.tv_sec == b->ctime.tv_sec &&
         a->ctime.tv_nsec == b->ctime.tv_nsec;
}

/* Opens path SQLITE_OPEN_READONLY and reads its header, so that a file SQLite cannot read fails here.
 * Nothing through this connection writes to the file: SQLite refuses every write on it, and a
 * read-only connection does not checkpoint the WAL into the file at close (NO_CKPT_ON_CLOSE makes
 * sure of it). It may make the -wal and -shm files beside the file, as any reader of a WAL log does
 * (*wal_before says whether a -wal was there: tidy_wal removes them after the close when it was not).
 * Where it cannot (a directory this user may not write, read-only media) SQLite cannot read a
 * WAL-mode file whose -wal is absent (or empty); such a file (its header says WAL) is opened again
 * immutable (no locks, no -wal or -shm): with no -wal beside it, no connection has it open in WAL mode,
 * so no writer is changing it, and its committed data is all in the file; so is one this user may not
 * write in a directory it may (below). With a -wal holding frames, immutable would ignore the commits
 * in it: refused with SQLite's words instead. Immutable holds no lock, so a
 * writer opening the file later may checkpoint into it under the reader: *unlocked is then set and
 * *before says what the file was just before it was opened, for palp_db_open_readonly to copy it at
 * once and check it did not change meanwhile. 0, or PALP_EIO / PALP_ENOMEM (message in err);
 * *probe_rc the header read's SQLite code, so that the caller can tell a non-database. */
static int open_ro(const char *path, sqlite3 **out, int *probe_rc, int *unlocked, file_id *before, int *wal_before,
                   char *err, size_t errlen) {
  *out = NULL;
  *probe_rc = SQLITE_OK;
  *unlocked = 0;
  char wal[4200];
  snprintf(wal, sizeof wal, "%s-wal", path);
  *wal_before = file_exists(wal);
  /* A reader who may write the directory but not the file: SQLite would make a -wal and -shm there that
   * tidy_wal cannot remove (its read-write open would be read-only), and that the log's owner could not
   * write: such a log is opened immutable at once, as one where nothing can be made beside it. */
  const int first = !*wal_before && dir_writable(path) && access(path, W_OK) != 0 && is_wal_file(path);
  sqlite3 *db = NULL;
  for (int immutable = first; immutable < 2; immutable++) {
    if (immutable && file_id_of(path, before) != 0) {
      palp_db__fmt(err, errlen, "%s: cannot open: it is gone", path);
      return PALP_EIO;
    }
    char *uri = immutable ? file_uri(path, "immutable=1") : NULL;
    if (immutable && !uri) return PALP_ENOMEM;
    const int flags = SQLITE_OPEN_READONLY | SQLITE_OPEN_FULLMUTEX | (immutable ? SQLITE_OPEN_URI : 0);
    int rc = sqlite3_open_v2(immutable ? uri : path, &db, flags, NULL);
    free(uri);
    if (rc != SQLITE_OK) {
      palp_db__fmt(err, errlen, "%s: cannot open: %s", path, db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
      sqlite3_close(db);
      return PALP_EIO;
    }
    sqlite3_extended_result_codes(db, 1);
    sqlite3_db_config(db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, (int *)NULL);
    /* A live log's writer may hold a lock for a moment (a checkpoint, WAL recovery): wait for it as every
     * other connection does, or a busy file would be called "not a palp session log". */
    sqlite3_busy_timeout(db, PALP_DB_BUSY_TIMEOUT_MS);
    sqlite3_stmt *st;
    rc = sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master", -1, &st, NULL);
    if (rc == SQLITE_OK) {
      rc = sqlite3_step(st);
      sqlite3_finalize(st);
      if (rc == SQLITE_ROW) rc = SQLITE_OK;
    }
    if (rc == SQLITE_OK) {
      *out = db;
      *unlocked = immutable;
      return 0;
    }
    const int primary = rc & 0xff;
    if (!immutable && (primary == SQLITE_READONLY || primary == SQLITE_CANTOPEN) && !wal_has_frames(wal) &&
        is_wal_file(path)) {
      sqlite3_close(db);
      db = NULL;
      continue;
    }
    *probe_rc = rc;
    *out = db; /* the caller words it: "not an SQLite database", or SQLite's reason */
    return 0;
  }
  return PALP_EIO; /* not reached */
}

/* After open_ro's connection to path has closed: the -wal and -shm SQLite made beside a WAL-mode log
 * that had no -wal when it was opened (wal_before 0), removed as SQLite removes them when the last
 * connection to a log closes. A read-only connection never removes them (it may not checkpoint), so
 * they stayed, owned by the reader, and the log's owner, unable to write them, could no longer write
 * the log ("attempt to write a readonly database"; found by review, 2026-12-06). A read-write
 * connection (no CREATE, no migration, one read so that SQLite opens the WAL) is opened and closed:
 * SQLite removes the -wal and -shm at a close only with an EXCLUSIVE lock on the file, which it cannot
 * have while any other connection, of any process, has the file open in WAL mode (each holds a SHARED
 * lock from its first read to its close), so a live writer's files stay; and it checkpoints first,
 * which with an empty WAL writes nothing to the file. Only where this user may write the file and its
 * directory: otherwise the open would be read-only again, or the files could not be removed. */
static void tidy_wal(const char *path, int wal_before) {
  char wal[4200];
  snprintf(wal, sizeof wal, "%s-wal", path);
  if (wal_before || !file_exists(wal) || !is_wal_file(path)) return;
  if (!dir_writable(path) || access(path, R_OK | W_OK) != 0) return;
  sqlite3 *db = NULL;
  if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_FULLMUTEX, NULL) == SQLITE_OK &&
      !sqlite3_db_readonly(db, "main")) {
    sqlite3_busy_timeout(db, PALP_DB_BUSY_TIMEOUT_MS);
    sqlite3_exec(db, "SELECT count(*) FROM sqlite_master", NULL, NULL, NULL);
  }
  sqlite3_close(db);
}

static void close_ro(sqlite3 *db, const char *path, int wal_before) {
  sqlite3_close(db);
  tidy_wal(path, wal_before);
}

/* Looks at a file read-only: is it a palp session log? 0 (*out the read-only connection, when out is
 * not NULL, and *version its schema version), or PALP_EINVAL / PALP_EIO / PALP_DB_ENEWER with a
 * message. Nothing is written, so an empty or foreign file stays as it was. */
static int check_palp_file(const char *path, sqlite3 **out, int *version_out, int *unlocked, file_id *before,
                           int *wal_before, char *err, size_t errlen) {
  if (out) *out = NULL;
  sqlite3 *db = NULL;
  int probe = SQLITE_OK, unlocked_ = 0, wal_before_ = 0;
  file_id before_;
  if (!wal_before) wal_before = &wal_before_;
  int rc = open_ro(path, &db, &probe, unlocked ? unlocked : &unlocked_, before ? before : &before_, wal_before, err,
                   errlen);
  if (rc) return rc;
  sqlite3_stmt *st;
  int version = -1, tables = -1, any = -1, have_version = 0;
  if (probe == SQLITE_OK && sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &st, NULL) == SQLITE_OK) {
    if (sqlite3_step(st) == SQLITE_ROW) version = sqlite3_column_int(st, 0), have_version = 1;
    sqlite3_finalize(st);
  }
  if (version >= 0 &&
      sqlite3_prepare_v2(db, "SELECT count(*), count(CASE WHEN type = 'table' AND name IN ('session', 'meta') THEN 1 END) "
                             "FROM sqlite_master",
                         -1, &st, NULL) == SQLITE_OK) {
    if (sqlite3_step(st) == SQLITE_ROW) any = sqlite3_column_int(st, 0), tables = sqlite3_column_int(st, 1);
    sqlite3_finalize(st);
  }
  const int primary = probe & 0xff;
  if (version > palp_db_migration_count) {
    palp_db__fmt(err, errlen, "%s: database schema version %d is newer than this palp (%d); upgrade palp", path,
                 version, palp_db_migration_count);
    rc = PALP_DB_ENEWER;
  } else if (have_version && version < 0) {
    /* an SQLite file read whole, whose header says a version no palp writes (it was "not an SQLite
     * database: not an error" until session 81) */
    palp_db__fmt(err, errlen, "%s: not a palp session log (an SQLite database whose schema version is %d, which no "
                 "palp writes; left untouched)", path, version);
    rc = PALP_EINVAL;
  } else if (version < 0 && probe != SQLITE_OK && primary != SQLITE_NOTADB && primary != SQLITE_CORRUPT) {
    /* the file may well be a log: SQLite could not read it (locked past the timeout, no -shm to be made beside a
     * -wal in a read-only directory, an I/O error) */
    palp_db__fmt(err, errlen, "%s: cannot read it: %s", path, sqlite3_errmsg(db));
    rc = PALP_EIO;
  } else if (version < 0) {
    palp_db__fmt(err, errlen, "%s: not a palp session log (not an SQLite database: %s)", path, sqlite3_errmsg(db));
    rc = PALP_EINVAL;
  } else if (version == 0 && any == 0) {
    palp_db__fmt(err, errlen, "%s: not a palp session log (an empty database or file; left untouched)", path);
    rc = PALP_EINVAL;
  } else if (tables < 2) {
    palp_db__fmt(err, errlen, "%s: not a palp session log (no palp schema; left untouched)", path);
    rc = PALP_EINVAL;
  }
  if (rc == 0 && out) *out = db;
  else close_ro(db, path, *wal_before);
  if (rc == 0 && version_out) *version_out = version;
  return rc;
}

int palp_db_open(const char *path, int create, palp_db **out, char *err, size_t errlen) {
  if (!out) return PALP_EINVAL;
  *out = NULL;
  if (!create && path && *path) {
    int rc = check_palp_file(path, NULL, NULL, NULL, NULL, NULL, err, errlen);
    if (rc) return rc;
  }
  palp_db *d = calloc(1, sizeof *d);
  if (!d) return PALP_ENOMEM;
  int rc = palp_db__connect(path, create, NULL, &d->db, err, errlen);
  if (rc) {
    free(d);
    return rc;
  }
  *out = d;
  return 0;
}

int palp_db_peek_version(const char *path, int *version, char *err, size_t errlen) {
  if (!path || !*path || !version) return PALP_EINVAL;
  return check_palp_file(path, NULL, version, NULL, NULL, NULL, err, errlen);
}

/* The file and its -wal: what the disk holds for this log, and what an in-memory copy of it
 * would hold at most. */
long long palp_db_file_bytes(const char *path) {
  struct stat st;
  long long n = 0;
  if (!path) return 0;
  if (stat(path, &st) == 0) n += st.st_size;
  char wal[4200];
  snprintf(wal, sizeof wal, "%s-wal", path);
  if (stat(wal, &st) == 0) n += st.st_size;
  return n;
}

/* The read-only file connection fh copied into a new in-memory database, which is then upgraded to
 * the current schema: the readers' queries are written for it (later columns, tables), and the file
 * itself must not be changed by reading it. */
static int upgraded_copy(sqlite3 *fh, const char *path, sqlite3 **out, char *err, size_t errlen) {
  *out = NULL;
  sqlite3 *mem = NULL;
  if (sqlite3_open_v2(":memory:", &mem, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, NULL) !=
      SQLITE_OK) {
    sqlite3_close(mem);
    palp_db__fmt(err, errlen, "%s: no memory for a copy of the log", path);
    return PALP_ENOMEM;
  }
  sqlite3_extended_result_codes(mem, 1);
  /* The backup refuses an in-memory destination whose page size differs from the source's. */
  int page = 0;
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(fh, "PRAGMA page_size", -1, &st, NULL) == SQLITE_OK) {
    if (sqlite3_step(st) == SQLITE_ROW) page = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
  }
  char sql[64];
  snprintf(sql, sizeof sql, "PRAGMA page_size = %d", page > 0 ? page : 4096);
  sqlite3_exec(mem, sql, NULL, NULL, NULL);
  sqlite3_backup *b = sqlite3_backup_init(mem, "main", fh, "main");
  int rc = b ? sqlite3_backup_step(b, -1) : sqlite3_errcode(mem);
  const int fin = b ? sqlite3_backup_finish(b) : rc;
  if (rc != SQLITE_DONE || fin != SQLITE_OK) {
    palp_db__fmt(err, errlen, "%s: copying the log into memory failed: %s", path,
                 sqlite3_errstr(rc != SQLITE_DONE ? rc : fin));
    sqlite3_close(mem);
    return rc == SQLITE_NOMEM ? PALP_ENOMEM : PALP_DB_ESQL;
  }
  if ((rc = palp_db__migrate(mem, path, NULL, err, errlen)) != 0) {
    sqlite3_close(mem);
    return rc;
  }
  /* as the file's connection refuses writes, so does its copy: a write to it would vanish at close */
  sqlite3_exec(mem, "PRAGMA foreign_keys=ON; PRAGMA query_only=1", NULL, NULL, NULL);
  *out = mem;
  return 0;
}

int palp_db_open_readonly(const char *path, long long copy_max_bytes, palp_db **out, char *err, size_t errlen) {
  if (!out) return PALP_EINVAL;
  *out = NULL;
  if (!path || !*path) {
    palp_db__fmt(err, errlen, "no database path given");
    return PALP_EINVAL;
  }
  sqlite3 *fh = NULL;
  int version = 0, unlocked = 0, wal_before = 0;
  file_id before;
  int rc = check_palp_file(path, &fh, &version, &unlocked, &before, &wal_before, err, errlen);
  if (rc) return rc;
  palp_db *d = calloc(1, sizeof *d);
  if (!d) {
    close_ro(fh, path, wal_before);
    return PALP_ENOMEM;
  }
  if (version == palp_db_migration_count && !unlocked) {
    /* read in place: palp_db_close tidies after it */
    if (!(d->ro_path = strdup(path))) {
      close_ro(fh, path, wal_before);
      free(d);
      return PALP_ENOMEM;
    }
    d->db = fh;
    d->wal_before = wal_before;
    *out = d;
    return 0;
  }
  /* An older schema is read through an upgraded copy; a file opened immutable (no locks) is copied at
   * once, whatever its schema (2026-12-06, found by review: it was read in place for the whole command,
   * and a writer opening the file meanwhile could checkpoint into it under the reads: rows of two
   * states, or pages SQLite takes for corrupt). */
  const long long bytes = palp_db_file_bytes(path);
  if (bytes > copy_max_bytes) {
    if (unlocked)
      palp_db__fmt(err, errlen,
                   "%s: there is no -wal beside it and this user cannot write the file or its directory, so "
                   "SQLite cannot read it with its locks; it is read from a copy in memory taken at once, and its "
                   "%.1f MB are more than the %.1f MB allowed (PALP_REVIEW_COPY_MB): raise PALP_REVIEW_COPY_MB, or "
                   "read a copy of the file that this user may write, in a directory it may write",
                   path, (double)bytes / 1048576.0, (double)(copy_max_bytes > 0 ? copy_max_bytes : 0) / 1048576.0);
    else
      palp_db__fmt(err, errlen,
                   "%s: its schema version %d is older than this palp's (%d), and reading it unchanged needs a copy "
                   "in memory of its %.1f MB, more than the %.1f MB allowed (PALP_REVIEW_COPY_MB); upgrade the file "
                   "itself with `palp-review --db %s migrate` (it writes to the file: work on a copy to keep the "
                   "original) and read it again",
                   path, version, palp_db_migration_count, (double)bytes / 1048576.0,
                   (double)(copy_max_bytes > 0 ? copy_max_bytes : 0) / 1048576.0, path);
    close_ro(fh, path, wal_before);
    free(d);
    return unlocked ? PALP_DB_ECOPY : PALP_DB_EOLDER;
  }
  rc = upgraded_copy(fh, path, &d->db, err, errlen);
  close_ro(fh, path, wal_before);
  file_id after;
  if (!rc && unlocked && (file_id_of(path, &after) != 0 || !file_id_same(&before, &after))) {
    /* a writer opened it while it was copied: the copy may hold pages of two states */
    palp_db__fmt(err, errlen,
                 "%s: changed while it was copied to be read without locks (a writer has opened it since): read it "
                 "again",
                 path);
    sqlite3_close(d->db);
    rc = PALP_EIO;
  }
  if (rc) {
    free(d);
    return rc;
  }
  d->copied_from = version < palp_db_migration_count ? version : 0;
  d->unlocked = unlocked;
  *out = d;
  return 0;
}

int palp_db_copied_from_version(palp_db *db) { return db ? db->copied_from : 0; }
int palp_db_copied_unlocked(palp_db *db) { return db ? db->unlocked : 0; }

void palp_db_close(palp_db *db) {
  if (!db) return;
  sqlite3_close(db->db);
  if (db->ro_path) tidy_wal(db->ro_path, db->wal_before);
  free(db->ro_path);
  free(db);
}

struct sqlite3 *palp_db_handle(palp_db *db) { return db->db; }
const char *palp_db_errmsg(palp_db *db) { return sqlite3_errmsg(db->db); }
const char *palp_db_error_text(int code) { return sqlite3_errstr(code); }

int palp_db_file_version(palp_db *db) {
  sqlite3_stmt *st;
  int v = -1;
  if (sqlite3_prepare_v2(db->db, "PRAGMA user_version", -1, &st, NULL) != SQLITE_OK) return -1;
  if (sqlite3_step(st) == SQLITE_ROW) v = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  return v;
}

/* A session's names from the file, as every tool prints them: control characters (an escape sequence
 * in a trainee's name retitles or clears an instructor's terminal) read as '?', the C1 ones (U+0080 to
 * U+009F in UTF-8, 0xC2 0x80..0x9F: CSI and OSC among them, which act as ESC [ and ESC ] do) as "??"
 * since session 90 (found by review: "car\u009b2J" cleared the screen of `palp-review show`). palp's
 * writers never log one; a file made or edited elsewhere may. */
static void col_str(sqlite3_stmt *st, int i, char *dst, size_t len) {
  const unsigned char *s = sqlite3_column_text(st, i);
  palp_db__fmt(dst, len, "%s", s ? (const char *)s : "");
  for (unsigned char *p = (unsigned char *)dst; *p; p++)
    if (*p < 0x20 || *p == 0x7f) *p = '?';
    else if (p[0] == 0xC2 && p[1] >= 0x80 && p[1] <= 0x9F) p[0] = p[1] = '?', p++;
}

#define SESSION_COLS                                                                                \
  "s.id, s.uid, s.trainee, s.station, s.phantom_id, s.phantom_name, s.tick_hz, s.dt_s, "           \
  "s.start_unix_s, s.end_unix_s, s.end_reason, s.end_detail, s.records_shed, s.records_failed, "   \
  "(SELECT count(*) FROM frame f WHERE f.session_id = s.id), "                                      \
  "(SELECT count(*) FROM contact_input c WHERE c.session_id = s.id), "                              \
  "(SELECT count(*) FROM mesh m WHERE m.session_id = s.id), "                                       \
  "(SELECT count(*) FROM event e WHERE e.session_id = s.id), "                                      \
  "(SELECT count(*) FROM note n WHERE n.session_id = s.id), "                                       \
  "(SELECT sim_time_s FROM frame f WHERE f.session_id = s.id ORDER BY frame DESC LIMIT 1), s.pruned_unix_s "

static void read_info(sqlite3_stmt *st, palp_db_session_info *o) {
  memset(o, 0, sizeof *o);
  o->id = sqlite3_column_int64(st, 0);
  col_str(st, 1, o->uid, sizeof o->uid);
  col_str(st, 2, o->trainee, sizeof o->trainee);
  col_str(st, 3, o->station, sizeof o->station);
  col_str(st, 4, o->phantom_id, sizeof o->phantom_id);
  col_str(st, 5, o->phantom_name, sizeof o->phantom_name);
  o->tick_hz = sqlite3_column_double(st, 6);
  o->dt_s = sqlite3_column_double(st, 7);
  o->start_unix_s = sqlite3_column_double(st, 8);
  o->end_unix_s = sqlite3_column_double(st, 9);
  col_str(st, 10, o->end_reason, sizeof o->end_reason);
  col_str(st, 11, o->end_detail, sizeof o->end_detail);
  o->records_shed = sqlite3_column_int64(st, 12);
  o->records_failed = sqlite3_column_int64(st, 13);
  o->frames = sqlite3_column_int64(st, 14);
  o->contact_inputs = sqlite3_column_int64(st, 15);
  o->meshes = sqlite3_column_int64(st, 16);
  o->events = sqlite3_column_int64(st, 17);
  o->notes = sqlite3_column_int64(st, 18);
  o->sim_duration_s = sqlite3_column_double(st, 19);
  /* any stamp, even one <= 0 or NaN from an edited file, says pruned: 1 s after 1970 stands for it */
  if (sqlite3_column_type(st, 20) != SQLITE_NULL) {
    o->pruned_unix_s = sqlite3_column_double(st, 20);
    if (!(o->pruned_unix_s > 0)) o->pruned_unix_s = 1;
  }
}

/* One growth rule for the lists read row by row: the room doubled (`first` rows at first).
 * NULL when out of memory, v and *cap then unchanged so that the caller frees what it holds. */
static void *grow_rows(void *v, int *cap, int first, size_t elem) {
  const int ncap = *cap ? 2 * *cap : first;
  void *nv = realloc(v, (size_t)ncap * elem);
  if (nv) *cap = ncap;
  return nv;
}

int palp_db_list_sessions(palp_db *db, const palp_db_filter *f, palp_db_session_info **out, int *count) {
  *out = NULL;
  *count = 0;
  sqlite3_stmt *st;
  const char *sql = "SELECT " SESSION_COLS "FROM session s WHERE "
                    "(?1 IS NULL OR s.trainee = ?1) AND "
                    "(?2 IS NULL OR s.phantom_id = ?2 OR s.phantom_name = ?2) AND "
                    "(?3 IS NULL OR s.start_unix_s >= ?3) AND (?4 IS NULL OR s.start_unix_s < ?4) "
                    "ORDER BY s.start_unix_s, s.id";
  if (sqlite3_prepare_v2(db->db, sql, -1, &st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  if (f && f->trainee) sqlite3_bind_text(st, 1, f->trainee, -1, SQLITE_STATIC);
  if (f && f->phantom) sqlite3_bind_text(st, 2, f->phantom, -1, SQLITE_STATIC);
  /* a bound that is not a number would bind as NULL, no bound: none matches instead */
  if (f && f->has_since) sqlite3_bind_double(st, 3, isnan(f->since_unix_s) ? INFINITY : f->since_unix_s);
  if (f && f->has_until) sqlite3_bind_double(st, 4, isnan(f->until_unix_s) ? -INFINITY : f->until_unix_s);
  int cap = 0, n = 0, rc;
  palp_db_session_info *v = NULL;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    if (n == cap) {
      palp_db_session_info *nv = grow_rows(v, &cap, 16, sizeof *v);
      if (!nv) {
        free(v);
        sqlite3_finalize(st);
        return PALP_ENOMEM;
      }
      v = nv;
    }
    read_info(st, &v[n++]);
  }
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) {
    free(v);
    return PALP_DB_ESQL;
  }
  *out = v;
  *count = n;
  return 0;
}

int palp_db_list_refused(palp_db *db, const palp_db_filter *f, palp_db_refused **out, int *count) {
  *out = NULL;
  *count = 0;
  sqlite3_stmt *st;
  const char *sql = "SELECT detail, SUM(count), MIN(wall_unix_s), MAX(wall_unix_s) FROM event "
                    "WHERE session_id IS NULL AND kind = ?1 AND "
                    "(?2 IS NULL OR wall_unix_s >= ?2) AND (?3 IS NULL OR wall_unix_s < ?3) "
                    "GROUP BY detail ORDER BY SUM(count) DESC, detail";
  if (sqlite3_prepare_v2(db->db, sql, -1, &st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  sqlite3_bind_text(st, 1, palp_db_event_kind_name(PALP_DB_EVENT_SECURITY_REFUSED), -1, SQLITE_STATIC);
  if (f && f->has_since) sqlite3_bind_double(st, 2, isnan(f->since_unix_s) ? INFINITY : f->since_unix_s);
  if (f && f->has_until) sqlite3_bind_double(st, 3, isnan(f->until_unix_s) ? -INFINITY : f->until_unix_s);
  int cap = 0, n = 0, rc;
  palp_db_refused *v = NULL;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    if (n == cap) {
      palp_db_refused *nv = grow_rows(v, &cap, 8, sizeof *v);
      if (!nv) {
        free(v);
        sqlite3_finalize(st);
        return PALP_ENOMEM;
      }
      v = nv;
    }
    col_str(st, 0, v[n].detail, sizeof v[n].detail); /* list prints it: no escape sequence (session 81) */
    v[n].count = sqlite3_column_int64(st, 1);
    v[n].first_unix_s = sqlite3_column_double(st, 2);
    v[n].last_unix_s = sqlite3_column_double(st, 3);
    n++;
  }
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) {
    free(v);
    return PALP_DB_ESQL;
  }
  *out = v;
  *count = n;
  return 0;
}

/* A session whose uid starts with ?1: compared with substr, not LIKE (whose wildcards the
 * argument would need escaped from). One clause for find_session and the candidates. */
#define UID_PREFIX_WHERE "substr(s.uid, 1, length(?1)) = ?1"

/* One row of sql (uid bound as ?1) into *out: 0, PALP_DB_ENOTFOUND, PALP_DB_EAMBIGUOUS (a second row),
 * PALP_DB_ESQL. */
static int find_one(palp_db *db, const char *sql, const char *uid, palp_db_session_info *out) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(db->db, sql, -1, &st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  sqlite3_bind_text(st, 1, uid, -1, SQLITE_STATIC);
  int rc = sqlite3_step(st);
  if (rc != SQLITE_ROW) {
    sqlite3_finalize(st);
    return rc == SQLITE_DONE ? PALP_DB_ENOTFOUND : PALP_DB_ESQL;
  }
  read_info(st, out);
  rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_ROW ? PALP_DB_EAMBIGUOUS : rc == SQLITE_DONE ? 0 : PALP_DB_ESQL;
}

int palp_db_find_session(palp_db *db, const char *uid, palp_db_session_info *out) {
  if (!uid || !*uid) return PALP_EINVAL;
  /* An exact uid wins; otherwise a unique prefix (uids are long: "<run uuid>-<n>"). The exact one is
   * asked alone, through the uid index: asked together (UNION ALL), the prefix's scan of every uid ran
   * too, and a delete of 5,000 sessions by uid on a 10,000-session log took 97 s resolving the names. */
  int rc = find_one(db, "SELECT " SESSION_COLS "FROM session s WHERE s.uid = ?1", uid, out);
  if (rc != PALP_DB_ENOTFOUND) return rc;
  return find_one(db, "SELECT " SESSION_COLS "FROM session s WHERE " UID_PREFIX_WHERE " LIMIT 2", uid, out);
}

int palp_db_find_session_uid(palp_db *db, const char *uid, palp_db_session_info *out) {
  if (!uid || !*uid) return PALP_EINVAL;
  return find_one(db, "SELECT " SESSION_COLS "FROM session s WHERE s.uid = ?1", uid, out);
}

int palp_db_session_candidates(palp_db *db, const char *arg, int by_number, palp_db_session_info *out, int max,
                               int *total) {
  if (!db || !arg || !*arg || max < 0 || (max > 0 && !out) || !total) return PALP_EINVAL;
  *total = 0;
  if (by_number) { /* "3": a whole number of at most 9 digits, nothing else */
    size_t n = strlen(arg);
    if (n > 9 || strspn(arg, "0123456789") != n) return 0;
  }
  /* The uid's tail after its last '-' is the station's session number (substr, as the prefix);
   * palp-recorder's uids, "dds-PHANTOM-SESSION-START_MS", have it between their last two. */
  const char *where = by_number ? "((substr(s.uid, 1, 4) <> 'dds-' AND substr(s.uid, length(s.uid) - length(?1)) = '-' || ?1)"
                                  " OR (substr(s.uid, 1, 4) = 'dds-' AND instr(substr(s.uid, 5), '-' || ?1 || '-') > 0))"
                                : UID_PREFIX_WHERE;
  char sql[1024];
  snprintf(sql, sizeof sql, "SELECT count(*) FROM session s WHERE %s", where);
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(db->db, sql, -1, &st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  sqlite3_bind_text(st, 1, arg, -1, SQLITE_STATIC);
  int rc = sqlite3_step(st);
  if (rc == SQLITE_ROW) *total = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  if (rc != SQLITE_ROW) return PALP_DB_ESQL;
  if (max == 0 || *total == 0) return 0;
  snprintf(sql, sizeof sql, "SELECT " SESSION_COLS "FROM session s WHERE %s ORDER BY s.start_unix_s DESC, s.id DESC "
           "LIMIT ?2", where);
  if (sqlite3_prepare_v2(db->db, sql, -1, &st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  sqlite3_bind_text(st, 1, arg, -1, SQLITE_STATIC);
  sqlite3_bind_int(st, 2, max);
  int n = 0;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW && n < max) read_info(st, &out[n++]);
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE && rc != SQLITE_ROW) return PALP_DB_ESQL;
  if (n < *total && n < max) *total = n; /* rows gone between the two reads */
  return 0;
}

static char *dup_col(sqlite3_stmt *st, int i) {
  const unsigned char *s = sqlite3_column_text(st, i);
  size_t n = s ? strlen((const char *)s) : 0;
  char *d = malloc(n + 1);
  if (d) {
    if (n) memcpy(d, s, n);
    d[n] = '\0';
  }
  return d;
}

int palp_db_session_json(palp_db *db, int64_t session_id, char **scene_json, char **params_json) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(db->db, "SELECT scene_json, params_json FROM session WHERE id = ?1", -1, &st,
                         NULL) != SQLITE_OK)
    return PALP_DB_ESQL;
  sqlite3_bind_int64(st, 1, session_id);
  int rc = sqlite3_step(st);
  if (rc != SQLITE_ROW) {
    sqlite3_finalize(st);
    return rc == SQLITE_DONE ? PALP_DB_ENOTFOUND : PALP_DB_ESQL;
  }
  if (scene_json) *scene_json = dup_col(st, 0);
  if (params_json) *params_json = dup_col(st, 1);
  sqlite3_finalize(st);
  return 0;
}

static int prep(palp_db *db, const char *sql, int64_t sid, sqlite3_stmt **st) {
  if (sqlite3_prepare_v2(db->db, sql, -1, st, NULL) != SQLITE_OK) return PALP_DB_ESQL;
  sqlite3_bind_int64(*st, 1, sid);
  return 0;
}

static int finish(sqlite3_stmt *st, int rc, int stopped) {
  sqlite3_finalize(st);
  if (stopped) return stopped;
  return rc == SQLITE_DONE ? 0 : PALP_DB_ESQL;
}

static palp_vec3 col_vec(sqlite3_stmt *st, int i) {
  palp_vec3 v = {sqlite3_column_double(st, i), sqlite3_column_double(st, i + 1),
                 sqlite3_column_double(st, i + 2)};
  return v;
}

int palp_db_each_contact(palp_db *db, int64_t sid, palp_db_contact_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT frame, sim_time_s, slot, op, kind, distribution, center_x_m, center_y_m, center_z_m, "
           "force_x_n, force_y_n, force_z_n, radius_m, patch_area_m2, sigma_fraction, offset_fraction, "
           "offset_dir_x, offset_dir_y, offset_dir_z FROM contact_input WHERE session_id = ?1 ORDER BY id",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    palp_db_contact c;
    memset(&c, 0, sizeof c);
    c.frame = sqlite3_column_int64(st, 0);
    c.sim_time_s = sqlite3_column_double(st, 1);
    c.slot = sqlite3_column_int(st, 2);
    /* NULL in a file made elsewhere (no NOT NULL there): read as an unknown value, as any other */
    const char *op = (const char *)sqlite3_column_text(st, 3);
    const char *kind = (const char *)sqlite3_column_text(st, 4);
    if (!op) op = "";
    if (!kind) kind = "";
    c.op = !strcmp(op, "add") ? PALP_DB_OP_ADD : !strcmp(op, "update") ? PALP_DB_OP_UPDATE : PALP_DB_OP_REMOVE;
    c.kind = !strcmp(kind, "force") ? PALP_DB_KIND_FORCE : PALP_DB_KIND_FINGER;
    c.def.distribution = (palp_distribution)sqlite3_column_int(st, 5);
    c.center_m = col_vec(st, 6);
    c.def.center = c.center_m;
    c.force_n = col_vec(st, 9);
    c.radius_m = sqlite3_column_double(st, 12);
    c.def.patch_area = sqlite3_column_double(st, 13);
    c.def.sigma_fraction = sqlite3_column_double(st, 14);
    c.def.offset_fraction = sqlite3_column_double(st, 15);
    c.def.offset_dir = col_vec(st, 16);
    stop = fn(user, &c);
  }
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_each_frame(palp_db *db, int64_t sid, palp_db_frame_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT frame, sim_time_s, top_disp_m, max_disp_m, volume_m3, pressure_pa, contact_force_n, "
           "state_hash FROM frame WHERE session_id = ?1 ORDER BY frame",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    palp_db_frame f;
    f.frame = sqlite3_column_int64(st, 0);
    f.sim_time_s = sqlite3_column_double(st, 1);
    f.top_disp_m = sqlite3_column_double(st, 2);
    f.max_disp_m = sqlite3_column_double(st, 3);
    f.volume_m3 = sqlite3_column_double(st, 4);
    f.pressure_pa = sqlite3_column_double(st, 5);
    f.contact_force_n = sqlite3_column_double(st, 6);
    int64_t h = sqlite3_column_int64(st, 7);
    memcpy(&f.state_hash, &h, sizeof h);
    stop = fn(user, &f);
  }
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_each_feedback(palp_db *db, int64_t sid, palp_db_feedback_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT frame, slot, force_x_n, force_y_n, force_z_n FROM feedback WHERE session_id = ?1 "
           "ORDER BY frame, slot",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW)
    stop = fn(user, sqlite3_column_int64(st, 0), sqlite3_column_int(st, 1), col_vec(st, 2));
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_session_exercise(palp_db *db, int64_t session_id, char *name, size_t namelen, char **exercise_json) {
  if (exercise_json) *exercise_json = NULL;
  sqlite3_stmt *st;
  if (prep(db, "SELECT exercise_name, exercise_json FROM session_exercise WHERE session_id = ?1", session_id, &st))
    return PALP_DB_ESQL;
  int rc = sqlite3_step(st);
  if (rc != SQLITE_ROW) {
    sqlite3_finalize(st);
    return rc == SQLITE_DONE ? PALP_DB_ENOTFOUND : PALP_DB_ESQL;
  }
  if (name && namelen) {
    col_str(st, 0, name, namelen); /* printed like the trainee's name: no control character (session 81) */
  }
  if (exercise_json && !(*exercise_json = dup_col(st, 1))) {
    sqlite3_finalize(st);
    return PALP_ENOMEM;
  }
  sqlite3_finalize(st);
  return 0;
}

int palp_db_each_finger_sample(palp_db *db, int64_t sid, palp_db_finger_sample_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT frame, slot, sim_time_s, radius_m, device_x_m, device_y_m, device_z_m, proxy_x_m, proxy_y_m, "
           "proxy_z_m, force_x_n, force_y_n, force_z_n, in_contact, point_x_m, point_y_m, point_z_m, area_m2, "
           "triangles FROM finger_sample WHERE session_id = ?1 ORDER BY frame, slot",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  int32_t tri[PALP_DB_MAX_SAMPLE_TRIANGLES];
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    palp_db_finger_sample fs = {0};
    fs.frame = sqlite3_column_int64(st, 0);
    fs.slot = sqlite3_column_int(st, 1);
    fs.sim_time_s = sqlite3_column_double(st, 2);
    fs.radius_m = sqlite3_column_double(st, 3);
    fs.device_m = col_vec(st, 4);
    fs.proxy_m = col_vec(st, 7);
    fs.force_n = col_vec(st, 10);
    fs.in_contact = sqlite3_column_int(st, 13) != 0;
    fs.point_m = col_vec(st, 14);
    fs.area_m2 = sqlite3_column_double(st, 17);
    /* A blob is checked before use: a whole number of int32, at most the writer's cap. A
     * malformed one reads as "no triangles" (the disc footprint), never past the buffer. */
    const unsigned char *b = sqlite3_column_blob(st, 18);
    const int bytes = sqlite3_column_bytes(st, 18);
    if (b && bytes > 0 && bytes % 4 == 0 && bytes / 4 <= PALP_DB_MAX_SAMPLE_TRIANGLES) {
      fs.triangle_count = bytes / 4;
      for (int i = 0; i < fs.triangle_count; i++)
        tri[i] = (int32_t)((uint32_t)b[4 * i] | (uint32_t)b[4 * i + 1] << 8 | (uint32_t)b[4 * i + 2] << 16 |
                           (uint32_t)b[4 * i + 3] << 24);
      fs.triangles = tri;
    }
    stop = fn(user, &fs);
  }
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_each_finding(palp_db *db, int64_t sid, palp_db_finding_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT mark_id, op, frame, sim_time_s, wall_unix_s, point_x_m, point_y_m, point_z_m FROM finding "
           "WHERE session_id = ?1 ORDER BY id",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    palp_db_finding f = {0};
    f.mark_id = sqlite3_column_int64(st, 0);
    const unsigned char *op = sqlite3_column_text(st, 1);
    f.op = op && !strcmp((const char *)op, "withdraw") ? PALP_DB_FINDING_WITHDRAW : PALP_DB_FINDING_MARK;
    f.frame = sqlite3_column_int64(st, 2);
    f.sim_time_s = sqlite3_column_double(st, 3);
    f.wall_unix_s = sqlite3_column_double(st, 4);
    if (f.op == PALP_DB_FINDING_MARK) f.point_m = col_vec(st, 5);
    stop = fn(user, &f);
  }
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_each_mesh(palp_db *db, int64_t sid, palp_db_mesh_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db, "SELECT frame, vertex_count, positions_m FROM mesh WHERE session_id = ?1 ORDER BY frame",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  palp_vec3 *pos = NULL;
  int cap = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    /* A row is checked before its blob is read: the count in 64 bits (178,956,971 x 24
     * wraps to 8 in 32) and within what a mesh can be. A malformed row is skipped. */
    const int64_t n64 = sqlite3_column_int64(st, 1);
    const unsigned char *b = sqlite3_column_blob(st, 2);
    if (n64 <= 0 || n64 > PALP_DB_MAX_VERTICES || (int64_t)sqlite3_column_bytes(st, 2) != n64 * 24 || !b) continue;
    const int n = (int)n64;
    if (n > cap) {
      palp_vec3 *np = realloc(pos, (size_t)n * sizeof *np);
      if (!np) {
        free(pos);
        sqlite3_finalize(st);
        return PALP_ENOMEM;
      }
      pos = np;
      cap = n;
    }
    for (int i = 0; i < n; i++) {
      double v[3];
      for (int k = 0; k < 3; k++) {
        uint64_t u = 0;
        for (int j = 0; j < 8; j++) u |= (uint64_t)b[(size_t)(i * 3 + k) * 8 + (size_t)j] << (8 * j);
        memcpy(&v[k], &u, 8);
      }
      pos[i].x = v[0];
      pos[i].y = v[1];
      pos[i].z = v[2];
    }
    stop = fn(user, sqlite3_column_int64(st, 0), pos, n);
  }
  free(pos);
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_each_event(palp_db *db, int64_t sid, palp_db_event_fn fn, void *user) {
  sqlite3_stmt *st;
  if (prep(db,
           "SELECT wall_unix_s, coalesce(frame, -1), kind, detail, count FROM event "
           "WHERE session_id = ?1 ORDER BY id",
           sid, &st))
    return PALP_DB_ESQL;
  int rc = SQLITE_DONE, stop = 0;
  while (!stop && (rc = sqlite3_step(st)) == SQLITE_ROW) {
    /* a NULL kind (a file made elsewhere, without NOT NULL) reads as an empty, unknown kind */
    const char *kind = (const char *)sqlite3_column_text(st, 2);
    stop = fn(user, sqlite3_column_double(st, 0), sqlite3_column_int64(st, 1), kind ? kind : "",
              (const char *)sqlite3_column_text(st, 3), sqlite3_column_int64(st, 4));
  }
  return finish(st, stop ? SQLITE_DONE : rc, stop);
}

int palp_db_add_note(palp_db *db, int64_t sid, const char *author, const char *text, const char *grade) {
  if (!author || !*author || !text) return PALP_EINVAL;
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(db->db,
                         "INSERT INTO note(session_id, author, wall_unix_s, text, grade) "
                         "VALUES(?1,?2,?3,?4,?5)",
                         -1, &st, NULL) != SQLITE_OK)
    return PALP_DB_ESQL;
  sqlite3_bind_int64(st, 1, sid);
  sqlite3_bind_text(st, 2, author, -1, SQLITE_STATIC);
  sqlite3_bind_double(st, 3, palp_db__now());
  sqlite3_bind_text(st, 4, text, -1, SQLITE_STATIC);
  if (grade) sqlite3_bind_text(st, 5, grade, -1, SQLITE_STATIC);
  int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? 0 : PALP_DB_ESQL;
}

int palp_db_log_health_get(palp_db *db, const palp_db_session_info *s, palp_db_log_health *h) {
  memset(h, 0, sizeof *h);
  h->ended = s->end_reason[0] != '\0';
  h->records_shed = s->records_shed;
  h->records_failed = s->records_failed;
  sqlite3_stmt *st;
  if (prep(db, "SELECT count(*), min(frame), max(frame), "
               "(SELECT sim_time_s FROM frame WHERE session_id = ?1 ORDER BY frame DESC LIMIT 1), "
               "(SELECT max(wall_unix_s) FROM event WHERE session_id = ?1) FROM frame WHERE session_id = ?1",
           s->id, &st))
    return PALP_DB_ESQL;
  /* An aggregate always gives its row: anything else is a read that failed (a damaged page under the
   * frame or event table), which must not read as an empty, complete session (2026-12-06). */
  if (sqlite3_step(st) != SQLITE_ROW) return finish(st, SQLITE_ERROR, 0);
  h->frames = sqlite3_column_int64(st, 0);
  h->first_frame = sqlite3_column_int64(st, 1);
  h->last_frame = sqlite3_column_int64(st, 2);
  h->last_sim_time_s = sqlite3_column_double(st, 3);
  h->last_event_unix_s = sqlite3_column_double(st, 4);
  sqlite3_finalize(st);
  /* The writer logs every k-th frame (k = tick rate / 100): k is the commonest gap. */
  h->frame_step = 1;
  if (h->frames > 1) {
    if (prep(db, "SELECT g FROM (SELECT frame - lag(frame) OVER (ORDER BY frame) AS g FROM frame WHERE session_id = ?1) "
                 "WHERE g > 0 GROUP BY g ORDER BY count(*) DESC, g LIMIT 1",
             s->id, &st))
      return PALP_DB_ESQL;
    const int rc = sqlite3_step(st);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) return finish(st, rc, 0);
    if (rc == SQLITE_ROW) h->frame_step = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    if (h->frame_step < 1) h->frame_step = 1;
  }
  if (h->frames > 0) {
    /* frame numbers from the file: a span past int64 (a damaged or forged row) would overflow */
    const double span = (double)h->last_frame - (double)h->first_frame;
    h->frames_expected = span >= 0 && span < 9e18 ? (h->last_frame - h->first_frame) / h->frame_step + 1 : h->frames;
    h->frames_missing = h->frames_expected > h->frames ? h->frames_expected - h->frames : 0;
  }
  h->cut_short = !h->ended;
  h->damaged = h->records_shed > 0 || h->records_failed > 0 || h->frames_missing > 0;
  h->pruned = s->pruned_unix_s > 0;
  h->complete = !h->cut_short && !h->damaged && !h->pruned;
  return 0;
}

void palp_db_log_health_describe(const palp_db_log_health *h, char *buf, size_t len) {
  char a[256] = "", b[256] = "";
  if (h->cut_short)
    palp_db__fmt(a, sizeof a, "CUT SHORT: no end was logged (the server was killed, or is still writing); the data "
                 "ends at frame %lld, t = %.3f s", (long long)h->last_frame, h->last_sim_time_s);
  if (h->damaged)
    palp_db__fmt(b, sizeof b, "DAMAGED: %lld records shed (queue full), %lld lost to disk errors, %lld of %lld "
                 "frames missing (%.1f%%)", (long long)h->records_shed, (long long)h->records_failed,
                 (long long)h->frames_missing, (long long)h->frames_expected,
                 h->frames_expected ? 100.0 * (double)h->frames_missing / (double)h->frames_expected : 0.0);
  if (h->complete)
    palp_db__fmt(buf, len, "complete: an end was logged; %lld of %lld frames present, no records shed or lost",
                 (long long)h->frames, (long long)h->frames_expected);
  else if (h->pruned)
    palp_db__fmt(buf, len, "PRUNED: its frames, inputs, meshes and finger samples were deleted (palp-review prune); "
                 "whether the log was whole before cannot be judged now%s%s", b[0] ? "; " : "", b);
  else
    palp_db__fmt(buf, len, "%s%s%s", a, a[0] && b[0] ? "; " : "", b);
}
