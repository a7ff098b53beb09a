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
  free(f->bdiag);
  free(f->brow);
  free(f->blk);
  free(f->dinv4);
  f->bcolp = f->brow = NULL;
  f->blk = NULL;
  f->bdiag = f->dinv4 = NULL;
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

static void free_block_numeric(palp_ldl *f) {
  free(f->dest), free(f->iwork), free(f->num);
  f->dest = f->iwork = NULL;
  f->num = NULL;
  f->ndest = 0;
  f->num_len = 0;
}

void palp_ldl_free(palp_ldl *f) {
  free_numeric(f);
  free_block_numeric(f);
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
      f->val[q] = (double)(float)Lx[p]; /* single precision: sparse_ldl.h */
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

/* Regroups the scalar factor into 3x3 blocks in single precision, by block column
 * (rows ascending within a column), each block column-major: both passes read this
 * one copy, the forward one from the first column to the last, the backward one from
 * the last to the first. Returns 0, PALP_ENOMEM, or -1 when the ordering did not keep
 * each vertex's unknowns together (the scalar form then stays in use). */
static int to_blocks(palp_ldl *f, int nb) {
  const int n = f->n;
  for (int k = 0; k < n; ++k)
    if (f->perm[k] / 3 != f->perm[k - k % 3] / 3 || f->perm[k] % 3 != k % 3) return -1;
  /* Off-diagonal blocks never outnumber the scalar entries. */
  const int cap = f->colp[n] > 0 ? f->colp[n] : 1;
  int *mark = malloc(sizeof(int) * (size_t)nb);
  f->bcolp = malloc(sizeof(int) * ((size_t)nb + 1));
  f->bdiag = calloc((size_t)nb * 3, sizeof(double));
  f->brow = malloc(sizeof(int) * (size_t)cap);
  f->blk = calloc((size_t)cap * 9 + 4, sizeof(float)); /* + 4: 4-lane loads of a block's last 3 entries read one past it */
  f->dinv4 = calloc((size_t)nb * 4, sizeof(double));
  if (!mark || !f->bcolp || !f->bdiag || !f->brow || !f->blk || !f->dinv4) {
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
        f->blk[9 * mark[I] + 3 * c + r] = (float)f->val[p]; /* exact: val is already rounded */
      }
    }
  }
  f->bcolp[nb] = nblk;
  free(mark);
  for (int j = 0; j < n; ++j) f->dinv4[4 * (j / 3) + j % 3] = f->dinv[j];
  f->nb = nb;
#ifdef PALP_LDL_X86
  /* libgcc reads the CPU in a constructor, before main: no __builtin_cpu_init here,
   * which the tangent-rebuild threads would otherwise race on. */
  f->simd = __builtin_cpu_supports("avx2") ? 1 : 0;
#endif
  return PALP_OK;
}

/* Where each triplet (ti, tj) lands among L's blocks (pattern bcolp, brow, in the
 * permuted order; an entry above the diagonal taken as its transpose), then the
 * diagonal blocks: 9 doubles each, column-major. Returns 0, PALP_ENOMEM, or 1 when an
 * entry falls outside L's pattern. */
static int block_map(palp_ldl *f, int nnz, const int *ti, const int *tj) {
  const int nb = f->nb, n = f->n, nblk = f->bcolp[nb];
  free_block_numeric(f);
  f->dest = malloc(sizeof(int) * (size_t)(nnz > 0 ? nnz : 1));
  f->iwork = malloc(sizeof(int) * 4 * (size_t)(nb > 0 ? nb : 1));
  int *iperm = malloc(sizeof(int) * (size_t)(n > 0 ? n : 1));
  if (!f->dest || !f->iwork || !iperm) {
    free(iperm);
    free_block_numeric(f);
    return PALP_ENOMEM;
  }
  for (int k = 0; k < n; ++k) iperm[f->perm[k]] = k;
  for (int k = 0; k < nnz; ++k) {
    int pi = iperm[ti[k]], pj = iperm[tj[k]];
    if (pi < pj) { /* within one block too: there pi < pj is r < c */
      const int t = pi;
      pi = pj, pj = t;
    }
    const int I = pi / 3, r = pi % 3, J = pj / 3, c = pj % 3;
    int at = -1;
    if (I == J) {
      at = nblk * 9 + 9 * J + 3 * c + r;
    } else { /* rows ascend within a block column */
      int lo = f->bcolp[J], hi = f->bcolp[J + 1] - 1;
      while (lo <= hi) {
        const int mid = (lo + hi) / 2;
        if (f->brow[mid] == I) {
          at = 9 * mid + 3 * c + r;
          break;
        }
        if (f->brow[mid] < I) lo = mid + 1;
        else hi = mid - 1;
      }
    }
    if (at < 0) {
      free(iperm);
      free_block_numeric(f);
      return 1;
    }
    f->dest[k] = at;
  }
  free(iperm);
  f->ndest = nnz;
  return PALP_OK;
}

/* Column J's updates from column K, whose block p is in row J: with Y = L_JK D_K
 * (Y[s][c] at 3 c + s),
 *   A_JJ -= L_JK Y^T (lower part: (r, s) -= sum_c L[r][c] Y[s][c]) and
 *   A_IJ -= L_IK Y^T for K's blocks q below p (I = brow[q], at slot[I] among J's),
 * each entry (L[r] Y[s] + L[3 + r] Y[3 + s]) + L[6 + r] Y[6 + s], subtracted: the
 * order every path keeps (block_numeric). X holds L's blocks, d = D_K's block;
 * column_update_diag makes Y and the diagonal block's part for both paths. */
static inline void column_update_diag(const double *restrict L, const double *restrict d, double *restrict a,
                                      double y[9]) {
  y[0] = L[0] * d[0], y[1] = L[1] * d[0], y[2] = L[2] * d[0], y[3] = L[3] * d[4], y[4] = L[4] * d[4];
  y[5] = L[5] * d[4], y[6] = L[6] * d[8], y[7] = L[7] * d[8], y[8] = L[8] * d[8];
  for (int sc = 0; sc < 3; ++sc)
    for (int r = sc; r < 3; ++r) a[3 * sc + r] -= (L[r] * y[sc] + L[3 + r] * y[3 + sc]) + L[6 + r] * y[6 + sc];
}

static inline void column_update(double *restrict X, const double *restrict d, double *restrict a,
                                 const int *restrict brow, const int *restrict slot, int p, int end) {
  double y[9];
  column_update_diag(X + 9 * (size_t)p, d, a, y);
  for (int q = p + 1; q < end; ++q) {
    const double *restrict B = X + 9 * (size_t)q;
    double *restrict T = X + 9 * (size_t)slot[brow[q]];
    for (int sc = 0; sc < 3; ++sc)
      for (int r = 0; r < 3; ++r) T[3 * sc + r] -= (B[r] * y[sc] + B[3 + r] * y[3 + sc]) + B[6 + r] * y[6 + sc];
  }
}

#ifdef PALP_LDL_X86
/* column_update in AVX2: a target block's 9 entries (column-major, k = 3 s + r) as
 * lanes k = 0-3 and 4-7 and a scalar for k = 8, each lane given its B[r + 3c] and
 * Y[s + 3c] (the block's columns permuted into the lanes' rows; Y's once per call),
 * so that each lane does the portable path's operations for its entry, in its order,
 * without fused multiply-adds: the same bits. The stores cover the block exactly (a
 * store overlapping the next load in part would stall store forwarding). The three
 * column loads read one value past the block's last column: the next block's first,
 * or after the last block the first diagonal block's, inside the array, never used. */
__attribute__((target("avx2"))) static void column_update_avx2(double *X, const double *d, double *a,
                                                               const int *restrict brow, const int *restrict slot,
                                                               int p, int end) {
  double y[9];
  column_update_diag(X + 9 * (size_t)p, d, a, y);
  /* lanes k = 0-3: (s, r) = (0,0) (0,1) (0,2) (1,0); k = 4-7: (1,1) (1,2) (2,0) (2,1) */
  const __m256d ya0 = _mm256_setr_pd(y[0], y[0], y[0], y[1]), ya1 = _mm256_setr_pd(y[3], y[3], y[3], y[4]),
                ya2 = _mm256_setr_pd(y[6], y[6], y[6], y[7]);
  const __m256d yb0 = _mm256_setr_pd(y[1], y[1], y[2], y[2]), yb1 = _mm256_setr_pd(y[4], y[4], y[5], y[5]),
                yb2 = _mm256_setr_pd(y[7], y[7], y[8], y[8]);
  for (int q = p + 1; q < end; ++q) {
    const double *B = X + 9 * (size_t)q;
    double *T = X + 9 * (size_t)slot[brow[q]];
    const __m256d c0 = _mm256_loadu_pd(B), c1 = _mm256_loadu_pd(B + 3), c2 = _mm256_loadu_pd(B + 6);
    /* rows (0, 1, 2, 0) and (1, 2, 0, 1) of each column */
    const __m256d a0 = _mm256_permute4x64_pd(c0, 0x24), a1 = _mm256_permute4x64_pd(c1, 0x24),
                  a2 = _mm256_permute4x64_pd(c2, 0x24);
    const __m256d b0 = _mm256_permute4x64_pd(c0, 0x49), b1 = _mm256_permute4x64_pd(c1, 0x49),
                  b2 = _mm256_permute4x64_pd(c2, 0x49);
    const __m256d ua = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a0, ya0), _mm256_mul_pd(a1, ya1)), _mm256_mul_pd(a2, ya2));
    const __m256d ub = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(b0, yb0), _mm256_mul_pd(b1, yb1)), _mm256_mul_pd(b2, yb2));
    _mm256_storeu_pd(T, _mm256_sub_pd(_mm256_loadu_pd(T), ua));
    _mm256_storeu_pd(T + 4, _mm256_sub_pd(_mm256_loadu_pd(T + 4), ub));
    T[8] -= (B[2] * y[2] + B[5] * y[5]) + B[8] * y[8];
  }
}
#endif

/* The numeric factorisation in 3x3 blocks over L's pattern, left-looking, from the
 * triplet values tx (block_map's pattern). Block column J gathers, for each column K
 * to its left with a block in row J, A_IJ -= L_IK D_K L_JK^T for the rows I >= J of
 * column K (the columns waiting on row J are linked in a list, each moved on to its
 * next row once used: Gilbert & Peierls' left-looking scheme, here by blocks), then
 * factors its diagonal block A_JJ = L_JJ D_J L_JJ^T and scales L_IJ = A_IJ L_JJ^-T D_J^-1.
 * Every operation in a fixed order, no fused multiply-add: the same bits on any
 * x86-64 machine. L's blocks are then rounded to single precision (sparse_ldl.h).
 * Returns 0, PALP_ENOMEM or PALP_ESOLVER (a pivot not positive: not positive definite);
 * on failure the factor held before is left as it was. */
static int block_numeric(palp_ldl *f, int nnz, const double *tx) {
  const int nb = f->nb, nblk = f->bcolp[nb];
  const int *restrict bcolp = f->bcolp, *restrict brow = f->brow;
  /* L in double while it is made: ~0.5 MB at 338 vertices. A world keeps three factors
   * (its own, the one a blend replaces, a job's spare), so it is kept between rebuilds
   * only up to PALP_LDL_KEEP_NUM bytes (sparse_ldl.h); larger, made and freed here. */
  const size_t len = (size_t)nblk * 9 + (size_t)nb * 9;
  const int keep = sizeof(double) * len <= PALP_LDL_KEEP_NUM;
  double *num = keep && f->num && f->num_len == len ? f->num : NULL;
  if (!num) {
    free(f->num);
    f->num = NULL, f->num_len = 0;
    num = malloc(sizeof(double) * len);
    if (!num) return PALP_ENOMEM;
    if (keep) f->num = num, f->num_len = len;
  }
  double *restrict X = num, *restrict Dg = num + (size_t)nblk * 9;
  int *restrict slot = f->iwork, *restrict head = f->iwork + nb, *restrict link = f->iwork + 2 * nb,
                *restrict next = f->iwork + 3 * nb;
  memset(X, 0, sizeof(double) * ((size_t)nblk * 9 + (size_t)nb * 9));
  for (int k = 0; k < nnz; ++k) X[f->dest[k]] += tx[k];
  for (int J = 0; J < nb; ++J) slot[J] = -1, head[J] = -1;
  for (int J = 0; J < nb; ++J) {
    for (int q = bcolp[J]; q < bcolp[J + 1]; ++q) slot[brow[q]] = q;
    double *restrict a = Dg + 9 * J; /* column-major 3x3: (r, c) at 3 c + r, lower part used */
    for (int K = head[J]; K >= 0;) {
      const int K_next = link[K], p = next[K];
#ifdef PALP_LDL_X86
      if (f->simd) column_update_avx2(X, Dg + 9 * K, a, brow, slot, p, bcolp[K + 1]);
      else
#endif
        column_update(X, Dg + 9 * K, a, brow, slot, p, bcolp[K + 1]);
      next[K] = p + 1;
      if (p + 1 < bcolp[K + 1]) {
        const int I = brow[p + 1];
        link[K] = head[I], head[I] = K;
      }
      K = K_next;
    }
    /* A_JJ = L_JJ D_J L_JJ^T: d0 at 0, l10 at 1, l20 at 2, d1 at 4, l21 at 5, d2 at 8 */
    const double d0 = a[0];
    if (!(d0 > 0.0)) goto not_spd;
    const double l10 = a[1] / d0, l20 = a[2] / d0;
    const double d1 = a[4] - l10 * a[1];
    if (!(d1 > 0.0)) goto not_spd;
    const double l21 = (a[5] - l20 * a[1]) / d1;
    const double d2 = (a[8] - l20 * a[2]) - l21 * l21 * d1;
    if (!(d2 > 0.0)) goto not_spd;
    a[1] = l10, a[2] = l20, a[4] = d1, a[5] = l21, a[8] = d2;
    /* L_IJ = A_IJ L_JJ^-T D_J^-1, row by row: z L_JJ^T = a_r, then z / d */
    for (int q = bcolp[J]; q < bcolp[J + 1]; ++q) {
      double *restrict B = X + 9 * (size_t)q;
      for (int r = 0; r < 3; ++r) {
        const double z0 = B[r], z1 = B[3 + r] - l10 * z0, z2 = (B[6 + r] - l20 * z0) - l21 * z1;
        B[r] = z0 / d0, B[3 + r] = z1 / d1, B[6 + r] = z2 / d2;
      }
      slot[brow[q]] = -1;
    }
    if (bcolp[J] < bcolp[J + 1]) {
      next[J] = bcolp[J];
      const int I = brow[bcolp[J]];
      link[J] = head[I], head[I] = J;
    }
  }
  for (size_t k = 0; k < (size_t)nblk * 9; ++k) f->blk[k] = (float)X[k];
  for (int J = 0; J < nb; ++J) {
    const double *a = Dg + 9 * J;
    f->bdiag[3 * J] = a[1], f->bdiag[3 * J + 1] = a[2], f->bdiag[3 * J + 2] = a[5];
    for (int c = 0; c < 3; ++c) f->dinv[3 * J + c] = f->dinv4[4 * J + c] = 1.0 / a[4 * c]; /* both solve paths' copies */
    f->dinv4[4 * J + 3] = 0.0;
  }
  if (num != f->num) free(num);
  return PALP_OK;
not_spd:
  if (num != f->num) free(num);
  return PALP_ESOLVER;
}

/* The vertex graph (CSC, both triangles) as CHOLMOD's symmetric pattern (its upper
 * triangle read), or NULL. */
static cholmod_sparse *vertex_graph(int nb, const int *gp, const int *gi, cholmod_common *c) {
  cholmod_sparse *G = cholmod_allocate_sparse((size_t)nb, (size_t)nb, (size_t)gp[nb], 0, 1, 1, CHOLMOD_PATTERN, c);
  if (!G) return NULL;
  memcpy(G->p, gp, sizeof(int) * ((size_t)nb + 1));
  memcpy(G->i, gi, sizeof(int) * (size_t)gp[nb]);
  return G;
}

/* The factorisation's flops [-] of the vertex graph eliminated in the order vp, from
 * CHOLMOD's symbolic analysis (no postordering, as factor() keeps the given order); -1
 * when it fails. */
static double order_flops(int nb, const int *gp, const int *gi, int *vp, cholmod_common *c) {
  cholmod_sparse *G = vertex_graph(nb, gp, gi, c);
  if (!G) return -1.0;
  c->nmethods = 1;
  c->method[0].ordering = CHOLMOD_GIVEN;
  c->postorder = 0;
  cholmod_factor *L = cholmod_analyze_p(G, vp, NULL, 0, c);
  const double fl = L ? c->fl : -1.0;
  cholmod_free_factor(&L, c);
  cholmod_free_sparse(&G, c);
  return fl;
}

/* The vertices' elimination order into vp: AMD, or for a net of PALP_LDL_ND_MIN vertices
 * and more CHOLMOD's nested dissection (METIS separators, CAMD within) when its
 * factorisation takes at most PALP_LDL_ND_GAIN of AMD's flops. Why: on the dome's
 * surface net AMD's fill grows faster than a separator order's; at 1,300 vertices
 * nested dissection needs ~26% fewer flops to factor (a rebuild's main cost there) and
 * ~10% fewer blocks in L (every solve), at 338 ~4% fewer blocks, which is not worth the
 * bits of every shipped phantom's sessions (docs/model.md, "The factor's order on a finer net").
 * Both orders are deterministic (METIS with its fixed seed). Returns 1 for nested
 * dissection, 0 for AMD, or an error. */
static int vertex_order(int nb, const int *gp, const int *gi, int *vp) {
  double control[AMD_CONTROL], info[AMD_INFO];
  amd_defaults(control);
  const int st = amd_order(nb, gp, gi, vp, control, info);
  if (st != AMD_OK && st != AMD_OK_BUT_JUMBLED) return PALP_ESOLVER;
  if (nb < PALP_LDL_ND_MIN) return 0;
  int *nd = malloc(sizeof(int) * 3 * (size_t)nb);
  cholmod_common c;
  if (!nd) return 0; /* AMD serves */
  cholmod_start(&c);
  c.print = 0;
  int use = 0;
  cholmod_sparse *G = vertex_graph(nb, gp, gi, &c);
  if (G) {
    const long nc = cholmod_nested_dissection(G, NULL, 0, nd, nd + nb, nd + 2 * nb, &c);
    cholmod_free_sparse(&G, &c);
    if (nc > 0 && c.status == CHOLMOD_OK) {
      const double fa = order_flops(nb, gp, gi, vp, &c), fn = order_flops(nb, gp, gi, nd, &c);
      if (fa > 0.0 && fn > 0.0 && fn <= PALP_LDL_ND_GAIN * fa) use = 1;
    }
  }
  cholmod_finish(&c);
  if (use) memcpy(vp, nd, sizeof(int) * (size_t)nb);
  free(nd);
  return use;
}

int palp_ldl_factor_blocks(palp_ldl *f, int nb, const int *gp, const int *gi, int nnz, const int *ti,
                           const int *tj, const double *tx) {
  /* The same pattern as the factor already held: the numeric part by blocks alone. */
  if (f->symbolic && f->nb == nb && nb > 0 && f->dest && f->ndest == nnz) return block_numeric(f, nnz, tx);
  int *perm = NULL, nested = -1;
  if (!f->symbolic) {
    /* AMD or nested dissection on the vertex graph (vertex_order), expanded to unknowns 3v, 3v+1, 3v+2. */
    int *vp = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    perm = malloc(sizeof(int) * (size_t)(3 * nb > 0 ? 3 * nb : 1));
    if (!vp || !perm) {
      free(vp), free(perm);
      return PALP_ENOMEM;
    }
    const int ord = vertex_order(nb, gp, gi, vp);
    if (ord < 0) {
      free(vp), free(perm);
      return ord;
    }
    nested = ord;
    for (int k = 0; k < nb; ++k)
      for (int c = 0; c < 3; ++c) perm[3 * k + c] = 3 * vp[k] + c;
    free(vp);
  }
  int e = factor(f, 3 * nb, nnz, ti, tj, tx, perm);
  free(perm);
  if (e) return e;
  if (nested >= 0) f->nested = nested; /* after factor(), which starts a new palp_ldl cleared */
  e = to_blocks(f, nb);
  if (e == PALP_ENOMEM) return e;
  if (e) return PALP_OK; /* the ordering split a vertex: CHOLMOD's scalar factor serves */
  /* L's block pattern is known: the map of the triplets into it, and this factor redone
   * by blocks, as every later one will be. */
  e = block_map(f, nnz, ti, tj);
  if (e < 0) return e;
  if (e > 0) return PALP_OK; /* an entry outside the pattern: keep CHOLMOD's factor */
  return block_numeric(f, nnz, tx);
}

/* y_J <- L_JJ^{-1} y_J for the unit lower diagonal block (l10, l20, l21), w wide. */
static inline void palp_ldl_diag_fwd(const double *d, double *yj, int w) {
  for (int r = 0; r < w; ++r) {
    yj[w + r] -= d[0] * yj[r];
    yj[2 * w + r] -= d[1] * yj[r] + d[2] * yj[w + r];
  }
}

/* Block solve for W interleaved right-hand sides, by block column in both passes:
 *   forward,  column J ascending:  y_J <- L_JJ^{-1} y_J, then for each block B below
 *             it (row I)  y_I <- y_I - ((B_0 a + B_1 b) + B_2 c),  B_k its k-th column,
 *             (a, b, c) = y_J;
 *   backward, column J descending: s_c = sum over the column's blocks, in order, of
 *             B_c (*) y_I (elementwise, one partial sum per row r), then
 *             y_J[c] <- y_J[c] - ((s_c[0] + s_c[1]) + s_c[2]), then L_JJ^{-T}.
 * One copy of the blocks serves both passes (a server core's step finds it out of the
 * caches: bytes are time). The AVX2 paths (for 1-3 right-hand sides, lanes over a
 * vertex's components; for 4, a lane per right-hand side) do the same operations in
 * the same order, lane by lane and without fused multiply-adds, so every path and width
 * gives the same bits (test model_sparse_ldl). With several right-hand
 * sides (compliance columns: unit vectors, nonzero only on their etree path) the
 * forward pass skips a column whose values are all zero; one right-hand side (the
 * step's, dense) never skips, on either path, so that they agree even in the sign of a
 * zero. A macro so that each width is compiled with W constant. */
#define PALP_LDL_BLOCK_SOLVE_BODY(W)                                                     \
  do {                                                                                   \
    for (int k = 0; k < n; ++k)                                                          \
      for (int r = 0; r < (W); ++r) y[k * (W) + r] = x[f->perm[k] * (W) + r];            \
    for (int J = 0; J < nb; ++J) {                                                       \
      double *yj = y + 3 * J * (W);                                                      \
      palp_ldl_diag_fwd(f->bdiag + 3 * J, yj, (W));                                      \
      if ((W) > 1) {                                                                     \
        int nz = 0;                                                                      \
        for (int e = 0; e < 3 * (W); ++e) nz |= yj[e] != 0.0;                            \
        if (!nz) continue;                                                               \
      }                                                                                  \
      for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {                              \
        double *yi = y + 3 * f->brow[q] * (W);                                           \
        const float *B = f->blk + 9 * q;                                                 \
        for (int i = 0; i < 3; ++i)                                                      \
          for (int r = 0; r < (W); ++r)                                                  \
            yi[i * (W) + r] -= ((double)B[i] * yj[r] + (double)B[3 + i] * yj[(W) + r]) + \
                               (double)B[6 + i] * yj[2 * (W) + r];                       \
      }                                                                                  \
    }                                                                                    \
    for (int j = 0; j < n; ++j)                                                          \
      for (int r = 0; r < (W); ++r) y[j * (W) + r] *= f->dinv[j];                        \
    for (int J = nb - 1; J >= 0; --J) {                                                  \
      double *yj = y + 3 * J * (W);                                                      \
      double sum[3][3][(W)];                                                             \
      memset(sum, 0, sizeof sum);                                                        \
      for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {                              \
        const double *v = y + 3 * f->brow[q] * (W);                                      \
        const float *B = f->blk + 9 * q;                                                 \
        for (int c = 0; c < 3; ++c)                                                      \
          for (int i = 0; i < 3; ++i)                                                    \
            for (int r = 0; r < (W); ++r) sum[c][i][r] += (double)B[3 * c + i] * v[i * (W) + r]; \
      }                                                                                  \
      for (int c = 0; c < 3; ++c)                                                        \
        for (int r = 0; r < (W); ++r)                                                    \
          yj[c * (W) + r] -= (sum[c][0][r] + sum[c][1][r]) + sum[c][2][r];               \
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
 * pad, never read back into the others): lane i does what the portable path does for
 * component i (forward) or row i's partial sum (backward). A block's columns are
 * loaded as 4 single-precision lanes, the fourth one past the column (the array
 * carries 4 spare entries), and widened exactly to double. */
__attribute__((target("avx2"))) static inline __m256d col4(const float *B) { return _mm256_cvtps_pd(_mm_loadu_ps(B)); }

__attribute__((target("avx2"))) static void solve_blocks_avx2(const palp_ldl *f, double *x, double *y) {
  const int nb = f->nb, n = f->n;
  y = (double *)(((uintptr_t)y + 31) & ~(uintptr_t)31); /* no 32-byte access split across cache lines */
  for (int k = 0; k < nb; ++k) y[4 * k + 3] = 0.0;
  for (int k = 0; k < n; ++k) y[4 * (k / 3) + k % 3] = x[f->perm[k]];
  for (int J = 0; J < nb; ++J) {
    double *yj = y + 4 * J;
    palp_ldl_diag_fwd(f->bdiag + 3 * J, yj, 1);
    const __m256d a = _mm256_broadcast_sd(yj), b = _mm256_broadcast_sd(yj + 1), c = _mm256_broadcast_sd(yj + 2);
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      double *yi = y + 4 * f->brow[q];
      const float *B = f->blk + 9 * q;
      __m256d t = _mm256_mul_pd(col4(B), a);
      t = _mm256_add_pd(t, _mm256_mul_pd(col4(B + 3), b));
      t = _mm256_add_pd(t, _mm256_mul_pd(col4(B + 6), c));
      _mm256_store_pd(yi, _mm256_sub_pd(_mm256_load_pd(yi), t));
    }
  }
  for (int k = 0; k < nb; ++k)
    _mm256_store_pd(y + 4 * k, _mm256_mul_pd(_mm256_load_pd(y + 4 * k), _mm256_loadu_pd(f->dinv4 + 4 * k)));
  for (int J = nb - 1; J >= 0; --J) {
    double *yj = y + 4 * J;
    __m256d s0 = _mm256_setzero_pd(), s1 = s0, s2 = s0;
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      const __m256d v = _mm256_load_pd(y + 4 * f->brow[q]);
      const float *B = f->blk + 9 * q;
      s0 = _mm256_add_pd(s0, _mm256_mul_pd(col4(B), v));
      s1 = _mm256_add_pd(s1, _mm256_mul_pd(col4(B + 3), v));
      s2 = _mm256_add_pd(s2, _mm256_mul_pd(col4(B + 6), v));
    }
    double l0[4], l1[4], l2[4];
    _mm256_storeu_pd(l0, s0), _mm256_storeu_pd(l1, s1), _mm256_storeu_pd(l2, s2);
    yj[0] -= (l0[0] + l0[1]) + l0[2];
    yj[1] -= (l1[0] + l1[1]) + l1[2];
    yj[2] -= (l2[0] + l2[1]) + l2[2];
    const double *d = f->bdiag + 3 * J;
    yj[1] -= d[2] * yj[2];
    yj[0] -= d[0] * yj[1] + d[1] * yj[2];
  }
  for (int k = 0; k < n; ++k) x[f->perm[k]] = y[4 * (k / 3) + k % 3];
}

/* The block solve for 2-4 right-hand sides in AVX2 (taken for 4; 2 and 3 take
 * solve_blocks_avx2_vlanes, below, which it is the reference for), one lane per right-hand side (the
 * lanes past w a pad of zeros, which every operation keeps +0): each unknown's w values
 * sit in 4 lanes, each block entry is broadcast, and every lane does what the portable
 * macro does for its right-hand side, in its order and without fused multiply-adds,
 * including the forward pass's skip of a block column whose values are all zero (NaN
 * counts as nonzero, as there). y needs 4 n + 4 doubles. */
__attribute__((target("avx2"))) static void solve_blocks_avx2_lanes(const palp_ldl *f, double *x, int w, double *y) {
  const int nb = f->nb, n = f->n;
  y = (double *)(((uintptr_t)y + 31) & ~(uintptr_t)31);
  for (int k = 0; k < n; ++k) {
    double *yk = y + 4 * k;
    yk[0] = yk[1] = yk[2] = yk[3] = 0.0;
    for (int r = 0; r < w; ++r) yk[r] = x[f->perm[k] * w + r];
  }
  const __m256d zero = _mm256_setzero_pd();
  for (int J = 0; J < nb; ++J) {
    double *yj = y + 12 * J;
    const double *d = f->bdiag + 3 * J;
    __m256d a = _mm256_load_pd(yj), b = _mm256_load_pd(yj + 4), c = _mm256_load_pd(yj + 8);
    b = _mm256_sub_pd(b, _mm256_mul_pd(_mm256_set1_pd(d[0]), a));
    c = _mm256_sub_pd(c, _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(d[1]), a), _mm256_mul_pd(_mm256_set1_pd(d[2]), b)));
    _mm256_store_pd(yj + 4, b), _mm256_store_pd(yj + 8, c);
    const __m256d nz = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(a, zero, _CMP_NEQ_UQ), _mm256_cmp_pd(b, zero, _CMP_NEQ_UQ)),
                                    _mm256_cmp_pd(c, zero, _CMP_NEQ_UQ));
    if (!_mm256_movemask_pd(nz)) continue;
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      double *yi = y + 12 * f->brow[q];
      const float *B = f->blk + 9 * q;
      for (int i = 0; i < 3; ++i) {
        const __m256d t = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd((double)B[i]), a),
                                                      _mm256_mul_pd(_mm256_set1_pd((double)B[3 + i]), b)),
                                        _mm256_mul_pd(_mm256_set1_pd((double)B[6 + i]), c));
        _mm256_store_pd(yi + 4 * i, _mm256_sub_pd(_mm256_load_pd(yi + 4 * i), t));
      }
    }
  }
  for (int j = 0; j < n; ++j) _mm256_store_pd(y + 4 * j, _mm256_mul_pd(_mm256_load_pd(y + 4 * j), _mm256_set1_pd(f->dinv[j])));
  for (int J = nb - 1; J >= 0; --J) {
    double *yj = y + 12 * J;
    __m256d s[3][3];
    for (int cc = 0; cc < 3; ++cc)
      for (int i = 0; i < 3; ++i) s[cc][i] = zero;
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      const double *v = y + 12 * f->brow[q];
      const float *B = f->blk + 9 * q;
      const __m256d v0 = _mm256_load_pd(v), v1 = _mm256_load_pd(v + 4), v2 = _mm256_load_pd(v + 8);
      for (int cc = 0; cc < 3; ++cc) {
        s[cc][0] = _mm256_add_pd(s[cc][0], _mm256_mul_pd(_mm256_set1_pd((double)B[3 * cc]), v0));
        s[cc][1] = _mm256_add_pd(s[cc][1], _mm256_mul_pd(_mm256_set1_pd((double)B[3 * cc + 1]), v1));
        s[cc][2] = _mm256_add_pd(s[cc][2], _mm256_mul_pd(_mm256_set1_pd((double)B[3 * cc + 2]), v2));
      }
    }
    __m256d y3[3];
    for (int cc = 0; cc < 3; ++cc)
      y3[cc] = _mm256_sub_pd(_mm256_load_pd(yj + 4 * cc), _mm256_add_pd(_mm256_add_pd(s[cc][0], s[cc][1]), s[cc][2]));
    const double *d = f->bdiag + 3 * J;
    y3[1] = _mm256_sub_pd(y3[1], _mm256_mul_pd(_mm256_set1_pd(d[2]), y3[2]));
    y3[0] = _mm256_sub_pd(y3[0], _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(d[0]), y3[1]),
                                               _mm256_mul_pd(_mm256_set1_pd(d[1]), y3[2])));
    for (int cc = 0; cc < 3; ++cc) _mm256_store_pd(yj + 4 * cc, y3[cc]);
  }
  for (int k = 0; k < n; ++k)
    for (int r = 0; r < w; ++r) x[f->perm[k] * w + r] = y[4 * k + r];
}
#endif

#ifdef PALP_LDL_X86
/* The block solve for 2 or 3 right-hand sides in AVX2, lanes over a vertex's components
 * as for one (solve_blocks_avx2), a vertex's w right-hand sides side by side: each
 * block column is widened once for all w (the lanes path widened and broadcast its 9
 * entries one by one, twice the instructions in the backward pass, which a compliance
 * column's solve is mostly: the forward one skips its zeros). For each right-hand side
 * lane i does what the lanes path does in its lane for component i (forward) or row
 * i's partial sum (backward), in its order and without fused multiply-adds, the
 * forward skip included: the same bits. y needs 4 w n / 3 + 4 doubles. */
__attribute__((target("avx2"))) static void solve_blocks_avx2_vlanes(const palp_ldl *f, double *x, int w, double *y) {
  const int nb = f->nb, n = f->n;
  y = (double *)(((uintptr_t)y + 31) & ~(uintptr_t)31);
  for (int k = 0; k < nb * w; ++k) y[4 * k + 3] = 0.0;
  for (int k = 0; k < n; ++k)
    for (int r = 0; r < w; ++r) y[4 * ((k / 3) * w + r) + k % 3] = x[f->perm[k] * w + r];
  for (int J = 0; J < nb; ++J) {
    double *yj = y + 4 * (size_t)J * w;
    const double *d = f->bdiag + 3 * J;
    int nz = 0;
    for (int r = 0; r < w; ++r) {
      double *v = yj + 4 * r;
      v[1] -= d[0] * v[0];
      v[2] -= d[1] * v[0] + d[2] * v[1];
      nz |= (v[0] != 0.0) | (v[1] != 0.0) | (v[2] != 0.0);
    }
    if (!nz) continue;
    __m256d a[3], b[3], c[3];
    for (int r = 0; r < w; ++r)
      a[r] = _mm256_broadcast_sd(yj + 4 * r), b[r] = _mm256_broadcast_sd(yj + 4 * r + 1),
      c[r] = _mm256_broadcast_sd(yj + 4 * r + 2);
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      double *yi = y + 4 * (size_t)f->brow[q] * w;
      const float *B = f->blk + 9 * q;
      const __m256d c0 = col4(B), c1 = col4(B + 3), c2 = col4(B + 6);
      for (int r = 0; r < w; ++r) {
        __m256d t = _mm256_mul_pd(c0, a[r]);
        t = _mm256_add_pd(t, _mm256_mul_pd(c1, b[r]));
        t = _mm256_add_pd(t, _mm256_mul_pd(c2, c[r]));
        _mm256_store_pd(yi + 4 * r, _mm256_sub_pd(_mm256_load_pd(yi + 4 * r), t));
      }
    }
  }
  for (int k = 0; k < nb; ++k) {
    const __m256d s = _mm256_loadu_pd(f->dinv4 + 4 * k);
    for (int r = 0; r < w; ++r) {
      double *v = y + 4 * ((size_t)k * w + r);
      _mm256_store_pd(v, _mm256_mul_pd(_mm256_load_pd(v), s));
    }
  }
  const __m256d zero = _mm256_setzero_pd();
  for (int J = nb - 1; J >= 0; --J) {
    double *yj = y + 4 * (size_t)J * w;
    __m256d s[3][3];
    for (int r = 0; r < w; ++r) s[r][0] = s[r][1] = s[r][2] = zero;
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      const double *v = y + 4 * (size_t)f->brow[q] * w;
      const float *B = f->blk + 9 * q;
      const __m256d c0 = col4(B), c1 = col4(B + 3), c2 = col4(B + 6);
      for (int r = 0; r < w; ++r) {
        const __m256d vr = _mm256_load_pd(v + 4 * r);
        s[r][0] = _mm256_add_pd(s[r][0], _mm256_mul_pd(c0, vr));
        s[r][1] = _mm256_add_pd(s[r][1], _mm256_mul_pd(c1, vr));
        s[r][2] = _mm256_add_pd(s[r][2], _mm256_mul_pd(c2, vr));
      }
    }
    const double *d = f->bdiag + 3 * J;
    for (int r = 0; r < w; ++r) {
      double l0[4], l1[4], l2[4], *v = yj + 4 * r;
      _mm256_storeu_pd(l0, s[r][0]), _mm256_storeu_pd(l1, s[r][1]), _mm256_storeu_pd(l2, s[r][2]);
      v[0] -= (l0[0] + l0[1]) + l0[2];
      v[1] -= (l1[0] + l1[1]) + l1[2];
      v[2] -= (l2[0] + l2[1]) + l2[2];
      v[1] -= d[2] * v[2];
      v[0] -= d[0] * v[1] + d[1] * v[2];
    }
  }
  for (int k = 0; k < n; ++k)
    for (int r = 0; r < w; ++r) x[f->perm[k] * w + r] = y[4 * ((k / 3) * w + r) + k % 3];
}
#endif

static void solve_blocks(const palp_ldl *f, double *x, int w, double *y) {
  const int nb = f->nb, n = f->n;
#ifdef PALP_LDL_X86
  if (w == 1 && f->simd) {
    solve_blocks_avx2(f, x, y);
    return;
  }
  if (w >= 2 && w <= 3 && f->simd) {
    solve_blocks_avx2_vlanes(f, x, w, y);
    return;
  }
  if (w == 4 && f->simd) {
    solve_blocks_avx2_lanes(f, x, w, y);
    return;
  }
#endif
  switch (w) {
  case 1: PALP_LDL_BLOCK_SOLVE_BODY(1); break;
  case 2: PALP_LDL_BLOCK_SOLVE_BODY(2); break;
  case 3: PALP_LDL_BLOCK_SOLVE_BODY(3); break;
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

int palp_ldl_etree(const palp_ldl *f, int *blk, int *parent) {
  const int nb = f->nb;
  for (int K = 0; K < nb; ++K) blk[f->perm[3 * K] / 3] = K;
  for (int J = 0; J < nb; ++J) parent[J] = f->bcolp[J] < f->bcolp[J + 1] ? f->brow[f->bcolp[J]] : -1;
  int h = 0; /* each column's path walked once: O(nb h), once per world */
  for (int J = 0; J < nb; ++J) {
    int d = 1;
    for (int I = parent[J]; I >= 0; I = parent[I]) d++;
    if (d > h) h = d;
  }
  return h;
}

int palp_ldl_unit_path(const palp_ldl *f, int J0, const int *parent, double *zw, int *path, double *val) {
  int n = 0;
  for (int c = 0; c < 3; ++c) zw[9 * J0 + 3 * c + c] = 1.0;
  for (int J = J0; J >= 0; J = parent[J]) {
    double *yj = zw + 9 * J;
    palp_ldl_diag_fwd(f->bdiag + 3 * J, yj, 3);
    for (int q = f->bcolp[J]; q < f->bcolp[J + 1]; ++q) {
      double *yi = zw + 9 * f->brow[q];
      const float *B = f->blk + 9 * q;
      for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c)
          yi[3 * i + c] -= ((double)B[i] * yj[c] + (double)B[3 + i] * yj[3 + c]) + (double)B[6 + i] * yj[6 + c];
    }
    path[n] = J;
    memcpy(val + 9 * (size_t)n, yj, sizeof(double) * 9);
    memset(yj, 0, sizeof(double) * 9);
    n++;
  }
  return n;
}

void palp_ldl_path_block(const palp_ldl *f, const int *pa, const double *va, int na, const int *pb, const double *vb,
                         int nb, double out[9]) {
  for (int e = 0; e < 9; ++e) out[e] = 0.0;
  for (int x = 0, y = 0; x < na && y < nb;) {
    if (pa[x] < pb[y]) x++;
    else if (pb[y] < pa[x]) y++;
    else {
      const double *za = va + 9 * x, *zb = vb + 9 * y, *dinv = f->dinv + 3 * pa[x];
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) out[3 * i + j] += za[3 * k + i] * dinv[k] * zb[3 * k + j];
      x++, y++;
    }
  }
}

size_t palp_ldl_work_size(int n, int w) {
  size_t m = (size_t)n * (size_t)(w > 0 ? w : 1);
  const size_t v = 4 * (((size_t)n + 2) / 3);
  if (v > m) m = v;
  if (w >= 2 && w <= 4 && 4 * (size_t)n > m) m = 4 * (size_t)n;
  return m + 4;
}

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
