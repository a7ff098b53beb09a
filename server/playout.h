/*
 * playout.h - a position-driven finger's device samples played out at a steady
 * delay (a jitter buffer; docs/station.md, latency item 5, "Jitter on the way in").
 *
 * A station sends its device point at the physics rate, stamped with its own clock
 * (palp_Contact.source_time_ns). Over a jittery network the samples reach the
 * server in bunches: a step sees no new point, the next one two, and the server's
 * world pushes the phantom with a device that stands still, then jumps. The
 * phantom answers a jump with its stiffness within one step (a ~0.1 mm jump at
 * 400 N/m is 0.04 N), so the hand feels a ripple at the network's jitter that the
 * undelayed station does not (measured: force content above ~25 Hz 0.011-0.014 N
 * RMS while pressing, against 0.001-0.006 N with the same 20 ms delay and no
 * jitter; tests/haptic/test_relay.c).
 *
 * The buffer maps the station's clock onto the server's with the smallest
 * one-way offset seen lately (arrival - source time over the last 1-2 s: the
 * fastest path, the clocks' offset included, so the two clocks need not agree;
 * arrivals are stamped on Cyclone's receive thread by the session's filter, not
 * when the tick takes them), takes the jitter D as the 90th percentile of how much
 * later than that the last 64 samples came, and plays the samples out at
 *   T = now - min offset - D     (D < 2.5 ms: none; at most PALP_SRV_PLAYOUT_MAX_DELAY)
 * interpolating linearly between the two samples around T. A sample late for its
 * turn (1 in 10 by construction, or lost) is bridged by continuing the last motion
 * for at most 10 ms (from two samples 1-20 ms apart, within the validator's reach),
 * rather than holding and then jumping to catch up. T advances with the clock and
 * is steered towards its target at most 10% faster or slower, so a changing
 * estimate bends the device's motion instead of making it jump.
 * With D = 0 (loopback, a steady link) T is never behind the newest sample and the
 * world sees exactly what it saw without the buffer: the newest point.
 *
 * A gap is caught up, not jumped (2026-12-07). A station or a server that does not run for
 * a while (a machine that swaps, a core lost to other work) leaves a gap in the station
 * times the world has played: the next sample is the hand's motion over the whole gap, and
 * played at once it moved the finger millimetres within one 4 ms step, which the phantom's
 * viscous response turns into newtons the hand never pushed with (measured, the paper's
 * membrane, a 12 mm slide at 20 mm/s whose peak is 0.36 N: 0.92 N after a 0.3 s stop of
 * the station, 1.11 N after a 0.2 s stop of the server; and 0.44-13.5 N in 14 of ~100 runs
 * of test_relay on a starved machine). The session log recorded them as the trainee's.
 * The station time played therefore advances by at most PALP_SRV_PLAYOUT_CATCHUP world
 * steps per step: after a gap the finger travels the hand's path (straight across the gap,
 * where no sample says otherwise) at most twice as fast as the hand did, and is back on time
 * after as long again as the gap. A lag over 0.5 s is caught up faster, shrinking at
 * (lag / PALP_SRV_PLAYOUT_CATCHUP_TIME - 1) s per s (the finger lag / 0.25 s times as fast as
 * the hand), so that no gap keeps the phantom behind the hand for more than a second or so (a
 * 1 s gap: 0.78 s; measured, a 0.6 s stop of the server: 0.96 N jumped, 0.43 N caught up). A
 * gap over PALP_SRV_PLAYOUT_CATCHUP_MAX (2 s) is jumped as before.
 * Without a gap the bound never acts (one step of the station's clock per step of the
 * world's; a sample a step late is two). While a gap is caught up the samples around the
 * point played are kept, however many come (palp_srv_playout_push). Measured
 * (test_relay, 20 +- 5 ms, 5% loss): D 6.6-9.4 ms; the device's per-step motion on
 * the server as even as the undelayed station's; the force's content above ~25 Hz
 * while pressed (median of 100 ms windows) 0.0007-0.0010 N, against 0.0055-0.0058 N
 * without the buffer. On a loaded machine a loopback's own arrivals spread too: in
 * the demo, beside an FE run, D would have been 0.8-2.3 ms with a 0.5 ms dead band,
 * and the 2.5 ms one leaves loopback as it was.
 *
 * Pure: no DDS, no clock of its own; the session hands it times in ns.
 */
#ifndef PALP_SRV_PLAYOUT_H
#define PALP_SRV_PLAYOUT_H

#include <stdint.h>

#include "palp.h"

#define PALP_SRV_PLAYOUT_SAMPLES 64 /* kept for interpolation: 256 ms at 250 Hz, 64 ms at 1 kHz */
#define PALP_SRV_PLAYOUT_OFFSETS 64 /* arrivals the jitter estimate looks at */
/* The most latency the buffer may add [s]: beyond it smoothness costs more than
 * it buys (a 30 ms older device point is 0.6 mm at a palpation's 20 mm/s). */
#define PALP_SRV_PLAYOUT_MAX_DELAY 0.030
/* After a gap, the station time played advances by at most this many world steps per step,
 * or by lag / PALP_SRV_PLAYOUT_CATCHUP_TIME [s] of it per second when that is more: the finger
 * moves at most max(2, gap / 0.25 s) times as fast as the hand moved. */
#define PALP_SRV_PLAYOUT_CATCHUP 2
#define PALP_SRV_PLAYOUT_CATCHUP_TIME 0.25
/* A gap longer than this [s] is jumped as before: the hand may be anywhere after it. */
#define PALP_SRV_PLAYOUT_CATCHUP_MAX 2.0
/* A catch-up this far behind [s] is a gap worth telling (the session log's events), once, when its
 * lag first reaches it (one already under way for a smaller lag included): a loaded link's late
 * sample is a step or two. */
#define PALP_SRV_PLAYOUT_GAP_NOTED 0.05

typedef struct palp_srv_playout_sample {
  int64_t src_ns; /* station clock */
  palp_vec3 x;    /* device point [m] */
  uint64_t seq;
} palp_srv_playout_sample;

typedef struct palp_srv_playout {
  palp_srv_playout_sample s[PALP_SRV_PLAYOUT_SAMPLES]; /* ring, by source time */
  int head, n;                                         /* oldest at head */
  int64_t off[PALP_SRV_PLAYOUT_OFFSETS];               /* recv - source [ns] */
  int off_head, off_n, off_dirty;
  int64_t min_cur, min_prev, bucket_ns; /* windowed minimum offset */
  double delay;                         /* D [s], the last target */
  int64_t play_ns;                      /* T on the station's clock; valid when playing */
  double reach;                         /* [m], 0: none */
  int64_t last_now_ns;
  int playing;
  int64_t step_ns;   /* the world's step [ns]; 0: no catch-up bound */
  int64_t played_ns; /* the station time played last; valid when have_played */
  int have_played;
  /* reported */
  uint64_t samples, late; /* taken; of them, arrived after their playout time */
  double delay_max;       /* largest D used [s] */
  uint64_t behind_steps;  /* steps played behind their turn, catching a gap up */
  double behind_max;      /* the most they were behind [s] */
  uint64_t gaps;          /* catch-ups that were PALP_SRV_PLAYOUT_GAP_NOTED or more behind */
  double gap_last;        /* how far behind the last of them was when it reached that [s] */
  int catching;           /* the last step played behind its turn */
  int told;               /* this catch-up is counted in gaps */
} palp_srv_playout;

/* reach: the largest |device point| [m] the validator lets through (0: no bound); a
 * late turn is not bridged beyond it. step: the world's step [s], one per palp_srv_playout_at
 * (0: gaps are jumped, not caught up). */
void palp_srv_playout_init(palp_srv_playout *p, double reach, double step);
/* Forgets the samples (a finger lifted or re-placed); keeps the offset estimate. */
void palp_srv_playout_clear(palp_srv_playout *p);
/* Forgets the samples and starts from a finger the world already has at x, standing for
 * station time src_ns: the samples pushed next are caught up from it as after a gap (a
 * finger placed below the phantom's surface is brought in from it; session.c, place).
 * PALP_EINVAL (nothing changed) for a stamp that is no clock reading. */
int palp_srv_playout_start(palp_srv_playout *p, int64_t src_ns, palp_vec3 x, uint64_t seq);
/* A sample received at recv_ns (server clock). Returns 1 when taken, 0 when it is
 * not newer than the newest (repeated or out of order: the newer one stands; a
 * stamp more than 1 s older is a station clock that went back, and starts the
 * buffer over), PALP_EINVAL for a stamp that is no clock reading (|t| >= 2^62 ns: 146 years
 * either side of the clock's zero, so a monotonic clock or Unix time until 2116). */
int palp_srv_playout_push(palp_srv_playout *p, int64_t src_ns, int64_t recv_ns, palp_vec3 x, uint64_t seq);
/* The device point to step with at now_ns (server clock): *x, the station time it
 * stands for (*src_ns) and the newest sample it uses (*seq). Returns 0 with no
 * sample, PALP_EINVAL for a now_ns that is no clock reading (|t| >= 2^62 ns; nothing
 * written), 1 otherwise. */
int palp_srv_playout_at(palp_srv_playout *p, int64_t now_ns, palp_vec3 *x, int64_t *src_ns, uint64_t *seq);

#endif
