/*
 * db_log.h - palp-server's session log: the server events (events.h) written
 * to SQLite through the db/ writer (palp_db_log_*), following the replay
 * contract of db/palp_db.h so `palp-review replay` reproduces a session bit for
 * bit. The tick-thread hooks only enqueue (the writer's worker thread does the
 * disk work); a full queue sheds records and counts them, never stalls a tick.
 */
#ifndef PALP_SRV_DB_LOG_H
#define PALP_SRV_DB_LOG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "events.h"
#include "palp_log.h"

typedef struct palp_srv_db_log palp_srv_db_log;

/* Opens (creating or upgrading) the database at path, its file capped at max_bytes (0: no cap;
 * config session_log_max_mb). Each session's own physics rate sets its logging cadence: frame
 * summaries and feedback at <= ~100 per second, meshes ~twice a second while the phantom moves.
 * Records lost to a full disk or the cap are said in log as they happen (palp_srv_events.log_counts,
 * every status period). */
int palp_srv_db_log_open(const char *path, int64_t max_bytes, palp_log *log, palp_srv_db_log **out, char *err,
                         size_t errlen);
const palp_srv_events *palp_srv_db_log_events(palp_srv_db_log *l);
/* Flushes and closes; logs the writer's counts (written, shed, failed). */
void palp_srv_db_log_close(palp_srv_db_log *l);

#endif
