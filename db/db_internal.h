/* Shared between the palp_db modules; not installed. */
#ifndef PALP_DB_INTERNAL_H
#define PALP_DB_INTERNAL_H

#include <sqlite3.h>
#include <stdarg.h>
#include <stddef.h>

#define PALP_DB_BUSY_TIMEOUT_MS 5000

/* Opens a connection, sets WAL and busy_timeout, creates or upgrades the schema.
 * create = 0 refuses a missing file. Returns 0 or a negative code with a message in err. */
int palp_db__connect(const char *path, int create, const char *app_version, sqlite3 **out,
                     char *err, size_t errlen);
/* Brings db's schema up to the current version in one transaction (no-op when current); refuses a
 * newer one. path names the file in messages only: palp_db_open_readonly migrates an in-memory copy. */
int palp_db__migrate(sqlite3 *db, const char *path, const char *app_version, char *err, size_t errlen);
double palp_db__now(void); /* wall time [s since 1970 UTC] */
void palp_db__fmt(char *buf, size_t len, const char *fmt, ...);
#endif
