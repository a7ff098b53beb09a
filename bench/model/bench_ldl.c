/*
 * bench_model_ldl - the block LDL^T kernels of a tangent rebuild (src/sparse_ldl.c) on
 * the model's own pattern, each against the portable path run in the same process.
 *
 * The pattern is the dome's at 338 and 1,300 vertices (src/mesh.c): each free vertex's
 * 3x3 block coupled to the vertices it links to and, through the skin's hinges, to
 * the far vertex of each neighbouring triangle, as world.c's build_graph does; the
 * values are random, diagonally dominant (symmetric positive definite). Timed:
 * - the numeric refactorisation (palp_ldl_factor_blocks on the same pattern: the block
 *   numeric path alone), what every tangent rebuild does first;
 * - the 3 compliance columns of one vertex (3 unit right-hand sides), what a rebuild
 *   then does for every vertex the fingertip touches;
 * - one dense right-hand side, the step's solve.
 * "default" is the path the library takes on this CPU (AVX2 where it has it), "portable"
 * the plain C one, alternated rep by rep; the factor and the solutions of the two are
 * compared bit for bit (they must be equal: src/sparse_ldl.h). Medians and p99 in us.
 *
 *   bench_model_ldl [--reps N]
 */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../bench_util.h"
#include "palp.h"
#include "sparse_ldl.h"

static double now_s(void) { return palp_bench_clock_s(CLOCK_MONOTONIC); }
static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void) { /* [-1, 1) */
  rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
  return (double)(rng >> 11) / 4503599627370496.0 - 1.0;
}

typedef struct pattern {
  int nb, *gp, *gi;       /* free-vertex graph, CSC, both triangles */
  int nnz, *ti, *tj;      /* lower triplets: every coupled pair's 9, each diagonal block's 6 */
  double *tx;
  int *row_of, *vertex_of; /* mesh vertex -> free row (-1 fixed), and back */
} pattern;

static int pair_cmp(const void *a, const void *b) {
  const int *x = a, *y = b;
  return x[0] != y[0] ? (x[0] > y[0]) - (x[0] < y[0]) : (x[1] > y[1]) - (x[1] < y[1]);
}

/* The model's graph on mesh m: links, and the four vertices of every pair of dome
 * triangles sharing an edge (a hinge) coupled to each other. */
static int pattern_build(const palp_mesh *m, pattern *p) {
  memset(p, 0, sizeof *p);
  const int nv = m->vertex_count, nt = m->dome_triangle_count;
  p->row_of = malloc(sizeof(int) * (size_t)nv);
  p->vertex_of = malloc(sizeof(int) * (size_t)nv);
  const size_t cap = 2 * (size_t)m->link_count + 36 * (size_t)nt + 16;
  int(*pr)[2] = malloc(sizeof *pr * cap);
  int(*edge)[3] = malloc(sizeof *edge * 3 * (size_t)nt); /* (a, b, triangle) with a < b */
  if (!p->row_of || !p->vertex_of || !pr || !edge) return -1;
  for (int i = 0; i < nv; ++i) p->row_of[i] = m->fixed[i] ? -1 : p->nb, p->vertex_of[p->nb] = i, p->nb += !m->fixed[i];
  size_t np = 0;
  for (int l = 0; l < m->link_count; ++l) {
    const int a = p->row_of[m->link[l][0]], b = p->row_of[m->link[l][1]];
    if (a >= 0 && b >= 0) pr[np][0] = a, pr[np++][1] = b, pr[np][0] = b, pr[np++][1] = a;
  }
  int ne = 0;
  for (int t = 0; t < nt; ++t)
    for (int e = 0; e < 3; ++e) {
      const int a = m->tri[t][e], b = m->tri[t][(e + 1) % 3];
      edge[ne][0] = a < b ? a : b, edge[ne][1] = a < b ? b : a, edge[ne++][2] = t;
    }
  qsort(edge, (size_t)ne, sizeof *edge, pair_cmp);
  for (int k = 0; k + 1 < ne; ++k) {
    if (edge[k][0] != edge[k + 1][0] || edge[k][1] != edge[k + 1][1]) continue;
    int v[4] = {edge[k][0], edge[k][1], -1, -1};
    for (int s = 0; s < 2; ++s)
      for (int c = 0; c < 3; ++c) {
        const int x = m->tri[edge[k + s][2]][c];
        if (x != v[0] && x != v[1]) v[2 + s] = x;
      }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const int a = p->row_of[v[i]], b = p->row_of[v[j]];
        if (i != j && a >= 0 && b >= 0) pr[np][0] = a, pr[np++][1] = b;
      }
  }
  qsort(pr, np, sizeof *pr, pair_cmp);
  p->gp = calloc((size_t)p->nb + 1, sizeof(int));
  p->gi = malloc(sizeof(int) * (np + 1));
  const size_t tcap = 9 * np / 2 + 6 * (size_t)p->nb + 16;
  p->ti = malloc(sizeof(int) * tcap), p->tj = malloc(sizeof(int) * tcap), p->tx = malloc(sizeof(double) * tcap);
  double *rowsum = calloc(3 * (size_t)p->nb, sizeof(double));
  if (!p->gp || !p->gi || !p->ti || !p->tj || !p->tx || !rowsum) return -1;
  int ng = 0;
  for (size_t k = 0; k < np; ++k) {
    if (k > 0 && pr[k][0] == pr[k - 1][0] && pr[k][1] == pr[k - 1][1]) continue;
    p->gi[ng++] = pr[k][1];
    p->gp[pr[k][0] + 1] = ng;
    if (pr[k][0] > pr[k][1]) /* one lower block per coupled pair */
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const double v = 0.3 * urand();
          p->ti[p->nnz] = 3 * pr[k][0] + r, p->tj[p->nnz] = 3 * pr[k][1] + c, p->tx[p->nnz++] = v;
          rowsum[3 * pr[k][0] + r] += v < 0 ? -v : v, rowsum[3 * pr[k][1] + c] += v < 0 ? -v : v;
        }
  }
  for (int r = 0; r < p->nb; ++r)
    if (p->gp[r + 1] < p->gp[r]) p->gp[r + 1] = p->gp[r];
  for (int b = 0; b < p->nb; ++b) /* diagonal blocks: dominant */
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c <= r; ++c) {
        const double v = r == c ? 1.0 + rowsum[3 * b + r] + 0.2 : 0.1 * urand();
        p->ti[p->nnz] = 3 * b + r, p->tj[p->nnz] = 3 * b + c, p->tx[p->nnz++] = v;
      }
  free(rowsum), free(pr), free(edge);
  return 0;
}

static void pattern_free(pattern *p) {
  free(p->gp), free(p->gi), free(p->ti), free(p->tj), free(p->tx), free(p->row_of), free(p->vertex_of);
}

static void report(const char *what, double *t[2], int reps) {
  double med[2], p99[2];
  for (int s = 0; s < 2; ++s) {
    qsort(t[s], (size_t)reps, sizeof(double), palp_bench_cmp);
    med[s] = t[s][reps / 2], p99[s] = t[s][(int)(0.99 * (reps - 1))];
  }
  printf("  %-34s %9.1f %9.1f %11.1f %9.1f %8.2f\n", what, 1e6 * med[0], 1e6 * p99[0], 1e6 * med[1], 1e6 * p99[1],
         med[1] / med[0]);
}

int main(int argc, char **argv) {
  int reps = 200;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
    else {
      fprintf(stderr, "usage: bench_model_ldl [--reps N]\n");
      return 2;
    }
  }
  if (reps < 10) reps = 10;
  printf("palp block LDL^T kernels on the dome's pattern (random SPD values), %d reps each, default path and "
         "portable alternated\n", reps);
  int all_same = 1;
  const int sizes[2] = {338, 1300};
  for (int z = 0; z < 2; ++z) {
    palp_mesh_def md = palp_mesh_default_def();
    md.vertex_count = sizes[z];
    palp_mesh m;
    pattern p;
    if (palp_mesh_create(&md, &m) || pattern_build(&m, &p)) {
      fprintf(stderr, "cannot build the %d-vertex pattern\n", sizes[z]);
      return 1;
    }
    palp_ldl f;
    memset(&f, 0, sizeof f);
    int e = palp_ldl_factor_blocks(&f, p.nb, p.gp, p.gi, p.nnz, p.ti, p.tj, p.tx);
    if (e || !f.nb) {
      fprintf(stderr, "factorisation failed (%d) or not by blocks\n", e);
      return 1;
    }
    const int simd = f.simd, n = f.n;
    printf("%d vertices (%d free, %d unknowns), %d off-diagonal blocks in L (%s order); default path %s\n", m.vertex_count,
           p.nb, n, f.bcolp[f.nb], f.nested ? "nested dissection" : "AMD",
           simd ? "AVX2" : "portable (no AVX2: both columns the same code)");
    printf("  %-34s %9s %9s %11s %9s %8s\n", "kernel [us]", "default", "p99", "portable", "p99", "ratio");
    double *t[2] = {malloc(sizeof(double) * (size_t)reps), malloc(sizeof(double) * (size_t)reps)};
    const size_t nblk9 = (size_t)f.bcolp[f.nb] * 9;
    float *blk0 = malloc(sizeof(float) * nblk9);
    double *x[2] = {malloc(sizeof(double) * 3 * (size_t)n), malloc(sizeof(double) * 3 * (size_t)n)};
    double *b = malloc(sizeof(double) * (size_t)n);
    double *work = malloc(sizeof(double) * palp_ldl_work_size(n, 4));
    if (!t[0] || !t[1] || !blk0 || !x[0] || !x[1] || !b || !work) return 1;
    /* the refactorisation */
    int same = 1;
    for (int k = 0; k < reps; ++k)
      for (int s = 0; s < 2; ++s) {
        f.simd = s ? 0 : simd;
        const double t0 = now_s();
        e = palp_ldl_factor_blocks(&f, p.nb, NULL, NULL, p.nnz, p.ti, p.tj, p.tx);
        t[s][k] = now_s() - t0;
        if (e) return 1;
        if (k == 0 && s == 0) memcpy(blk0, f.blk, sizeof(float) * nblk9);
        if (k == 0 && s == 1) same &= memcmp(blk0, f.blk, sizeof(float) * nblk9) == 0;
      }
    f.simd = simd;
    report("refactorisation", t, reps);
    /* one vertex's 3 compliance columns: vertices near the pole, as a fingertip's */
    const int near = 24;
    for (int k = 0; k < reps; ++k) {
      const int r = p.row_of[m.top_vertex] >= 0 ? (p.row_of[m.top_vertex] + k % near) % p.nb : k % p.nb;
      for (int s = 0; s < 2; ++s) {
        memset(x[s], 0, sizeof(double) * 3 * (size_t)n);
        for (int c = 0; c < 3; ++c) x[s][3 * (3 * r + c) + c] = 1.0;
        f.simd = s ? 0 : simd;
        const double t0 = now_s();
        palp_ldl_solve(&f, x[s], 3, work);
        t[s][k] = now_s() - t0;
      }
      same &= memcmp(x[0], x[1], sizeof(double) * 3 * (size_t)n) == 0;
    }
    f.simd = simd;
    report("3 compliance columns of a vertex", t, reps);
    /* one dense right-hand side */
    for (int i = 0; i < n; ++i) b[i] = urand();
    for (int k = 0; k < reps; ++k) {
      for (int s = 0; s < 2; ++s) {
        memcpy(x[s], b, sizeof(double) * (size_t)n);
        f.simd = s ? 0 : simd;
        const double t0 = now_s();
        palp_ldl_solve(&f, x[s], 1, work);
        t[s][k] = now_s() - t0;
      }
      same &= memcmp(x[0], x[1], sizeof(double) * (size_t)n) == 0;
    }
    f.simd = simd;
    report("one dense right-hand side", t, reps);
    printf("  default and portable paths bit-identical (factor and solutions): %s\n", same ? "yes" : "NO");
    all_same &= same;
    free(t[0]), free(t[1]), free(blk0), free(x[0]), free(x[1]), free(b), free(work);
    palp_ldl_free(&f);
    pattern_free(&p);
    palp_mesh_destroy(&m);
  }
  return all_same ? 0 : 1;
}
