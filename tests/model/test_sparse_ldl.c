/* The block LDL^T solve (src/sparse_ldl.c) on a symmetric positive definite matrix of
 * 3x3 blocks over a triangulated grid (the model's kind of pattern: each vertex
 * coupled to 6 neighbours), with dense full blocks:
 * - it solves: relative residual ||A x - b|| / ||b|| <= 1e-7. L's entries are stored
 *   in single precision (src/sparse_ldl.h: unit roundoff 2^-24 = 6e-8 per entry), so
 *   the solve is exact for a matrix within ~1e-7 of A; the matrix is diagonally
 *   dominant, condition ~10, so the residual stays at that level (measured 7e-9; a
 *   double factor left ~1e-15);
 * - the AVX2 path (taken for one right-hand side when the CPU has AVX2) gives the
 *   same bits as the portable path, so a session log replays identically on any
 *   x86-64 machine (tolerance 0, compared with memcmp);
 * - two and three interleaved right-hand sides give, column by column, the same bits
 *   as one at a time (tolerance 0);
 * - for two, three and four interleaved right-hand sides the AVX2 paths (for 2-3 lanes
 *   over a vertex's components, for 4 a lane per right-hand side) give the same bits as
 *   the portable one: dense ones, the unit
 *   columns of one vertex the fingertip's compliance columns solve for (where the
 *   forward pass skips the block columns that are still all zero, which decides the
 *   sign of some zeros), ones holding -0.0, and all -0.0 (which tells a path that does not
 *   skip from one that does) (memcmp, tolerance 0);
 * - a refactorisation of the same pattern (the block numeric path alone, no CHOLMOD)
 *   solves a second matrix to the same residual bound, gives the same bits as a first
 *   factorisation of that matrix in a new factor and as the portable block update
 *   where the default one is AVX2 (memcmp, tolerance 0), and refuses a
 *   matrix with a negative pivot (PALP_ESOLVER), keeping the factor it had (its
 *   residual unchanged);
 * - the vertices' order on the dome's own net (links and hinges): the 338-vertex dome keeps
 *   AMD's (below PALP_LDL_ND_MIN: the shipped phantoms keep their order and bits; L's
 *   blocks equal AMD's own count, amd_order's Info[AMD_LNZ] computed here apart from the
 *   library); the 1,300-vertex dome takes nested dissection, with at least 5% fewer blocks
 *   in L than AMD's count (measured 10.4%), a solve within the residual bound and the AVX2
 *   and portable paths the same bits (tolerance 0). */
#include <amd.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "palp.h"
#include "sparse_ldl.h"

#define GX 17
#define GY 14
#define NB (GX * GY)
#define N (3 * NB)

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void) { /* [-1, 1) */
  rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
  return (double)(rng >> 11) / 4503599627370496.0 - 1.0;
}

/* Two block factors of one pattern hold the same bits (blocks, diagonal blocks, 1/D). */
static int same_factor(const palp_ldl *a, const palp_ldl *b, size_t nblk) {
  return memcmp(a->blk, b->blk, sizeof(float) * nblk * 9) == 0 && memcmp(a->bdiag, b->bdiag, sizeof(double) * NB * 3) == 0 &&
         memcmp(a->dinv4, b->dinv4, sizeof(double) * NB * 4) == 0;
}

/* The dome's net of vertex_count vertices (palp_mesh), coupled as the model couples it:
 * the links, and the four vertices of every pair of dome triangles sharing an edge (a
 * hinge). 3x3 blocks, the off-diagonal ones random, the diagonal ones dominant. The order
 * taken against AMD's own fill, a solve's residual by the triplets, and the AVX2 path
 * against the portable one. */
#define DOME_MAX 1300
static int pair_cmp(const void *x, const void *y) {
  const int *p = x, *q = y;
  return p[0] != q[0] ? (p[0] > q[0]) - (p[0] < q[0]) : (p[1] > q[1]) - (p[1] < q[1]);
}
static void dome_net(int vertex_count, int expect_nested) {
  enum { NBMAX = DOME_MAX, PMAX = 40 * DOME_MAX };
  static int row_of[NBMAX], pr[PMAX][2], edge[3 * 2 * NBMAX][3], gp[NBMAX + 1], gi[PMAX], ti[9 * PMAX], tj[9 * PMAX];
  static double tx[9 * PMAX], rowsum[3 * NBMAX], b[3 * NBMAX], x[3 * NBMAX], xp[3 * NBMAX], ax[3 * NBMAX],
      work[12 * NBMAX + 4];
  palp_mesh_def md = palp_mesh_default_def();
  md.vertex_count = vertex_count;
  palp_mesh m;
  CHECK(palp_mesh_create(&md, &m) == 0 && m.vertex_count <= NBMAX, "the %d-vertex dome", vertex_count);
  int nb = 0, np = 0, ne = 0, ng = 0, nnz = 0;
  for (int i = 0; i < m.vertex_count; ++i) row_of[i] = m.fixed[i] ? -1 : nb++;
  for (int l = 0; l < m.link_count; ++l) {
    const int p = row_of[m.link[l][0]], q = row_of[m.link[l][1]];
    if (p >= 0 && q >= 0) pr[np][0] = p, pr[np++][1] = q, pr[np][0] = q, pr[np++][1] = p;
  }
  for (int t = 0; t < m.dome_triangle_count; ++t)
    for (int e = 0; e < 3; ++e) {
      const int p = m.tri[t][e], q = m.tri[t][(e + 1) % 3];
      edge[ne][0] = p < q ? p : q, edge[ne][1] = p < q ? q : p, edge[ne++][2] = t;
    }
  qsort(edge, (size_t)ne, sizeof *edge, pair_cmp);
  for (int k = 0; k + 1 < ne; ++k) {
    if (edge[k][0] != edge[k + 1][0] || edge[k][1] != edge[k + 1][1]) continue;
    int v[4] = {edge[k][0], edge[k][1], -1, -1};
    for (int s2 = 0; s2 < 2; ++s2)
      for (int c = 0; c < 3; ++c) {
        const int u = m.tri[edge[k + s2][2]][c];
        if (u != v[0] && u != v[1]) v[2 + s2] = u;
      }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (i != j && v[i] >= 0 && v[j] >= 0 && row_of[v[i]] >= 0 && row_of[v[j]] >= 0 && np < PMAX)
          pr[np][0] = row_of[v[i]], pr[np++][1] = row_of[v[j]];
  }
  qsort(pr, (size_t)np, sizeof *pr, pair_cmp);
  memset(gp, 0, sizeof gp);
  memset(rowsum, 0, sizeof rowsum);
  for (int k = 0; k < np; ++k) {
    if (k > 0 && pr[k][0] == pr[k - 1][0] && pr[k][1] == pr[k - 1][1]) continue;
    gi[ng++] = pr[k][1];
    gp[pr[k][0] + 1] = ng;
    if (pr[k][0] > pr[k][1])
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double a = urand();
          ti[nnz] = 3 * pr[k][0] + i, tj[nnz] = 3 * pr[k][1] + j, tx[nnz++] = a;
          rowsum[3 * pr[k][0] + i] += fabs(a), rowsum[3 * pr[k][1] + j] += fabs(a);
        }
  }
  for (int r = 0; r < nb; ++r)
    if (gp[r + 1] < gp[r]) gp[r + 1] = gp[r];
  for (int v = 0; v < nb; ++v)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) {
        const double a = 0.2 * urand();
        ti[nnz] = 3 * v + i, tj[nnz] = 3 * v + j, tx[nnz++] = i == j ? rowsum[3 * v + i] + 0.4 + 1.0 : a;
      }
  palp_mesh_destroy(&m);
  palp_ldl f;
  memset(&f, 0, sizeof f);
  const int e = palp_ldl_factor_blocks(&f, nb, gp, gi, nnz, ti, tj, tx);
  CHECK(e == 0 && f.nb == nb, "dome %d: factor by blocks: %s (nb %d)", vertex_count, palp_strerror(e), f.nb);
  if (e || f.nb != nb) return;
  /* AMD's own fill for its order (amd_order's Info[AMD_LNZ]: L's off-diagonal entries of
   * the vertex graph, i.e. blocks of the block factor), computed here apart from the library */
  static int vp[NBMAX];
  double control[AMD_CONTROL], info[AMD_INFO];
  amd_defaults(control);
  const int st = amd_order(nb, gp, gi, vp, control, info);
  CHECK(st == AMD_OK || st == AMD_OK_BUT_JUMBLED, "amd_order: %d", st);
  const double amd_blocks = info[AMD_LNZ];
  printf("dome of %d vertices (%d free): %s order, %d off-diagonal blocks in L; AMD's order holds %.0f (%+.1f%%)\n",
         vertex_count, nb, f.nested ? "nested dissection" : "AMD", f.bcolp[nb], amd_blocks,
         100.0 * (f.bcolp[nb] / amd_blocks - 1.0));
  CHECK(f.nested == expect_nested, "dome %d: %s order expected", vertex_count, expect_nested ? "nested dissection" : "AMD");
  if (expect_nested)
    CHECK(f.bcolp[nb] < 0.95 * amd_blocks, "nested dissection's L holds %d blocks, not 5%% under AMD's %.0f", f.bcolp[nb],
          amd_blocks);
  else
    CHECK(f.bcolp[nb] == (int)amd_blocks, "AMD's order: %d blocks in L against AMD's count %.0f", f.bcolp[nb], amd_blocks);
  const int n = 3 * nb;
  for (int r = 0; r < n; ++r) b[r] = urand();
  memcpy(x, b, sizeof(double) * (size_t)n);
  palp_ldl_solve(&f, x, 1, work);
  const int simd = f.simd;
  f.simd = 0;
  memcpy(xp, b, sizeof(double) * (size_t)n);
  palp_ldl_solve(&f, xp, 1, work);
  f.simd = simd;
  const int same = memcmp(x, xp, sizeof(double) * (size_t)n) == 0;
  CHECK(same, "dome %d: the default (%s) and portable solves differ", vertex_count, simd ? "AVX2" : "portable");
  memset(ax, 0, sizeof ax);
  for (int k = 0; k < nnz; ++k) {
    ax[ti[k]] += tx[k] * x[tj[k]];
    if (ti[k] != tj[k]) ax[tj[k]] += tx[k] * x[ti[k]];
  }
  double rr = 0.0, bb = 0.0;
  for (int r = 0; r < n; ++r) rr += (ax[r] - b[r]) * (ax[r] - b[r]), bb += b[r] * b[r];
  const double rel = sqrt(rr / bb);
  printf("dome of %d vertices: relative residual %.3g (tolerance 1e-7); default and portable solves bit-identical: %s\n",
         vertex_count, rel, same ? "yes" : "no");
  CHECK(rel <= 1e-7, "dome %d: relative residual %.3g (tolerance 1e-7)", vertex_count, rel);
  palp_ldl_free(&f);
}

/* Dense copy of A for the residual, and its lower-triangle triplets. */
static double A[N][N];

int main(void) {
  /* Vertex graph: grid edges plus one diagonal per cell (a triangulation). */
  static int gp[NB + 1], gi[NB * 7];
  int ng = 0;
  for (int v = 0; v < NB; ++v) {
    gp[v] = ng;
    const int x = v % GX, y = v / GX;
    const int dx[6] = {1, -1, 0, 0, 1, -1}, dy[6] = {0, 0, 1, -1, 1, -1};
    for (int k = 0; k < 6; ++k) {
      const int xx = x + dx[k], yy = y + dy[k];
      if (xx >= 0 && xx < GX && yy >= 0 && yy < GY) gi[ng++] = yy * GX + xx;
    }
  }
  gp[NB] = ng;
  /* Off-diagonal blocks random in [-1, 1); each diagonal block a random symmetric
   * matrix plus (sum of the row's off-diagonal magnitudes + 1) I: dominant. */
  for (int v = 0; v < NB; ++v)
    for (int q = gp[v]; q < gp[v + 1]; ++q) {
      const int u = gi[q];
      if (u >= v) continue;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) A[3 * v + i][3 * u + j] = A[3 * u + j][3 * v + i] = urand();
    }
  for (int v = 0; v < NB; ++v)
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j <= i; ++j) A[3 * v + i][3 * v + j] = A[3 * v + j][3 * v + i] = 0.2 * urand();
    }
  for (int r = 0; r < N; ++r) {
    double s = 0.0;
    for (int c = 0; c < N; ++c)
      if (c != r) s += fabs(A[r][c]);
    A[r][r] += s + 1.0;
  }
  static int ti[N * 30], tj[N * 30];
  static double tx[N * 30];
  int nnz = 0;
  for (int r = 0; r < N; ++r)
    for (int c = 0; c <= r; ++c)
      if (A[r][c] != 0.0) ti[nnz] = r, tj[nnz] = c, tx[nnz++] = A[r][c];

  palp_ldl f;
  memset(&f, 0, sizeof f);
  const int e = palp_ldl_factor_blocks(&f, NB, gp, gi, nnz, ti, tj, tx);
  CHECK(e == 0, "factor: %s", palp_strerror(e));
  CHECK(f.nb == NB, "the factor is kept in 3x3 blocks (nb %d, expected %d)", f.nb, NB);
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  const int avx2 = __builtin_cpu_supports("avx2");
  CHECK((f.simd != 0) == (avx2 != 0), "the AVX2 path is chosen exactly when the CPU has AVX2 (simd %d, avx2 %d)", f.simd, avx2);
  printf("CPU has AVX2: %s\n", avx2 ? "yes (both paths compared)" : "no (portable path only)");
#endif

  static double b[3][N], x1[3][N], xp[3][N], x3[3 * N], x2[2 * N], work[4 * N + 4];
  CHECK(palp_ldl_work_size(N, 4) <= sizeof work / sizeof *work, "work holds %zu doubles",
        palp_ldl_work_size(N, 4));
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < N; ++r) b[k][r] = urand();
  const int simd = f.simd;
  double worst = 0.0;
  for (int k = 0; k < 3; ++k) {
    memcpy(x1[k], b[k], sizeof b[k]);
    palp_ldl_solve(&f, x1[k], 1, work);
    f.simd = 0;
    memcpy(xp[k], b[k], sizeof b[k]);
    palp_ldl_solve(&f, xp[k], 1, work);
    f.simd = simd;
    CHECK(memcmp(x1[k], xp[k], sizeof x1[k]) == 0, "right-hand side %d: default and portable paths differ", k);
    double rr = 0.0, bb = 0.0;
    for (int r = 0; r < N; ++r) {
      double ax = 0.0;
      for (int c = 0; c < N; ++c) ax += A[r][c] * x1[k][c];
      rr += (ax - b[k][r]) * (ax - b[k][r]);
      bb += b[k][r] * b[k][r];
    }
    const double rel = sqrt(rr / bb);
    if (rel > worst) worst = rel;
    CHECK(rel <= 1e-7, "right-hand side %d: relative residual %.3g (tolerance 1e-7)", k, rel);
  }
  printf("%d unknowns, %d off-diagonal factor blocks: worst relative residual %.3g (tolerance 1e-7)\n", N,
         f.bcolp ? f.bcolp[NB] : -1, worst);
  for (int r = 0; r < N; ++r) {
    for (int k = 0; k < 3; ++k) x3[3 * r + k] = b[k][r];
    for (int k = 0; k < 2; ++k) x2[2 * r + k] = b[k][r];
  }
  palp_ldl_solve(&f, x3, 3, work);
  palp_ldl_solve(&f, x2, 2, work);
  int diff3 = 0, diff2 = 0;
  for (int r = 0; r < N; ++r) {
    for (int k = 0; k < 3; ++k) diff3 += memcmp(&x3[3 * r + k], &x1[k][r], sizeof(double)) != 0;
    for (int k = 0; k < 2; ++k) diff2 += memcmp(&x2[2 * r + k], &x1[k][r], sizeof(double)) != 0;
  }
  CHECK(diff3 == 0, "3 interleaved right-hand sides: %d entries differ from one at a time", diff3);
  CHECK(diff2 == 0, "2 interleaved right-hand sides: %d entries differ from one at a time", diff2);
  /* The AVX2 lanes path against the portable one, bit for bit, widths 2-4. */
  static double xa[4 * N], xq[4 * N];
  int cases = 0, differ = 0;
  for (int w = 2; w <= 4; ++w)
    for (int kind = 0; kind < 4; ++kind) {
      for (int q = 0; q < w * N; ++q) xa[q] = 0.0;
      if (kind == 0) { /* dense */
        for (int q = 0; q < w * N; ++q) xa[q] = urand();
      } else if (kind == 1) { /* unit columns of vertex 7 (and one more for w = 4) */
        for (int c = 0; c < w; ++c) xa[(3 * 7 + c % 3 + (c / 3) * 3) * w + c] = 1.0;
      } else if (kind == 2) { /* sparse, with negative zeros beside the nonzeros */
        for (int q = 0; q < w * N; ++q) xa[q] = (q % 5 == 0) ? urand() : (q % 5 == 1 ? -0.0 : 0.0);
      } else { /* all -0.0: every block column is skipped, and where one is not, a row whose
                * three entries are positive turns -0 into +0 (-0 - -0 = +0) */
        for (int q = 0; q < w * N; ++q) xa[q] = -0.0;
      }
      memcpy(xq, xa, sizeof(double) * (size_t)(w * N));
      palp_ldl_solve(&f, xa, w, work);
      f.simd = 0;
      palp_ldl_solve(&f, xq, w, work);
      f.simd = simd;
      cases++;
      if (memcmp(xa, xq, sizeof(double) * (size_t)(w * N)) != 0) {
        differ++;
        CHECK(0, "width %d, case %d: the default path differs from the portable one", w, kind);
      }
    }
  printf("widths 2-4, dense / unit-column / signed-zero / all -0 right-hand sides: %d of %d cases bit-identical between the "
         "default (%s) and portable paths\n", cases - differ, cases, simd ? "AVX2" : "portable");
  /* A refactorisation of the same pattern takes the block numeric path alone: a second
   * matrix (off-diagonal blocks halved, still dominant) solves to the same residual,
   * and its factor is the same bits as a first factorisation of it in a new palp_ldl
   * (CHOLMOD's analysis, then the same block path); a matrix that is not positive
   * definite is refused with PALP_ESOLVER and leaves the factor it had. */
  {
    CHECK(f.dest != NULL, "the factor keeps the block numeric path's map");
    static double tx2[N * 30], tx3[N * 30];
    for (int k = 0; k < nnz; ++k) tx2[k] = ti[k] / 3 != tj[k] / 3 ? 0.5 * tx[k] : tx[k];
    for (int r = 0; r < N; ++r)
      for (int c = 0; c < N; ++c)
        if (r / 3 != c / 3) A[r][c] *= 0.5;
    const int e2 = palp_ldl_factor_blocks(&f, NB, NULL, NULL, nnz, ti, tj, tx2);
    CHECK(e2 == 0, "refactor: %s", palp_strerror(e2));
    palp_ldl g;
    memset(&g, 0, sizeof g);
    const int eg = palp_ldl_factor_blocks(&g, NB, gp, gi, nnz, ti, tj, tx2);
    CHECK(eg == 0 && g.nb == NB, "first factorisation of the second matrix: %s", palp_strerror(eg));
    const size_t nblk = (size_t)f.bcolp[NB];
    const int same = eg == 0 && g.bcolp[NB] == f.bcolp[NB] && same_factor(&g, &f, nblk);
    CHECK(same, "a refactorisation and a first factorisation of one matrix give the same bits (tolerance 0)");
    /* the portable block update against the default (AVX2 where the CPU has it) */
    f.simd = 0;
    const int ep = palp_ldl_factor_blocks(&f, NB, NULL, NULL, nnz, ti, tj, tx2);
    f.simd = simd;
    const int same_p = ep == 0 && same_factor(&g, &f, nblk);
    CHECK(same_p, "the portable numeric factorisation gives the default path's bits (tolerance 0)");
    printf("refactorisation: the default (%s) and portable block updates give the same factor, bit for bit: %s\n",
           simd ? "AVX2" : "portable", same_p ? "yes" : "no");
    palp_ldl_free(&g);
    /* residual against the second matrix, after it and after a refused third */
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1) {
        for (int k = 0; k < nnz; ++k) tx3[k] = tx2[k];
        for (int k = 0; k < nnz; ++k)
          if (ti[k] == N / 2 && tj[k] == N / 2) tx3[k] = -1.0; /* a negative pivot midway */
        const int e3 = palp_ldl_factor_blocks(&f, NB, NULL, NULL, nnz, ti, tj, tx3);
        CHECK(e3 == PALP_ESOLVER, "a matrix with a negative diagonal entry is refused (%s)", palp_strerror(e3));
      }
      double rr = 0.0, bb = 0.0;
      memcpy(x1[0], b[0], sizeof b[0]);
      palp_ldl_solve(&f, x1[0], 1, work);
      for (int r = 0; r < N; ++r) {
        double ax = 0.0;
        for (int c = 0; c < N; ++c) ax += A[r][c] * x1[0][c];
        rr += (ax - b[0][r]) * (ax - b[0][r]);
        bb += b[0][r] * b[0][r];
      }
      const double rel = sqrt(rr / bb);
      printf("refactored by blocks%s: relative residual %.3g (tolerance 1e-7)\n",
             pass ? ", after a refused matrix" : "", rel);
      CHECK(rel <= 1e-7, "refactored%s: relative residual %.3g (tolerance 1e-7)", pass ? ", refused one after" : "", rel);
    }
  }
  palp_ldl_free(&f);
  dome_net(338, 0);
  dome_net(1300, 1);
  CHECK_DONE();
}
