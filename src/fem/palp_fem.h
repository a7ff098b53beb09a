/*
 * palp_fem.h - the nonlinear viscoelastic finite-element reference ("golden
 * standard") for the breast phantom of Widmer & Hu 2011.
 *
 * A structured hexahedral mesh of the 8.0 cm hemisphere (gel core under a 2 mm
 * membrane, base fixed) is loaded at the very points the real-time model is loaded
 * at, and integrated implicitly in time. The result is the same per-frame record
 * the real-time model produces, so the two can be compared vertex by vertex.
 *
 * Units are SI throughout (m, kg, s, N, Pa; D1 in 1/Pa). Functions return 0 or a
 * negative PALP_E* code from palp.h. No globals: every handle is owned by its
 * creator and released by the matching destroy call.
 */
#ifndef PALP_FEM_H
#define PALP_FEM_H

#include <stddef.h>
#include <stdint.h>

#include "palp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped whenever a change alters results, so cached references are recomputed. */
#define PALP_FEM_CODE_VERSION 3 /* 2: fem-speed (element kernel round-off, Newton path within rtol);
                                  3: fem-frames (background renewal of the factor, within rtol) */

/* ---- mesh ---------------------------------------------------------------- */
enum { PALP_FEM_GEL = 0, PALP_FEM_MEMBRANE = 1 };

typedef struct palp_fem_set {
  char name[32];  /* upper case, as in the .inp file */
  int is_element; /* 0: node set, 1: element set */
  int count;
  int *items; /* 0-based node or element indices */
} palp_fem_set;

/* 8-node hexahedra, Abaqus C3D8 node order (1-4 one face counter-clockwise seen
 * from inside the element, 5-8 the opposite face), positive reference volume. */
typedef struct palp_fem_mesh {
  int node_count;
  int element_count;
  double (*x)[3];    /* [node_count] reference positions [m] */
  int (*hex)[8];     /* [element_count] node indices */
  uint8_t *region;   /* [element_count] PALP_FEM_GEL or PALP_FEM_MEMBRANE */
  uint8_t *fixed;    /* [node_count] 1 on the clamped base */
  int top_node;      /* node at the pole (largest z on the surface) */
  int set_count;
  palp_fem_set *sets;
} palp_fem_mesh;

/* The O-grid hemisphere: a half-cube core of half-size core_fraction * (radius -
 * membrane_thickness), five radial gel blocks out to the membrane, and
 * membrane_layers element layers through the membrane. Level n >= 1 uses 2n core
 * cells across half the cube and 2n gel layers; level 4 has 10,496 hexahedra. */
/* Validation bounds (palp_fem_config_validate, since session 82): the finest generated
 * level (level 8 took 5 GB; each level ~2.5x more), the loosest Newton tolerances. */
#define PALP_FEM_MAX_LEVEL 8
#define PALP_FEM_MAX_RTOL 1e-2
#define PALP_FEM_MAX_ATOL 1e-3 /* [N] */
/* An --inp mesh's ceiling, of level 8's order (87,040 hexahedra). */
#define PALP_FEM_MAX_ELEMENTS 100000
/* Peak memory [GB] of a run on a hex mesh of this many elements: level 8's 5.0 GB
 * scaled by (elements / 87,040)^(4/3), a 3D sparse factor's fill. A rough estimate. */
double palp_fem_memory_estimate_gb(double elements);

typedef struct palp_fem_mesh_def {
  double radius;             /* [m], 0.04 */
  double membrane_thickness; /* [m], 0.002 (Table I) */
  double core_fraction;      /* [-], 0.5 */
  int level;                 /* >= 1, default 2 */
  int membrane_layers;       /* >= 2; 0 picks max(2, level - 1) */
  /* Local refinement for the fingertip (docs/fem.md, "The fingertip's mesh"): the
   * element size at one spot of the surface against the uniform lattice's, in (0, 1];
   * 0 or 1: the uniform lattice, bit for bit. The spot is at grading_polar_deg in the
   * x-z plane (0 the pole; the fingertip sites' 45, 60, 70 deg). Each lattice coordinate
   * s is mapped about the spot's s0 by g(s) = s0 + (s - s0) (alpha + (1 - alpha) u^2),
   * u = |s - s0| / (the interval's end - s0): g keeps the ends and s0, g' = alpha at s0
   * and 3 - 2 alpha at the ends, so cells at the spot shrink by alpha and the farthest
   * grow by up to 3 - 2 alpha. x and y are graded (y about 0); z too when the spot is on
   * the cube's side (>= 45 deg). Why: the skin's bending length under a fingertip
   * (~3 mm) is below a uniform level-4 cell (3.9 mm). */
  double grading;
  double grading_polar_deg;
} palp_fem_mesh_def;

palp_fem_mesh_def palp_fem_mesh_default_def(void);
int palp_fem_mesh_create(const palp_fem_mesh_def *def, palp_fem_mesh *out);
void palp_fem_mesh_destroy(palp_fem_mesh *mesh);
const palp_fem_set *palp_fem_mesh_find_set(const palp_fem_mesh *mesh, const char *name, int is_element);
/* Signed volume of element e in the reference configuration [m^3]. */
double palp_fem_element_volume(const palp_fem_mesh *mesh, int e);

/* Abaqus .inp exchange: *NODE, *ELEMENT TYPE=C3D8, *NSET, *ELSET (BASE, SURFACE,
 * TOP, MEMBRANE, GEL). Reading accepts any C3D8-family hex mesh; regions come from
 * the MEMBRANE / GEL element sets (all gel if absent), the clamped base from NSET
 * BASE (else every node with z <= 1e-9 m). err receives a message naming the line. */
int palp_fem_inp_write(const palp_fem_mesh *mesh, const char *path, const char *heading);
int palp_fem_inp_read(const char *path, palp_fem_mesh *out, char *err, size_t errlen);

/* ---- material ------------------------------------------------------------ */
#define PALP_FEM_MAX_PRONY 4

/* Abaqus compressible Neo-Hookean, U = C10 (I1bar - 3) + (J - 1)^2 / D1, with a
 * Prony series g(t) = 1 - sum_k g_k (1 - exp(-t / tau_k)) on the deviatoric part. */
typedef struct palp_fem_material {
  double density; /* [kg/m^3] */
  double c10;     /* [Pa]; instantaneous or long-term, see palp_fem_c10_reading */
  double d1;      /* [1/Pa]; bulk modulus K = 2 / D1 */
  int prony_count;
  double g[PALP_FEM_MAX_PRONY];   /* [-], sum < 1 */
  double tau[PALP_FEM_MAX_PRONY]; /* [s] */
} palp_fem_material;

typedef enum palp_fem_c10_reading {
  PALP_FEM_C10_LONG_TERM = 0,    /* C10 is the relaxed modulus; instantaneous = C10 / g_inf */
  PALP_FEM_C10_INSTANTANEOUS = 1 /* C10 is the instantaneous modulus; relaxed = g_inf C10 */
} palp_fem_c10_reading;

/* How a real-time vertex's load reaches the FE surface, and its displacement comes
 * back (docs/fem.md, "Surface map"). POINT: the four nodes of the one FE face the
 * vertex's ray hits, bilinear weights: a point force on the continuum, whose peak
 * displacement grows without bound as the FE mesh is refined (the paper's literal
 * nodal load). PATCH: the vertex's hat function on the real-time surface (1 at the
 * vertex, 0 at its neighbours), carried over to the FE surface radially and
 * integrated: the load is a traction over the vertex's one-ring with the vertex's
 * own force as resultant, and the displacement is the same hat-weighted average,
 * so the two models compare at the real-time mesh's resolution and the FE side
 * converges with refinement. */
typedef enum palp_fem_load_map {
  PALP_FEM_LOAD_POINT = 0,
  PALP_FEM_LOAD_PATCH = 1
} palp_fem_load_map;

/* ---- configuration ------------------------------------------------------- */
typedef struct palp_fem_config {
  palp_fem_mesh_def mesh;
  char inp_path[512]; /* non-empty: read the mesh from this .inp instead */
  palp_fem_material membrane;
  palp_fem_material gel;
  palp_fem_c10_reading c10_reading;
  char material[32];    /* the profile the materials came from (palp_fem_config_set_material); "" if custom */
  double dt;            /* [s] time step; 0 means one step per output frame */
  double newmark_beta;  /* 0.25 (average acceleration) */
  double newmark_gamma; /* 0.5 */
  /* Hilber-Hughes-Taylor alpha in [-1/3, 0]; 0 is plain Newmark (the trapezoidal
   * rule, no numerical dissipation). Nonzero: the internal and external forces of
   * the equation of motion are taken at 1 + alpha of the step, with beta = (1 -
   * alpha)^2 / 4 and gamma = 1/2 - alpha, so modes the step cannot resolve decay
   * and the ones it can keep second-order accuracy. Abaqus/Standard's *DYNAMIC
   * default is -0.05 ("slight numerical damping"). */
  double hht_alpha;
  int max_newton;       /* iterations per step before the step is cut back, 12 */
  double newton_rtol;   /* residual tolerance relative to the force scale, 1e-4 */
  double newton_atol;   /* absolute residual floor [N], 1e-9 */
  int max_cutbacks;     /* dt halvings allowed per step, 8 */
  int full_newton;      /* 1: factor the tangent every iteration; 0: reuse the factor as CG preconditioner */
  int pcg_refactor;     /* renew the factor when CG took more iterations than this; 0 = automatic */
  int threads;          /* assembly threads, 2 (results do not depend on it beyond round-off) */
  /* automatic mode (pcg_refactor 0, full_newton 0): a factor renewed by the renewal
   * rule is made on a background thread from the K_eff of the step attempt that
   * decided it and replaces the old one at the start of the factor_lag-th attempt
   * after (waiting for it if it is not ready), so the results depend on factor_lag,
   * never on the thread's timing; 0 renews in the foreground (before fem-frames) */
  int factor_lag;
  char cache_dir[512];  /* "" disables the cache; default "cache/fem" */
  palp_fem_load_map load_map; /* see palp_fem_load_map */
} palp_fem_config;

/* The default material profile is "paper_long_term" (docs/materials.md); a scene's
 * "material" names the one its parameters were fitted to, and the tools prefer it. */
palp_fem_config palp_fem_default_config(void);
/* Sets hht_alpha and the Newmark beta and gamma that go with it (alpha 0: plain
 * Newmark, beta 1/4, gamma 1/2). */
void palp_fem_config_set_hht(palp_fem_config *cfg, double alpha);
/* The FEM a scene answers to: the default config with the material profile the scene's
 * parameters were fitted to, when it names one (palp_scene.material). A FEM config file
 * or --material applied after it still win. PALP_EINVAL with a message for a profile
 * the FEM does not know. */
int palp_fem_config_for_scene(const palp_scene *scene, palp_fem_config *out, char *err, size_t errlen);

/* ---- material profiles (docs/materials.md) -------------------------------- */
/* Named material sets: "paper_long_term" (Tables I-II, C10 the relaxed modulus;
 * the default), "paper_instantaneous" (the same numbers read as instantaneous
 * moduli: a reproduction of the paper's literal reading, ~1% of the stiffness
 * when relaxed) and "breast_tissue" (literature moduli of breast fat and skin).
 * Sets cfg->membrane, cfg->gel, cfg->c10_reading and cfg->material; returns
 * PALP_EINVAL with a message listing the names for an unknown one. */
int palp_fem_config_set_material(palp_fem_config *cfg, const char *name, char *err, size_t errlen);
/* The label printed beside a profile's results, e.g. "reproduction of the
 * paper's literal reading" for paper_instantaneous; "" for an unknown name. */
const char *palp_fem_material_label(const char *name);
/* The profile names, NULL-terminated. */
const char *const *palp_fem_material_names(void);
/* Overrides fields of *cfg from a JSON file; unknown keys are errors. */
int palp_fem_config_load(const char *path, palp_fem_config *cfg, char *err, size_t errlen);
int palp_fem_config_parse(const char *json, palp_fem_config *cfg, char *err, size_t errlen);
int palp_fem_config_validate(const palp_fem_config *cfg, char *err, size_t errlen);

/* ---- runs ---------------------------------------------------------------- */
/* The per-frame record, frames x vertices, frame f at time[f] = (f + 1) * frame_period. */
typedef struct palp_fem_result {
  int frames;
  int vertex_count;  /* real-time mesh vertices */
  int top_vertex;
  double *time;      /* [frames] [s] */
  palp_vec3 *disp;   /* [frames * vertex_count] displacement of each mapped vertex [m] */
  palp_vec3 *top_disp; /* [frames] [m] */
  int contact_vertex_count;
  int *contact_vertex; /* [contact_vertex_count] real-time vertex index */
  int *contact_of;     /* [contact_vertex_count] scene contact index */
  palp_vec3 *feedback; /* [frames * contact_vertex_count] force on the finger [N] */
  /* statistics of the run that produced it */
  int node_count, element_count, dof_count;
  long steps, newton_iterations, cutbacks, factorizations, pcg_iterations;
  double wall_seconds; /* of the original computation (also when read from cache) */
  /* wall seconds of the computation in element assembly, numeric factorisations,
   * solves with the factor, and the other Krylov work (0 when read from cache) */
  double sec_assemble, sec_factor, sec_solve, sec_krylov;
  long assemblies, tangent_assemblies, solves;
  /* wall seconds before the first step (mesh, surface map, model, symbolic analysis,
   * the first numeric factorisation; part of wall_seconds; 0 when read from cache) */
  double sec_setup;
  /* factorisations made on the background thread (factor_lag), and the wall seconds
   * the run waited for them at their step (0 when read from cache) */
  long background_factorizations;
  double sec_factor_wait;
  int from_cache;
  uint64_t key;        /* cache key */
} palp_fem_result;

void palp_fem_result_destroy(palp_fem_result *r);

/* Called once with frame 0 when the setup is done (before the first step), then
 * after every frame. Return non-zero to cancel the run (palp_fem_run then returns
 * PALP_EINVAL). */
typedef int (*palp_fem_progress_fn)(void *ud, int frame, int frames, double sim_time);

/* Runs a scene (its contacts, profiles, frames and frame period; the real-time
 * mesh from scene->world.mesh) through the FE reference. Looks the result up in
 * cfg->cache_dir first and stores it there afterwards. err gets a message. */
int palp_fem_run(const palp_fem_config *cfg, const palp_scene *scene, palp_fem_result *out,
                 palp_fem_progress_fn cb, void *ud, char *err, size_t errlen);
/* The cache key of a run: FNV-1a over every input and PALP_FEM_CODE_VERSION. (palp_fem_run
 * adds a marker to it when a contact's load map touches the clamped base: docs/fem.md.) */
uint64_t palp_fem_run_key(const palp_fem_config *cfg, const palp_fem_mesh *mesh, const palp_scene *scene);

int palp_fem_cache_load(const char *dir, uint64_t key, palp_fem_result *out);
int palp_fem_cache_store(const char *dir, const palp_fem_result *r);

#ifdef __cplusplus
}
#endif
#endif
