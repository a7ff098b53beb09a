/*
 * test_netem_slots.c - palp-netem's session slots are reclaimed (session 81 review).
 *
 * Until session 81 a side's 64 session slots (a partition's publisher and writers each) were
 * never freed: the relay carried 64 sessions per lifetime, and the 65th was dropped even with
 * nothing else open. White-box, like test_netem_stats.c: netem.c is compiled in and its slot
 * logic (part_slot, part_note: what writer_for runs under the lock before it makes or uses a
 * slot's writers) runs on a made-up clock, with no DDS entity (a slot's publisher stays 0).
 *
 * 1. 70 sessions one after another, 0.2 s apart, each writing 3 instances for 0.3 s and then
 *    unregistering them; session 1000 stays open throughout (writes every 0.1 s, never ends).
 *    Every session gets a slot; 70 + 1 - 64 = 7 of them reclaimed (those of sessions 1..7, by hand:
 *    the first 63 sessions fill the 63 slots left by session 1000); session 1000 keeps its slot.
 * 2. 64 made-up session ids each write one instance and never end (a forger), all at t0: a new
 *    session finds no slot at t0 + 1 s and t0 + 29.9 s (they are open and not idle 30 s), and
 *    gets one at t0 + 30 s (the least recently used of them: the first forged id's slot).
 */
#include "netem.c"

static int failures;
#define CHECK(cond, ...) \
  do { \
    if (!(cond)) { \
      fprintf(stderr, "FAIL " __VA_ARGS__); \
      fputc('\n', stderr); \
      ++failures; \
    } \
  } while (0)

#define S(x) ((int64_t)((x) * 1e9))

/* What writer_for does with a session topic's sample, minus the DDS writers. */
static int cross(palp_netem *n, uint32_t sid, int64_t now, int op, dds_instance_handle_t ih) {
  const int i = part_slot(n, &n->s[0], sid, now);
  if (i >= 0) part_note(&n->s[0].part[i], now, op, 0, ih);
  return i;
}

int main(void) {
  static palp_netem n; /* large: not on the stack */
  memset(&n, 0, sizeof n);
  /* 1. sequential sessions beside one long one */
  const uint32_t LONG_SID = 1000;
  const int long_slot = cross(&n, LONG_SID, S(0), 0, 999);
  CHECK(long_slot >= 0, "the long session got no slot");
  int relayed = 0;
  for (int k = 1; k <= 70; k++) {
    const int64_t t = S(0.2 * k);
    int ok = 1;
    for (int step = 0; step <= 3; step++) /* writes at t, t + 0.1, t + 0.2, t + 0.3 */
      for (dds_instance_handle_t j = 1; j <= 3; j++) ok &= cross(&n, (uint32_t)k, t + S(0.1 * step), 0, 10u * k + j) >= 0;
    for (dds_instance_handle_t j = 1; j <= 3; j++) ok &= cross(&n, (uint32_t)k, t + S(0.35), 2, 10u * k + j) >= 0;
    CHECK(ok, "session %d (of 70, one after another) was not relayed", k);
    relayed += ok;
    CHECK(cross(&n, LONG_SID, t + S(0.1), 0, 999) == long_slot, "the open session lost its slot at session %d", k);
  }
  printf("70 sequential sessions beside an open one: %d relayed, %llu slots reclaimed (want 70, 7)\n", relayed,
         (unsigned long long)n.st.sessions_reclaimed);
  CHECK(relayed == 70 && n.st.sessions_reclaimed == 7, "want 70 relayed and 7 reclaimed");

  /* 2. a forger's 64 open sessions: blocked while they may be live, not for ever */
  memset(&n, 0, sizeof n);
  const int64_t t0 = S(100);
  for (uint32_t f = 0; f < MAX_PARTS; f++) CHECK(cross(&n, 5000 + f, t0 + (int64_t)f, 0, 50000 + f) >= 0, "forged %u", f);
  const int at1 = cross(&n, 7, t0 + S(1), 0, 70);
  const int at29 = cross(&n, 7, t0 + S(29.9), 0, 70);
  const int at30 = cross(&n, 7, t0 + S(30) + MAX_PARTS, 0, 70);
  printf("64 forged open sessions: a new session at +1 s %s, at +29.9 s %s, at +30 s %s (want none, none, the "
         "first forged id's slot)\n", at1 < 0 ? "none" : "a slot", at29 < 0 ? "none" : "a slot",
         at30 < 0 ? "none" : n.s[0].part[at30].sid == 7 && at30 == 0 ? "the first forged id's slot" : "another slot");
  CHECK(at1 < 0 && at29 < 0, "a slot taken from a session that may still be live");
  CHECK(at30 == 0, "no slot (or not the least recently used) after 30 s idle: got %d", at30);
  if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
  return failures ? 1 : 0;
}
