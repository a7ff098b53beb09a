/*
 * fem_solver.c - sparse symmetric positive-definite solves with CHOLMOD.
 *
 * The pattern of the effective stiffness never changes for a mesh, so the fill-
 * reducing ordering and symbolic factor are computed once (cholmod_analyze tries
 * AMD and, if METIS is built in, nested dissection, and keeps the one with less
 * fill); every Newton iteration only refactors numerically. CHOLMOD picks a
 * supernodal factorisation for the 3D meshes here (dense BLAS on the fronts). A
 * matrix that is not positive definite falls back to a simplicial LDL^T of the
 * same pattern (analysed on first need): the tangent of a nearly incompressible
 * solid under large compressive pressure (p > mu, e.g. the relaxed gel under a
 * point load) is legitimately indefinite on a few mesh-scale modes, and Newton
 * still converges quadratically with an indefinite but non-singular tangent. Only
 * a singular matrix is reported (the caller then cuts the time step).
 *
 * Background factorisation (palp_fem_solver_factor_start / _finish): a second
 * factor object of the same symbolic analysis is factorised numerically on a
 * thread of its own, with its own cholmod_common (CHOLMOD keeps its workspace in
 * the common, so two concurrent calls need two) and its own copy of the values,
 * while the caller keeps solving with the current factor; _finish joins the
 * thread and swaps the two factors. The caller decides when to call _finish
 * (fem_model.c: at a fixed step count), so the results never depend on how long
 * the thread took.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include <cholmod.h>

#include "fem_internal.h"

/* OpenBLAS's thread control, when the process runs OpenBLAS (Debian's libblas.so.3
 * alternative); weak, so NULL under any other BLAS. */
extern void openblas_set_num_threads(int n) __attribute__((weak));
extern int openblas_get_num_threads(void) __attribute__((weak));

/* CHOLMOD's calls run with BLAS on one thread: measured at level 4 with OpenBLAS on
 * the 2-core machine, a solve takes 29-31 ms on one thread against 45 ms (load 3)
 * to 131 ms (load 7) on two, whose worker spins on sched_yield between the
 * thousands of small dtrsv/dgemv calls and loses the core to other processes; the
 * factorisation takes 1.0-1.2 s on one thread against 1.1-2.4 s on two (the two
 * vCPUs gave no BLAS-3 speed-up even at load 0.8: 1.09 s). Returns the previous
 * count for blas_restore (0: nothing to restore). */
static int blas_single(void) {
  if (!openblas_set_num_threads || !openblas_get_num_threads) return 0;
  const int t = openblas_get_num_threads();
  if (t > 1) openblas_set_num_threads(1);
  return t > 1 ? t : 0;
}

static void blas_restore(int t) {
  if (t > 1) openblas_set_num_threads(t);
}

/* OpenMP's nesting control, present when CHOLMOD runs with an OpenMP runtime (Debian's
 * links libgomp); weak, so NULL without one. */
extern void omp_set_max_active_levels(int levels) __attribute__((weak));
extern int omp_get_max_active_levels(void) __attribute__((weak));

/* CHOLMOD's factorisations on one thread. Debian's CHOLMOD 5.12 runs loops inside
 * cholmod_super_numeric as OpenMP regions of a fixed num_threads(4) (CHOLMOD_OMP_NUM_THREADS,
 * cholmod_core.h), which OMP_NUM_THREADS and omp_set_num_threads do not lower: four threads
 * on the 2-core machine, meeting at barriers (26.9k futex calls in a 3-depth level-2
 * fingertip run, 3.7-5.6 s of system time in test fem_finger_lesion). With max-active-levels
 * 0 every parallel region is inactive, run by the thread that meets it (measured 2026-12-03
 * with OMP_THREAD_LIMIT=1, the same effect: fem_finger_lesion alone 19.5-21.2 s against
 * 28.6-32.1 s, beside fem_finger_reuse 24.9-27.5 s against 37.0-41.2 s for the pair, the
 * forces the same). Set and restored around each factorisation on the thread that makes
 * it: the OpenMP runtime may keep the setting per thread. Returns the previous setting for
 * omp_restore (-1: no OpenMP runtime). */
static int omp_serial(void) {
  if (!omp_set_max_active_levels || !omp_get_max_active_levels) return -1;
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(0);
  return levels;
}

/* Restores what omp_serial returned (-1: nothing to restore). */
static void omp_restore(int levels) {
  if (levels >= 0) omp_set_max_active_levels(levels);
}

struct palp_fem_solver {
  cholmod_common cc;
  cholmod_sparse *A;
  cholmod_factor *L;
  cholmod_factor *Lldl; /* simplicial LDL^T fallback */
  cholmod_factor *last; /* the factor the next solve uses */
  cholmod_dense *b;
  cholmod_dense *x, *Y, *E; /* reusable workspaces of cholmod_solve2 */
  int n;
  long ldl_count; /* factorisations that needed the LDL^T fallback */
  int shift_index;     /* palp_fem_solver_factor_spd: the shift that worked last */
  long shifted_count;  /* factors of a shifted matrix (preconditioners) */
  /* background factorisation: its own common, values (allocated on first use) and
   * factor (symbolic copy of L made at create, numeric from its first use) */
  cholmod_common bcc;
  int have_bcc;
  cholmod_sparse *A2;
  cholmod_factor *L2;
  pthread_t thread;
  int running;    /* 0 idle; 1 a thread to join; -1 made at _start; -2 to make at _finish (bg_mode 2) */
  int bg_rc;      /* its outcome: PALP_OK or PALP_ESOLVER (not positive definite) */
  int bg_blas;    /* the OpenBLAS thread count to restore when it is joined */
  int bg_mode;    /* palp_fem_solver_set_background_mode */
};

palp_fem_solver *palp_fem_solver_create(int n, const int *colp, const int *rowi, long nnz) {
  palp_fem_solver *s = calloc(1, sizeof *s);
  if (!s) return NULL;
  cholmod_start(&s->cc);
  s->cc.print = 0;
  s->n = n;
  s->A = cholmod_allocate_sparse((size_t)n, (size_t)n, (size_t)(nnz ? nnz : 1), 1, 1, 1, CHOLMOD_REAL, &s->cc);
  s->b = cholmod_zeros((size_t)n, 1, CHOLMOD_REAL, &s->cc);
  if (!s->A || !s->b) {
    palp_fem_solver_destroy(s);
    return NULL;
  }
  memcpy(s->A->p, colp, sizeof(int) * ((size_t)n + 1));
  memcpy(s->A->i, rowi, sizeof(int) * (size_t)nnz);
  /* a symbolic analysis needs no values, but keep them finite */
  double *x = s->A->x;
  for (long k = 0; k < nnz; ++k) x[k] = 0.0;
  s->L = cholmod_analyze(s->A, &s->cc);
  if (!s->L) {
    palp_fem_solver_destroy(s);
    return NULL;
  }
  /* the background factor's symbolic part, copied while L is still symbolic (a copy
   * of the numeric L would copy its values too: 160 MB at level 4); its values are
   * allocated by its first factorisation, on the background thread */
  cholmod_start(&s->bcc);
  s->bcc.print = 0;
  s->have_bcc = 1;
  s->L2 = cholmod_copy_factor(s->L, &s->bcc);
  if (!s->L2) {
    palp_fem_solver_destroy(s);
    return NULL;
  }
  return s;
}

void palp_fem_solver_destroy(palp_fem_solver *s) {
  if (!s) return;
  if (s->running) palp_fem_solver_factor_finish(s, 0);
  if (s->L2) cholmod_free_factor(&s->L2, &s->bcc);
  if (s->A2) cholmod_free_sparse(&s->A2, &s->bcc);
  if (s->have_bcc) cholmod_finish(&s->bcc);
  if (s->L) cholmod_free_factor(&s->L, &s->cc);
  if (s->Lldl) cholmod_free_factor(&s->Lldl, &s->cc);
  if (s->A) cholmod_free_sparse(&s->A, &s->cc);
  if (s->b) cholmod_free_dense(&s->b, &s->cc);
  if (s->x) cholmod_free_dense(&s->x, &s->cc);
  if (s->Y) cholmod_free_dense(&s->Y, &s->cc);
  if (s->E) cholmod_free_dense(&s->E, &s->cc);
  cholmod_finish(&s->cc);
  free(s);
}

static int solver_factor(palp_fem_solver *s, const double *val) {
  const int *p = s->A->p;
  memcpy(s->A->x, val, sizeof(double) * (size_t)p[s->n]);
  s->last = s->L;
  if (cholmod_factorize(s->A, s->L, &s->cc) && s->cc.status == CHOLMOD_OK && s->L->minor >= (size_t)s->n)
    return PALP_OK;
  if (!s->Lldl) {
    const int sn = s->cc.supernodal, ll = s->cc.final_ll;
    s->cc.supernodal = CHOLMOD_SIMPLICIAL;
    s->cc.final_ll = 0;
    s->Lldl = cholmod_analyze(s->A, &s->cc);
    s->cc.supernodal = sn;
    s->cc.final_ll = ll;
    if (!s->Lldl) return PALP_ESOLVER;
  }
  s->ldl_count++;
  s->last = s->Lldl;
  const int ok = cholmod_factorize(s->A, s->Lldl, &s->cc);
  if (!ok || s->Lldl->minor < (size_t)s->n) return PALP_ESOLVER;
  /* a zero or non-finite pivot leaves minor < n; anything else is usable */
  return PALP_OK;
}

static int solver_solve(palp_fem_solver *s, const double *b, double *x) {
  memcpy(s->b->x, b, sizeof(double) * (size_t)s->n);
  if (!cholmod_solve2(CHOLMOD_A, s->last ? s->last : s->L, s->b, NULL, &s->x, NULL, &s->Y, &s->E, &s->cc)) return PALP_ESOLVER;
  memcpy(x, s->x->x, sizeof(double) * (size_t)s->n);
  return PALP_OK;
}

int palp_fem_solver_factor(palp_fem_solver *s, const double *val) {
  const int t = blas_single(), levels = omp_serial();
  const int rc = solver_factor(s, val);
  omp_restore(levels);
  blas_restore(t);
  return rc;
}

/* The supernodal LL^T of A + sigma |diag(A)| (the diagonal is the last entry of
 * each column of the upper triangle) into L; 1 if positive definite. */
static int factor_shifted_once(palp_fem_solver *s, const double *val, double sigma) {
  const int *p = s->A->p, *ri = s->A->i;
  double *x = s->A->x;
  memcpy(x, val, sizeof(double) * (size_t)p[s->n]);
  for (int c = 0; c < s->n; ++c) {
    const int d = p[c + 1] - 1;
    if (d >= p[c] && ri[d] == c) x[d] += sigma * fabs(x[d]);
  }
  s->last = s->L;
  return cholmod_factorize(s->A, s->L, &s->cc) && s->cc.status == CHOLMOD_OK && s->L->minor >= (size_t)s->n;
}

/* A preconditioner for an indefinite tangent that keeps the supernodal LL^T: a
 * matrix that is not positive definite is factorised with its diagonal raised by
 * sigma |a_ii|, sigma = 1e-4 ... 1 (starting from the last one that worked, so a
 * run of indefinite tangents does not pay for the failed attempts every time).
 * Why not the exact LDL^T: CHOLMOD's LDL^T of this pattern is simplicial (no dense
 * kernels), 8x slower than the supernodal LL^T at level 3 (2.2 s against 0.26 s)
 * and more at level 4, and a finger pressed from the last depth's state meets
 * indefinite tangents in most of its first iterates (the surface overlapped by the
 * whole depth step; dropping the contact normal's rotation term did not make them
 * definite; the secant start, fem_finger.c, avoids most). The shifted factor is not of A, so the caller solves with
 * a Krylov method (*shifted = 1). Only if no shift up to 1 gives a positive
 * definite matrix does it fall back to palp_fem_solver_factor (*shifted = 0). */
int palp_fem_solver_factor_spd(palp_fem_solver *s, const double *val, int *shifted) {
  static const double sigmas[] = {1e-4, 1e-3, 1e-2, 1e-1, 1.0};
  const int ns = (int)(sizeof sigmas / sizeof sigmas[0]);
  const int t = blas_single(), levels = omp_serial();
  *shifted = 0;
  int ok = factor_shifted_once(s, val, 0.0);
  for (int k = s->shift_index; !ok && k < ns; ++k)
    if ((ok = factor_shifted_once(s, val, sigmas[k]))) {
      *shifted = 1;
      s->shift_index = k;
      s->shifted_count++;
    }
  int rc = PALP_OK;
  if (!ok) rc = solver_factor(s, val); /* the exact LDL^T */
  else if (!*shifted && s->shift_index > 0)
    s->shift_index--; /* positive definite again: try a smaller shift next time */
  omp_restore(levels);
  blas_restore(t);
  return rc;
}

long palp_fem_solver_shifted_count(const palp_fem_solver *s) { return s->shifted_count; }

int palp_fem_solver_solve(palp_fem_solver *s, const double *b, double *x) {
  const int t = blas_single();
  const int rc = solver_solve(s, b, x);
  blas_restore(t);
  return rc;
}

/* Fill statistics of the factor, for the benchmark and docs. */
double palp_fem_solver_factor_nnz(const palp_fem_solver *s) { return s->cc.lnz; }
double palp_fem_solver_factor_flops(const palp_fem_solver *s) { return s->cc.fl; }
long palp_fem_solver_ldl_count(const palp_fem_solver *s) { return s->ldl_count; }

/* The background thread: a supernodal LL^T of A2 into L2 with the second common.
 * No LDL^T fallback here: a matrix that is not positive definite is reported and
 * the caller factorises it in the foreground, where the fallback lives. */
static void *factor_thread(void *arg) {
  palp_fem_solver *s = arg;
  const int levels = omp_serial();
  const int ok = cholmod_factorize(s->A2, s->L2, &s->bcc);
  omp_restore(levels);
  s->bg_rc = ok && s->bcc.status == CHOLMOD_OK && s->L2->minor >= (size_t)s->n ? PALP_OK : PALP_ESOLVER;
  return NULL;
}

int palp_fem_solver_factor_start(palp_fem_solver *s, const double *val) {
  if (s->running) return PALP_EINVAL;
  if (!s->A2) s->A2 = cholmod_copy_sparse(s->A, &s->bcc);
  if (!s->A2 || !s->L2) return PALP_ENOMEM;
  memcpy(s->A2->x, val, sizeof(double) * (size_t)((const int *)s->A->p)[s->n]);
  /* BLAS on one thread for both factorisations while the thread runs (see
   * blas_single); only this (the caller's) thread changes the count */
  s->bg_blas = blas_single();
  s->bg_rc = PALP_ESOLVER;
  if (s->bg_mode == 2) { /* made at _finish: the slowest possible thread */
    s->running = -2;
    return PALP_OK;
  }
  if (s->bg_mode == 1 || pthread_create(&s->thread, NULL, factor_thread, s)) {
    factor_thread(s); /* here and now (no thread available: the same result) */
    s->running = -1;  /* done, nothing to join */
    return PALP_OK;
  }
  s->running = 1;
  return PALP_OK;
}

void palp_fem_solver_set_background_mode(palp_fem_solver *s, int mode) { s->bg_mode = mode; }

int palp_fem_solver_factor_finish(palp_fem_solver *s, int install) {
  if (!s->running) return PALP_EINVAL;
  if (s->running > 0) pthread_join(s->thread, NULL);
  else if (s->running == -2) factor_thread(s);
  s->running = 0;
  blas_restore(s->bg_blas);
  s->bg_blas = 0;
  if (!install || s->bg_rc) return s->bg_rc;
  cholmod_factor *t = s->L;
  s->L = s->L2;
  s->L2 = t;
  s->last = s->L;
  return PALP_OK;
}

int palp_fem_solver_factor_running(const palp_fem_solver *s) { return s->running != 0; }
