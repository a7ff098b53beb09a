/*
 * harness.h - an in-process palp server on a test's own DDS domain, plus small
 * helpers for stations and assertions. Every test uses a domain id of its own so
 * CTest can run them in parallel on the loopback config.
 */
#ifndef PALP_TEST_SERVER_HARNESS_H
#define PALP_TEST_SERVER_HARNESS_H

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

#include "palp_dds.h"
#include "server.h"
#include "station.h"

extern int palp_test_failures;

/* Evaluates cond exactly once; returns through `palp_test_last` for REQUIRE. */
extern int palp_test_last;
#define CHECK(cond, ...)                                                                                     \
  do {                                                                                                       \
    palp_test_last = (cond) ? 1 : 0;                                                                         \
    if (!palp_test_last) {                                                                                   \
      palp_test_failures++;                                                                                  \
      fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                                        \
      fprintf(stderr, __VA_ARGS__);                                                                          \
      fputc('\n', stderr);                                                                                   \
    } else {                                                                                                 \
      fprintf(stderr, "ok   ");                                                                              \
      fprintf(stderr, __VA_ARGS__);                                                                          \
      fputc('\n', stderr);                                                                                   \
    }                                                                                                        \
  } while (0)

#define REQUIRE(cond, ...)                                                                                   \
  do {                                                                                                       \
    CHECK(cond, __VA_ARGS__);                                                                                \
    if (!palp_test_last) exit(1);                                                                            \
  } while (0)

typedef struct test_server {
  palp_srv *srv;
  pthread_t thread;
  int running;
} test_server;

/* Config JSON for the shipped paper scene, hosted as phantoms 1 and 2. */
void test_config(palp_srv_config *cfg, unsigned domain, double tick_rate_hz);
/* Starts palp_srv_run on a thread; exits the test on failure. */
void test_server_start(test_server *ts, const palp_srv_config *cfg);
/* The same with a def of the caller's (events, a log: palp_srv_create copies it). */
void test_server_start_def(test_server *ts, const palp_srv_def *def);
void test_server_stop(test_server *ts);

/* Opens a station and joins; exits the test on failure. */
void test_station_join(palp_cli_station *st, unsigned domain, const char *label, int role, uint32_t phantom,
                       uint32_t session, int want_feedback, int want_deformation);
/* The same with a join of the caller's (role, ids, wants, flags such as local_models_only). */
void test_station_join_as(palp_cli_station *st, unsigned domain, const char *label, const palp_cli_join *j);

/* Sends one force-driven contact (distribution d, at polar/azimuth [deg], |F| [N] along -normal). */
void test_send_force(palp_cli_station *st, int finger, int d, double polar, double azimuth, double force,
                     uint64_t seq);
void test_send_raw(palp_cli_station *st, const palp_Contact *c);
/* Sends one position-driven 8 mm fingertip (finger 0) whose sphere goes depth [m] below the 40 mm
 * dome's undeformed surface along the normal at polar/azimuth [deg]. */
void test_send_finger(palp_cli_station *st, double polar, double azimuth, double depth, uint64_t seq);
/* The same with a fingertip of radius r [m]. */
void test_send_finger_r(palp_cli_station *st, double polar, double azimuth, double depth, double r, uint64_t seq);

/* Takes feedback samples for `seconds`, returning the last finger-0 force magnitude [N]. */
double test_last_feedback(palp_cli_station *st, double seconds, int *samples);

void test_sleep(double seconds);

/* The newest palp_server_guard sample on reader r within wait [s]: 1 if one came. */
int test_latest_guard(dds_entity_t r, double wait, palp_ServerGuard *out);
/* Uses the loopback config (CYCLONEDDS_URI) unless set. */
void test_init(void);
/* This process's resident set (VmRSS) [kB], or -1. */
long test_rss_kb(void);

#endif
