/*
 * sparse_ldl.h - a fixed sparse LDL^T factor with fast multi-right-hand-side solves.
 *
 * CHOLMOD (SuiteSparse) orders (AMD) and factors the matrix once per time step
 * size; the per-step solves then run here over plain arrays, because cholmod_solve
 * allocates its dense operands on every call, which costs more than the solve itself
 * at the model's size (a few hundred unknowns). Right-hand sides are interleaved,
 * w values per unknown, so each factor entry is loaded once for all of them.
 */
#ifndef PALP_SPARSE_LDL_H
#define PALP_SPARSE_LDL_H

typedef struct palp_ldl {
  int n;
  int *colp;   /* [n+1] column starts of the strictly lower part of L (unit diagonal) */
  int *row;    /* [nnz] row indices (in permuted order) */
  double *val; /* [nnz] */
  double *dinv; /* [n] 1 / D */
  int *perm;   /* [n] permuted index -> original index */
} palp_ldl;

/* Factors the symmetric positive definite matrix given by lower-triangle triplets
 * (i >= j; duplicates are summed). Returns 0, PALP_ENOMEM or PALP_ESOLVER. */
int palp_ldl_factor(palp_ldl *f, int n, int nnz, const int *ti, const int *tj, const double *tx);
void palp_ldl_free(palp_ldl *f);

/* Solves A X = B in place for w interleaved right-hand sides (x[i*w + k]);
 * work needs n*w doubles. */
void palp_ldl_solve(const palp_ldl *f, double *x, int w, double *work);

#endif
