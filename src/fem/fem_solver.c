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
#include <immintrin.h>

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

/* A foreground factorisation's settings (both above), saved by serial_enter and put back
 * by serial_leave. */
typedef struct serial_state {
  int blas, levels;
} serial_state;

static serial_state serial_enter(void) {
  const serial_state st = {blas_single(), omp_serial()};
  return st;
}

static void serial_leave(serial_state st) {
  omp_restore(st.levels);
  blas_restore(st.blas);
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
  /* L rounded to single precision for the Krylov solver's preconditioner
   * (palp_fem_solver_precond), made at its first use after each factorisation (on
   * the background thread it delayed the renewals: at factor_lag 4 the frames waited
   * 0.17-0.68 s a run for them, none with the copy made here, ~2e7 entries at level 4);
   * lf_valid: made from L's current values. pv: [largest supernode's rows], py: [n]. */
  float *lf;
  size_t lf_len;
  int lf_valid;
  double *pv, *py;
  int simd; /* 1: the AVX2 kernels (the CPU has them, and the tests did not ask for the portable ones) */
};

palp_fem_solver *palp_fem_solver_create(int n, const int *colp, const int *rowi, long nnz) {
  palp_fem_solver *s = calloc(1, sizeof *s);
  if (!s) return NULL;
  cholmod_start(&s->cc);
  s->cc.print = 0;
  s->n = n;
  s->simd = __builtin_cpu_supports("avx2") != 0;
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
  free(s->lf), free(s->pv), free(s->py);
  free(s);
}

static int solver_factor(palp_fem_solver *s, const double *val) {
  const int *p = s->A->p;
  s->lf_valid = 0;
  memcpy(s->A->x, val, sizeof(double) * (size_t)p[s->n]);
  s->last = s->L;
  if (cholmod_factorize(s->A, s->L, &s->cc) && s->cc.status == CHOLMOD_OK && s->L->minor >= (size_t)s->n)
    return PALP_OK;
  /* out of memory is not an indefinite matrix: no LDL^T retry, and the step stops at once
   * with "out of memory" instead of cutting back 8 times (since session 82) */
  if (s->cc.status == CHOLMOD_OUT_OF_MEMORY) return PALP_ENOMEM;
  if (!s->Lldl) {
    const int sn = s->cc.supernodal, ll = s->cc.final_ll;
    s->cc.supernodal = CHOLMOD_SIMPLICIAL;
    s->cc.final_ll = 0;
    s->Lldl = cholmod_analyze(s->A, &s->cc);
    s->cc.supernodal = sn;
    s->cc.final_ll = ll;
    if (!s->Lldl) return s->cc.status == CHOLMOD_OUT_OF_MEMORY ? PALP_ENOMEM : PALP_ESOLVER;
  }
  s->ldl_count++;
  s->last = s->Lldl;
  const int ok = cholmod_factorize(s->A, s->Lldl, &s->cc);
  if (s->cc.status == CHOLMOD_OUT_OF_MEMORY) return PALP_ENOMEM;
  if (!ok || s->Lldl->minor < (size_t)s->n) return PALP_ESOLVER;
  /* a zero or non-finite pivot leaves minor < n; anything else is usable */
  return PALP_OK;
}

static int solver_solve(palp_fem_solver *s, const double *b, double *x) {
  memcpy(s->b->x, b, sizeof(double) * (size_t)s->n);
  if (!cholmod_solve2(CHOLMOD_A, s->last ? s->last : s->L, s->b, NULL, &s->x, NULL, &s->Y, &s->E, &s->cc))
    return s->cc.status == CHOLMOD_OUT_OF_MEMORY ? PALP_ENOMEM : PALP_ESOLVER;
  memcpy(x, s->x->x, sizeof(double) * (size_t)s->n);
  return PALP_OK;
}

int palp_fem_solver_factor(palp_fem_solver *s, const double *val) {
  const serial_state st = serial_enter();
  const int rc = solver_factor(s, val);
  serial_leave(st);
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
  s->lf_valid = 0;
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
  const serial_state st = serial_enter();
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
  serial_leave(st);
  return rc;
}

long palp_fem_solver_shifted_count(const palp_fem_solver *s) { return s->shifted_count; }

/* ---- the preconditioner's single-precision solve -------------------------- *
 * A Krylov iteration (fem_model.c) asks the factor for z = M^-1 r dozens of times per
 * frame, and at level 4 each solve reads the supernodal L (nnz(L) 2e7, 160 MB in
 * double) twice: 25 ms of memory traffic, more than half a frame's time. The same L
 * rounded to single precision is half the bytes. M~ = L~ L~^T with |L~ - L| <= 2^-24 |L|
 * is still symmetric positive definite (a perturbation of L, not of A), so it is as
 * valid a CG preconditioner as M; the iteration's own residuals stay in double, and
 * its answer is held to the same tolerance. The solves that stand for A^-1 itself (a
 * Newton step with a fresh factor, the direct solve after a stall) keep the double L
 * (palp_fem_solver_solve). */

/* f <- L's values in single precision, same layout (supernodal LL^T only).
 * Returns 0, or -1 (not supernodal, or out of memory: the caller solves in double). */
static int factor_to_float(const cholmod_factor *L, float **f, size_t *len) {
  if (!L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL) return -1;
  const size_t nx = ((const int *)L->px)[L->nsuper];
  if (*len < nx) {
    float *g = realloc(*f, sizeof(float) * (nx ? nx : 1));
    if (!g) return -1;
    *f = g, *len = nx;
  }
  const double *x = L->x;
  float *restrict o = *f;
  for (size_t k = 0; k < nx; ++k) o[k] = (float)x[k];
  return 0;
}

/* The single-precision solve's kernels, the factor's entries widened to double. Four
 * columns at a time, so v (the supernode's rows, in the cache) is read once for four
 * columns of the factor (streamed from memory): one column at a time, v's traffic was
 * twice the factor's and the solve no faster than CHOLMOD's double one. Fixed orders of
 * operations (no fused multiply-add), so the AVX2 versions give the portable ones' bits.
 * fwd4: v[i] -= (c0 v0 + c1 v1) + (c2 v2 + c3 v3), i0 <= i < n.
 * dot4: d[q] = sum_i cq[i] v[i] as four lanes of stride 4, summed (l0 + l2) + (l1 + l3). */
static void fwd4(const float *const c[4], double *restrict v, const double w[4], int i0, int n) {
  for (int i = i0; i < n; ++i)
    v[i] -= ((double)c[0][i] * w[0] + (double)c[1][i] * w[1]) + ((double)c[2][i] * w[2] + (double)c[3][i] * w[3]);
}

static void dot4(const float *const c[4], const double *restrict v, int i0, int n, double d[4]) {
  for (int q = 0; q < 4; ++q) {
    double a[4] = {0};
    int i = i0;
    for (; i + 3 < n; i += 4)
      for (int l = 0; l < 4; ++l) a[l] += (double)c[q][i + l] * v[i + l];
    double t = (a[0] + a[2]) + (a[1] + a[3]);
    for (; i < n; ++i) t += (double)c[q][i] * v[i];
    d[q] = t;
  }
}

__attribute__((target("avx2"))) static inline __m256d wide(const float *c) { return _mm256_cvtps_pd(_mm_loadu_ps(c)); }

__attribute__((target("avx2"))) static void fwd4_avx2(const float *const c[4], double *restrict v, const double w[4],
                                                       int i0, int n) {
  const __m256d w0 = _mm256_set1_pd(w[0]), w1 = _mm256_set1_pd(w[1]), w2 = _mm256_set1_pd(w[2]),
                w3 = _mm256_set1_pd(w[3]);
  int i = i0;
  for (; i + 3 < n; i += 4) {
    const __m256d t01 = _mm256_add_pd(_mm256_mul_pd(wide(c[0] + i), w0), _mm256_mul_pd(wide(c[1] + i), w1));
    const __m256d t23 = _mm256_add_pd(_mm256_mul_pd(wide(c[2] + i), w2), _mm256_mul_pd(wide(c[3] + i), w3));
    _mm256_storeu_pd(v + i, _mm256_sub_pd(_mm256_loadu_pd(v + i), _mm256_add_pd(t01, t23)));
  }
  for (; i < n; ++i)
    v[i] -= ((double)c[0][i] * w[0] + (double)c[1][i] * w[1]) + ((double)c[2][i] * w[2] + (double)c[3][i] * w[3]);
}

__attribute__((target("avx2"))) static void dot4_avx2(const float *const c[4], const double *restrict v, int i0,
                                                       int n, double d[4]) {
  __m256d a0 = _mm256_setzero_pd(), a1 = a0, a2 = a0, a3 = a0;
  int i = i0;
  for (; i + 3 < n; i += 4) {
    const __m256d vi = _mm256_loadu_pd(v + i);
    a0 = _mm256_add_pd(a0, _mm256_mul_pd(wide(c[0] + i), vi));
    a1 = _mm256_add_pd(a1, _mm256_mul_pd(wide(c[1] + i), vi));
    a2 = _mm256_add_pd(a2, _mm256_mul_pd(wide(c[2] + i), vi));
    a3 = _mm256_add_pd(a3, _mm256_mul_pd(wide(c[3] + i), vi));
  }
  double a[4][4];
  _mm256_storeu_pd(a[0], a0), _mm256_storeu_pd(a[1], a1), _mm256_storeu_pd(a[2], a2), _mm256_storeu_pd(a[3], a3);
  for (int q = 0; q < 4; ++q) {
    double t = (a[q][0] + a[q][2]) + (a[q][1] + a[q][3]);
    for (int k = i; k < n; ++k) t += (double)c[q][k] * v[k];
    d[q] = t;
  }
}

/* x = (L~ L~^T)^-1 P b P^T: y = P b; L~ y' = y by supernodes, forward; L~^T x' = y'
 * backward; x = P^T x'. Each supernode (columns k1..k2-1, nsrow rows listed in Ls, the
 * first nscol of them k1..k2-1) is one column-major nsrow x nscol block; v [nsrow]
 * holds its rows in double while the block is streamed once, four columns at a time
 * (the last nscol mod 4 one at a time, as blocks with zero weights would read past it). */
static void solve_float(const cholmod_factor *L, const float *lf, const double *b, double *x, double *y, double *v,
                        int simd) {
  const int n = (int)L->n, ns = (int)L->nsuper;
  const int *super = L->super, *pi = L->pi, *px = L->px, *Ls = L->s, *perm = L->Perm;
  for (int k = 0; k < n; ++k) y[k] = b[perm[k]];
  for (int s = 0; s < ns; ++s) { /* L y' = y */
    const int k1 = super[s], nscol = super[s + 1] - k1, nsrow = pi[s + 1] - pi[s];
    const int *rows = Ls + pi[s];
    const float *blk = lf + px[s];
    for (int i = 0; i < nscol; ++i) v[i] = y[k1 + i];
    for (int i = nscol; i < nsrow; ++i) v[i] = 0.0;
    int j = 0;
    for (; j + 3 < nscol; j += 4) {
      const float *c[4];
      double w[4];
      for (int q = 0; q < 4; ++q) c[q] = blk + (size_t)(j + q) * (size_t)nsrow;
      for (int q = 0; q < 4; ++q) { /* the 4x4 diagonal block */
        w[q] = v[j + q] / c[q][j + q];
        v[j + q] = w[q];
        for (int r = q + 1; r < 4; ++r) v[j + r] -= (double)c[q][j + r] * w[q];
      }
      if (simd) fwd4_avx2(c, v, w, j + 4, nsrow);
      else fwd4(c, v, w, j + 4, nsrow);
    }
    for (; j < nscol; ++j) {
      const float *c = blk + (size_t)j * (size_t)nsrow;
      const double vj = v[j] / c[j];
      v[j] = vj;
      for (int i = j + 1; i < nsrow; ++i) v[i] -= (double)c[i] * vj;
    }
    for (int i = 0; i < nscol; ++i) y[k1 + i] = v[i];
    for (int i = nscol; i < nsrow; ++i) y[rows[i]] += v[i];
  }
  for (int s = ns - 1; s >= 0; --s) { /* L^T x' = y' */
    const int k1 = super[s], nscol = super[s + 1] - k1, nsrow = pi[s + 1] - pi[s];
    const int *rows = Ls + pi[s];
    const float *blk = lf + px[s];
    for (int i = 0; i < nscol; ++i) v[i] = y[k1 + i];
    for (int i = nscol; i < nsrow; ++i) v[i] = y[rows[i]];
    int j = nscol - 1;
    for (; j >= 0 && (j + 1) % 4 != 0; --j) { /* the last nscol mod 4 columns, one at a time */
      const float *c = blk + (size_t)j * (size_t)nsrow;
      double t = 0.0;
      for (int i = j + 1; i < nsrow; ++i) t += (double)c[i] * v[i];
      v[j] = (v[j] - t) / c[j];
    }
    for (; j >= 3; j -= 4) { /* columns j-3..j: their dots over the rows below j at once */
      const int j0 = j - 3;
      const float *c[4];
      double d[4];
      for (int q = 0; q < 4; ++q) c[q] = blk + (size_t)(j0 + q) * (size_t)nsrow;
      if (simd) dot4_avx2(c, v, j + 1, nsrow, d);
      else dot4(c, v, j + 1, nsrow, d);
      for (int q = 3; q >= 0; --q) { /* the 4x4 diagonal block, from its last row */
        double t = v[j0 + q] - d[q];
        for (int r = q + 1; r < 4; ++r) t -= (double)c[q][j0 + r] * v[j0 + r];
        v[j0 + q] = t / c[q][j0 + q];
      }
    }
    for (int i = 0; i < nscol; ++i) y[k1 + i] = v[i];
  }
  for (int k = 0; k < n; ++k) x[perm[k]] = y[k];
}

int palp_fem_solver_precond(palp_fem_solver *s, const double *b, double *x) {
  const cholmod_factor *L = s->L;
  if (s->last != s->L || !L->is_super) return palp_fem_solver_solve(s, b, x);
  if (!s->lf_valid) s->lf_valid = factor_to_float(L, &s->lf, &s->lf_len) == 0;
  if (!s->py) s->py = malloc(sizeof(double) * (size_t)(s->n ? s->n : 1));
  if (!s->pv) { /* sized once for the largest supernode's rows: the pattern never changes */
    size_t rows = 1;
    for (size_t q = 0; q < L->nsuper; ++q) {
      const size_t r = (size_t)(((const int *)L->pi)[q + 1] - ((const int *)L->pi)[q]);
      if (r > rows) rows = r;
    }
    s->pv = malloc(sizeof(double) * rows);
  }
  if (!s->lf_valid || !s->py || !s->pv) return palp_fem_solver_solve(s, b, x);
  solve_float(L, s->lf, b, x, s->py, s->pv, s->simd);
  return PALP_OK;
}

void palp_fem_solver_set_precond_simd(palp_fem_solver *s, int on) {
  s->simd = on && __builtin_cpu_supports("avx2");
}

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
  s->lf_valid = 0;
  return PALP_OK;
}

int palp_fem_solver_factor_running(const palp_fem_solver *s) { return s->running != 0; }
