/* sparse_ldl.c - see sparse_ldl.h. */
#include "sparse_ldl.h"

#include <cholmod.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

void palp_ldl_free(palp_ldl *f) {
  free(f->colp);
  free(f->row);
  free(f->val);
  free(f->dinv);
  free(f->perm);
  memset(f, 0, sizeof *f);
}

int palp_ldl_factor(palp_ldl *f, int n, int nnz, const int *ti, const int *tj, const double *tx) {
  memset(f, 0, sizeof *f);
  cholmod_common c;
  cholmod_start(&c);
  c.print = 0;
  c.supernodal = CHOLMOD_SIMPLICIAL;
  c.final_ll = 0; /* keep LDL^T: no square roots, and D is read off directly */
  int rc = PALP_ESOLVER;
  cholmod_triplet *T = cholmod_allocate_triplet((size_t)n, (size_t)n, (size_t)nnz, -1, CHOLMOD_REAL, &c);
  cholmod_sparse *A = NULL;
  cholmod_factor *L = NULL;
  if (!T) goto done;
  int *Ti = T->i, *Tj = T->j;
  double *Tx = T->x;
  for (int k = 0; k < nnz; ++k) {
    Ti[k] = ti[k];
    Tj[k] = tj[k];
    Tx[k] = tx[k];
  }
  T->nnz = (size_t)nnz;
  A = cholmod_triplet_to_sparse(T, (size_t)nnz, &c);
  if (!A) goto done;
  L = cholmod_analyze(A, &c);
  if (!L) goto done;
  if (!cholmod_factorize(A, L, &c) || c.status != CHOLMOD_OK || L->minor < (size_t)n) goto done;
  if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, L, &c)) goto done;

  const int *Lp = L->p, *Li = L->i, *Perm = L->Perm;
  const double *Lx = L->x;
  const int lnz = Lp[n] - n; /* diagonal entries (D) come first in each column */
  f->n = n;
  f->colp = malloc(sizeof(int) * ((size_t)n + 1));
  f->row = malloc(sizeof(int) * (size_t)(lnz > 0 ? lnz : 1));
  f->val = malloc(sizeof(double) * (size_t)(lnz > 0 ? lnz : 1));
  f->dinv = malloc(sizeof(double) * (size_t)n);
  f->perm = malloc(sizeof(int) * (size_t)n);
  if (!f->colp || !f->row || !f->val || !f->dinv || !f->perm) {
    palp_ldl_free(f);
    rc = PALP_ENOMEM;
    goto done;
  }
  int q = 0;
  for (int j = 0; j < n; ++j) {
    f->colp[j] = q;
    const double d = Lx[Lp[j]];
    if (!(d > 0.0)) {
      palp_ldl_free(f);
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
  rc = PALP_OK;
done:
  cholmod_free_factor(&L, &c);
  cholmod_free_sparse(&A, &c);
  cholmod_free_triplet(&T, &c);
  cholmod_finish(&c);
  return rc;
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
  /* Constant widths let the compiler unroll the inner loops. */
  switch (w) {
  case 1: PALP_LDL_SOLVE_BODY(1); break;
  case 2: PALP_LDL_SOLVE_BODY(2); break;
  default: PALP_LDL_SOLVE_BODY(w); break;
  }
}
