/* test_finding_answers.c - a trainee's findings paired with the server's answers as a reader of
 * the wire sees both (src/finding_answers.c): every order the two topics and the keep-last-1
 * status allow, and the statuses that answer nothing (the server's 2 Hz refresh, the historical
 * copy a reader that starts mid-session is handed; session 83). Expected verdicts are written out
 * by hand, in the order findings were sent. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "palp_finding_answers.h"

typedef struct log_t {
  int n;
  uint32_t id[64];
  int withdraw[64], verdict[64];
  char reason[64][128];
} log_t;

static void record(void *ctx, const palp_finding_sent *f, int verdict, const char *reason) {
  log_t *l = ctx;
  if (l->n == 64) return;
  l->id[l->n] = f->mark_id;
  l->withdraw[l->n] = f->withdraw;
  l->verdict[l->n] = verdict;
  snprintf(l->reason[l->n], sizeof l->reason[0], "%s", reason);
  l->n++;
}

static void mark(palp_finding_answers *a, log_t *l, uint32_t id, int withdraw, double now) {
  const palp_finding_sent f = {.mark_id = id, .withdraw = withdraw, .point = {0.001 * id, 0, 0.03}, .t = now};
  palp_finding_answers_finding(a, &f, now, record, l);
}

/* A status as the server writes it: the answer to mark id, with the marks standing after it. */
static void answer(palp_finding_answers *a, log_t *l, uint32_t id, int ok, const char *why, uint32_t marks, double now) {
  palp_finding_answers_answer(a, id, ok, why, marks, 0, now, record, l);
}

#define EXPECT(l, k, mid, wd, v)                                                                            \
  CHECK((l).n > (k) && (l).id[k] == (mid) && (l).withdraw[k] == (wd) && (l).verdict[k] == (v),              \
        "verdict %d: mark %u withdraw %d verdict %d (got n %d, mark %u, withdraw %d, verdict %d)", k, mid, wd, \
        v, (l).n, (l).id[k], (l).withdraw[k], (l).verdict[k])

int main(void) {
  static palp_finding_answers a;
  static log_t l;
  palp_finding_answers_reset(&a);

  /* the plain order: mark, its answer */
  mark(&a, &l, 1, 0, 0.0);
  CHECK(l.n == 0, "no verdict before the answer (%d)", l.n);
  answer(&a, &l, 1, 1, "", 1, 0.01);
  EXPECT(l, 0, 1u, 0, PALP_VERDICT_ACCEPTED);
  CHECK(a.findings == 0 && a.answers == 0, "nothing left (%d, %d)", a.findings, a.answers);

  /* the answer overtakes its mark (two topics) */
  answer(&a, &l, 4, 1, "", 2, 0.1);
  CHECK(l.n == 1, "an answer alone decides nothing (%d)", l.n);
  mark(&a, &l, 4, 0, 0.11);
  EXPECT(l, 1, 4u, 0, PALP_VERDICT_ACCEPTED);

  /* mark 2's answer replaced by mark 3's before it went out: 2 unanswered, then 3 */
  mark(&a, &l, 2, 0, 0.2);
  mark(&a, &l, 3, 0, 0.21);
  answer(&a, &l, 3, 1, "", 4, 0.22);
  EXPECT(l, 2, 2u, 0, PALP_VERDICT_UNANSWERED);
  EXPECT(l, 3, 3u, 0, PALP_VERDICT_ACCEPTED);

  /* refused, with the server's reason */
  mark(&a, &l, 5, 0, 0.3);
  answer(&a, &l, 5, 0, "mark 5: too close to mark 4", 4, 0.31);
  EXPECT(l, 4, 5u, 0, PALP_VERDICT_REFUSED);
  CHECK(!strcmp(l.reason[4], "mark 5: too close to mark 4"), "reason \"%s\"", l.reason[4]);

  /* a mark and its withdrawal share the id. Answered one at a time (the mark's answer seen before
   * the withdrawal is taken from the wire), each gets its own. */
  mark(&a, &l, 6, 0, 0.4);
  answer(&a, &l, 6, 1, "", 5, 0.42);
  mark(&a, &l, 6, 1, 0.43);
  answer(&a, &l, 6, 1, "", 4, 0.44);
  EXPECT(l, 5, 6u, 0, PALP_VERDICT_ACCEPTED);
  EXPECT(l, 6, 6u, 1, PALP_VERDICT_ACCEPTED);

  /* no answer: given up after the wait, not before */
  mark(&a, &l, 7, 0, 1.0);
  palp_finding_answers_settle(&a, 1.0 + PALP_FINDING_ANSWER_WAIT_S - 0.1, PALP_FINDING_ANSWER_WAIT_S, 0, record, &l);
  CHECK(l.n == 7, "still waiting 0.1 s before the wait ends (%d verdicts)", l.n);
  palp_finding_answers_settle(&a, 1.0 + PALP_FINDING_ANSWER_WAIT_S + 0.1, PALP_FINDING_ANSWER_WAIT_S, 0, record, &l);
  EXPECT(l, 7, 7u, 0, PALP_VERDICT_UNANSWERED);

  /* Session 81 review: a mark and its withdrawal both pending when the one answer comes (the server
   * took both in one pass; keep-last 1 sent only the withdrawal's). The answer is the withdrawal's:
   * the mark, whose answer was replaced, is given up unanswered, so no log keeps it standing. Before,
   * the mark took it (accepted) and the withdrawal waited out unanswered: the withdrawn mark stood. */
  {
    static palp_finding_answers b;
    static log_t m;
    palp_finding_answers_reset(&b);
    mark(&b, &m, 10, 0, 2.0);
    mark(&b, &m, 10, 1, 2.01);
    answer(&b, &m, 10, 1, "", 0, 2.02);
    EXPECT(m, 0, 10u, 0, PALP_VERDICT_UNANSWERED);
    EXPECT(m, 1, 10u, 1, PALP_VERDICT_ACCEPTED);
    CHECK(b.findings == 0 && b.answers == 0, "nothing left pending (%d, %d)", b.findings, b.answers);
    /* the withdrawal refused (its mark was refused, say): the refusal is the withdrawal's, not the mark's */
    mark(&b, &m, 11, 0, 2.1);
    mark(&b, &m, 11, 1, 2.11);
    answer(&b, &m, 11, 0, "withdrawal of mark 11, which is not standing", 0, 2.12);
    EXPECT(m, 2, 11u, 0, PALP_VERDICT_UNANSWERED);
    EXPECT(m, 3, 11u, 1, PALP_VERDICT_REFUSED);
    /* An answer that overtakes both findings is taken by the mark as it arrives, nothing newer of its
     * id pending then (the wire cannot tell whose it was; the withdrawal then waits its own answer) */
    answer(&b, &m, 12, 1, "", 1, 2.2);
    mark(&b, &m, 12, 0, 2.21);
    CHECK(m.n == 5, "the answer taken by the mark while it is the only finding of its id (%d)", m.n);
    EXPECT(m, 4, 12u, 0, PALP_VERDICT_ACCEPTED);
  }

  /* a stale answer (a transient-local copy) expires; a mark of that id sent later is not taken by it */
  answer(&a, &l, 9, 1, "", 5, 4.0);
  answer(&a, &l, 0, 1, "", 5, 4.0); /* mark 0: none yet, ignored */
  CHECK(a.answers == 1, "mark 0's answer ignored (%d answers)", a.answers);
  palp_finding_answers_settle(&a, 4.0 + PALP_FINDING_ANSWER_WAIT_S + 0.1, PALP_FINDING_ANSWER_WAIT_S, 0, record, &l);
  CHECK(a.answers == 0, "stale answer expired (%d)", a.answers);
  mark(&a, &l, 9, 0, 6.5);
  CHECK(l.n == 8, "mark 9 waits for its own answer (%d)", l.n);

  /* Session 83 review: statuses that answer nothing. */
  {
    static palp_finding_answers c;
    static log_t n;
    palp_finding_answers_reset(&c);
    /* (1) The server writes its status again at 2 Hz with the last answer in it. Mark 20 and its
     * withdrawal are answered; the refresh that follows is no answer, so the trainee's second
     * press of "withdraw" 0.2 s later waits for its own answer, the server's refusal, and is
     * logged refused. The refresh was queued before, and the second withdrawal took it: accepted. */
    mark(&c, &n, 20, 0, 10.0);
    answer(&c, &n, 20, 1, "", 1, 10.01);
    answer(&c, &n, 20, 1, "", 1, 10.5); /* the refresh */
    CHECK(c.answers == 0, "a refresh of the status is not queued as an answer (%d queued)", c.answers);
    mark(&c, &n, 20, 1, 10.6);
    answer(&c, &n, 20, 1, "", 0, 10.61);
    answer(&c, &n, 20, 1, "", 0, 11.0); /* the refresh */
    mark(&c, &n, 20, 1, 11.2);          /* withdrawn again: a double press */
    CHECK(n.n == 2, "the second withdrawal waits for its own answer (%d verdicts)", n.n);
    answer(&c, &n, 20, 1, "", 0, 11.5); /* the refresh again, before the server took it */
    answer(&c, &n, 20, 0, "withdrawal of mark 20, which is not standing", 0, 11.51);
    EXPECT(n, 0, 20u, 0, PALP_VERDICT_ACCEPTED);
    EXPECT(n, 1, 20u, 1, PALP_VERDICT_ACCEPTED);
    EXPECT(n, 2, 20u, 1, PALP_VERDICT_REFUSED);
    CHECK(c.findings == 0 && c.answers == 0, "nothing left (%d, %d)", c.findings, c.answers);
    /* (2) The reviewer's case: a reader starts mid-session and is handed the status (transient-
     * local): mark 3's withdrawal, accepted, a finding this reader never saw; then its 2 Hz
     * refresh. 0.4 s later the trainee withdraws mark 3 again and the server refuses it. */
    static palp_finding_answers d;
    static log_t o;
    palp_finding_answers_reset(&d);
    palp_finding_answers_answer(&d, 3, 1, "", 2, 1, 20.0, record, &o); /* historical */
    answer(&d, &o, 3, 1, "", 2, 20.3);                                 /* its refresh */
    mark(&d, &o, 3, 1, 20.4);
    CHECK(o.n == 0, "the late reader's withdrawal waits for its answer (%d verdicts)", o.n);
    answer(&d, &o, 3, 0, "withdrawal of mark 3, which is not standing", 2, 20.41);
    EXPECT(o, 0, 3u, 1, PALP_VERDICT_REFUSED);
    /* (3) What is lost: a second refusal like the first, of the same id, right after it (the
     * finding then counts as unanswered after the wait, never as another verdict) */
    mark(&d, &o, 3, 1, 21.0);
    answer(&d, &o, 3, 0, "withdrawal of mark 3, which is not standing", 2, 21.01);
    palp_finding_answers_settle(&d, 21.0 + PALP_FINDING_ANSWER_WAIT_S + 0.1, PALP_FINDING_ANSWER_WAIT_S, 0, record, &o);
    EXPECT(o, 1, 3u, 1, PALP_VERDICT_UNANSWERED);
  }

  /* a flood: the 33rd pending finding gives up the oldest (mark 9) */
  for (uint32_t k = 0; k < PALP_FINDING_ANSWERS_PENDING; k++) mark(&a, &l, 100 + k, 0, 7.0);
  EXPECT(l, 8, 9u, 0, PALP_VERDICT_UNANSWERED);
  CHECK(a.findings == PALP_FINDING_ANSWERS_PENDING, "bounded at %d (%d)", PALP_FINDING_ANSWERS_PENDING, a.findings);

  /* the session ends: everything left is unanswered, oldest first */
  palp_finding_answers_settle(&a, 7.1, PALP_FINDING_ANSWER_WAIT_S, 1, record, &l);
  CHECK(l.n == 9 + PALP_FINDING_ANSWERS_PENDING, "all given up (%d)", l.n);
  EXPECT(l, 9, 100u, 0, PALP_VERDICT_UNANSWERED);
  EXPECT(l, 8 + PALP_FINDING_ANSWERS_PENDING, 100u + PALP_FINDING_ANSWERS_PENDING - 1, 0, PALP_VERDICT_UNANSWERED);
  CHECK(a.findings == 0 && a.answers == 0, "empty (%d, %d)", a.findings, a.answers);
  CHECK_DONE();
}
