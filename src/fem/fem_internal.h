/*
 * fem_internal.h - the FE reference's building blocks, exposed to its tests and
 * benchmark: material law, hexahedral element, model state and Newton solvers,
 * surface mapping. Not part of the stable palp_fem API.
 *
 * Voigt order for symmetric tensors: 11, 22, 33, 12, 23, 13 (stresses as is;
 * tangent moduli as the 6x6 matrix of d S / d(E) with engineering shear).
 */
#ifndef PALP_FEM_INTERNAL_H
#define PALP_FEM_INTERNAL_H

#include "palp_fem.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PALP_FEM_PI 3.14159265358979323846

/* ---- mesh helpers (fem_mesh.c) -------------------------------------------- */
int palp_fem_mesh_add_set(palp_fem_mesh *m, const char *name, int is_element, int *items, int count);
void palp_fem_mesh_orient(palp_fem_mesh *m);
int palp_fem_mesh_standard_sets(palp_fem_mesh *m);

/* ---- material law (fem_material.c) -------------------------------------- */
/* Relaxed fraction g_inf = 1 - sum g_k. */
double palp_fem_ginf(const palp_fem_material *m);
/* Instantaneous C10 [Pa] under a reading. */
double palp_fem_c10_instant(const palp_fem_material *m, palp_fem_c10_reading r);

/* Isochoric Neo-Hookean 2nd Piola-Kirchhoff stress and its material tangent
 * for right Cauchy-Green tensor C (Voigt, C11..C13) with instantaneous C10 [Pa]:
 *   S = 2 C10 J^(-2/3) (I - I1/3 C^-1)
 *   CC = 4/3 C10 J^(-2/3) [ I1 C^-1 (.) C^-1 + I1/3 C^-1 x C^-1 - I x C^-1 - C^-1 x I ]
 * D may be NULL. */
void palp_fem_nh_iso(double c10, const double C[6], double S[6], double D[6][6]);
/* Volumetric pressure p = dU/dJ = 2 (J - 1) / D1 [Pa], dp/dJ = 2 / D1. */
static inline double palp_fem_pressure(double d1, double J) { return 2.0 * (J - 1.0) / d1; }

/* Prony hereditary integral with the recursive update exact for S0 linear in time
 * over the step (FEBio, Abaqus):
 *   H_k+ = exp(-x_k) H_k + g_k (1 - exp(-x_k)) / x_k (S0+ - S0),  x_k = dt / tau_k
 *   S+   = g_inf S0+ + sum_k H_k+,   dS+/dS0+ = gamma = g_inf + sum_k g_k (1 - exp(-x_k)) / x_k
 * dt = 0 gives the instantaneous response, dt = INFINITY the relaxed one.
 * Hold and Hnew are [prony_count * 6]. Returns gamma. */
double palp_fem_prony_update(const palp_fem_material *m, double dt, const double S0new[6],
                             const double S0old[6], const double *Hold, double *Hnew,
                             double S[6]);

/* ---- hexahedron (fem_hex.c) ---------------------------------------------- */
/* Trilinear shape-function derivatives dN/dxi at the 2x2x2 Gauss points. */
void palp_fem_hex_dshape(const double xi[3], double dN[8][3]);
extern const double palp_fem_gauss[8][3];
/* Element e's reference Jacobian at Gauss point g: dN (the shape gradients dN/dxi there) and
 * J = dX/dxi = sum_a X_a (x) dN_a filled; returns det J [m^3 per unit reference volume]. One
 * place for the model's set-up, the volume and the .inp reader's inverted-element check. */
double palp_fem_hex_jacobian(const palp_fem_mesh *mesh, int e, int g, double dN[8][3], double J[3][3]);

/* ---- model (fem_model.c) --------------------------------------------------- */
typedef struct palp_fem_solver palp_fem_solver;

/* HHT's Newton tolerance floor, as a fraction of the largest load of the run (fem_model.c,
 * try_step; part of the cache key of HHT runs, fem_run.c) */
#define PALP_FEM_HHT_FLOOR 1e-8

typedef struct palp_fem_model {
  const palp_fem_mesh *mesh; /* borrowed */
  palp_fem_material mat[2];  /* [PALP_FEM_GEL], [PALP_FEM_MEMBRANE], C10 already instantaneous */
  int ndof;                  /* 3 * node_count */
  int nfree;
  int *eq;             /* [ndof] equation number or -1 when prescribed */
  double *prescribed;  /* [ndof] prescribed displacement [m] (used where eq < 0) */
  double *mass;        /* [node_count] lumped mass [kg] */
  /* per element per Gauss point: dN/dX [8][3] and weight * det J0 [m^3] */
  double *gp_dNdX;     /* [E * 8 * 24] */
  double *gp_w;        /* [E * 8] */
  double *vol0;        /* [E] */
  /* committed state */
  double *u, *v, *a;   /* [ndof] [m], [m/s], [m/s^2] */
  double *S0, *H;      /* [E*8*6], [E*8*nprony*6] viscoelastic history */
  double time;         /* [s] */
  /* trial state */
  double *S0t, *Ht;    /* trial history of the last evaluation */
  double *fint;        /* [ndof] internal force at the last evaluation [N] */
  double *fext;        /* [ndof] */
  double *res, *du, *utrial, *atrial;
  /* sparse structure: upper triangle in compressed columns over free equations */
  int *colp, *rowi; /* [nfree+1], [nnz] */
  long nnz;
  int *emap;        /* [E * 576] value index or -1 */
  double *kval;     /* [nnz] */
  palp_fem_solver *solver;
  double *pcg;        /* [7 * nfree] CG work vectors */
  int factored;       /* the solver holds a usable factor */
  double factor_c0;   /* mass coefficient 1 / (beta dt^2) the factor was made with */
  int last_pcg;       /* CG iterations of the last solve */
  int full_newton;    /* refactor every iteration */
  /* palp_fem_solve_static: 0 factors the tangent at every Newton iteration (exact
   * steps); 1 solves each Newton step by preconditioned Krylov on the consistent
   * tangent with the last factor, renewed as in time stepping (fem_model.c, solve_static) */
  int static_reuse;
  int in_static;      /* solve_static under static_reuse is running: shifted factors allowed */
  int factor_shifted; /* the current factor is of K with a raised diagonal (a preconditioner only) */
  int pcg_refactor;   /* renew the factor when CG needed more than this (0: automatic) */
  /* automatic renewal (fem_model.c, renew_factor): step attempts and solves so far,
   * and their counts when the factor was made and when the current attempt began */
  long attempts, fac_attempt, fac_solves, step_solves0;
  int renew;          /* renew the factor at the next Newton solve */
  /* palp_fem_model_prefactor: the factor was made in setup from kfac [nnz] (K_eff
   * at the first step's start point); the first Newton solve uses it as a fresh
   * factor when its K_eff is bit for bit the same, so results do not change */
  int prefactored;
  double *kfac;
  /* background renewal (palp_fem_config.factor_lag): the attempt that started the
   * thread; renew_fg: the background factor failed (not positive definite), renew
   * in the foreground; statistics: factors installed from the thread, seconds
   * waited for them */
  int factor_lag;
  long bg_attempt;
  int renew_fg;
  long bg_factorizations;
  double sec_wait;
  long pcg_iterations; /* CG and GMRES iterations */
  long gmres_solves;  /* solves that needed GMRES (indefinite tangent or preconditioner) */
  double *gmres_ws;   /* GMRES basis, allocated on first need */
  double h_next;      /* step to try next [s] after cut-backs (0: the full dt) */
  int streak;         /* successful steps since the last cut or growth */
  int threads;        /* assembly workers */
  /* Hooks (fem_finger.c, fem_lesion.c): a per-element C10 multiplier (NULL: 1),
   * borrowed; and an extra force/tangent term added after every assembly
   * (contact), called with the trial displacement. */
  const double *c10_scale;
  int (*extra_fn)(void *ud, struct palp_fem_model *m, const double *u, int want_tangent);
  void *extra_ud;
  double *tbuf;       /* [(threads - 1) * (ndof + nnz)] private force and stiffness of extra workers */
  int nprony;
  /* statistics */
  long steps, newton_iterations, cutbacks, factorizations;
  /* where the time goes (wall seconds, CLOCK_MONOTONIC): element assembly,
   * numeric factorisations, preconditioner solves with the factor, and the rest of
   * the Krylov iterations (products with K, dot products, vector updates) */
  double sec_assemble, sec_factor, sec_solve, sec_krylov;
  long assemblies, tangent_assemblies, solves;
  /* Newton trace of the last step (residual norms), for convergence tests */
  int trace_count;
  double trace[64];
  double newmark_beta, newmark_gamma;
  double hht_alpha;   /* 0: Newmark; else HHT-alpha (palp_fem_config) */
  double *fint_prev;  /* [ndof] internal force at the last committed state (HHT only) [N] */
  double *fext_prev;  /* [ndof] external force of the last committed step (HHT only) [N] */
  double fext_max;    /* largest external force norm a step has seen [N] (HHT's tolerance floor) */
  double rtol, atol;
  int max_newton, max_cutbacks;
  char err[256];
} palp_fem_model;

/* Builds the model over a mesh: base nodes (mesh->fixed) prescribed to zero. */
int palp_fem_model_create(palp_fem_model *m, const palp_fem_mesh *mesh, const palp_fem_config *cfg);
void palp_fem_model_destroy(palp_fem_model *m);
/* Prescribes one DOF (node, dir) to value [m]; call before palp_fem_model_finalize. */
void palp_fem_model_prescribe(palp_fem_model *m, int node, int dir, double value);
/* Numbers the free equations, builds the sparsity pattern and the symbolic factor. */
int palp_fem_model_finalize(palp_fem_model *m);

/* Internal force and (if want_tangent) the tangent at displacement u under a
 * viscoelastic step of length dt from the committed history (dt = 0: instantaneous,
 * INFINITY: relaxed). Fills m->fint, m->S0t, m->Ht and m->kval (free part only).
 * Returns PALP_EUNSTABLE when an element inverts (det F <= 0). */
int palp_fem_assemble(palp_fem_model *m, const double *u, double dt, int want_tangent);
/* Element-level evaluation used by the tests: internal force fe[24] and tangent
 * ke[24][24] (may be NULL) of element e at nodal displacements ue[24]. */
int palp_fem_element(const palp_fem_model *m, int e, const double *ue, double dt, double *fe,
                     double (*ke)[24], double *S0t, double *Ht);
/* Cauchy stress [Pa] at Gauss point g of element e at displacement u after dt. */
int palp_fem_element_cauchy(const palp_fem_model *m, int e, int g, const double *u, double dt,
                            double sigma[6]);

/* Static equilibrium f_int(u) = fext with prescribed DOFs ramped over `increments`
 * (viscous step dt per increment; INFINITY for the relaxed solid). Commits. */
int palp_fem_solve_static(palp_fem_model *m, const double *fext, int increments, double dt);
/* The first numeric factorisation ahead of the first step (setup rather than the
 * first frame): K_eff = K_T + M / (beta dt^2) at the committed state and the
 * prescribed values, with the step length dt the first palp_fem_step will try. The
 * first Newton solve then uses it as palp_fem_step would have made it (the same
 * bits) if its matrix is bit-identical, and as a mere preconditioner otherwise.
 * No-op with full_newton or an existing factor; only for models without extra_fn
 * state that a call could change. */
int palp_fem_model_prefactor(palp_fem_model *m, double dt);
/* One implicit Newmark step of length dt with external force fext [ndof] at its end,
 * cut back by halving up to max_cutbacks times. Commits on success. */
int palp_fem_step(palp_fem_model *m, const double *fext, double dt);

/* ---- sparse solver (fem_solver.c) -------------------------------------------- */
palp_fem_solver *palp_fem_solver_create(int n, const int *colp, const int *rowi, long nnz);
void palp_fem_solver_destroy(palp_fem_solver *s);
/* Numeric Cholesky of the upper-triangle values, LDL^T if indefinite;
 * PALP_ESOLVER if singular. */
int palp_fem_solver_factor(palp_fem_solver *s, const double *val);
/* A positive definite factor for use as a preconditioner: of val if it is positive
 * definite, else of val with its diagonal raised (*shifted = 1; solve with a
 * Krylov method), else the exact LDL^T (fem_solver.c) */
int palp_fem_solver_factor_spd(palp_fem_solver *s, const double *val, int *shifted);
long palp_fem_solver_shifted_count(const palp_fem_solver *s);
int palp_fem_solver_solve(palp_fem_solver *s, const double *b, double *x);
/* z = M~^-1 r with the factor rounded to single precision (a Krylov preconditioner:
 * half the memory traffic of palp_fem_solver_solve); the double solve where the factor
 * is not a supernodal LL^T (the LDL^T fallback) */
int palp_fem_solver_precond(palp_fem_solver *s, const double *b, double *x);
/* 0: the portable kernels even where the CPU has AVX2 (the same bits; for the tests) */
void palp_fem_solver_set_precond_simd(palp_fem_solver *s, int on);
/* Background numeric LL^T of val (the same pattern) on a thread of its own while
 * solves go on with the current factor; at most one at a time. _finish joins it
 * (waiting if need be) and, if install and it succeeded, makes it the factor the
 * solves use; it returns PALP_ESOLVER when the matrix was not positive definite
 * (nothing installed: factorise it with palp_fem_solver_factor, which has the
 * LDL^T fallback). _running: started and not yet finished. */
int palp_fem_solver_factor_start(palp_fem_solver *s, const double *val);
int palp_fem_solver_factor_finish(palp_fem_solver *s, int install);
int palp_fem_solver_factor_running(const palp_fem_solver *s);
/* For tests of the timing independence: 0 a thread (default), 1 factorise at
 * _start in the caller's thread (the fastest thread), 2 at _finish (the slowest). */
void palp_fem_solver_set_background_mode(palp_fem_solver *s, int mode);
/* Nonzeros of L and flops of the last factorisation. */
double palp_fem_solver_factor_nnz(const palp_fem_solver *s);
double palp_fem_solver_factor_flops(const palp_fem_solver *s);
long palp_fem_solver_ldl_count(const palp_fem_solver *s);

/* ---- surface map (fem_map.c) ------------------------------------------------- */
/* Each real-time vertex v maps to FE nodes node[start[v] .. start[v+1]) with weights
 * w summing to 1: the four bilinear weights of one face (PALP_FEM_LOAD_POINT) or its
 * hat function integrated over the FE surface (PALP_FEM_LOAD_PATCH). A load F_v puts
 * w_va F_v on node a; the vertex's displacement is sum_a w_va u_a. */
typedef struct palp_fem_map {
  int count;
  int *start; /* [count + 1] */
  int *node;
  double *w;
} palp_fem_map;
/* Outer surface faces (single-owner hex faces not entirely on the clamped base),
 * outward oriented; *faces is malloc'ed. */
int palp_fem_surface_faces(const palp_fem_mesh *mesh, int (**faces)[4], int *count);
/* Distribution II of the paper as a dead load: a vertical traction, uniform per unit area,
 * over the surface within horizontal radius sqrt(area / pi) of the pole axis, integrated
 * with gauss x gauss points per face (2 or 6; a point in the cap loads its face), scaled so
 * the nodal z forces sum to exactly -F [N]. f [3 * node_count] is overwritten. */
int palp_fem_cap_traction(const palp_fem_mesh *mesh, double F, double area, int gauss, double *f);
int palp_fem_map_create(const palp_fem_mesh *mesh, const palp_vec3 *points, int count, palp_fem_map *out);
/* PALP_FEM_LOAD_PATCH: rt's dome triangles carry its vertices' hat functions. */
int palp_fem_map_create_patch(const palp_fem_mesh *mesh, const palp_mesh *rt, palp_fem_map *out);
void palp_fem_map_destroy(palp_fem_map *map);
/* The FE dome's outer radius (the largest |x| of any node: the base centre is the
 * origin) against the scene's dome radius [m]: both load maps project radially, so a
 * mesh of another size or unit would "match" anywhere. PALP_EINVAL with both radii
 * in err beyond PALP_FEM_RADIUS_TOL (relative). */
#define PALP_FEM_RADIUS_TOL 0.02
int palp_fem_check_radius(const palp_fem_mesh *mesh, double scene_radius, char *err, size_t errlen);
/* The nodal load palp_fem_run applies at time t [s] for cfg and scene (for tests):
 * *mesh gets the FE mesh (palp_fem_mesh_destroy), *fext [3 * node_count] the load
 * (free). Clamped nodes carry none. */
int palp_fem_run_load(const palp_fem_config *cfg, const palp_scene *scene, double t, palp_fem_mesh *mesh,
                      double **fext, char *err, size_t errlen);

/* ---- hashing -------------------------------------------------------------- */
static inline uint64_t palp_fem_fnv(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = (const unsigned char *)data;
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}
#define PALP_FEM_FNV_SEED 14695981039346656037ull

#ifdef __cplusplus
}
#endif
#endif
