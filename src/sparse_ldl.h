/*
 * sparse_ldl.h - a fixed sparse LDL^T factor with fast multi-right-hand-side solves.
 *
 * CHOLMOD (SuiteSparse) analyses the pattern (with an AMD vertex ordering) and factors
 * the matrix the first time; later factorisations of the same pattern (tangent
 * rebuilds, a new step size) are numeric only and run here by 3x3 blocks, 2.9x
 * faster at the model's size. The per-step solves run here over plain arrays, because cholmod_solve
 * allocates its dense operands on every call, which costs more than the solve itself
 * at the model's size (a few hundred unknowns). Right-hand sides are interleaved,
 * w values per unknown, so each factor entry is loaded once for all of them.
 *
 * L's entries are rounded to single precision (D and the arithmetic stay double):
 * the solve is then exact, to double rounding, for A~ = L~ D L~^T with |L~ - L| <=
 * 2^-24 |L|, still symmetric positive definite, and the factor is half the bytes. A
 * server core steps many sessions in turn, so each step finds its factor out of the
 * caches, and the solve's time is the time to stream the factor in (docs/model.md:
 * one copy of the blocks, a cold solve takes 0.53-0.57x the time it did). The model's
 * own tangent is lagged by far more than 2^-24 (it is rebuilt only when a link has
 * turned by 30 degrees or its tension stiffness has left a margin, world.c), so the
 * rounding is not seen in its results beyond the bits (test model_sparse_ldl bounds
 * the residual).
 */
#ifndef PALP_SPARSE_LDL_H
#define PALP_SPARSE_LDL_H

#include <stddef.h>

typedef struct palp_ldl {
  void *symbolic; /* CHOLMOD's analysis (ordering, pattern), kept across refactorisations */
  void *common;   /* the cholmod_common it belongs to */
  int n;
  int *colp;   /* [n+1] column starts of the strictly lower part of L (unit diagonal) */
  int *row;    /* [nnz] row indices (in permuted order) */
  double *val; /* [nnz] (rounded to single precision, below) */
  double *dinv; /* [n] 1 / D */
  int *perm;   /* [n] permuted index -> original index */
  /* Block form (palp_ldl_factor_blocks): L in 3x3 vertex blocks, one index per block,
   * its off-diagonal blocks in single precision (below), by block column. */
  int nb;         /* block columns (vertices); 0 when the scalar form is used */
  int *bcolp;     /* [nb+1] starts of each block column's off-diagonal blocks */
  int *brow;      /* [nblocks] block row of each, ascending within a column */
  float *blk;     /* [nblocks*9 + 4] the blocks, each column-major */
  double *bdiag;  /* [nb*3] strictly lower part of each diagonal block: l10, l20, l21 */
  double *dinv4;  /* [nb*4] 1/D padded to 4 lanes per vertex */
  int nested;     /* 1: the vertices were ordered by nested dissection (vertex_order), 0: by AMD */
  int simd;       /* 1: palp_ldl_solve (w <= 4) and the block factorisation take their AVX2 paths (same bits as the portable ones) */
  /* The block numeric factorisation (palp_ldl_factor_blocks): */
  int *dest;      /* [ndest] where each triplet lands among L's blocks, then the diagonal blocks */
  int ndest;
  int *iwork;     /* [4*nb] row -> block of the current column, list heads, links, next rows */
  /* L in double while it is made, kept between rebuilds when it is at most
   * PALP_LDL_KEEP_NUM bytes: a fresh one each time page-faulted in anew (a rebuild's
   * page faults were ~20% of its time on 1,300 vertices; docs/model.md). */
  double *num;
  size_t num_len; /* doubles num holds */
} palp_ldl;

#define PALP_LDL_KEEP_NUM ((size_t)16 << 20)
/* Nested dissection is tried for nets of this many vertices and more, and taken when it
 * needs at most this share of AMD's factorisation flops (sparse_ldl.c vertex_order). */
#define PALP_LDL_ND_MIN 600
#define PALP_LDL_ND_GAIN 0.9

void palp_ldl_free(palp_ldl *f); /* frees everything, the analysis included */

/* Factors the symmetric positive definite matrix of 3x3 blocks (unknown 3v + c
 * belongs to vertex v) given by lower-triangle triplets (i >= j; duplicates summed).
 * The first call orders the vertices on the vertex graph (CSC, both triangles, nb
 * vertices) by AMD, or by nested dissection on a net of PALP_LDL_ND_MIN vertices and
 * more where that factors with fewer flops (palp_ldl.nested), keeping each vertex's 3
 * unknowns together, and has CHOLMOD
 * analyse the pattern and factor once, which gives L's block pattern; later calls with
 * the same triplets' rows and columns in the same order (the caller's promise, as for
 * CHOLMOD's analysis; gp, gi may then be NULL) redo only the numeric
 * factorisation, here, by 3x3 blocks (left-looking: each block column gathers the
 * updates of the columns to its left, then is scaled by its diagonal block's
 * L D L^T). The first call's factor is redone the same way, so every factor of a
 * matrix is the same bits whichever call made it. The factor is stored and solved in
 * dense 3x3 blocks (scalar form, CHOLMOD's, if the ordering split a vertex).
 * Returns 0, PALP_ENOMEM or PALP_ESOLVER. */
int palp_ldl_factor_blocks(palp_ldl *f, int nb, const int *gp, const int *gi, int nnz, const int *ti,
                           const int *tj, const double *tx);

/* Solves A X = B in place for w interleaved right-hand sides (x[i*w + k]);
 * work needs palp_ldl_work_size(n, w) doubles. */
void palp_ldl_solve(const palp_ldl *f, double *x, int w, double *work);

/* The doubles palp_ldl_solve's work needs for n unknowns and w right-hand sides:
 * max(n w, 4 ceil(n / 3), 4 n for 2 <= w <= 4 (the AVX2 paths' lanes)) + 4 (their
 * 32-byte alignment). */
size_t palp_ldl_work_size(int n, int w);

/* The factor's etree by blocks and unit right-hand sides along it (a block factor, nb > 0):
 * blk[v] the block column of vertex v, parent[J] block column J's etree parent (-1 at a
 * root; every row of L's column J is an ancestor of J). Returns the longest path's length. */
int palp_ldl_etree(const palp_ldl *f, int *blk, int *parent);
/* z = L^{-1} P e for vertex v's 3 unit right-hand sides (3v + c), which lies on the path from
 * its block column J0 = blk[v] to the root: the forward pass walked along it alone, the same
 * operations in the same order as palp_ldl_solve's forward pass. Writes the path's block
 * columns to path and z there to val ([n][9], component i of right-hand side c at 3i + c);
 * zw is 9 nb doubles, zero before and after. Returns the path's length n. */
int palp_ldl_unit_path(const palp_ldl *f, int J0, const int *parent, double *zw, int *path, double *val);
/* The 3x3 block of A^{-1} between two vertices from their paths (palp_ldl_unit_path), out[3i + j]
 * = A^{-1} at (3 v_a + i, 3 v_b + j) = the sum over the common ancestors J of z_a D^{-1} z_b
 * (A = P^T L D L^T P). */
void palp_ldl_path_block(const palp_ldl *f, const int *pa, const double *va, int na, const int *pb, const double *vb,
                         int nb, double out[9]);

#endif
