/* sparse_ldl.c - see sparse_ldl.h. */
#include "sparse_ldl.h"

#include <amd.h>
#include <cholmod.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

static void free_numeric(palp_ldl *f) {
  free(f->bcolp);
  free(f->brow);
  free(f->bval);
  free(f->bdiag);
  f->bcolp = f->brow = NULL;
  f->bval = f->bdiag = NULL;
  f->nb = 0;
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
  f->bval = calloc((size_t)cap * 9, sizeof(double));
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

static void solve_blocks(const palp_ldl *f, double *x, int w, double *y) {
  const int nb = f->nb, n = f->n;
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
