/*
 * fem_model.c - model state, assembly, and the Newton solvers (static and
 * implicit Newmark dynamics with automatic step cut-back).
 *
 * Newmark (beta, gamma), lumped mass M:
 *   a+ = (u+ - u - dt v) / (beta dt^2) - (1 / (2 beta) - 1) a
 *   v+ = v + dt ((1 - gamma) a + gamma a+)
 *   r(u+) = f_ext+ - M a+ - f_int(u+) = 0,   K_eff = K_T + M / (beta dt^2)
 * HHT-alpha (hht_alpha != 0; Hilber, Hughes & Taylor 1977), with beta = (1 - alpha)^2 / 4
 * and gamma = 1/2 - alpha:
 *   r(u+) = (1 + alpha) f_ext+ - alpha f_ext - M a+ - (1 + alpha) f_int(u+) + alpha f_int(u),
 *   K_eff = (1 + alpha) K_T + M / (beta dt^2)
 * (f_ext the force of the previous step, f_int(u) the internal force the previous
 * step converged to, viscoelastic history included).
 * Newton stops when ||r|| <= rtol * max(||f_ext||, ||f_int||, ||M a||) + atol, r over
 * the free equations, ||f_int|| over all (reactions included). A step that does not converge within max_newton
 * iterations, inverts an element, or meets an indefinite K_eff is retried with
 * half the step (the mass term M / (beta dt^2) grows as dt shrinks, which is
 * what restores definiteness); after max_cutbacks halvings the step fails.
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fem_internal.h"

/* Wall clock [s] for the model's time breakdown (statistics only). */
static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void palp_fem_model_destroy(palp_fem_model *m) {
  if (!m) return;
  free(m->eq);
  free(m->prescribed);
  free(m->mass);
  free(m->gp_dNdX);
  free(m->gp_w);
  free(m->vol0);
  free(m->u);
  free(m->v);
  free(m->a);
  free(m->S0);
  free(m->H);
  free(m->S0t);
  free(m->Ht);
  free(m->fint);
  free(m->fint_prev);
  free(m->fext_prev);
  free(m->fext);
  free(m->res);
  free(m->du);
  free(m->utrial);
  free(m->atrial);
  free(m->colp);
  free(m->rowi);
  free(m->emap);
  free(m->kval);
  free(m->pcg);
  free(m->gmres_ws);
  free(m->tbuf);
  free(m->kfac);
  palp_fem_solver_destroy(m->solver);
  memset(m, 0, sizeof *m);
}

int palp_fem_model_create(palp_fem_model *m, const palp_fem_mesh *mesh, const palp_fem_config *cfg) {
  memset(m, 0, sizeof *m);
  m->mesh = mesh;
  m->mat[PALP_FEM_GEL] = cfg->gel;
  m->mat[PALP_FEM_MEMBRANE] = cfg->membrane;
  for (int r = 0; r < 2; ++r) m->mat[r].c10 = palp_fem_c10_instant(&m->mat[r], cfg->c10_reading);
  m->nprony = cfg->gel.prony_count > cfg->membrane.prony_count ? cfg->gel.prony_count : cfg->membrane.prony_count;
  /* a material with fewer terms gets zero-weight extra terms */
  for (int r = 0; r < 2; ++r)
    for (int k = m->mat[r].prony_count; k < m->nprony; ++k) {
      m->mat[r].g[k] = 0.0;
      m->mat[r].tau[k] = 1.0;
    }
  for (int r = 0; r < 2; ++r) m->mat[r].prony_count = m->nprony;
  m->newmark_beta = cfg->newmark_beta;
  m->newmark_gamma = cfg->newmark_gamma;
  m->hht_alpha = cfg->hht_alpha;
  m->rtol = cfg->newton_rtol;
  m->atol = cfg->newton_atol;
  m->max_newton = cfg->max_newton;
  m->max_cutbacks = cfg->max_cutbacks;
  m->full_newton = cfg->full_newton;
  m->pcg_refactor = cfg->pcg_refactor;
  m->factor_lag = cfg->factor_lag;
  m->threads = cfg->threads < 1 ? 1 : cfg->threads > 16 ? 16 : cfg->threads;
  const int N = mesh->node_count, E = mesh->element_count, np = m->nprony;
  m->ndof = 3 * N;
  const size_t nd = (size_t)m->ndof;
  m->eq = malloc(sizeof(int) * nd);
  m->prescribed = calloc(nd, sizeof(double));
  m->mass = calloc((size_t)N, sizeof(double));
  m->gp_dNdX = malloc(sizeof(double) * (size_t)E * 8 * 24);
  m->gp_w = malloc(sizeof(double) * (size_t)E * 8);
  m->vol0 = malloc(sizeof(double) * (size_t)E);
  m->u = calloc(nd, sizeof(double));
  m->v = calloc(nd, sizeof(double));
  m->a = calloc(nd, sizeof(double));
  m->S0 = calloc((size_t)E * 8 * 6, sizeof(double));
  m->H = calloc((size_t)E * 8 * (size_t)(np ? np : 1) * 6, sizeof(double));
  m->S0t = calloc((size_t)E * 8 * 6, sizeof(double));
  m->Ht = calloc((size_t)E * 8 * (size_t)(np ? np : 1) * 6, sizeof(double));
  m->fint = calloc(nd, sizeof(double));
  m->fext = calloc(nd, sizeof(double));
  m->res = calloc(nd, sizeof(double));
  m->du = calloc(nd, sizeof(double));
  m->utrial = calloc(nd, sizeof(double));
  m->atrial = calloc(nd, sizeof(double));
  if (m->hht_alpha != 0.0) {
    m->fint_prev = calloc(nd, sizeof(double));
    m->fext_prev = calloc(nd, sizeof(double));
    if (!m->fint_prev || !m->fext_prev) {
      palp_fem_model_destroy(m);
      return PALP_ENOMEM;
    }
  }
  if (!m->eq || !m->prescribed || !m->mass || !m->gp_dNdX || !m->gp_w || !m->vol0 || !m->u || !m->v || !m->a ||
      !m->S0 || !m->H || !m->S0t || !m->Ht || !m->fint || !m->fext || !m->res || !m->du || !m->utrial ||
      !m->atrial) {
    palp_fem_model_destroy(m);
    return PALP_ENOMEM;
  }
  for (size_t d = 0; d < nd; ++d) m->eq[d] = mesh->fixed[d / 3] ? -1 : 0;
  /* reference geometry at the Gauss points: dN/dX = dN/dxi J0^-1 */
  for (int e = 0; e < E; ++e) {
    double vol = 0.0;
    for (int g = 0; g < 8; ++g) {
      double dN[8][3], J[3][3];
      const double det = palp_fem_hex_jacobian(mesh, e, g, dN, J);
      if (!(det > 0.0)) {
        /* destroy clears the model, err included: the message is kept across it */
        char why[sizeof m->err];
        snprintf(why, sizeof why,
                 "element %d (1-based, in mesh order) has a non-positive Jacobian at Gauss point %d (inverted or "
                 "its corners out of the C3D8 order)", e + 1, g + 1);
        palp_fem_model_destroy(m);
        memcpy(m->err, why, sizeof m->err);
        return PALP_EINVAL;
      }
      double Ji[3][3];
      Ji[0][0] = (J[1][1] * J[2][2] - J[1][2] * J[2][1]) / det;
      Ji[0][1] = (J[0][2] * J[2][1] - J[0][1] * J[2][2]) / det;
      Ji[0][2] = (J[0][1] * J[1][2] - J[0][2] * J[1][1]) / det;
      Ji[1][0] = (J[1][2] * J[2][0] - J[1][0] * J[2][2]) / det;
      Ji[1][1] = (J[0][0] * J[2][2] - J[0][2] * J[2][0]) / det;
      Ji[1][2] = (J[0][2] * J[1][0] - J[0][0] * J[1][2]) / det;
      Ji[2][0] = (J[1][0] * J[2][1] - J[1][1] * J[2][0]) / det;
      Ji[2][1] = (J[0][1] * J[2][0] - J[0][0] * J[2][1]) / det;
      Ji[2][2] = (J[0][0] * J[1][1] - J[0][1] * J[1][0]) / det;
      double *out = m->gp_dNdX + ((size_t)e * 8 + (size_t)g) * 24;
      for (int a = 0; a < 8; ++a)
        for (int k = 0; k < 3; ++k) out[3 * a + k] = dN[a][0] * Ji[0][k] + dN[a][1] * Ji[1][k] + dN[a][2] * Ji[2][k];
      m->gp_w[(size_t)e * 8 + (size_t)g] = det; /* Gauss weights are 1 */
      vol += det;
      /* row-sum lumped mass: m_a = rho int N_a dV0 */
      const double *xi = palp_fem_gauss[g];
      for (int a = 0; a < 8; ++a) {
        static const double s[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                       {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
        const double Na = 0.125 * (1 + xi[0] * s[a][0]) * (1 + xi[1] * s[a][1]) * (1 + xi[2] * s[a][2]);
        m->mass[mesh->hex[e][a]] += m->mat[mesh->region[e]].density * Na * det;
      }
    }
    m->vol0[e] = vol;
  }
  return PALP_OK;
}

void palp_fem_model_prescribe(palp_fem_model *m, int node, int dir, double value) {
  m->eq[3 * node + dir] = -1;
  m->prescribed[3 * node + dir] = value;
}

static int cmp_int(const void *a, const void *b) {
  const int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

int palp_fem_model_finalize(palp_fem_model *m) {
  const palp_fem_mesh *mesh = m->mesh;
  const int N = mesh->node_count, E = mesh->element_count;
  int nf = 0;
  for (int d = 0; d < m->ndof; ++d) m->eq[d] = m->eq[d] < 0 ? -1 : nf++;
  m->nfree = nf;
  for (int d = 0; d < m->ndof; ++d)
    if (m->eq[d] < 0) m->u[d] = 0.0;
  /* node adjacency through elements */
  int *deg = calloc((size_t)N + 1, sizeof(int));
  if (!deg) return PALP_ENOMEM;
  for (int e = 0; e < E; ++e)
    for (int a = 0; a < 8; ++a) deg[mesh->hex[e][a] + 1] += 8;
  for (int i = 0; i < N; ++i) deg[i + 1] += deg[i];
  int *adj = malloc(sizeof(int) * (size_t)deg[N]);
  int *fill = calloc((size_t)N, sizeof(int));
  int *adjn = calloc((size_t)N, sizeof(int));
  if (!adj || !fill || !adjn) {
    free(deg), free(adj), free(fill), free(adjn);
    return PALP_ENOMEM;
  }
  for (int e = 0; e < E; ++e)
    for (int a = 0; a < 8; ++a) {
      const int na = mesh->hex[e][a];
      for (int b = 0; b < 8; ++b) adj[deg[na] + fill[na]++] = mesh->hex[e][b];
    }
  for (int i = 0; i < N; ++i) {
    int *l = adj + deg[i], n = fill[i];
    qsort(l, (size_t)n, sizeof(int), cmp_int);
    int k = 0;
    for (int j = 0; j < n; ++j)
      if (k == 0 || l[j] != l[k - 1]) l[k++] = l[j];
    adjn[i] = k;
  }
  /* columns in equation order; rows <= column, ascending (eq is monotone in dof) */
  free(m->colp);
  m->colp = malloc(sizeof(int) * ((size_t)nf + 1));
  long nnz = 0;
  for (int pass = 0; pass < 2; ++pass) {
    nnz = 0;
    for (int d = 0; d < m->ndof; ++d) {
      const int c = m->eq[d];
      if (c < 0) continue;
      if (pass == 0) m->colp[c] = (int)nnz;
      const int node = d / 3;
      for (int j = 0; j < adjn[node]; ++j)
        for (int k = 0; k < 3; ++k) {
          const int r = m->eq[3 * adj[deg[node] + j] + k];
          if (r < 0 || r > c) continue;
          if (pass == 1) m->rowi[nnz] = r;
          ++nnz;
        }
    }
    if (pass == 0) {
      m->colp[nf] = (int)nnz;
      free(m->rowi);
      m->rowi = malloc(sizeof(int) * (size_t)(nnz ? nnz : 1));
      if (!m->rowi) break;
    }
  }
  free(deg), free(adj), free(fill), free(adjn);
  if (!m->colp || !m->rowi) return PALP_ENOMEM;
  m->nnz = nnz;
  free(m->kval);
  free(m->emap);
  m->kval = calloc((size_t)(nnz ? nnz : 1), sizeof(double));
  free(m->pcg);
  m->pcg = malloc(sizeof(double) * 7 * (size_t)(nf ? nf : 1));
  m->factored = 0;
  m->prefactored = 0;
  free(m->kfac);
  m->kfac = NULL;
  if (!m->pcg) return PALP_ENOMEM;
  free(m->tbuf);
  m->tbuf = NULL;
  if (m->threads > 1 && E >= 256) {
    m->tbuf = malloc(sizeof(double) * (size_t)(m->threads - 1) * ((size_t)m->ndof + (size_t)nnz));
    if (!m->tbuf) m->threads = 1; /* fall back to one worker rather than fail */
  } else
    m->threads = 1;
  m->emap = malloc(sizeof(int) * (size_t)E * 576);
  if (!m->kval || !m->emap) return PALP_ENOMEM;
  for (int e = 0; e < E; ++e)
    for (int A = 0; A < 24; ++A)
      for (int B = 0; B < 24; ++B) {
        const int rA = m->eq[3 * mesh->hex[e][A / 3] + A % 3], rB = m->eq[3 * mesh->hex[e][B / 3] + B % 3];
        int idx = -1;
        if (rA >= 0 && rB >= 0 && rA <= rB) {
          int lo = m->colp[rB], hi = m->colp[rB + 1] - 1;
          while (lo <= hi) {
            const int mid = (lo + hi) / 2;
            if (m->rowi[mid] < rA) lo = mid + 1;
            else if (m->rowi[mid] > rA) hi = mid - 1;
            else {
              idx = mid;
              break;
            }
          }
        }
        m->emap[(size_t)e * 576 + (size_t)A * 24 + (size_t)B] = idx;
      }
  palp_fem_solver_destroy(m->solver);
  m->solver = palp_fem_solver_create(nf, m->colp, m->rowi, nnz);
  if (!m->solver) {
    snprintf(m->err, sizeof m->err, "CHOLMOD symbolic analysis failed");
    return PALP_ESOLVER;
  }
  return PALP_OK;
}

/* One worker's share of the assembly: elements [e0, e1) into its own fint / kval. */
typedef struct assembly_job {
  palp_fem_model *m;
  const double *u;
  double dt;
  int want_tangent;
  int e0, e1;
  double *fint, *kval;
  int rc;
} assembly_job;

static void *assemble_range(void *arg) {
  assembly_job *j = arg;
  palp_fem_model *m = j->m;
  const palp_fem_mesh *mesh = m->mesh;
  const int np = m->nprony;
  memset(j->fint, 0, sizeof(double) * (size_t)m->ndof);
  if (j->want_tangent) memset(j->kval, 0, sizeof(double) * (size_t)m->nnz);
  double ue[24], fe[24], ke[24][24];
  j->rc = PALP_OK;
  for (int e = j->e0; e < j->e1; ++e) {
    const int *h = mesh->hex[e];
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) ue[3 * a + i] = j->u[3 * h[a] + i];
    const int rc = palp_fem_element(m, e, ue, j->dt, fe, j->want_tangent ? ke : NULL, m->S0t + (size_t)e * 48,
                                    m->Ht + (size_t)e * 8 * (size_t)np * 6);
    if (rc) {
      j->rc = rc;
      return NULL;
    }
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) j->fint[3 * h[a] + i] += fe[3 * a + i];
    if (!j->want_tangent) continue;
    const int *map = m->emap + (size_t)e * 576;
    for (int k = 0; k < 576; ++k)
      if (map[k] >= 0) j->kval[map[k]] += (&ke[0][0])[k];
  }
  return NULL;
}

/* Elements are split into `threads` contiguous ranges; each worker scatters into
 * private buffers that are summed afterwards, so no locks and a deterministic
 * result for a given thread count. */
static int assemble(palp_fem_model *m, const double *u, double dt, int want_tangent);

int palp_fem_assemble(palp_fem_model *m, const double *u, double dt, int want_tangent) {
  const double t0 = now_s();
  const int rc = assemble(m, u, dt, want_tangent);
  m->sec_assemble += now_s() - t0;
  m->assemblies++;
  if (want_tangent) m->tangent_assemblies++;
  return rc;
}

static int assemble(palp_fem_model *m, const double *u, double dt, int want_tangent) {
  const int E = m->mesh->element_count, T = m->threads > 1 && m->tbuf ? m->threads : 1;
  assembly_job job[16];
  pthread_t tid[16];
  int started[16] = {0};
  for (int t = 0; t < T; ++t) {
    job[t] = (assembly_job){.m = m, .u = u, .dt = dt, .want_tangent = want_tangent,
                            .e0 = (int)((long)E * t / T), .e1 = (int)((long)E * (t + 1) / T)};
    if (t == 0) {
      job[t].fint = m->fint;
      job[t].kval = m->kval;
    } else {
      double *b = m->tbuf + (size_t)(t - 1) * ((size_t)m->ndof + (size_t)m->nnz);
      job[t].fint = b;
      job[t].kval = b + m->ndof;
    }
  }
  for (int t = 1; t < T; ++t) started[t] = pthread_create(&tid[t], NULL, assemble_range, &job[t]) == 0;
  assemble_range(&job[0]);
  for (int t = 1; t < T; ++t) {
    if (started[t]) pthread_join(tid[t], NULL);
    else assemble_range(&job[t]); /* no thread available: do its share here */
  }
  for (int t = 0; t < T; ++t)
    if (job[t].rc) return job[t].rc;
  for (int t = 1; t < T; ++t) {
    for (int d = 0; d < m->ndof; ++d) m->fint[d] += job[t].fint[d];
    if (want_tangent)
      for (long k = 0; k < m->nnz; ++k) m->kval[k] += job[t].kval[k];
  }
  if (m->extra_fn) return m->extra_fn(m->extra_ud, m, u, want_tangent);
  return PALP_OK;
}

static double norm_all(const palp_fem_model *m, const double *v) {
  double s = 0.0;
  for (int d = 0; d < m->ndof; ++d) s += v[d] * v[d];
  return sqrt(s);
}

static double norm_free(const palp_fem_model *m, const double *v) {
  double s = 0.0;
  for (int d = 0; d < m->ndof; ++d)
    if (m->eq[d] >= 0) s += v[d] * v[d];
  return sqrt(s);
}

/* y = K x for the symmetric K stored as its upper triangle (colp, rowi, kval). */
static void symv(const palp_fem_model *m, const double *x, double *y) {
  memset(y, 0, sizeof(double) * (size_t)m->nfree);
  for (int c = 0; c < m->nfree; ++c) {
    double yc = 0.0;
    const double xc = x[c];
    for (int p = m->colp[c]; p < m->colp[c + 1]; ++p) {
      const int r = m->rowi[p];
      const double v = m->kval[p];
      y[r] += v * xc;
      if (r != c) yc += v * x[r];
    }
    y[c] += yc;
  }
}

static double dot(const double *a, const double *b, int n) {
  double s = 0.0;
  for (int i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

/* The bookkeeping of a new factor: the renewal rule counts from here. */
static void factor_made(palp_fem_model *m) {
  m->factorizations++;
  m->fac_attempt = m->attempts;
  m->fac_solves = m->solves;
  m->renew = 0;
  m->renew_fg = 0;
}

/* The factorisation and the solves with it, timed for the statistics. */
static int factor(palp_fem_model *m) {
  if (palp_fem_solver_factor_running(m->solver)) {
    /* a foreground factor (CG stalled, static solve) is newer than the background
     * one, which is dropped (after the join: it uses the solver's second factor) */
    const double tw = now_s();
    palp_fem_solver_factor_finish(m->solver, 0);
    m->sec_wait += now_s() - tw;
  }
  const double t0 = now_s();
  int shifted = 0;
  const int rc = m->in_static ? palp_fem_solver_factor_spd(m->solver, m->kval, &shifted)
                              : palp_fem_solver_factor(m->solver, m->kval);
  m->factor_shifted = shifted;
  m->sec_factor += now_s() - t0;
  factor_made(m);
  return rc;
}

/* A factor of this very K (LDL^T where indefinite), whatever the mode. */
static int factor_exact(palp_fem_model *m) {
  const int in_static = m->in_static;
  m->in_static = 0;
  const int rc = factor(m);
  m->in_static = in_static;
  return rc;
}

/* x = K~^-1 b with the factor: exact (a Newton step with a factor of this very K, the
 * direct solve after a stall) or, for the Krylov iterations, with the factor rounded to
 * single precision (krylov = 1: half the bytes to stream, fem_solver.c). */
static int precond_(palp_fem_model *m, const double *b, double *x, int krylov) {
  const double t0 = now_s();
  const int rc = krylov ? palp_fem_solver_precond(m->solver, b, x) : palp_fem_solver_solve(m->solver, b, x);
  m->sec_solve += now_s() - t0;
  m->solves++;
  return rc;
}

static int precond(palp_fem_model *m, const double *b, double *x) { return precond_(m, b, x, 1); }
static int solve_exact(palp_fem_model *m, const double *b, double *x) { return precond_(m, b, x, 0); }

/* Right-preconditioned restarted GMRES(k) for K x = b with the (stale) factor as
 * preconditioner, used where CG cannot go: an indefinite tangent or an LDL^T
 * (indefinite) preconditioner. Modified Gram-Schmidt, Givens rotations.
 * Returns the iterations taken, or -1 if ||b - K x|| <= eta ||b|| was not reached
 * within max_it. W holds (2k + 1) n doubles. */
#define GMRES_K 30
static int gmres(palp_fem_model *m, const double *b, double *x, double eta, int max_it, double *W, int *rc) {
  const int n = m->nfree, k = GMRES_K;
  double *V = W, *Z = W + (size_t)(k + 1) * (size_t)n;
  double H[GMRES_K + 1][GMRES_K], cs[GMRES_K], sn[GMRES_K], g[GMRES_K + 1], y[GMRES_K];
  const double bn = sqrt(dot(b, b, n));
  memset(x, 0, sizeof(double) * (size_t)n);
  if (!(bn > 0.0)) return 0;
  int total = 0;
  *rc = 0;
  while (total < max_it) {
    /* r = b - K x into V[0] */
    symv(m, x, V);
    for (int i = 0; i < n; ++i) V[i] = b[i] - V[i];
    double beta = sqrt(dot(V, V, n));
    if (beta <= eta * bn) return total;
    for (int i = 0; i < n; ++i) V[i] /= beta;
    memset(g, 0, sizeof g);
    g[0] = beta;
    int j = 0, done = 0;
    for (; j < k && total < max_it; ++j, ++total) {
      double *vj = V + (size_t)j * (size_t)n, *zj = Z + (size_t)j * (size_t)n, *w = V + (size_t)(j + 1) * (size_t)n;
      *rc = precond(m, vj, zj);
      if (*rc) return -1;
      symv(m, zj, w);
      for (int i = 0; i <= j; ++i) {
        const double *vi = V + (size_t)i * (size_t)n;
        H[i][j] = dot(w, vi, n);
        for (int q = 0; q < n; ++q) w[q] -= H[i][j] * vi[q];
      }
      H[j + 1][j] = sqrt(dot(w, w, n));
      if (H[j + 1][j] > 0.0)
        for (int q = 0; q < n; ++q) w[q] /= H[j + 1][j];
      for (int i = 0; i < j; ++i) { /* previous rotations */
        const double t = cs[i] * H[i][j] + sn[i] * H[i + 1][j];
        H[i + 1][j] = -sn[i] * H[i][j] + cs[i] * H[i + 1][j];
        H[i][j] = t;
      }
      const double den = hypot(H[j][j], H[j + 1][j]);
      cs[j] = den > 0.0 ? H[j][j] / den : 1.0;
      sn[j] = den > 0.0 ? H[j + 1][j] / den : 0.0;
      H[j][j] = den;
      H[j + 1][j] = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      if (fabs(g[j + 1]) <= eta * bn) {
        ++j, ++total;
        done = 1;
        break;
      }
    }
    /* x += Z y, H y = g (upper triangular, j columns) */
    for (int i = j - 1; i >= 0; --i) {
      double t = g[i];
      for (int q = i + 1; q < j; ++q) t -= H[i][q] * y[q];
      y[i] = H[i][i] != 0.0 ? t / H[i][i] : 0.0;
    }
    for (int i = 0; i < j; ++i) {
      const double *zi = Z + (size_t)i * (size_t)n;
      for (int q = 0; q < n; ++q) x[q] += y[i] * zi[q];
    }
    if (done) return total;
  }
  return -1;
}

/* Solves K du = res on the free equations (kval holds the consistent K).
 *
 * A Cholesky factorisation costs ~1e10 flops at 10^4 elements, a solve with it
 * ~5e7: so the factor is kept and reused as the preconditioner of conjugate
 * gradients on the current consistent tangent, which it approximates closely while
 * strains stay moderate (Newton's quadratic convergence needs the exact tangent
 * system solved, not the exact tangent factored). The factor is renewed when CG
 * needed more than pcg_refactor iterations last time, or when CG fails;
 * full_newton renews it every iteration. With pcg_refactor = 0 (automatic) the
 * limit is the cost of a factorisation in solves (factor_cost_solves), and the
 * factor is also renewed at the start of a time step by the renewal rule of
 * renew_factor. A changed dt (cut-back)
 * keeps the factor: the mass term is small beside the stiffness and CG absorbs
 * the change of the viscous factor gamma.
 * CG stops at ||K du - r|| <= eta ||r||, eta from newton_forcing. */
static int newton_solve_(palp_fem_model *m, double kscale_c0, double eta, double eta_gmres, int allow_gmres, const double *guess);

/* The cost of a numeric factorisation in preconditioner solves, from the flop
 * count fl of the factorisation and the nonzeros lnz of its factor. A solve with L
 * reads L twice (forward and back, 4 lnz flops, 8 lnz bytes in single precision,
 * fem_solver.c) and is memory-bound; the factorisation runs dense BLAS-3 on the
 * supernodes. Measured at level 4 (OpenBLAS, one core, CHOLMOD's loops on one thread,
 * 2026-12-03): 22.4 Gflop in 0.87-0.99 s against 8e7 flop in 14-18 ms, a
 * factorisation = ~58 solves, so cost = fl / (5 * 4 lnz) = 56 solves. It was
 * fl / (8 * 4 lnz) = 35 with the double solve and the four-thread factorisation
 * (1.05 s against 29 ms): priced at 35, renewals came early, 4 factorisations and 354
 * CG iterations in a 40-frame run against 3 and 376 now, whose mean frame was lower
 * in 4 of 5 alternated pairs (-6..-19%; +4% in one; docs/fem.md "The lag again"). A
 * constant rather than a measured ratio, so the run's results do not depend on the
 * timing. (The reference BLAS factorises ~8x slower; set pcg_refactor there.) */
static double factor_cost_solves(double fl, double lnz) {
  return lnz > 0.0 && fl > 0.0 ? fmax(1.0, fl / (20.0 * lnz)) : 20.0;
}

/* The cost of a factorisation made on the background thread (factor_lag > 0) in
 * the renewal rule, as a fraction of factor_cost_solves. It costs the foreground no
 * solve time, only a share of the CPU over the factor_lag attempts it overlaps
 * (none while a core is idle); but the factor it yields is factor_lag attempts old
 * when installed. Counted in full, the rule renewed as late as in the foreground
 * and CG ran on the aged factor through the lag (level 4, 40 frames: 361 CG
 * iterations against 292, up to 14 solves per step); counted at a quarter it
 * renews earlier, and the installed factor is about as good as the foreground
 * one (293 CG iterations, at most 10 solves per step but one 3-Newton step with
 * 14) for 4 factorisations in 40 frames instead of 2 (docs/fem.md, fem-frames). */
#define BACKGROUND_COST 0.25

/* Background renewal only for a run that has been benign so far: no step cut
 * back, no indefinite tangent (GMRES) and no LDL^T factor. In the hard runs (the
 * instantaneous reading's transient) most factorisations are forced anyway (CG
 * stalled), and a step left on the old factor through the lag failed more often
 * and was cut back: level 1, paper scene, 400 frames: 896 steps and 6 cut-backs
 * against 472 and 23, a different sub-step sequence (a different time
 * discretisation: top vertex 1.5% of its peak, feedback 11%). Counted over the
 * whole run (sticky), so such a run renews in the foreground from its first
 * difficulty on, as before fem-frames; deterministic, as all counts. */
static int background_ok(const palp_fem_model *m) {
  return m->factor_lag > 0 && m->cutbacks == 0 && m->gmres_solves == 0 && palp_fem_solver_ldl_count(m->solver) == 0;
}

/* Renewal rule for the reused factor (the replacement policy that minimises the
 * long-run average cost when the running cost grows with age): with the factor
 * used over `steps` time-step attempts since it was made, at a total of `solves`
 * preconditioner solves, renew it when the last attempt's solves exceed the
 * average cost per attempt including the factorisation,
 *   last > (factor_cost + solves) / steps   [solves per step].
 * CG needs more iterations as the state drifts from the factorised one; while the
 * count stays flat the rule never fires. */
static int renew_factor(double factor_cost, long solves, long steps, long last) {
  return steps >= 1 && (double)last * (double)steps > factor_cost + (double)solves;
}

/* newton_solve_ timed: what is not factorisation or preconditioner solve is Krylov work.
 * eta: CG's forcing term (newton_forcing); eta_gmres: GMRES's when CG meets negative
 * curvature, the plain min(0.1, r / scale) without the aim at the tolerance (capped
 * at 1e-2 there): an indefinite tangent (instantaneous reading) converges slowly
 * under GMRES, and a solve aimed at the tolerance stalled and refactored instead
 * (level 2, instantaneous, 15 frames: 299 factorisations and 46 s against 241 and
 * 33 s with the plain term; 112 and 38 s before fem-speed).
 * guess [ndof] (may be NULL): a direction d for CG's start x0 = alpha d, alpha =
 * d.b / d.K d, the K-orthogonal projection of the solution on d (so the start's
 * energy error is never above that of x0 = 0; one product with K). The first
 * Newton increment of a step continues the motion, and the velocity as d saves
 * ~15% of the CG iterations at level 4 (182 -> 155 over 20 frames). */
static int newton_solve(palp_fem_model *m, double kscale_c0, double eta, double eta_gmres, int allow_gmres, const double *guess) {
  const double t0 = now_s(), other0 = m->sec_factor + m->sec_solve;
  const int rc = newton_solve_(m, kscale_c0, eta, eta_gmres, allow_gmres, guess);
  m->sec_krylov += (now_s() - t0) - (m->sec_factor + m->sec_solve - other0);
  return rc;
}

static int newton_solve_(palp_fem_model *m, double kscale_c0, double eta, double eta_gmres, int allow_gmres, const double *guess) {
  const int n = m->nfree;
  double *b = m->pcg, *x = b + n, *r = x + n, *z = r + n, *p = z + n, *q = p + n;
  for (int d = 0; d < m->ndof; ++d)
    if (m->eq[d] >= 0) b[m->eq[d]] = m->res[d];
  int fresh = 0;
  (void)kscale_c0;
  int limit = m->pcg_refactor;
  if (limit <= 0) { /* automatic: one solve that cost more than a factorisation */
    const double lnz = palp_fem_solver_factor_nnz(m->solver), fl = palp_fem_solver_factor_flops(m->solver);
    limit = (int)fmin(400.0, fmax(10.0, factor_cost_solves(fl, lnz)));
  }
  if (m->prefactored) { /* the factor made in setup (palp_fem_model_prefactor), if of this very K */
    m->prefactored = 0;
    if (m->factored && m->kfac && !memcmp(m->kfac, m->kval, sizeof(double) * (size_t)m->nnz)) {
      factor_made(m);
      m->factor_c0 = kscale_c0;
      fresh = 1;
    }
  }
  if (!fresh && m->renew && !m->renew_fg && background_ok(m) && m->factored && !m->full_newton &&
      !palp_fem_solver_factor_running(m->solver)) {
    /* renewal on the background thread from this K_eff; this step goes on with
     * the old factor as CG's preconditioner (install_background) */
    const int rc = palp_fem_solver_factor_start(m->solver, m->kval);
    if (rc) return rc;
    m->bg_attempt = m->attempts;
    m->renew = 0;
  }
  int renewed = 0; /* static_reuse: a factor of this K (maybe shifted) was made for this solve */
  if (!fresh && (!m->factored || m->full_newton || m->last_pcg > limit || m->renew)) {
    int rc = factor(m);
    m->factored = rc == 0;
    if (rc) return rc;
    m->factor_c0 = kscale_c0;
    fresh = !m->factor_shifted; /* a shifted factor is only a preconditioner */
    renewed = 1;
  }
  int rc = 0;
  if (fresh) {
    rc = solve_exact(m, b, x); /* the factor is of this very K */
    m->last_pcg = 0;
  } else {
  krylov:;
    const double bn = sqrt(dot(b, b, n));
    memcpy(r, b, sizeof(double) * (size_t)n);
    memset(x, 0, sizeof(double) * (size_t)n);
    if (guess) { /* x0 = alpha d, d = guess on the free equations (see newton_solve) */
      double *dv = q + n;
      for (int d = 0; d < m->ndof; ++d)
        if (m->eq[d] >= 0) dv[m->eq[d]] = guess[d];
      symv(m, dv, q);
      const double dkd = dot(dv, q, n);
      if (dkd > 0.0) {
        const double al = dot(dv, b, n) / dkd;
        for (int i = 0; i < n; ++i) {
          x[i] = al * dv[i];
          r[i] = b[i] - al * q[i];
        }
      }
    }
    rc = precond(m, r, z);
    memcpy(p, z, sizeof(double) * (size_t)n);
    double rz = dot(r, z, n);
    int it = 0, ok = 0, broke = 0;
    while (!rc && it < 2 * limit + 20) {
      symv(m, p, q);
      const double pq = dot(p, q, n);
      if (!(pq > 0.0)) { /* indefinite direction (tangent or LDL^T preconditioner) */
        broke = 1;
        break;
      }
      const double alpha = rz / pq;
      for (int i = 0; i < n; ++i) {
        x[i] += alpha * p[i];
        r[i] -= alpha * q[i];
      }
      ++it;
      if (sqrt(dot(r, r, n)) <= eta * bn) {
        ok = 1;
        break;
      }
      rc = precond(m, r, z);
      const double rz2 = dot(r, z, n);
      const double beta = rz2 / rz;
      rz = rz2;
      for (int i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
    }
    m->pcg_iterations += it;
    m->last_pcg = it;
    if (!rc && !ok && broke && allow_gmres) { /* indefinite: GMRES with the same preconditioner */
      if (!m->gmres_ws) m->gmres_ws = malloc(sizeof(double) * (size_t)(2 * GMRES_K + 1) * (size_t)n);
      if (m->gmres_ws) {
        const int git = gmres(m, b, x, fmin(eta_gmres, 1e-2), 2 * limit + 20, m->gmres_ws, &rc);
        if (git >= 0) {
          ok = 1;
          m->pcg_iterations += git;
          m->gmres_solves++;
          m->last_pcg = it + git;
        }
      }
    }
    if (!rc && !ok && m->in_static && !renewed) {
      /* static_reuse, the old factor stalled: a factor of this K, shifted if it is
       * indefinite (then the Krylov solve again), before the exact LDL^T */
      rc = factor(m);
      m->factored = rc == 0;
      if (rc) return rc;
      m->factor_c0 = kscale_c0;
      renewed = 1;
      if (m->factor_shifted) goto krylov;
      m->last_pcg = 0;
      rc = solve_exact(m, b, x);
    } else if (!rc && !ok) { /* CG/GMRES stalled: renew the factor and solve directly */
      rc = factor_exact(m);
      m->factored = rc == 0;
      if (rc) return rc;
      m->factor_c0 = kscale_c0;
      m->last_pcg = 0;
      rc = solve_exact(m, b, x);
    }
  }
  for (int d = 0; d < m->ndof; ++d) m->du[d] = m->eq[d] >= 0 ? x[m->eq[d]] : 0.0;
  return rc;
}

static int solve_static(palp_fem_model *m, const double *fext, int increments, double dt);
static double newton_forcing(int it, double r, double scale, double tol);

static void commit(palp_fem_model *m) {
  const size_t E = (size_t)m->mesh->element_count;
  memcpy(m->S0, m->S0t, sizeof(double) * E * 48);
  memcpy(m->H, m->Ht, sizeof(double) * E * 8 * (size_t)m->nprony * 6);
}

int palp_fem_solve_static(palp_fem_model *m, const double *fext, int increments, double dt) {
  if (increments < 1) increments = 1;
  /* Static solves serve verification: full Newton (a fresh factor every
   * iteration, LDL^T where indefinite) for exact Newton steps, unless static_reuse
   * asks for the inexact steps of solve_static. */
  const int full = m->full_newton;
  m->full_newton = !m->static_reuse;
  m->in_static = m->static_reuse;
  const int rc = solve_static(m, fext, increments, dt);
  m->in_static = 0;
  m->full_newton = full;
  return rc;
}

static int solve_static(palp_fem_model *m, const double *fext, int increments, double dt) {
  const size_t nd = (size_t)m->ndof;
  for (int inc = 1; inc <= increments; ++inc) {
    const double lam = (double)inc / increments;
    double *u = m->utrial;
    memcpy(u, m->u, sizeof(double) * nd);
    for (size_t d = 0; d < nd; ++d)
      if (m->eq[d] < 0) u[d] = lam * m->prescribed[d];
    m->trace_count = 0;
    int converged = 0;
    for (int it = 0; it <= m->max_newton; ++it) {
      int rc = palp_fem_assemble(m, u, dt, 1);
      /* an iterate that inverts an element is pulled back along the step */
      for (int half = 0; rc == PALP_EUNSTABLE && it > 0 && half < 6; ++half) {
        for (size_t d = 0; d < nd; ++d) {
          m->du[d] *= 0.5;
          u[d] -= m->du[d];
        }
        rc = palp_fem_assemble(m, u, dt, 1);
      }
      if (rc) {
        snprintf(m->err, sizeof m->err, "static increment %d/%d: %s", inc, increments,
                 rc == PALP_EUNSTABLE ? "an element inverted (det F <= 0); use more increments" : palp_strerror(rc));
        return rc;
      }
      for (size_t d = 0; d < nd; ++d) m->res[d] = (fext ? lam * fext[d] : 0.0) - m->fint[d];
      const double r = norm_free(m, m->res);
      /* the force scale includes the reactions: at equilibrium f_int vanishes on
       the free equations but not on the prescribed ones */
      const double scale = fmax(fext ? lam * norm_free(m, fext) : 0.0, norm_all(m, m->fint));
      if (m->trace_count < 64) m->trace[m->trace_count++] = r;
      if (!isfinite(r)) return PALP_EUNSTABLE;
      if (r <= m->rtol * scale + m->atol) {
        converged = 1;
        break;
      }
      if (it == m->max_newton) break;
      if (m->static_reuse) {
        /* Inexact Newton on the consistent tangent: CG (GMRES where the tangent or
         * the factor is indefinite) preconditioned by the last factor, renewed when a
         * solve costs more than a factorisation (newton_solve_). A run of nearby
         * equilibria (a finger pressed depth by depth, its augmented-Lagrangian
         * updates) changes the tangent little between solves, so most Newton steps
         * cost tens of preconditioner solves (~30 ms each at level 4) instead of a
         * factorisation (1 s, several as a simplicial LDL^T where indefinite). The
         * converged state meets the same residual test. */
        const double tol = m->rtol * scale + m->atol;
        const double eta = newton_forcing(it, r, scale, tol);
        rc = newton_solve(m, isinf(dt) ? -1.0 : -2.0 - dt, eta, newton_forcing(0, r, scale, tol), 1, NULL);
      } else
        rc = newton_solve(m, isinf(dt) ? -1.0 : -2.0 - dt, fmin(0.1, r / fmax(scale, 1e-300)), 0.1, 0, NULL);
      if (rc) return rc;
      m->newton_iterations++;
      for (size_t d = 0; d < nd; ++d) u[d] += m->du[d];
    }
    if (!converged) {
      snprintf(m->err, sizeof m->err, "static increment %d/%d did not converge in %d Newton iterations", inc,
               increments, m->max_newton);
      return PALP_ESOLVER;
    }
    memcpy(m->u, u, sizeof(double) * nd);
    commit(m);
    m->steps++;
  }
  return PALP_OK;
}

/* Forcing term of the inexact Newton iteration: the Krylov solve of iteration
 * `it` stops at ||K du - r|| <= eta ||r||, r [N] the residual, scale [N] the force
 * scale, tol [N] the step's tolerance.
 *   eta = min(0.1, r / scale)        keeps the iteration quadratic (r / scale -> 0);
 *   eta <= 0.5 tol / r  for it >= 1  aims the next iterate at the tolerance.
 * The first iterate of a step moves the mesh by the whole step's increment and
 * leaves a nonlinear residual of ~10-60% of the force scale whatever the solve's
 * accuracy (the 2 GPa volumetric penalty acting on the increment's second-order
 * volume change, K (grad du)^2), so it is solved loosely; from the second on, the nonlinear remainder
 * after an exact solve is ~1e-6 of the scale (level 2: 0.63 -> 0.068 -> 1e-8 with
 * exact solves), so a solve to half the tolerance ends the step one iterate
 * earlier than eta = r / scale would (0.072 -> 4.4e-3 -> 1.3e-6): 2 instead of 3
 * Newton iterations per step for about the same number of CG iterations. The
 * convergence test itself (on the true residual) is unchanged. */
static double newton_forcing(int it, double r, double scale, double tol) {
  double eta = fmin(0.1, r / fmax(scale, 1e-300));
  if (it >= 1 && r > 0.0) eta = fmin(eta, 0.5 * tol / r);
  return eta;
}

/* Installs the factor of the background thread (waiting for it if need be); if
 * that matrix was not positive definite, the next solve renews in the foreground. */
static void install_background(palp_fem_model *m) {
  const double t0 = now_s();
  const int rc = palp_fem_solver_factor_finish(m->solver, 1);
  m->sec_wait += now_s() - t0;
  if (rc) {
    m->renew = 1;
    m->renew_fg = 1;
    return;
  }
  factor_made(m);
  m->bg_factorizations++;
  m->factored = 1;
  m->last_pcg = 0; /* CG's count belonged to the old factor */
}

/* One Newmark step of length dt without cut-back; leaves the trial state in
 * utrial / atrial / S0t / Ht on success. */
static int try_step(palp_fem_model *m, const double *fext, double dt) {
  const size_t nd = (size_t)m->ndof;
  const double beta = m->newmark_beta;
  const double c0 = 1.0 / (beta * dt * dt), c1 = 1.0 / (beta * dt), c2 = 1.0 / (2.0 * beta) - 1.0;
  const double alpha = m->hht_alpha;
  double *u = m->utrial, *a = m->atrial;
  /* Newton starts from the last converged state: extrapolating with the velocity
   * (u + dt v, or + dt^2/2 a) was tried and costs more iterations and cut-backs,
   * because the undamped Newmark velocity carries the high-frequency ringing of
   * the step load and the gel's volumetric penalty (K = 2 GPa) turns any error of
   * the start point into a residual K (grad du)^2. */
  for (size_t d = 0; d < nd; ++d) u[d] = m->eq[d] < 0 ? m->prescribed[d] : m->u[d];
  m->trace_count = 0;
  /* automatic renewal of the reused factor, decided once per attempt from counts
   * (deterministic): see renew_factor */
  const long last = m->solves - m->step_solves0;
  m->step_solves0 = m->solves;
  m->attempts++;
  /* a background factor is installed at a fixed attempt count, factor_lag after
   * the attempt that started it, never when the thread happens to finish: the
   * results do not depend on the timing */
  const int running = palp_fem_solver_factor_running(m->solver);
  if (running && m->attempts >= m->bg_attempt + m->factor_lag) install_background(m);
  else if (m->pcg_refactor <= 0 && m->factored && !m->full_newton && !running) {
    double cost = factor_cost_solves(palp_fem_solver_factor_flops(m->solver), palp_fem_solver_factor_nnz(m->solver));
    if (background_ok(m)) cost *= BACKGROUND_COST;
    if (renew_factor(cost, m->solves - m->fac_solves, m->attempts - m->fac_attempt, last)) m->renew = 1;
  }
  const double fnorm = fext ? norm_free(m, fext) : 0.0;
  /* HHT only: the residual's round-off floor, 1e-8 of the largest load of the run. It
   * sits near 1e-9 of the load (4e-9 N at 3 N, level 2: the 2 GPa volumetric terms),
   * and once HHT has damped the ringing a relaxed dome's force scale, hence rtol x
   * scale, falls below it (the long-term profile's recovery stalled there at t =
   * 2.82 s). The trapezoidal rule keeps its tolerance as it was, bit for bit. */
  if (fnorm > m->fext_max) m->fext_max = fnorm;
  const double floor_hht = m->hht_alpha != 0.0 ? PALP_FEM_HHT_FLOOR * m->fext_max : 0.0;
  double r0 = 0.0;
  /* The tangent is assembled with the force unless this iterate is expected to
   * converge (then only the force, ~1/4 of the cost; a wrong guess assembles again
   * with the tangent, the force and residual being the same) */
  int tangent = 1;
  for (int it = 0; it <= m->max_newton; ++it) {
    for (size_t d = 0; d < nd; ++d) a[d] = c0 * (u[d] - m->u[d]) - c1 * m->v[d] - c2 * m->a[d];
    int rc = palp_fem_assemble(m, u, dt, tangent);
    if (rc) return rc;
    double ma2 = 0.0;
    if (alpha == 0.0) {
      for (size_t d = 0; d < nd; ++d) {
        const double ma = m->mass[d / 3] * a[d];
        m->res[d] = (fext ? fext[d] : 0.0) - ma - m->fint[d];
        if (m->eq[d] >= 0) ma2 += ma * ma;
      }
    } else {
      for (size_t d = 0; d < nd; ++d) {
        const double ma = m->mass[d / 3] * a[d];
        m->res[d] = (1.0 + alpha) * ((fext ? fext[d] : 0.0) - m->fint[d]) - alpha * (m->fext_prev[d] - m->fint_prev[d]) - ma;
        if (m->eq[d] >= 0) ma2 += ma * ma;
      }
    }
    const double r = norm_free(m, m->res);
    const double scale = fmax(fmax(fnorm, sqrt(ma2)), norm_all(m, m->fint));
    if (m->trace_count < 64) m->trace[m->trace_count++] = r;
    if (!isfinite(r)) return PALP_EUNSTABLE;
    if (it == 0) r0 = r;
    if (r <= m->rtol * scale + m->atol + floor_hht) return PALP_OK;
    if (it == m->max_newton || (it > 2 && r > 1e3 * r0)) break;
    if (!tangent && (rc = palp_fem_assemble(m, u, dt, 1))) return rc;
    if (alpha != 0.0)
      for (long k = 0; k < m->nnz; ++k) m->kval[k] *= 1.0 + alpha;
    /* K_eff = K_T + M / (beta dt^2): the diagonal is the last entry of each column */
    for (size_t d = 0; d < nd; ++d) {
      const int c = m->eq[d];
      if (c >= 0) m->kval[m->colp[c + 1] - 1] += c0 * m->mass[d / 3];
    }
    const double tol = m->rtol * scale + m->atol + floor_hht;
    const double eta = newton_forcing(it, r, scale, tol);
    rc = newton_solve(m, c0, eta, newton_forcing(0, r, scale, tol), 1, it == 0 ? m->v : NULL);
    if (rc) return rc;
    m->newton_iterations++;
    for (size_t d = 0; d < nd; ++d) u[d] += m->du[d];
    /* an iterate whose linear solve aimed at the tolerance is expected to meet it */
    tangent = !(eta * r <= 0.5 * tol);
  }
  return PALP_ESOLVER;
}

int palp_fem_model_prefactor(palp_fem_model *m, double dt) {
  if (m->full_newton || m->factored || !(dt > 0.0)) return PALP_OK; /* nothing to gain */
  const size_t nd = (size_t)m->ndof;
  const double c0 = 1.0 / (m->newmark_beta * dt * dt); /* [1/s^2], as try_step's first attempt */
  double *u = m->utrial;
  for (size_t d = 0; d < nd; ++d) u[d] = m->eq[d] < 0 ? m->prescribed[d] : m->u[d];
  int rc = palp_fem_assemble(m, u, dt, 1);
  if (rc) return rc;
  if (m->hht_alpha != 0.0)
    for (long k = 0; k < m->nnz; ++k) m->kval[k] *= 1.0 + m->hht_alpha;
  for (size_t d = 0; d < nd; ++d) {
    const int c = m->eq[d];
    if (c >= 0) m->kval[m->colp[c + 1] - 1] += c0 * m->mass[d / 3];
  }
  if (!m->kfac) m->kfac = malloc(sizeof(double) * (size_t)(m->nnz ? m->nnz : 1));
  if (!m->kfac) return PALP_ENOMEM;
  memcpy(m->kfac, m->kval, sizeof(double) * (size_t)m->nnz);
  const double t0 = now_s();
  rc = palp_fem_solver_factor(m->solver, m->kval);
  m->sec_factor += now_s() - t0;
  m->factored = rc == 0;
  m->prefactored = m->factored;
  /* a singular K_eff is the first step's business (it cuts the step back) */
  return rc == PALP_ESOLVER ? PALP_OK : rc;
}

int palp_fem_step(palp_fem_model *m, const double *fext, double dt) {
  const size_t nd = (size_t)m->ndof;
  /* Sub-steps are counted in integer units of dt / 2^max_cutbacks, so halved,
   * doubled and clipped steps add up to the frame exactly: with steps kept in
   * seconds, a step clipped to the remainder carried round-off into the remembered
   * step, doubling it gave a full step 1e-9 short of dt, and the leftover sliver of
   * ~1e-11 s was then tried as a step of its own (c0 = 1 / (beta h^2) ~ 1e22), which
   * failed every cut-back. */
  const long full = 1L << m->max_cutbacks;
  /* A cut step is remembered across calls and doubles back only after three
   * successes in a row: retrying the full dt at once after every cut wastes a
   * failing Newton sequence each time. */
  long h = full;
  if (m->h_next > 0.0 && m->h_next < dt) h = lround(m->h_next / dt * (double)full);
  if (h < 1) h = 1;
  if (h > full) h = full;
  long done = 0;
  int halvings = 0;
  const double t_start = m->time;
  while (done < full) {
    if (h > full - done) h = full - done;
    const double hs = dt * (double)h / (double)full; /* [s] */
    const int rc = try_step(m, fext, hs);
    if (rc == PALP_ENOMEM) { /* not retried: a smaller step needs the same factor */
      snprintf(m->err, sizeof m->err, "time step at t = %.6g s: out of memory (the sparse factor of %d equations)",
               m->time, m->nfree);
      return rc;
    }
    if (rc) {
      if (h < 2) {
        /* the halvings made in this call: a step that starts from a remembered shorter
         * h_next makes fewer than max_cutbacks (the message used to print max_cutbacks) */
        snprintf(m->err, sizeof m->err,
                 "time step at t = %.6g s failed after %d cut-backs (dt = %.3g s): %s", m->time,
                 halvings, hs,
                 rc == PALP_EUNSTABLE ? "an element inverted or the residual became non-finite"
                                      : "Newton did not converge or the tangent was singular");
        return rc == PALP_ESOLVER ? PALP_ESOLVER : PALP_EUNSTABLE;
      }
      h /= 2;
      halvings++;
      m->cutbacks++;
      m->streak = 0;
      continue;
    }
    const double g = m->newmark_gamma;
    for (size_t d = 0; d < nd; ++d) {
      m->v[d] += hs * ((1.0 - g) * m->a[d] + g * m->atrial[d]);
      m->a[d] = m->atrial[d];
      m->u[d] = m->utrial[d];
    }
    if (m->hht_alpha != 0.0) { /* the forces the next step's alpha-weighting starts from */
      memcpy(m->fint_prev, m->fint, sizeof(double) * nd);
      for (size_t d = 0; d < nd; ++d) m->fext_prev[d] = fext ? fext[d] : 0.0;
    }
    commit(m);
    done += h;
    m->time = done == full ? t_start + dt : m->time + hs; /* land exactly on the frame */
    m->steps++;
    if (h < full && ++m->streak >= 3) {
      h = 2 * h < full ? 2 * h : full;
      m->streak = 0;
    }
  }
  m->h_next = dt * (double)h / (double)full;
  return PALP_OK;
}
