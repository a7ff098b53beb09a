/* sparse_ldl.c - see sparse_ldl.h. */
#include "sparse_ldl.h"

#include <amd.h>
#include <cholmod.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PALP_LDL_X86 1
#endif

#include "palp.h"

static void free_numeric(palp_ldl *f) {
  free(f->bcolp);
  free(f->brow);
  free(f->bval);
  free(f->bdiag);
  free(f->bcol);
  free(f->dinv4);
  free(f->rowp);
  free(f->rcol);
  free(f->bbwd);
  free(f->rbwd);
  f->rowp = f->rcol = f->rbwd = NULL;
  f->bbwd = NULL;
  f->bcolp = f->brow = NULL;
  f->bval = f->bdiag = f->bcol = f->dinv4 = NULL;
  f->nb = 0;
  f->simd = 0;
  free(f->colp);
  free(f->row);
  free(f->val);
  free(f->dinv);
  free(f->perm);
  f->colp = f->row = f->perm = NULL;
  f->val = f->dinv = NULL;
}

void palp_ldl_free(palp_ldl *f) {
  free_numeric(f);
  if (f->common) {
    cholmod_factor *L = f->symbolic;
    cholmod_free_factor(&L, f->common);
    cholmod_finish(f->common);
    free(f->common);
  }
  memset(f, 0, sizeof *f);
}

static int factor(palp_ldl *f, int n, int nnz, const int *ti, const int *tj, const double *tx, int *user_perm) {
  if (f->common && f->n != n) palp_ldl_free(f);
  if (!f->common) {
    memset(f, 0, sizeof *f);
    f->common = malloc(sizeof(cholmod_common));
    if (!f->common) return PALP_ENOMEM;
    cholmod_start(f->common);
    cholmod_common *c0 = f->common;
    c0->print = 0;
    c0->supernodal = CHOLMOD_SIMPLICIAL;
    c0->final_ll = 0; /* keep LDL^T: no square roots, and D is read off directly */
    if (user_perm) {
      /* Keep the given vertex-block order: no etree postordering, which could split
       * a vertex's three unknowns. */
      c0->nmethods = 1;
      c0->method[0].ordering = CHOLMOD_GIVEN;
      c0->postorder = 0;
    }
  }
  cholmod_common *c = f->common;
  int rc = PALP_ESOLVER;
  cholmod_triplet *T = cholmod_allocate_triplet((size_t)n, (size_t)n, (size_t)nnz, -1, CHOLMOD_REAL, c);
  cholmod_sparse *A = NULL;
  cholmod_factor *N = NULL;
  if (!T) goto done;
  int *Ti = T->i, *Tj = T->j;
  double *Tx = T->x;
  for (int k = 0; k < nnz; ++k) {
    Ti[k] = ti[k];
    Tj[k] = tj[k];
    Tx[k] = tx[k];
  }
  T->nnz = (size_t)nnz;
  A = cholmod_triplet_to_sparse(T, (size_t)nnz, c);
  if (!A) goto done;
  if (!f->symbolic) {
    f->symbolic = user_perm ? cholmod_analyze_p(A, user_perm, NULL, 0, c) : cholmod_analyze(A, c);
    if (!f->symbolic) goto done;
  }
  /* Factor a copy of the symbolic analysis, so that it stays reusable. */
  N = cholmod_copy_factor(f->symbolic, c);
  if (!N) goto done;
  if (!cholmod_factorize(A, N, c) || c->status != CHOLMOD_OK || N->minor < (size_t)n) goto done;
  if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, N, c)) goto done;

  free_numeric(f);
  const int *Lp = N->p, *Li = N->i, *Perm = N->Perm;
  const double *Lx = N->x;
  const int lnz = Lp[n] - n; /* diagonal entries (D) come first in each column */
  f->n = n;
  f->colp = malloc(sizeof(int) * ((size_t)n + 1));
  f->row = malloc(sizeof(int) * (size_t)(lnz > 0 ? lnz : 1));
  f->val = malloc(sizeof(double) * (size_t)(lnz > 0 ? lnz : 1));
  f->dinv = malloc(sizeof(double) * (size_t)n);
  f->perm = malloc(sizeof(int) * (size_t)n);
  if (!f->colp || !f->row || !f->val || !f->dinv || !f->perm) {
    free_numeric(f);
    rc = PALP_ENOMEM;
    goto done;
  }
  int q = 0;
  for (int j = 0; j < n; ++j) {
    f->colp[j] = q;
    const double d = Lx[Lp[j]];
    if (!(d > 0.0)) {
      free_numeric(f);
      goto done;
    }
    f->dinv[j] = 1.0 / d;
    for (int p = Lp[j] + 1; p < Lp[j + 1]; ++p) {
      f->row[q] = Li[p];
      f->val[q] = Lx[p];
      ++q;
    }
    f->perm[j] = Perm ? Perm[j] : j;
  }
  f->colp[n] = q;
  f->n = n;
  rc = PALP_OK;
done:
  cholmod_free_factor(&N, c);
  cholmod_free_sparse(&A, c);
  cholmod_free_triplet(&T, c);
  return rc;
}

/* Regroups the scalar factor into 3x3 blocks; returns 0, or -1 when the ordering did
 * not keep each vertex's unknowns together (the scalar form then stays in use). */
static int to_blocks(palp_ldl *f, int nb) {
  const int n = f->n;
  for (int k = 0; k < n; ++k)
    if (f->perm[k] / 3 != f->perm[k - k % 3] / 3 || f->perm[k] % 3 != k % 3) return -1;
  int *mark = malloc(sizeof(int) * (size_t)nb);
  f->bcolp = malloc(sizeof(int) * ((size_t)nb + 1));
  f->bdiag = calloc((size_t)nb * 3, sizeof(double));
  /* Off-diagonal blocks never outnumber the scalar entries. */
  const int cap = f->colp[n] > 0 ? f->colp[n] : 1;
  f->brow = malloc(sizeof(int) * (size_t)cap);
  f->bval = calloc((size_t)cap * 9 + 4, sizeof(double)); /* + 4: the AVX2 path loads 4 lanes from the last 3 */
  if (!mark || !f->bcolp || !f->bdiag || !f->brow || !f->bval) {
    free(mark);
    return PALP_ENOMEM;
  }
  for (int i = 0; i < nb; ++i) mark[i] = -1;
  int nblk = 0;
  for (int J = 0; J < nb; ++J) {
    f->bcolp[J] = nblk;
    for (int c = 0; c < 3; ++c) {
      const int j = 3 * J + c;
      for (int p = f->colp[j]; p < f->colp[j + 1]; ++p) {
        const int i = f->row[p], I = i / 3, r = i % 3;
        if (I == J) { /* strictly lower entry of the diagonal block */
          f->bdiag[3 * J + (r == 1 ? 0 : (c == 0 ? 1 : 2))] = f->val[p];
          continue;
        }
        if (mark[I] < f->bcolp[J]) {
          mark[I] = nblk;
          f->brow[nblk++] = I;
        }
        f->bval[9 * mark[I] + 3 * r + c] = f->val[p];
      }
    }
  }
  f->bcolp[nb] = nblk;
  f->nb = nb;
  free(mark);
#ifdef PALP_LDL_X86
  /* The blocks again by block row, each column-major, for the forward pass of the
   * AVX2 solve (row-oriented: it accumulates in a register instead of scattering
   * into y); the backward pass reads the row-major blocks by column as they are.
   * Within a row the columns ascend, the order the portable path adds them in. */
  f->rowp = calloc((size_t)nb + 1, sizeof(int));
  f->rcol = malloc(sizeof(int) * (size_t)(nblk > 0 ? nblk : 1));
  f->bcol = calloc((size_t)nblk * 9 + 4, sizeof(double));
  f->dinv4 = calloc((size_t)nb * 4, sizeof(double));
  int *fill = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
  if (!f->rowp || !f->rcol || !f->bcol || !f->dinv4 || !fill) {
    free(fill);
    return PALP_ENOMEM;
  }
  for (int p = 0; p < nblk; ++p) f->rowp[f->brow[p] + 1]++;
  for (int I = 0; I < nb; ++I) f->rowp[I + 1] += f->rowp[I];
  memcpy(fill, f->rowp, sizeof(int) * (size_t)nb);
  for (int J = 0; J < nb; ++J)
    for (int p = f->bcolp[J]; p < f->bcolp[J + 1]; ++p) {
      const int q = fill[f->brow[p]]++;
      f->rcol[q] = J;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) f->bcol[9 * q + 3 * c + r] = f->bval[9 * p + 3 * r + c];
    }
  free(fill);
  /* The backward pass walks the columns from last to first: its blocks are stored
   * in that order, so that it streams through memory forwards. */
  f->bbwd = malloc(sizeof(double) * ((size_t)nblk * 9 + 4));
  f->rbwd = malloc(sizeof(int) * (size_t)(nblk > 0 ? nblk : 1));
  if (!f->bbwd || !f->rbwd) return PALP_ENOMEM;
  memset(f->bbwd + (size_t)nblk * 9, 0, 4 * sizeof(double));
  for (int J = nb - 1, q = 0; J >= 0; --J)
    for (int p = f->bcolp[J]; p < f->bcolp[J + 1]; ++p, ++q) {
      f->rbwd[q] = f->brow[p];
      memcpy(f->bbwd + 9 * q, f->bval + 9 * p, 9 * sizeof(double));
    }
  for (int j = 0; j < n; ++j) f->dinv4[4 * (j / 3) + j % 3] = f->dinv[j];
  /* libgcc reads the CPU in a constructor, before main: no __builtin_cpu_init here,
   * which the tangent-rebuild threads would otherwise race on. */
  f->simd = __builtin_cpu_supports("avx2") ? 1 : 0;
#endif
  return PALP_OK;
}

int palp_ldl_factor_blocks(palp_ldl *f, int nb, const int *gp, const int *gi, int nnz, const int *ti,
                           const int *tj, const double *tx) {
  int *perm = NULL;
  if (!f->symbolic) {
    /* AMD on the vertex graph, expanded to unknowns 3v, 3v+1, 3v+2. */
    int *vp = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    perm = malloc(sizeof(int) * (size_t)(3 * nb > 0 ? 3 * nb : 1));
    if (!vp || !perm) {
      free(vp), free(perm);
      return PALP_ENOMEM;
    }
    double control[AMD_CONTROL], info[AMD_INFO];
    amd_defaults(control);
    const int st = amd_order(nb, gp, gi, vp, control, info);
    if (st != AMD_OK && st != AMD_OK_BUT_JUMBLED) {
      free(vp), free(perm);
      return PALP_ESOLVER;
    }
    for (int k = 0; k < nb; ++k)
      for (int c = 0; c < 3; ++c) perm[3 * k + c] = 3 * vp[k] + c;
    free(vp);
  }
  int e = factor(f, 3 * nb, nnz, ti, tj, tx, perm);
  free(perm);
  if (e) return e;
  e = to_blocks(f, nb);
  return e > 0 ? PALP_OK : e == PALP_ENOMEM ? e : PALP_OK;
}

/* Block solve for W interleaved right-hand sides: 3x3 blocks times 3-vectors. A
 * macro so that each width is compiled with W constant (unrolled inner loops). */
#define PALP_LDL_BLOCK_SOLVE_BODY(W)                                                     \
  do {                                                                                   \
    for (int k = 0; k < n; ++k)                                                          \
      for (int r = 0; r < (W); ++r) y[k * (W) + r] = x[f->perm[k] * (W) + r];            \
    for (int J = 0; J < nb; ++J) {                                                       \
      double *yj = y + 3 * J * (W);                                                      \
      /* A unit right-hand side (a compliance column) is nonzero only on its etree   */ \
      /* path: skipping zero blocks saves most of the forward pass for it.           */ \
      int nz = 0;                                                                        \
      for (int r = 0; r < 3 * (W); ++r) nz |= yj[r] != 0.0;                              \
      if (!nz) continue;                                                                 \
      const double *d = f->bdiag + 3 * J;                                                \
      for (int r = 0; r < (W); ++r) {                                                    \
        yj[(W) + r] -= d[0] * yj[r];                                                     \
        yj[2 * (W) + r] -= d[1] * yj[r] + d[2] * yj[(W) + r];                            \
      }                                                                                  \
      for (int p = f->bcolp[J]; p < f->bcolp[J + 1]; ++p) {                              \
        double *yi = y + 3 * f->brow[p] * (W);                                           \
        const double *B = f->bval + 9 * p;                                               \
        for (int r = 0; r < (W); ++r) {                                                  \
          const double a = yj[r], b = yj[(W) + r], c = yj[2 * (W) + r];                  \
          yi[r] -= B[0] * a + B[1] * b + B[2] * c;                                       \
          yi[(W) + r] -= B[3] * a + B[4] * b + B[5] * c;                                 \
          yi[2 * (W) + r] -= B[6] * a + B[7] * b + B[8] * c;                             \
        }                                                                                \
      }                                                                                  \
    }                                                                                    \
    for (int j = 0; j < n; ++j)                                                          \
      for (int r = 0; r < (W); ++r) y[j * (W) + r] *= f->dinv[j];                        \
    for (int J = nb - 1; J >= 0; --J) {                                                  \
      double *yj = y + 3 * J * (W);                                                      \
      for (int p = f->bcolp[J]; p < f->bcolp[J + 1]; ++p) {                              \
        const double *yi = y + 3 * f->brow[p] * (W);                                     \
        const double *B = f->bval + 9 * p;                                               \
        for (int r = 0; r < (W); ++r) {                                                  \
          const double a = yi[r], b = yi[(W) + r], c = yi[2 * (W) + r];                  \
          yj[r] -= B[0] * a + B[3] * b + B[6] * c;                                       \
          yj[(W) + r] -= B[1] * a + B[4] * b + B[7] * c;                                 \
          yj[2 * (W) + r] -= B[2] * a + B[5] * b + B[8] * c;                             \
        }                                                                                \
      }                                                                                  \
      const double *d = f->bdiag + 3 * J;                                                \
      for (int r = 0; r < (W); ++r) {                                                    \
        yj[(W) + r] -= d[2] * yj[2 * (W) + r];                                           \
        yj[r] -= d[0] * yj[(W) + r] + d[1] * yj[2 * (W) + r];                            \
      }                                                                                  \
    }                                                                                    \
    for (int k = 0; k < n; ++k)                                                          \
      for (int r = 0; r < (W); ++r) x[f->perm[k] * (W) + r] = y[k * (W) + r];            \
  } while (0)

#ifdef PALP_LDL_X86
/* The block solve for one right-hand side in AVX2, 4 lanes per vertex (the fourth a
 * pad whose contents are never read back). Each lane does exactly what the portable
 * path does for its row, in the same order and without fused multiply-adds:
 * forward  y_i <- y_i - ((B_0 a + B_1 b) + B_2 c)  (B_k the block's k-th column),
 * backward y_j <- y_j - ((R_0 a + R_1 b) + R_2 c)  (R_k its k-th row, a, b, c = y_i),
 * so both give the same bits. 4-lane loads of 3-entry columns and rows read one entry
 * past them into the pad lane (the arrays carry 4 spare entries at their end). */
/* ((B_0 v_0 + B_1 v_1) + B_2 v_2) for the 3-entry vectors B_k at B, B + 3, B + 6 (each
 * loaded with one entry past it into the pad lane) and the scalars v_0..2. */
__attribute__((target("avx2"))) static inline __m256d block_mv(const double *B, const double *v) {
  __m256d t = _mm256_mul_pd(_mm256_loadu_pd(B), _mm256_broadcast_sd(v));
  t = _mm256_add_pd(t, _mm256_mul_pd(_mm256_loadu_pd(B + 3), _mm256_broadcast_sd(v + 1)));
  return _mm256_add_pd(t, _mm256_mul_pd(_mm256_loadu_pd(B + 6), _mm256_broadcast_sd(v + 2)));
}

__attribute__((target("avx2"))) static void solve_blocks_avx2(const palp_ldl *f, double *x, double *y) {
  const int nb = f->nb, n = f->n;
  y = (double *)(((uintptr_t)y + 31) & ~(uintptr_t)31); /* no 32-byte access split across cache lines */
  for (int k = 0; k < nb; ++k) y[4 * k + 3] = 0.0;
  for (int k = 0; k < n; ++k) y[4 * (k / 3) + k % 3] = x[f->perm[k]];
  for (int I = 0; I < nb; ++I) {
    double *yi = y + 4 * I;
    __m256d acc = _mm256_loadu_pd(yi);
    for (int q = f->rowp[I]; q < f->rowp[I + 1]; ++q)
      acc = _mm256_sub_pd(acc, block_mv(f->bcol + 9 * q, y + 4 * f->rcol[q]));
    _mm256_storeu_pd(yi, acc);
    const double *d = f->bdiag + 3 * I;
    yi[1] -= d[0] * yi[0];
    yi[2] -= d[1] * yi[0] + d[2] * yi[1];
  }
  for (int k = 0; k < nb; ++k)
    _mm256_storeu_pd(y + 4 * k, _mm256_mul_pd(_mm256_loadu_pd(y + 4 * k), _mm256_loadu_pd(f->dinv4 + 4 * k)));
  for (int J = nb - 1, q = 0; J >= 0; --J) {
    double *yj = y + 4 * J;
    __m256d acc = _mm256_loadu_pd(yj);
    for (const int qend = q + f->bcolp[J + 1] - f->bcolp[J]; q < qend; ++q)
      acc = _mm256_sub_pd(acc, block_mv(f->bbwd + 9 * q, y + 4 * f->rbwd[q]));
    _mm256_storeu_pd(yj, acc);
    const double *d = f->bdiag + 3 * J;
    yj[1] -= d[2] * yj[2];
    yj[0] -= d[0] * yj[1] + d[1] * yj[2];
  }
  for (int k = 0; k < n; ++k) x[f->perm[k]] = y[4 * (k / 3) + k % 3];
}
#endif

static void solve_blocks(const palp_ldl *f, double *x, int w, double *y) {
  const int nb = f->nb, n = f->n;
#ifdef PALP_LDL_X86
  if (w == 1 && f->simd) {
    solve_blocks_avx2(f, x, y);
    return;
  }
#endif
  switch (w) {
  case 1: PALP_LDL_BLOCK_SOLVE_BODY(1); break;
  case 2: PALP_LDL_BLOCK_SOLVE_BODY(2); break;
  default: PALP_LDL_BLOCK_SOLVE_BODY(w); break;
  }
}

/* A = P^T L D L^T P: y = P b; L z = y; z /= D; L^T w = z; x = P^T w. */
#define PALP_LDL_SOLVE_BODY(W)                                                                  \
  do {                                                                                          \
    for (int k = 0; k < n; ++k)                                                                 \
      for (int r = 0; r < (W); ++r) y[k * (W) + r] = x[f->perm[k] * (W) + r];                   \
    for (int j = 0; j < n; ++j) {                                                               \
      const double *yj = y + j * (W);                                                           \
      for (int p = f->colp[j]; p < f->colp[j + 1]; ++p) {                                       \
        double *yi = y + f->row[p] * (W);                                                       \
        const double l = f->val[p];                                                             \
        for (int r = 0; r < (W); ++r) yi[r] -= l * yj[r];                                       \
      }                                                                                         \
    }                                                                                           \
    for (int j = 0; j < n; ++j)                                                                 \
      for (int r = 0; r < (W); ++r) y[j * (W) + r] *= f->dinv[j];                               \
    for (int j = n - 1; j >= 0; --j) {                                                          \
      double *yj = y + j * (W);                                                                 \
      for (int p = f->colp[j]; p < f->colp[j + 1]; ++p) {                                       \
        const double *yi = y + f->row[p] * (W);                                                 \
        const double l = f->val[p];                                                             \
        for (int r = 0; r < (W); ++r) yj[r] -= l * yi[r];                                       \
      }                                                                                         \
    }                                                                                           \
    for (int k = 0; k < n; ++k)                                                                 \
      for (int r = 0; r < (W); ++r) x[f->perm[k] * (W) + r] = y[k * (W) + r];                   \
  } while (0)

void palp_ldl_solve(const palp_ldl *f, double *x, int w, double *y) {
  const int n = f->n;
  if (f->nb) {
    solve_blocks(f, x, w, y);
    return;
  }
  /* Constant widths let the compiler unroll the inner loops. */
  switch (w) {
  case 1: PALP_LDL_SOLVE_BODY(1); break;
  case 2: PALP_LDL_SOLVE_BODY(2); break;
  default: PALP_LDL_SOLVE_BODY(w); break;
  }
}
