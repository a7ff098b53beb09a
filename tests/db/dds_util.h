/* dds_util.h - what the db tests that play a palp-server over DDS share (test_recorder*.c): a sleep,
 * a wait for a writer's match, the recorder started and stopped, a catalogue entry. */
#ifndef PALP_TEST_DB_DDS_UTIL_H
#define PALP_TEST_DB_DDS_UTIL_H
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "palp.h"
#include "palp_dds.h"

static inline void sleep_ms(int ms) {
  struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
  nanosleep(&ts, NULL);
}

/* 0 once the writer has matched `want` readers, -1 after timeout_s. */
static inline int wait_matched(dds_entity_t w, int want, double timeout_s) {
  for (int i = 0; i < (int)(timeout_s * 100); i++) {
    dds_publication_matched_status_t st;
    if (dds_get_publication_matched_status(w, &st) == 0 && (int)st.current_count >= want) return 0;
    sleep_ms(10);
  }
  return -1;
}

/* Starts palp-recorder `exe` on `domain` into db, logging to logf, for at most 60 s; max_mb: its --max-mb,
 * or NULL. Its pid, or -1 when it cannot fork. */
static inline pid_t start_recorder(const char *exe, const char *db, int domain, const char *logf, const char *max_mb) {
  char dom[16];
  snprintf(dom, sizeof dom, "%d", domain);
  const pid_t pid = fork();
  if (pid == 0) {
    if (max_mb)
      execl(exe, exe, "--db", db, "--domain", dom, "--duration", "60", "--max-mb", max_mb, "--log-file", logf,
            (char *)NULL);
    else
      execl(exe, exe, "--db", db, "--domain", dom, "--duration", "60", "--log-file", logf, (char *)NULL);
    _exit(127);
  }
  return pid;
}

/* Stops the recorder (SIGTERM, as systemd does) and returns 1 when it exited 0. */
static inline int stop_recorder(pid_t pid, int *status) {
  kill(pid, SIGTERM);
  waitpid(pid, status, 0);
  return WIFEXITED(*status) && WEXITSTATUS(*status) == 0;
}

/* A catalogue entry for the default dome: its rest mesh (rest, mesh->vertex_count entries, the
 * caller's) and the paper's membrane and gel parameters. */
static inline palp_Phantom test_phantom(uint32_t id, const char *name, const palp_mesh_def *md, const palp_mesh *mesh,
                                        palp_Vec3 *rest, double tick_rate_hz) {
  palp_Phantom ph;
  memset(&ph, 0, sizeof ph);
  ph.phantom_id = id;
  snprintf(ph.name, sizeof ph.name, "%s", name);
  ph.radius = md->radius;
  ph.tick_rate_hz = tick_rate_hz;
  ph.max_force = 20;
  ph.membrane = (palp_MembraneParams){0.002, 950, 4.2e6, 2e8, 8e6, 8e5};
  ph.gel = (palp_GelParams){0, 101325, 10, 5e6, 0};
  ph.top_vertex = mesh->top_vertex;
  ph.dome_triangle_count = mesh->dome_triangle_count;
  for (int i = 0; i < mesh->vertex_count; i++) rest[i] = (palp_Vec3){mesh->rest[i].x, mesh->rest[i].y, mesh->rest[i].z};
  ph.rest._length = ph.rest._maximum = (uint32_t)mesh->vertex_count;
  ph.rest._buffer = rest;
  return ph;
}
#endif
