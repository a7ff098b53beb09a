/* palp_dds_origin's writer cache under more writers than it holds (no DDS: its find and put).
 * usage: test_db_recorder_origin
 *
 * palp-recorder asks the cache for every contact's and finding's writer it has not taken as a station's,
 * and for each server writer's first sample in a session (db/recorder/recorder.c, server_run_of). Until
 * 2026-12-06 the cache emptied itself whole once 768 of its 1024 entries were used: past ~100 sessions'
 * writers each refill forgot every writer, and nearly every sample asked DDS again. Now a full set forgets
 * one writer not found since its clock's hand passed. Checked, with handles as Cyclone hands them out
 * (consecutive, from a random base):
 *  - 5000 distinct writers put: every one findable right after its put, the cache never holds more than
 *    PALP_DDS_ORIGIN_WRITERS, and it is full at the end (no wholesale reset emptied it);
 *  - 512 writers found again and again (64 sessions' busy writers) while 40 new writers come between two
 *    rounds of them (12,000 in 300 rounds): after the first round none of the 512 is ever missed (the
 *    wholesale reset missed all 512 each 768 puts: ~15 times here);
 *  - a writer's entry keeps what was put (participant, partition; "" for a partition too long or NULL). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "palp_dds_origin.h"

static palp_dds_origin o; /* ~100 kB: static */

static int held_count(void) {
  int n = 0;
  for (int i = 0; i < PALP_DDS_ORIGIN_WRITERS; i++) n += o.w[i].pub != 0;
  return n;
}

int main(void) {
  const dds_instance_handle_t base = 0x5b3c7e1d00000000ull + 12345; /* Cyclone's: a random base, counted up */

  palp_dds_origin_init(&o);
  int unfindable = 0, over = 0;
  for (int i = 0; i < 5000; i++) {
    const dds_instance_handle_t pub = base + (dds_instance_handle_t)i;
    palp_dds_origin_put(&o, pub, pub + 1, "palp/session/1");
    if (!palp_dds_origin_find(&o, pub)) unfindable++;
    if (held_count() > PALP_DDS_ORIGIN_WRITERS) over++;
  }
  CHECK(unfindable == 0 && over == 0, "each writer findable right after its put (%d not), never over the bound (%d)",
        unfindable, over);
  CHECK(held_count() == PALP_DDS_ORIGIN_WRITERS, "full after 5000 writers: %d of %d entries held", held_count(),
        PALP_DDS_ORIGIN_WRITERS);

  palp_dds_origin_init(&o);
  enum { HOT = 512, ROUNDS = 300, COLD_PER_ROUND = 40 };
  const dds_instance_handle_t hot0 = base + 100000, cold0 = base + 200000;
  long long hot_misses = 0, first_round_misses = 0;
  for (int round = 0; round < ROUNDS; round++) {
    for (int h = 0; h < HOT; h++) {
      const dds_instance_handle_t pub = hot0 + (dds_instance_handle_t)h;
      if (palp_dds_origin_find(&o, pub)) continue;
      if (round == 0) first_round_misses++;
      else hot_misses++;
      palp_dds_origin_put(&o, pub, pub + 1, "");
    }
    for (int c = 0; c < COLD_PER_ROUND; c++) {
      const dds_instance_handle_t pub = cold0 + (dds_instance_handle_t)(round * COLD_PER_ROUND + c);
      if (!palp_dds_origin_find(&o, pub)) palp_dds_origin_put(&o, pub, pub + 1, "");
    }
  }
  printf("%d busy writers among %d one-off ones: %lld busy misses after the first round (%lld in it), %llu "
         "writers forgotten\n",
         HOT, ROUNDS * COLD_PER_ROUND, hot_misses, first_round_misses, (unsigned long long)o.evictions);
  CHECK(first_round_misses == HOT && hot_misses == 0,
        "the busy writers missed once each (%lld of %d), then never while one-off writers come (%lld misses)",
        first_round_misses, HOT, hot_misses);

  palp_dds_origin_init(&o);
  char longp[100];
  memset(longp, 'p', sizeof longp - 1);
  longp[sizeof longp - 1] = '\0';
  palp_dds_origin_put(&o, 7, 70, "palp/s/alice/7");
  palp_dds_origin_put(&o, 8, 80, longp);
  palp_dds_origin_put(&o, 9, 90, NULL);
  const palp_dds_origin_writer *a = palp_dds_origin_find(&o, 7), *b = palp_dds_origin_find(&o, 8),
                               *c = palp_dds_origin_find(&o, 9);
  CHECK(a && a->participant == 70 && !strcmp(a->partition, "palp/s/alice/7") && b && b->participant == 80 &&
            b->partition[0] == '\0' && c && c->participant == 90 && c->partition[0] == '\0',
        "entries keep their participant and partition");
  CHECK(!palp_dds_origin_put(&o, 0, 1, "x") && !palp_dds_origin_find(&o, 0), "handle 0 is no writer");
  CHECK_DONE();
}
