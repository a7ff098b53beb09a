/*
 * assess_log.c - the assessment of a session from palp-server's log (issue 13): the
 * session's exercise (palp_db_session_exercise), its phantom's rest mesh (the logged
 * scene, palp_db_world_from_scene), the finger samples and findings (the readers) into
 * palp_assess. Used by exercise_trainees.sh on sessions played by palp-client's
 * scripted trainees over real DDS.
 *
 * usage: assess_log DB TRAINEE expert|novice
 * Asserts for an expert: every lesion found, no false positive, medium coverage >= 0.95,
 * pattern vertical strip; for a novice: medium coverage < 0.30 and not every lesion found.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_assess.h"
#include "palp_db.h"

typedef struct acc {
  palp_assess_sample *s;
  int n, cap;
  int *tri;
  size_t *tri_at;
  size_t ntri, tricap;
  double radius;
  palp_finding f[128];
  int nf;
  uint32_t id[128];
} acc;

static int on_sample(void *user, const palp_db_finger_sample *fs) {
  acc *a = user;
  if (a->n == a->cap) {
    a->cap = a->cap ? 2 * a->cap : 4096;
    a->s = realloc(a->s, sizeof *a->s * (size_t)a->cap);
    a->tri_at = realloc(a->tri_at, sizeof *a->tri_at * (size_t)a->cap);
    if (!a->s || !a->tri_at) return 1;
  }
  if (a->ntri + (size_t)fs->triangle_count > a->tricap) {
    a->tricap = 2 * a->tricap + (size_t)fs->triangle_count + 65536;
    a->tri = realloc(a->tri, sizeof *a->tri * a->tricap);
    if (!a->tri) return 1;
  }
  for (int k = 0; k < fs->triangle_count; k++) a->tri[a->ntri + (size_t)k] = fs->triangles[k];
  a->s[a->n] = (palp_assess_sample){.t = fs->sim_time_s, .device = fs->device_m, .proxy = fs->proxy_m,
                                    .force = fs->force_n, .contact = fs->in_contact, .point = fs->point_m,
                                    .area = fs->area_m2, .triangle_count = fs->triangle_count};
  a->tri_at[a->n++] = a->ntri;
  a->ntri += (size_t)fs->triangle_count;
  a->radius = fs->radius_m;
  return 0;
}

static int on_finding(void *user, const palp_db_finding *f) {
  acc *a = user;
  if (f->op == PALP_DB_FINDING_MARK && a->nf < 128) {
    a->id[a->nf] = (uint32_t)f->mark_id;
    a->f[a->nf++] = (palp_finding){.t = f->sim_time_s, .point = f->point_m, .withdrawn = 0};
  } else if (f->op == PALP_DB_FINDING_WITHDRAW)
    for (int i = 0; i < a->nf; i++)
      if (a->id[i] == (uint32_t)f->mark_id) a->f[i].withdrawn = 1;
  return 0;
}

int main(int argc, char **argv) {
  if (argc != 4 || (strcmp(argv[3], "expert") && strcmp(argv[3], "novice"))) {
    fprintf(stderr, "usage: %s DB TRAINEE expert|novice\n", argv[0]);
    return 2;
  }
  const int expert = !strcmp(argv[3], "expert");
  char err[512];
  palp_db *db = NULL;
  if (palp_db_open(argv[1], 0, &db, err, sizeof err) < 0) {
    fprintf(stderr, "FAIL %s: %s\n", argv[1], err);
    return 1;
  }
  palp_db_filter flt = {.trainee = argv[2]};
  palp_db_session_info *ss = NULL;
  int ns = 0;
  if (palp_db_list_sessions(db, &flt, &ss, &ns) < 0 || ns < 1) {
    fprintf(stderr, "FAIL no session of %s in %s\n", argv[2], argv[1]);
    return 1;
  }
  const palp_db_session_info *si = &ss[ns - 1];
  char name[64];
  char *exj = NULL, *scene = NULL, *params = NULL;
  palp_exercise ex;
  if (palp_db_session_exercise(db, si->id, name, sizeof name, &exj) < 0 ||
      palp_exercise_parse(exj, NULL, &ex, err, sizeof err) < 0) {
    fprintf(stderr, "FAIL session %s: no exercise in the log (%s)\n", si->uid, err);
    return 1;
  }
  int e = 0;
  palp_world *w = palp_db_session_json(db, si->id, &scene, &params) == 0
                      ? palp_db_world_from_scene(scene, si->dt_s, &e, err, sizeof err)
                      : NULL;
  if (!w) {
    fprintf(stderr, "FAIL session %s: cannot rebuild the phantom: %s\n", si->uid, err);
    return 1;
  }
  acc a = {0};
  palp_db_each_finger_sample(db, si->id, on_sample, &a);
  palp_db_each_finding(db, si->id, on_finding, &a);
  for (int i = 0; i < a.n; i++) a.s[i].triangles = a.s[i].triangle_count ? a.tri + a.tri_at[i] : NULL;
  palp_assess_result r;
  int rc = palp_assess(&ex, palp_world_mesh(w), a.radius, a.s, a.n, a.f, a.nf, &r, NULL, NULL);
  if (rc < 0 || a.n == 0) {
    fprintf(stderr, "FAIL session %s: %d samples, palp_assess %d\n", si->uid, a.n, rc);
    return 1;
  }
  printf("%s (session %s, exercise %s): %d samples, %d findings: found %d/%d, false %d, coverage light %.3f "
         "medium %.3f deep %.3f, pattern %s (axial %.2f), time %.1f s, peak %.2f N, score %.1f, pass %d\n",
         argv[2], si->uid, name, a.n, a.nf, r.found, r.lesion_count, r.false_positives, r.coverage[0], r.coverage[1],
         r.coverage[2], palp_pattern_name(r.pattern), r.evidence.share_axial, r.duration, r.peak_force, r.score,
         r.pass);
  int fail = 0;
#define CHECK(c, ...)                                                                                            \
  do {                                                                                                           \
    printf("%s ", (c) ? "ok  " : "FAIL");                                                                        \
    printf(__VA_ARGS__);                                                                                         \
    printf("\n");                                                                                                \
    fail |= !(c);                                                                                                \
  } while (0)
  if (expert) {
    CHECK(r.found == r.lesion_count && r.lesion_count > 0, "the expert finds every lesion (%d of %d)", r.found,
          r.lesion_count);
    CHECK(r.false_positives == 0, "no false positive (%d)", r.false_positives);
    CHECK(r.coverage[PALP_BAND_MEDIUM] >= 0.95, "medium coverage %.3f >= 0.95", r.coverage[PALP_BAND_MEDIUM]);
    CHECK(r.pattern == PALP_PATTERN_VERTICAL_STRIP, "pattern vertical strip (%s)", palp_pattern_name(r.pattern));
  } else {
    CHECK(r.coverage[PALP_BAND_MEDIUM] < 0.30, "novice medium coverage %.3f < 0.30", r.coverage[PALP_BAND_MEDIUM]);
    CHECK(r.found < r.lesion_count, "the novice misses a lesion (%d of %d found)", r.found, r.lesion_count);
  }
  free(a.s), free(a.tri), free(a.tri_at), free(exj), free(scene), free(params), free(ss);
  palp_world_destroy(w);
  palp_db_close(db);
  return fail;
}
