/*
 * test_alloc_fail.c - a finger added after a failed allocation (palp_world_add_finger_def).
 *
 * The library has no allocation hook (and keeps no globals), so this executable is linked
 * with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc (tests/model/CMakeLists.txt): every
 * allocation the library's objects make goes through the wrappers below, which fail the
 * n-th one after they are armed. The knob is the test's, not the library's.
 *
 * For each contact surface (facets, smooth) and each allocation n that adding the first
 * finger makes (counted on a world where none fails): add_finger with the n-th allocation
 * failing returns PALP_ENOMEM; the next add_finger, with memory back, returns a finger; and
 * 40 steps pressing it 2 mm into the pole (1 kHz) then succeed and give the same state as a
 * world whose add_finger never failed, bit for bit (state hash and contact force; tolerance
 * 0: the scratch is made afresh either way). Each case runs in a child process, so a case
 * that crashes (before the fix: the scratch was kept half made, and the step dereferenced
 * its missing arrays) is reported as such and the others still run.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "palp.h"

void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);

/* The test's knob: counting allocations while armed; the fail_at-th fails (0: none). */
static int armed = 0;
static long seen = 0, fail_at = 0;
static int fail_now(void) { return armed && ++seen == fail_at; }
void *__wrap_malloc(size_t size) { return fail_now() ? NULL : __real_malloc(size); }
void *__wrap_calloc(size_t n, size_t size) { return fail_now() ? NULL : __real_calloc(n, size); }
void *__wrap_realloc(void *p, size_t size) { return fail_now() ? NULL : __real_realloc(p, size); }

static palp_world *make(int surface) {
  palp_world_def d = palp_world_default_def();
  d.dt = 0.001;
  d.finger_surface = surface;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(e));
    exit(2);
  }
  return w;
}

static const double R = 0.04, r = 0.008;

/* 40 steps lowering the device from 1 mm above to 2 mm into the pole's surface; the state
 * hash after them and the finger's contact force [N] (its length). -1 hash on a failed step. */
static unsigned long long press(palp_world *w, int f, double *force) {
  for (int k = 0; k < 40; ++k) {
    const double z = R + r + 0.001 - 0.003 * (k + 1) / 40.0;
    palp_world_set_finger_device(w, f, (palp_vec3){0, 0, z});
    if (palp_world_step(w) != 0) return (unsigned long long)-1;
  }
  palp_vec3 F = {0, 0, 0};
  palp_world_contact_feedback(w, f, &F);
  *force = sqrt(F.x * F.x + F.y * F.y + F.z * F.z);
  return (unsigned long long)palp_world_hash(w);
}

/* One case in this process: the n-th allocation of the first add_finger fails. */
static int one_case(int surface, long n, unsigned long long want_hash, double want_force) {
  palp_world *w = make(surface);
  const palp_vec3 start = {0, 0, R + r + 0.001};
  seen = 0, fail_at = n, armed = 1;
  const int e1 = palp_world_add_finger(w, start, r);
  armed = 0;
  CHECK(e1 == PALP_ENOMEM, "allocation %ld failing: add_finger returns %d, want PALP_ENOMEM", n, e1);
  const int f = palp_world_add_finger(w, start, r);
  CHECK(f >= 0, "allocation %ld failed before: the next add_finger returns %d", n, f);
  if (f >= 0) {
    double force = NAN;
    const unsigned long long h = press(w, f, &force);
    CHECK(h == want_hash && force == want_force,
          "allocation %ld failed before: pressed 2 mm, hash %016llx force %.9g N, want %016llx %.9g N (tolerance 0)",
          n, h, force, want_hash, want_force);
  }
  palp_world_destroy(w);
  return check_failures;
}

static void test_surface(int surface) {
  const char *name = palp_finger_surface_name(surface);
  /* the reference, and how many allocations the first add_finger makes */
  palp_world *w = make(surface);
  seen = 0, fail_at = 0, armed = 1;
  const int f = palp_world_add_finger(w, (palp_vec3){0, 0, R + r + 0.001}, r);
  armed = 0;
  const long n_alloc = seen;
  double want_force = NAN;
  const unsigned long long want_hash = f >= 0 ? press(w, f, &want_force) : 0;
  palp_world_destroy(w);
  CHECK(f >= 0 && n_alloc > 10 && want_force > 0.05, "%s: reference finger %d, %ld allocations, force %.4f N", name, f,
        n_alloc, want_force);
  int crashed = 0, failed = 0;
  for (long n = 1; n <= n_alloc; ++n) {
    fflush(NULL);
    const pid_t pid = fork();
    if (pid == 0) _exit(one_case(surface, n, want_hash, want_force) ? 1 : 0);
    int st = 0;
    if (pid < 0 || waitpid(pid, &st, 0) != pid) {
      CHECK(0, "%s: allocation %ld: fork/wait failed", name, n);
      continue;
    }
    if (WIFSIGNALED(st)) {
      crashed++;
      CHECK(0, "%s: allocation %ld failing in the first add_finger: the process died of signal %d", name, n,
            WTERMSIG(st));
    } else if (WEXITSTATUS(st) != 0) {
      failed++;
      CHECK(0, "%s: allocation %ld failing in the first add_finger: checks failed (above)", name, n);
    }
  }
  printf("%s: the first add_finger makes %ld allocations; with each failing in turn: %ld returned PALP_ENOMEM and the "
         "next add_finger gave the unfailed world's press bit for bit (%.4f N), %d crashed, %d failed checks\n",
         name, n_alloc, n_alloc - crashed - failed, want_force, crashed, failed);
}

int main(void) {
  test_surface(PALP_FINGER_SURFACE_FACETS);
  test_surface(PALP_FINGER_SURFACE_SMOOTH);
  CHECK_DONE();
}
