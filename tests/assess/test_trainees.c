/*
 * test_trainees.c - scripted trainees in an in-process world at 250 Hz, assessed by
 * palp_assess (docs/assessment.md, "Scripted trainees").
 *
 * The expert runs on tests/assess/exercise_expert.json: two 15 mm lumps 10 mm deep, 5x the
 * fat, on the breast-tissue dome (phantom_stiff.json; the shipped teaching exercise). There
 * each lump raises the fingertip force at equal depth by +18-26% over the same spot without
 * it (tests/assess/phantom_figures, 2-15 mm); in the expert's exam the two lumps' largest
 * rises over the fitted surroundings are +16.4% and +17.5% and the worst spot away from
 * them +2.7% (her deep level 14.5 mm, since 2026-12-05; +16.5 / +18.2% and +2.9% at 16 mm;
 * since 2026-11-28, when the rule's fit gained its term for the rise towards
 * the base; +21.8 / +20.0% and +5.6% with the quadratic alone); the expert marks above
 * 12%. Asserted with margins: each lump rises >= 15%, no spot away from them above 7%.
 *
 * The novice runs on the test exercise and on the shipped hard one (1 cm, 10 mm deep).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp_assess.h"
#include "recorder.h"

#define RISE_THRESHOLD 0.12 /* the expert's "harder than around it" [-] */
#define CLUSTER 0.015       /* marks closer than this are one lump [m] */

static palp_world *world_for(const char *path, palp_exercise *ex, palp_scene *sc) {
  char err[512] = "";
  CHECK(palp_exercise_load(path, ex, err, sizeof err) == 0, "%s: %s", path, err);
  CHECK(palp_exercise_scene(ex, sc, err, sizeof err) == 0, "%s: %s", path, err);
  int e = 0;
  palp_world *w = palp_world_create(&sc->world, &e);
  CHECK(w != NULL, "world: %s", palp_strerror(e));
  return w;
}

static void report(const char *who, const palp_assess_result *r) {
  printf("%s: found %d/%d, false %d, coverage light %.3f medium %.3f deep %.3f, pattern %s (axial %.2f tangential "
         "%.2f radial %.2f, %d strips in order %.2f, path %.2f m, plan %.2f m, presses %d, overlap %.2f, gaps %.3f, largest gap %.2f cm^2), "
         "time %.1f s, peak %.2f N, out of range %d, score %.1f, pass %d\n",
         who, r->found, r->lesion_count, r->false_positives, r->coverage[0], r->coverage[1], r->coverage[2],
         palp_pattern_name(r->pattern), r->evidence.share_axial, r->evidence.share_tangential,
         r->evidence.share_radial, r->evidence.strips, r->evidence.sweep_monotony, r->evidence.path_length, r->evidence.plan_length, r->evidence.presses,
         r->evidence.overlap, r->evidence.gap_share, r->evidence.largest_gap * 1e4, r->duration, r->peak_force,
         r->out_of_range, r->score, r->pass);
}

/* The expert's exam on the exercise at path, assessed, and the lump rule's margins: the
 * largest rise at each lump and away from them (farther than radius + 10 mm from every
 * lump's surface point, the assessment's match distance). Returns the world (the caller
 * destroys it) with the recorder and result filled. */
static palp_world *expert_run(const char *path, double r, palp_exercise *ex, palp_scene *sc, recorder *rc,
                              palp_assess_result *er, double at[PALP_MAX_LESIONS], double *away, int *judged) {
  palp_world *w = world_for(path, ex, sc);
  if (!w) return NULL;
  const double R = sc->world.mesh.radius;
  CHECK(rec_init(rc, w, R, r, (palp_vec3){0, 0, R + r + 0.005}) >= 0, "finger");
  expert_cfg cfg = expert_default();
  int nspots = 0;
  expert_spot *sp = expert_exam(rc, &cfg, &nspots);
  rec_finish(rc);
  CHECK(!rc->failed && sp, "the exam ran (%d samples)", rc->n);
  palp_finding f[16];
  double max_rise = 0;
  const int nf = expert_findings(rc, sp, nspots, RISE_THRESHOLD, CLUSTER, f, 16, &max_rise);
  int match[16];
  CHECK(palp_assess(ex, palp_world_mesh(w), r, rc->s, rc->n, f, nf, er, match, NULL) == 0, "assess");
  printf("expert on %s: %d spots, %d samples, %d marks, largest rise %.3f\n", path, nspots, rc->n, nf, max_rise);
  report("expert", er);
  palp_cli_hand h;
  rec_hand(rc, &h);
  double *rise = malloc(sizeof(double) * (size_t)(nspots > 0 ? nspots : 1));
  CHECK(rise && sp && palp_cli_expert_rises(&h, sp, nspots, &cfg, rise) == 0, "rises");
  *away = -INFINITY;
  *judged = 0;
  for (int l = 0; l < PALP_MAX_LESIONS; ++l) at[l] = -INFINITY;
  for (int i = 0; rise && sp && i < nspots; ++i) {
    if (!isfinite(rise[i])) continue;
    (*judged)++;
    int near = 0;
    for (int l = 0; l < ex->lesion_count; ++l) {
      const palp_vec3 q = palp_exercise_lesion_surface(&ex->lesion[l], R);
      const double dx = R * sp[i].n.x - q.x, dy = R * sp[i].n.y - q.y, dz = R * sp[i].n.z - q.z;
      if (sqrt(dx * dx + dy * dy + dz * dz) <= ex->lesion[l].diameter / 2 + 0.010) near = 1, at[l] = fmax(at[l], rise[i]);
    }
    if (!near) *away = fmax(*away, rise[i]);
  }
  printf("expert: %d spots judged; largest rise at the lumps %+.3f %+.3f, away from them %+.3f\n", *judged, at[0], at[1],
         *away);
  free(rise);
  free(sp);
  return w;
}

int main(void) {
  const double r = 0.008;
  char path[1024];

  /* 1. The expert. */
  palp_exercise ex;
  palp_scene sc;
  snprintf(path, sizeof path, "%s/exercise_expert.json", PALP_TEST_DIR);
  recorder rc;
  palp_assess_result er;
  double at[PALP_MAX_LESIONS], away;
  int judged;
  palp_world *w = expert_run(path, r, &ex, &sc, &rc, &er, at, &away, &judged);
  if (!w) CHECK_DONE();
  const double R = sc.world.mesh.radius;
  CHECK(er.found == ex.lesion_count && er.lesion_count == 2, "the expert finds every lesion (%d of %d)", er.found,
        er.lesion_count);
  CHECK(er.false_positives == 0, "no false positive (%d)", er.false_positives);
  CHECK(er.coverage[PALP_BAND_MEDIUM] >= 0.95, "medium coverage %.3f >= 0.95", er.coverage[PALP_BAND_MEDIUM]);
  CHECK(er.coverage[PALP_BAND_LIGHT] >= 0.90 && er.coverage[PALP_BAND_DEEP] >= 0.80,
        "light %.3f >= 0.90, deep %.3f >= 0.80", er.coverage[PALP_BAND_LIGHT], er.coverage[PALP_BAND_DEEP]);
  CHECK(er.pattern == PALP_PATTERN_VERTICAL_STRIP, "the expert's pattern is named vertical strip (%s)",
        palp_pattern_name(er.pattern));
  /* her script strokes 14-15 strips in one pass across the dome, each next to the one before
   * (measured 14, order 1.00; 15 with her deep level at 16 mm, before 2026-12-05); 13 allows for edge strips shorter than the 16 mm a strip needs */
  CHECK(er.evidence.strips >= 13 && er.evidence.sweep_monotony >= 0.9, "the expert's strips in order: %d, order %.2f",
        er.evidence.strips, er.evidence.sweep_monotony);
  CHECK(er.pass && er.score >= 90.0, "the expert passes with >= 90 (%.1f)", er.score);
  CHECK(er.duration <= ex.time_limit, "within the time limit (%.1f s)", er.duration);
  /* The lump rule's margins (measured +16.4 / +17.5 % and +2.7 %, threshold 12 %; +16.5 / +18.2 %
   * and +2.9 % with her deep level at 16 mm). */
  CHECK(at[0] >= 0.15 && at[1] >= 0.15, "each lump rises >= 15%% over its surroundings (%+.3f, %+.3f; measured "
        "+0.164, +0.175)", at[0], at[1]);
  CHECK(away <= 0.07, "no spot away from the lumps rises above 7%% (%+.3f; measured +0.027)", away);
  CHECK(judged >= 60, "the rule judges >= 60 spots (%d; measured 85)", judged);

  /* 2. The novice on the same exercise: five light presses at random places. */
  palp_world_destroy(w);
  w = world_for(path, &ex, &sc);
  recorder nc;
  rec_init(&nc, w, R, r, (palp_vec3){0, 0, R + r + 0.005});
  palp_vec3 guess = {0, 0, 0};
  novice_exam(&nc, 5, 0.003, 7u, &guess);
  rec_finish(&nc);
  const palp_finding nfnd = {.t = palp_world_time(w), .point = guess, .withdrawn = 0}; /* a guess at the last press */
  palp_assess_result nr;
  CHECK(palp_assess(&ex, palp_world_mesh(w), r, nc.s, nc.n, &nfnd, 1, &nr, NULL, NULL) == 0, "assess");
  report("novice", &nr);
  CHECK(nr.coverage[PALP_BAND_LIGHT] < 0.25 && nr.coverage[PALP_BAND_MEDIUM] < 0.05 && nr.coverage[PALP_BAND_DEEP] < 0.05,
        "novice thoroughness low: light %.3f < 0.25, medium %.3f, deep %.3f < 0.05", nr.coverage[0], nr.coverage[1],
        nr.coverage[2]);
  CHECK(nr.pattern == PALP_PATTERN_UNSYSTEMATIC, "novice unsystematic (%s)", palp_pattern_name(nr.pattern));
  CHECK(nr.score < er.score - 40.0 && !nr.pass, "novice scores far below the expert (%.1f vs %.1f) and fails",
        nr.score, er.score);
  rec_free(&nc);
  palp_world_destroy(w);

  /* 3. The novice on the shipped hard exercise (1 cm, 10 mm deep) misses it: light presses only. */
  snprintf(path, sizeof path, "%s/exercises/hard.json", PALP_CONFIG_DIR);
  w = world_for(path, &ex, &sc);
  if (w) {
    rec_init(&nc, w, R, r, (palp_vec3){0, 0, R + r + 0.005});
    novice_exam(&nc, 5, 0.003, 11u, &guess);
    rec_finish(&nc);
    const palp_finding g = {.t = palp_world_time(w), .point = guess, .withdrawn = 0};
    CHECK(palp_assess(&ex, palp_world_mesh(w), r, nc.s, nc.n, &g, 1, &nr, NULL, NULL) == 0, "assess");
    report("novice (hard)", &nr);
    CHECK(nr.found == 0 && nr.sensitivity == 0.0, "the novice misses the lesion");
    CHECK(nr.coverage[PALP_BAND_DEEP] == 0.0, "and never pressed deep (%.3f)", nr.coverage[PALP_BAND_DEEP]);
    rec_free(&nc);
    palp_world_destroy(w);
  }
  rec_free(&rc);

  /* 4. The expert on the shipped teaching exercise, as the demo runs it: the shipped
   * breast-tissue phantom with its stiffening support (docs/model.md). Its force rises
   * towards the base; with a quadratic fit alone the lesion-free spots rose to +9.8% here
   * (+12.8% and a false lump in the demo with the cubic law first tried), with the rule's
   * term for it +3.2%. Asserted: both lumps found, no false mark, each lump >= 15%
   * (measured +21.5%, +21.6% with the hinges seeing the lesion, 2026-11-28; +19.9%,
   * +20.6% with the support's relaxing branch alone; +18.9%,
   * +19.2% after the refit to the level-3 fingertip, +18.6%, +18.3% before), every spot
   * away from them at most 7% (measured +5.5%;
   * deterministic, in process). Measured 2026-12-05 with the expert's deep level at 14.5 mm:
   * +23.2%, +22.0%, away +3.2% (+23.6%, +23.1%, +3.3% at 16 mm the same day). */
  snprintf(path, sizeof path, "%s/exercises/teaching.json", PALP_CONFIG_DIR);
  w = expert_run(path, r, &ex, &sc, &rc, &er, at, &away, &judged);
  if (w) {
    CHECK(sc.world.gel.support_stiffening > 0.0, "the shipped phantom stiffens (beta %g)", sc.world.gel.support_stiffening);
    CHECK(er.found == 2 && er.false_positives == 0, "shipped teaching: 2 of 2 found (%d), no false mark (%d)", er.found,
          er.false_positives);
    CHECK(at[0] >= 0.15 && at[1] >= 0.15, "shipped teaching: each lump rises >= 15%% (%+.3f, %+.3f; measured +0.232, "
          "+0.220)", at[0], at[1]);
    CHECK(away <= 0.07, "shipped teaching: no spot away from the lumps above 7%% (%+.3f; measured +0.032)", away);
    /* The expert shows the technique inside the model's valid range: her deep presses reach
     * the deep band (9-18 mm of indentation) and stay within the depths the shipped parameters
     * were validated to against the FE (config/params/breast_tissue.json "validated": 12 mm at
     * the pole, 45 and 70 deg, 14 mm at 60 deg). Measured: deepest 11.48 mm, 0 steps beyond
     * (her device's deep level 14.5 mm); at 16 mm she pressed to 12.46 mm and 1,577 steps of
     * 4 ms were beyond the table, by up to 0.46 mm. */
    double deepest = 0.0;
    for (int i = 0; i < rc.n; ++i) {
      const palp_vec3 q = rc.s[i].proxy;
      deepest = fmax(deepest, R + r - sqrt(q.x * q.x + q.y * q.y + q.z * q.z));
    }
    palp_world_health hl;
    palp_world_get_health(w, &hl);
    CHECK(deepest >= 0.010, "shipped teaching: the expert's deep presses reach %.2f mm, >= 10 mm (deep band from 9)",
          deepest * 1e3);
    CHECK(hl.beyond_validated_steps == 0 && hl.max_beyond_validated == 0.0,
          "shipped teaching: the expert never presses deeper than validated (%lld steps, by up to %.2f mm; measured 0)",
          (long long)hl.beyond_validated_steps, hl.max_beyond_validated * 1e3);
    rec_free(&rc);
    palp_world_destroy(w);
  }
  CHECK_DONE();
}
