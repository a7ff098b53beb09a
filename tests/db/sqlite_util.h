/* sqlite_util.h - SQLite helpers shared by the db tests. */
#ifndef PALP_TEST_DB_SQLITE_UTIL_H
#define PALP_TEST_DB_SQLITE_UTIL_H
#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <unistd.h>

/* First column of the first row of `sql`; -1 when there is no row, -2 when it does
 * not prepare. */
static inline int64_t db_scalar(sqlite3 *h, const char *sql) {
  sqlite3_stmt *st;
  int64_t v = -1;
  if (sqlite3_prepare_v2(h, sql, -1, &st, NULL) != SQLITE_OK) return -2;
  if (sqlite3_step(st) == SQLITE_ROW) v = sqlite3_column_int64(st, 0);
  sqlite3_finalize(st);
  return v;
}

/* First column of the first row of `sql` as text into buf ("" when there is no row or it does
 * not prepare). */
static inline void db_text(sqlite3 *h, const char *sql, char *buf, size_t n) {
  sqlite3_stmt *st;
  buf[0] = 0;
  if (sqlite3_prepare_v2(h, sql, -1, &st, NULL) != SQLITE_OK) return;
  if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0))
    snprintf(buf, n, "%s", (const char *)sqlite3_column_text(st, 0));
  sqlite3_finalize(st);
}

/* Writes dir/name into buf and removes any database left there by an earlier run,
 * with its WAL and shared-memory files. */
static inline void db_fresh_path(char *buf, size_t n, const char *dir, const char *name) {
  snprintf(buf, n, "%s/%s", dir, name);
  unlink(buf);
  char aux[1100];
  snprintf(aux, sizeof aux, "%s-wal", buf);
  unlink(aux);
  snprintf(aux, sizeof aux, "%s-shm", buf);
  unlink(aux);
}
#endif
