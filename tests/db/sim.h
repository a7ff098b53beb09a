/* A scripted palpation session driven through the session-log writer exactly as the server does
 * (the replay contract in db/palp_db.h, through the palp_db_world_* logged calls): a real
 * palp_world at the tick rate, a force contact
 * ramped by a trainee, a sliding finger updated every tick, feedback, meshes at ~30 Hz, events. */
#ifndef PALP_TEST_DB_SIM_H
#define PALP_TEST_DB_SIM_H
#include <stdint.h>

#include "palp_db.h"

typedef struct sim_opts {
  const char *db;
  const char *uid;
  const char *scene_path;
  double seconds;  /* simulated length [s] */
  double tick_hz;  /* [Hz] */
  int realtime;    /* pace the ticks on the wall clock (absolute sleeps) */
  int progress;    /* print "frames N" to stdout every 10 frames (for the crash test) */
  int64_t max_db_bytes;
  int keep;        /* keep what was sent in the result (for comparisons) */
} sim_opts;

typedef struct sim_sent_fb {
  int64_t frame;
  int slot;
  palp_vec3 f;
} sim_sent_fb;

typedef struct sim_result {
  int64_t frames_stepped;   /* palp_world_step calls that returned 0 */
  int64_t frames_logged;    /* frames the writer accepted (stepped - shed frame records) */
  int64_t records_refused;  /* direct log calls (feedback, mesh, events) that returned PALP_EFULL */
  int64_t log_errors;       /* direct log calls that returned anything but 0 or PALP_EFULL */
  int meshes, events;
  palp_db_writer_stats st;  /* after close-time flush */
  /* with keep: everything sent, in order */
  palp_db_frame *frames;
  int nframes;
  palp_db_contact *contacts;
  int ncontacts;
  sim_sent_fb *fb;
  int nfb;
} sim_result;

/* Returns 0, or a negative code with a message on stderr. */
int sim_run(const sim_opts *o, sim_result *r);
void sim_result_free(sim_result *r);
#endif
