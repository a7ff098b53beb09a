/*
 * test_state_hash.c - palp_world_state_hash covers the state a later step reads, and
 * palp_world_hash (logged with every frame, compared by replay) keeps its definition.
 *
 * White box: world.c is compiled into this test (it replaces the library's copy at link
 * time: the library is static and every symbol of world.o is defined here first), so the
 * test can change one field of a world and nothing else. Two worlds are built and driven
 * alike: the default phantom with the literal gel law (a3 = 0.2 dt^2), stepped at 1 kHz
 * as the server steps it (rebuilds deferred and blended in), a fingertip pressing 15 mm
 * into the pole and circling. Asserted:
 *  - equal state hashes after every frame (nothing uninitialised or host-dependent in it);
 *  - in frames where the fingertip pushes, a rebuild is pending and a blend runs: each of
 *    the fields the reviewer named (the literal gel's previous pressure, a finger's proxy,
 *    a warm-start force, its drift observer) and the others the state hash adds (the gel's
 *    previous step, the kept A^{-1} g, the installed tangent's factor and link data, the
 *    stale flag, the blend's replaced factor, the pending rebuild's matrix, the sleep
 *    timer, the local model, the device), changed in one world by one ulp (or 1), changes
 *    its state hash and leaves palp_world_hash as it was; put back, the hashes are equal
 *    again;
 *  - they are state: with the previous pressure 1 Pa off (and nothing else), the next
 *    steps' palp_world_hash differ;
 *  - sign pairs (session 83 review): the signs of two doubles flipped in one world (the
 *    pole's vx and vy, as the reviewer did, two vertices' x, two links' stresses, two
 *    entries of the kept A^{-1} g) change its state hash; put back, equal again. The logged
 *    hash's fold cancels the first two pairs (palp.h says so; it leaves out the other two):
 *    printed, not asserted.
 */
#include "world.c"

#include "check.h"

static palp_world *make(void) {
  palp_world_def d = palp_world_default_def();
  d.dt = 0.001;
  d.gel.law = PALP_GEL_PAPER_LITERAL;
  d.gel.a3 = 0.2 * d.dt * d.dt;
  d.refactor_lag = palp_world_refactor_lag_for(d.dt);
  d.refactor_blend = palp_world_refactor_blend_for(d.dt);
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(e));
    exit(2);
  }
  return w;
}

static palp_vec3 device_at(int k) {
  const double R = 0.04, r = 0.008, t = 0.001 * k;
  const double depth = fmin(0.015, 0.03 * t); /* [m] below the surface, then held */
  const double a = 2.0 * 3.14159265358979 * 2.0 * t, rho = 0.002 * fmin(1.0, t / 0.2);
  return (palp_vec3){rho * cos(a), rho * sin(a), R + r + 0.001 - depth};
}

typedef struct tried {
  int changed, missed, narrow_moved, unrestored;
} tried;

/* After one field of b was changed: the state hash must differ, the logged hash not
 * (in_narrow 0) ; then after it was put back both must be equal again (check_back). */
static void check_changed(const palp_world *a, const palp_world *b, const char *what, int in_narrow, tried *t) {
  t->changed++;
  if (palp_world_state_hash(a) == palp_world_state_hash(b)) {
    t->missed++;
    CHECK(0, "%s changed by one ulp (an integer by 1): the state hash did not change", what);
  }
  if (!in_narrow && palp_world_hash(a) != palp_world_hash(b)) {
    t->narrow_moved++;
    CHECK(0, "%s changed: palp_world_hash changed too (it is logged: its definition must stay)", what);
  }
}
static void check_back(const palp_world *a, const palp_world *b, const char *what, tried *t) {
  if (palp_world_state_hash(a) != palp_world_state_hash(b) || palp_world_hash(a) != palp_world_hash(b)) {
    t->unrestored++;
    CHECK(0, "%s put back: the hashes differ", what);
  }
}

#define TRY_D(field, what)                          \
  do {                                              \
    const double keep_ = (field);                   \
    (field) = nextafter(keep_, INFINITY);           \
    check_changed(a, b, what, 0, &t);               \
    (field) = keep_;                                \
    check_back(a, b, what, &t);                     \
  } while (0)
#define TRY_F(field, what)                          \
  do {                                              \
    const float keep_ = (field);                    \
    (field) = nextafterf(keep_, INFINITY);          \
    check_changed(a, b, what, 0, &t);               \
    (field) = keep_;                                \
    check_back(a, b, what, &t);                     \
  } while (0)
#define TRY_I(field, what)                          \
  do {                                              \
    const int64_t keep_ = (field);                  \
    (field) = keep_ + 1;                            \
    check_changed(a, b, what, 0, &t);               \
    (field) = keep_;                                \
    check_back(a, b, what, &t);                     \
  } while (0)

int main(void) {
  palp_world *a = make(), *b = make();
  const palp_finger_def fd = palp_finger_default_def();
  const int fa = palp_world_add_finger_def(a, &fd, device_at(0));
  const int fb = palp_world_add_finger_def(b, &fd, device_at(0));
  CHECK(fa >= 0 && fa == fb, "fingers %d %d", fa, fb);
  int same = 1, in_contact = 0, pending = 0, blending = 0;
  tried t = {0, 0, 0, 0};
  const int frames = 1500;
  for (int k = 0; k < frames; ++k) {
    palp_world_set_finger_device(a, fa, device_at(k));
    palp_world_set_finger_device(b, fb, device_at(k));
    CHECK(palp_world_step(a) == 0 && palp_world_step(b) == 0, "step %d", k);
    same &= palp_world_state_hash(a) == palp_world_state_hash(b) && palp_world_hash(a) == palp_world_hash(b);
    contact *kb = &b->contacts[fb];
    int row = -1; /* a finger row pushing */
    for (int q = 0; q < kb->nfinger && row < 0; ++q)
      if (kb->clam[q] > 0.0) row = q;
    /* every 50th frame in contact, and the first 3 in contact with a rebuild pending and
     * while a blend runs */
    const int job_now = b->job_state != JOB_NONE && pending < 3, blend_now = b->blend_k > 0 && blending < 3;
    if (row < 0 || (k % 50 != 0 && !job_now && !blend_now)) continue;
    in_contact++;
    TRY_D(b->p_abs_prev, "the literal gel's previous pressure");
    TRY_D(b->h_gel_prev, "the literal gel's previous step");
    TRY_D(kb->proxy.x, "a finger's proxy");
    TRY_D(kb->clam[row], "a warm-start force");
    TRY_I(kb->ckey[row], "a warm-start key");
    TRY_D(kb->drift_corr.x, "a finger's drift observer");
    TRY_D(kb->lm.drift.x, "a finger's local model (drift)");
    TRY_D(kb->lm.stiffness[0][0], "a finger's local model (stiffness)");
    TRY_D(kb->lm.force.z, "a finger's local model (force)");
    TRY_D(kb->device.y, "a finger's device point");
    TRY_D(kb->total.z, "a finger's total feedback");
    TRY_D(kb->cn[row].x, "a contact row's normal");
    TRY_D(b->dir[0].x, "a link's direction");
    TRY_D(b->sigma[0], "a link's stress");
    TRY_D(b->p_gauge, "the reported gel pressure");
    TRY_D(b->h_factored, "the installed tangent's step");
    TRY_F(b->ldl.blk[0], "the installed factor (a block)");
    TRY_D(b->ldl.dinv[b->ldl.n - 1], "the installed factor (1/D)");
    TRY_D(b->fdir[0].x, "the tangent's link direction");
    TRY_D(b->fbeta[0], "the tangent's transverse share");
    TRY_D(b->fslack[0], "the tangent's mass slack");
    TRY_I(b->stale, "the stale flag");
    TRY_D(b->quiet, "the sleep timer");
    if (b->u_valid) TRY_D(b->g_u[0], "the kept A^{-1} g's gradient");
    if (b->fsoft) TRY_D(b->fsoft[0], "the turn rule's softest stiffness");
    if (b->blend_k > 0) {
      blending++;
      TRY_I(b->blend_k, "the blend's frame");
      TRY_F(b->ldl_prev.blk[0], "the blend's replaced factor");
    }
    if (b->job_state != JOB_NONE) {
      pending++;
      TRY_D(b->job->tx[0], "the pending rebuild's matrix");
      TRY_D(b->job->fdir[0].x, "the pending rebuild's link data");
      TRY_I(b->job_obsolete, "the pending rebuild's obsolete flag");
    }
  }
  printf("%d frames alike, state hashes %s; fields changed one at a time in %d frames in contact (%d with a rebuild "
         "pending, %d blending): %d changes, %d missed by the state hash, %d moved the logged hash, %d not equal when "
         "put back\n",
         frames, same ? "equal every frame" : "DIFFERED", in_contact, pending, blending, t.changed, t.missed,
         t.narrow_moved, t.unrestored);
  CHECK(same, "two worlds driven alike: equal state hashes after every frame (tolerance 0)");
  CHECK(in_contact >= 10 && pending >= 1 && blending >= 1,
        "the fields were tried in frames in contact (%d), with a rebuild pending (%d) and blending (%d)", in_contact,
        pending, blending);

  /* sign pairs: both signs flipped at once (the top bit of each double) */
  {
    const int top = b->mesh.top_vertex, other = b->mesh.vertex_count / 2;
    struct {
      double *p, *q;
      const char *what;
    } pair[] = {{&b->vel[top].x, &b->vel[top].y, "the pole's vx and vy"},
                {&b->pos[top].x, &b->pos[other].x, "two vertices' x"},
                {&b->sigma[0], &b->sigma[1], "two links' stresses"},
                {b->u_valid ? &b->g_u[0] : &b->sigma[2], b->u_valid ? &b->g_u[1] : &b->sigma[3],
                 b->u_valid ? "two entries of the kept A^{-1} g's gradient" : "two more links' stresses"}};
    int missed = 0, logged_equal = 0, unrestored = 0;
    for (size_t i = 0; i < sizeof pair / sizeof *pair; ++i) {
      double *f[2] = {pair[i].p, pair[i].q};
      for (int k = 0; k < 2; ++k) { /* flip */
        uint64_t u;
        memcpy(&u, f[k], 8);
        u ^= 1ull << 63;
        memcpy(f[k], &u, 8);
      }
      const int differs = palp_world_state_hash(a) != palp_world_state_hash(b);
      const int logged_same = palp_world_hash(a) == palp_world_hash(b);
      printf("signs of %s flipped: state hash %s, logged hash %s\n", pair[i].what, differs ? "differs" : "EQUAL",
             logged_same ? "equal" : "differs");
      missed += !differs;
      logged_equal += logged_same;
      for (int k = 0; k < 2; ++k) { /* and back */
        uint64_t u;
        memcpy(&u, f[k], 8);
        u ^= 1ull << 63;
        memcpy(f[k], &u, 8);
      }
      unrestored += palp_world_state_hash(a) != palp_world_state_hash(b);
    }
    CHECK(missed == 0, "every sign pair changes the state hash (%d missed)", missed);
    CHECK(unrestored == 0, "put back, the state hashes are equal again (%d not)", unrestored);
    (void)logged_equal;
  }

  /* the previous pressure is state: 1 Pa off, the next steps differ */
  b->p_abs_prev += 1.0;
  const uint64_t h0a = palp_world_hash(a), h0b = palp_world_hash(b);
  int diverged = 0;
  for (int k = frames; k < frames + 5; ++k) {
    palp_world_set_finger_device(a, fa, device_at(k));
    palp_world_set_finger_device(b, fb, device_at(k));
    palp_world_step(a), palp_world_step(b);
    diverged += palp_world_hash(a) != palp_world_hash(b);
  }
  printf("the literal gel's previous pressure 1 Pa off: logged hashes %s before, differ in %d of the next 5 steps\n",
         h0a == h0b ? "equal" : "different", diverged);
  CHECK(h0a == h0b && diverged == 5, "equal logged hashes, then 5 of 5 steps differ (%d)", diverged);
  palp_world_destroy(a), palp_world_destroy(b);
  CHECK_DONE();
}
