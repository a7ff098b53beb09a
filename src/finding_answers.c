/* finding_answers.c - findings paired with the server's answers (palp_finding_answers.h). */
#include "palp_finding_answers.h"

#include <stdio.h>
#include <string.h>

void palp_finding_answers_reset(palp_finding_answers *a) {
  a->findings = 0;
  a->answers = 0;
  a->last.valid = 0;
}

static void drop_finding(palp_finding_answers *a, int i) {
  memmove(&a->finding[i], &a->finding[i + 1], sizeof a->finding[0] * (size_t)(a->findings - i - 1));
  a->findings--;
}

static void drop_answer(palp_finding_answers *a, int i) {
  memmove(&a->answer[i], &a->answer[i + 1], sizeof a->answer[0] * (size_t)(a->answers - i - 1));
  a->answers--;
}

/* Every finding that has an answer gets it; the findings sent before it, which the server
 * answered first, lost their answers (keep-last 1) and are given up. Again from the oldest after
 * each match: a later answer may now match an earlier-queued finding of the same id. */
static void match(palp_finding_answers *a, palp_finding_verdict_fn fn, void *ctx) {
  for (int i = 0; i < a->findings; i++) {
    int k = 0;
    while (k < a->answers && a->answer[k].mark_id != a->finding[i].f.mark_id) k++;
    if (k == a->answers) continue;
    /* A mark and its withdrawal carry one id. With both pending, the answer is the withdrawal's:
     * the server answers findings in the order it takes them, on a keep-last-1 topic, so the answer
     * a reader sees is the latest it wrote; taken in one pass (the usual case when the withdrawal
     * follows at once), the mark's answer was replaced before it went out. Given to the mark, the
     * withdrawal waited out unanswered and the log kept a withdrawn mark standing (or a refused
     * withdrawal dropped a standing one; session 81 review). So the newest pending finding of the
     * id takes it, and the older, as every finding before an answered one, is given up. */
    int newer = 0;
    for (int j = i + 1; j < a->findings && !newer; j++) newer = a->finding[j].f.mark_id == a->finding[i].f.mark_id;
    if (newer) continue;
    for (int j = 0; j < i; j++) fn(ctx, &a->finding[j].f, PALP_VERDICT_UNANSWERED, "");
    fn(ctx, &a->finding[i].f, a->answer[k].accepted ? PALP_VERDICT_ACCEPTED : PALP_VERDICT_REFUSED,
       a->answer[k].accepted ? "" : a->answer[k].reason);
    drop_answer(a, k);
    for (int j = 0; j <= i; j++) drop_finding(a, 0);
    i = -1;
  }
}

void palp_finding_answers_finding(palp_finding_answers *a, const palp_finding_sent *f, double now,
                                  palp_finding_verdict_fn fn, void *ctx) {
  if (a->findings == PALP_FINDING_ANSWERS_PENDING) { /* a flood: the oldest is given up */
    fn(ctx, &a->finding[0].f, PALP_VERDICT_UNANSWERED, "");
    drop_finding(a, 0);
  }
  a->finding[a->findings].f = *f;
  a->finding[a->findings++].since = now;
  match(a, fn, ctx);
}

void palp_finding_answers_answer(palp_finding_answers *a, uint32_t mark_id, int accepted, const char *reason,
                                 uint32_t marks, int historical, double now, palp_finding_verdict_fn fn, void *ctx) {
  /* A repeat of the status before (the server's 2 Hz refresh) or a historical copy (the one a
   * reader that joined mid-session is handed) answers nothing: queued, it was taken by the next
   * finding of its id (palp_finding_answers.h). Either still becomes the status to compare with. */
  char why[sizeof a->last.reason];
  snprintf(why, sizeof why, "%s", reason ? reason : "");
  const int repeat = a->last.valid && a->last.mark_id == mark_id && a->last.accepted == (accepted != 0) &&
                     a->last.marks == marks && !strcmp(a->last.reason, why);
  a->last.valid = 1;
  a->last.mark_id = mark_id;
  a->last.marks = marks;
  a->last.accepted = accepted != 0;
  memcpy(a->last.reason, why, sizeof why);
  if (mark_id == 0 || repeat || historical) return;
  if (a->answers == PALP_FINDING_ANSWERS_QUEUED) drop_answer(a, 0);
  a->answer[a->answers].mark_id = mark_id;
  a->answer[a->answers].accepted = accepted != 0;
  snprintf(a->answer[a->answers].reason, sizeof a->answer[0].reason, "%s", why);
  a->answer[a->answers++].since = now;
  match(a, fn, ctx);
}

void palp_finding_answers_settle(palp_finding_answers *a, double now, double wait, int all,
                                 palp_finding_verdict_fn fn, void *ctx) {
  match(a, fn, ctx);
  while (a->findings && (all || now - a->finding[0].since > wait)) {
    fn(ctx, &a->finding[0].f, PALP_VERDICT_UNANSWERED, "");
    drop_finding(a, 0);
  }
  while (a->answers && (all || now - a->answer[0].since > wait)) drop_answer(a, 0);
}
