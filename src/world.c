/*
 * world.c - the phantom world: state, the step pipeline, contacts and queries.
 *
 * Time integration (argued in docs/model.md): linearly implicit Euler,
 *   (M + h^2 K~ + c g g^T) v_{n+1} = M v_n + h f_n,   x_{n+1} = x_n + h v_{n+1},
 * where f_n holds the external loads, the membrane forces predicted at the end of
 * the step for unchanged strain (Burgers relaxation over the step included) and the
 * gel pressure force; K~ is the membrane's algorithmic tangent along the links'
 * rest directions, factored once per step size (see refactor()); and
 * c g g^T is the gel's rank-1 volume stiffness and damping, applied with the
 * Sherman-Morrison formula. Burgers states are then advanced exactly with the new
 * strains. The membrane's physical vertex masses make explicit schemes need
 * h < ~50 us; this one is stable at the paper's 10 ms and the haptic 1 ms.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "bending.h"
#include "burgers.h"
#include "finger.h"
#include "gel.h"
#include "palp.h"
#include "palp_rng.h"
#include "sparse_ldl.h"
#include "vec3.h"

enum { CONTACT_NONE = 0, CONTACT_FORCE = 1, CONTACT_FINGER = 2 };
/* A deferred refactorisation's state: requested by a step, claimed by a host that
 * computes it elsewhere, handed back done; installed at its due frame. */
enum { JOB_NONE = 0, JOB_REQUESTED = 1, JOB_CLAIMED = 2, JOB_DONE = 3 };
/* The longest step of the haptic physics rates (500 Hz and up), where a rebuilt tangent is
 * blended in (palp_world_refactor_blend_for) and a factor past its stability margin is
 * rebuilt at once (try_step); at slower rates the station blends each model over several
 * haptic ticks, and rebuilds on the tick cost more than they gave (docs/haptics.md). */
#define PALP_HAPTIC_MAX_DT 0.002 /* [s] */

/* Why a factor must be rebuilt at once (palp_world.unsafe, bits): it is beyond its
 * margin (a link's tension stiffness above twice what it holds, or the stiffening
 * support's tangent past the mass term's), so a blend with it would not be stable; or
 * its turned links near the margin (turn_quotient above PALP_TURN_UNSAFE), where it is
 * still stable and the new factor is blended in. */
#define PALP_UNSAFE_MARGIN 1
#define PALP_UNSAFE_TURN 2
/* A link turned by theta from the direction the factor holds its axial stiffness k_l
 * along has k_l sin^2(theta) of it across that direction, where the factor holds only
 * what the vertex has there. At a free vertex, with S the smallest stiffness of the
 * factor's diagonal block there (mass / h^2 included), the quotient
 *   q = sum over the vertex's links of k_l sin^2(theta_l) / S
 * estimates what the linearly implicit step sees beyond the factor in a mode of that
 * vertex: the step's amplification there is about q, neutral at 1 (turn_quotient takes
 * it per link, the larger sum of its ends over the softer end). The long-term dome slid
 * at 1 kHz rang at the Nyquist rate from q ~ 1.06 (its skin's viscous tangent is 13x its
 * static modulus) while every link's turn was under 17 deg and its tension under 0.8 of
 * what the factor holds (docs/haptics.md, "A turned stiff link rings"). Stale at 0.5 (a
 * deferred rebuild then starts where the amplification is at most 0.5), at once at 0.9. */
#define PALP_TURN_STALE 0.5
#define PALP_TURN_UNSAFE 0.9

typedef struct contact {
  int kind;
  int count;       /* vertices loaded (force) or touched last step (finger) */
  int cap;
  int *vertex;     /* [cap] */
  double *weight;  /* [cap] force contacts only */
  palp_vec3 *feedback; /* [cap] per-vertex force of the phantom on the finger [N] */
  palp_vec3 force;  /* [N] */
  palp_vec3 total;  /* summed feedback [N] */
  /* Fingers (docs/haptics.md): a rigid sphere (the proxy) coupled to the device. */
  palp_finger_def fdef;
  palp_vec3 device, proxy; /* [m] */
  int ncon, ccap;          /* contact constraints of the last step */
  int *ctri;               /* [ccap] triangle of each constraint */
  double (*cbary)[3];      /* barycentric weights of its closest point */
  palp_vec3 *cn;           /* unit normal, surface -> proxy */
  palp_vec3 *cq;           /* closest point [m] */
  double *clam;            /* contact force [N] */
  int64_t *ckey;           /* closest feature (warm start across steps) */
  int nfinger;             /* rows [0, nfinger) are the finger's, the rest the base's */
  palp_local_model lm;
  palp_vec3 drift_corr;    /* the drift observer's correction [m/s] (palp_drift_observe) */
} contact;

/* Compliance columns for finger contacts: the 3 columns of the factor's inverse
 * A^{-1} at a free vertex, computed on demand and kept until the next
 * refactorisation, in a bounded pool reused least-recently first. */
#define PALP_FINGER_MAX_CON 96 /* constraints per finger and step */
/* A vertex's compliance by its etree path (a nested-dissection factor; finger_zslot):
 * per slot z = L^{-1} P e for the vertex's 3 unit right-hand sides on its path from its
 * block column to the root, [cap][h] block columns and [cap][h][9] values (component i,
 * right-hand side c at 3i + c), and the 3x3 blocks of A^{-1} between slots, [cap][cap][9],
 * valid where pair_ok says so; all of one factor. The finger's store is the tick's; a
 * deferred job fills its own for the new factor, swapped in at install. */
#define PALP_ZSTORE_KEEP 96 /* slots a finger's path store keeps across steps (stage_fingers) */
typedef struct zstore {
  int h, cap, used;    /* path length bound (etree height + 1), slots, slots taken */
  int *row_slot;       /* [nfree] -1 */
  int *slot_row;       /* [cap] */
  int64_t *stamp;      /* [cap] the finger step that last used the slot */
  int *len, *path;     /* [cap], [cap][h] */
  double *val;         /* [cap][h][9] */
  double *pair;        /* [cap][cap][9] */
  uint8_t *pair_ok;    /* [cap][cap] */
  double *zw;          /* [9 nfree] dense forward-pass scratch, zero between uses */
  const int *blk, *parent; /* the world's (read only; zpaths_setup) */
} zstore;

typedef struct finger_scratch {
  int slots, n3;        /* pool size, 3 nfree */
  float *pool;          /* [slots][3][n3], single precision (below) */
  int *slot_row;        /* [slots] free row held, -1 */
  int64_t *slot_used;   /* [slots] last step the slot served */
  int *row_slot;        /* [nfree] slot of a row, -1 */
  double *solve;        /* [3 n3] interleaved right-hand sides */
  double *work;         /* [3 n3] */
  int *vloc;            /* [vertex_count] local index of a contact vertex, -1 */
  int *lvert;           /* [3 PALP_FINGER_MAX_CON] contact vertices */
  double *lf;           /* [3 * 3 PALP_FINGER_MAX_CON] local forces [N] */
  double *y;            /* [PALP_FINGER_MAX_CON][9 PALP_FINGER_MAX_CON] A^{-1} H_s^T n_s at local dofs */
  double *W, *b, *lwork; /* [m^2], [m], [m^2 + 3m] */
  double *G;            /* [3 nl][3 nl] this step's compliance among the local dofs */
  size_t G_cap;         /* doubles G holds */
  int *G_lvert, G_nl;   /* [3 PALP_FINGER_MAX_CON] the local vertices G was gathered for, in order */
  int G_owner;          /* the contact it was gathered for, -1 none (also after a refactorisation) */
  uint8_t *cand;        /* [vertex_count] */
  palp_vec3 *fpos;      /* [vertex_count] free positions x + h v_free of this collection [m] (free_pos) */
  const palp_vec3 *gpos; /* where this collection takes the geometry: fpos, or w->pos (def.finger_linearise) */
  double max_link;      /* [m] longest rest link */
  /* The smooth contact surface (def.finger_surface, finger.h), NULL with the facets:
   * one patch per dome triangle and a bound on its offset from the facet [m]; per
   * vertex the rest normal, its ring's rest normal, and the current normal (computed
   * once per finger collection, when nstamp says so); the dome triangles at each
   * vertex (CSR). */
  palp_smooth_patch *patch;
  double *patch_max;
  palp_vec3 *nrest, *mrest, *ncur;
  palp_vec3 *tcross;      /* [dome triangles] a triangle's cross product at the free positions [m^2] */
  int64_t *nstamp, *tstamp, ncount;
  int *vtri_start, *vtri; /* both surfaces: the collection marks the triangles at its candidates */
  int *clist;             /* [vertex_count] this collection's candidate vertices */
  uint64_t *tbits;        /* [ceil(dome triangles / 64)] triangles at a candidate, cleared as read */
  int *tlist;             /* [dome triangles] those triangles, ascending */
  int64_t stamp;
  /* During a blend, the replaced factor's 3 columns at the rows asked for (prev_cols),
   * [prev_slots][3][n3], and which row each slot holds. */
  float *prev_pool;
  int prev_slots, prev_count;
  int *prev_row_slot; /* [nfree] -1 */
  int *prev_slot_row; /* [prev_slots] */
  /* The compliance by etree paths (a nested-dissection factor, not blending; zstore). */
  zstore z;
  int *zblk, *zparent; /* [nfree] each free row's permuted block column; each block column's etree parent, -1 */
} finger_scratch;

typedef void (*stage_fn)(palp_world *w, double h);
typedef struct stage {
  const char *name;
  stage_fn fn;
} stage;

struct palp_world {
  palp_world_def def;
  palp_mesh mesh;

  /* Vertices (SoA). */
  palp_vec3 *pos, *vel, *force;
  double *mass;  /* [kg] lumped from membrane thickness x density x area */
  double *sarea; /* [m^2] vertex area x the lesions' support scale: the support's weight */
  palp_vec3 *sq; /* [m] the relaxing support's dashpot positions (NULL without it) */
  double *sheight; /* [m] the gel's height above the base under each vertex at rest (NULL: a linear support) */
  palp_vec3 *fsu;  /* [m] each vertex's displacement the factor was built with (with sheight) */
  int *row_of;   /* vertex -> free row, -1 if fixed */
  int *vertex_of; /* free row -> vertex */
  int nfree;

  /* Membrane links (allocated only with membrane elasticity). */
  int nlink;
  double *rest_len; /* [m] */
  double *inv_rest; /* [1/m] 1 / rest_len: the per-step strain multiplies (a division per link cost 10% of a step) */
  double *ld;       /* [3 nlink] scratch of stage_membrane_state: the links' vectors by component [m] */
  double *kx;       /* [m] xsec / rest_len: a link's axial stiffness per unit modulus */
  double *xsec;     /* effective cross-section t (A_left + A_right) / L0 [m^2] */
  double *eps;      /* current strain [-] */
  palp_vec3 *dir;   /* current unit direction first -> second vertex */
  double *sigma;    /* current stress [Pa] */
  palp_vec3 *fdir;  /* direction the factor was built with */
  double *fbeta;    /* transverse stiffness fraction the factor was built with */
  double *link_mass; /* [kg] min over the free ends of vertex mass / links at the vertex */
  double *fslack;   /* [N/m] transverse stiffness the mass term absorbs at the factor's step */
  /* The turn rule's (turn_rule; all NULL without it): */
  double *fsoft;    /* [nfree + 1] [N/m] the factor's softest stiffness at each free vertex (turn_quotient),
                     * and their least at [nfree] */
  double *soft_blk; /* [6 nfree] scratch of soft_stiffness */
  int link_degree;  /* the most links at any vertex */
  double *lturn;    /* [nlink] scratch: k_l sin^2 of each link's turn from its factor direction [N/m] */
  double *vturn;    /* [vertex_count] scratch: their sum at each vertex [N/m] */
  int stale;        /* the factor left its stability region: rebuild before the next step */
  int unsafe;       /* PALP_UNSAFE_*: rebuild now even when rebuilds are deferred */
  int64_t refactors;
  int reject;       /* the solve cannot be used: 1 not finite or too fast, 2 left its linearisation */
  int last_resort;  /* at the last halving: cap speeds instead of rejecting, accept inaccuracy */
  int64_t clamped_steps;
  int64_t margin_rebuilds;
  int64_t factor_analyses; /* first uses of a factor's storage: ordering and analysis (health) */
  int64_t finger_paths;    /* finger compliance by etree paths, vertices (health) */
  double min_rest_len; /* [m] shortest link */
  uint8_t *vfast;      /* [vertex_count] scratch of the solve's linearisation check: moves by > 0.05 min_rest_len */
  int64_t substeps, large_strain_steps;
  double max_strain, step_max_strain;
  /* Set by any accepted part (half, quarter, ...) of the current frame's step, counted
   * once per frame by palp_world_step_dt: the health counters are per step, as the server
   * log and the replay summary read them, and a split step's halves are not steps. */
  int frame_large_strain, frame_large_bend;
  double (*xs)[2];  /* Burgers internal strains (only with membrane viscosity) */
  palp_burgers burgers; /* coefficients for h_burgers */
  double h_burgers;
  double E_static;  /* elastic-only modulus: E1 E2 / (E1 + E2) [Pa] */

  /* Skin bending (only with membrane.bending_stiffness > 0): linearised hinges,
   * whose constant stiffness sits in the factor (bending.h). */
  int nhinge;
  int (*hinge)[4];       /* edge ends a, b; wings c, d */
  palp_vec3 (*hgrad)[4]; /* rest gradient of the hinge's angle [1/m] */
  double *hk;            /* k_e [N m] */
  int *vhinge_start;     /* [vertex_count + 1] hinges at each vertex: entries 4 e + k, */
  int *vhinge;           /* the vertex being hinge e's k-th (feedback) */
  palp_vec3 *ubuf;       /* [vertex_count] displacement from rest, once per step [m] */
  double step_max_bend, max_bend; /* [rad] */
  int64_t large_bend_steps;
  double max_beyond_validated; /* [m] (def.validated_*) */
  int64_t beyond_validated_steps;
  double *hrest;         /* [nhinge] rest angle (palp_hinge_angle) [rad] */
  int hcheck_next;       /* the next hinge whose true angle is checked */
  uint8_t *hbeyond;      /* [nhinge] 1 if its last check found it beyond the linear range */
  int hbeyond_count;     /* hinges so found */
  double max_bend_err;   /* largest |true - linear| turn checked [rad] */

  /* Gel (allocated only with gel pressure). */
  double V0, V, Vdot; /* [m^3], [m^3/s] */
  palp_vec3 *grad;    /* dV/dx [m^2] */
  double p_gauge;     /* reported gauge pressure [Pa] */
  double p_abs, p_abs_prev; /* literal law state [Pa] */
  double h_gel_prev;  /* [s] the step that made p_abs from p_abs_prev (the literal law's momentum) */
  int64_t gel_momentum_dropped; /* literal-law frames whose momentum term was left out (health) */
  double c_rank1;     /* coefficient of g g^T in the system [kg] */
  double *u;          /* A^{-1} g_u, [nfree*3] */
  double *g_u;        /* gradient u was computed for, [nfree*3] */
  int u_valid;

  /* Solver. */
  palp_ldl ldl;
  double h_factored;
  int *gp, *gi; /* free-vertex graph (CSC, both triangles): the blocks' ordering */
  palp_factor_job *job; /* deferred lagged-tangent rebuild (def.refactor_lag > 0) */
  int job_state, job_obsolete;
  int64_t job_due;      /* frame at whose start the job is installed */
  double *rhs;  /* [nfree*6]: 3 columns of M v + h f, 3 of g when u is refreshed */
  double *work; /* [nfree*6] */
  /* A rebuilt tangent blended in over def.refactor_blend frames (factor_solve): the
   * factor it replaced and the frames of the blend so far (0: none; blend_weight). */
  palp_ldl ldl_prev;
  /* The synchronous rebuild's triplets (refactor), [nnz_bound] each, kept between rebuilds:
   * made afresh each time they page-faulted in anew (docs/model.md). */
  int *rti, *rtj;
  double *rtx;
  int blend_k;
  double *bx; /* [nfree*6] the replaced factor's solve; allocated with def.refactor_blend > 0 */

  /* Contacts. */
  contact *contacts;
  finger_scratch *fs;   /* allocated with the first finger */
  double sm_coef; /* c / (1 + c g.u) of the last solve: the gel's rank-1 term for the finger solve */
  int64_t base_contacts, finger_unsolved;
  /* Links at each vertex (only with force feedback): the feedback needs the membrane
   * force at contact vertices only, so it is summed there from the links' stresses
   * rather than accumulated over the whole mesh every step. Entry +(l+1) when the
   * vertex is the link's first end, -(l+1) when its second. */
  int *vlink_start; /* [vertex_count + 1] */
  int *vlink;       /* [2 * nlink] */

  /* Pipeline. */
  stage stages[PALP_STAGE_COUNT];
  int stage_count;
  palp_stage_timings timings;

  double t;
  int64_t frame;
  int awake;
  double quiet; /* [s] without load below the sleep speed */
  int broken;
};

/* ---- defaults and effects --------------------------------------------- */

palp_world_def palp_world_default_def(void) {
  /* The shipped parameters, config/params/calibrated.json, written by `palp-eval
   * calibrate` against the FEM reference (docs/evaluation.md); test_scene checks that
   * the two agree. The hand-set phantom they started from is
   * config/params/handset.json (docs/model.md). Gravity is off by default: the
   * paper's experiment has none. */
  palp_world_def d = {
      .mesh = palp_mesh_default_def(),
      .membrane = {.thickness = 0.002, .density = 950.0, .E1 = 279971.432, .eta1 = 13161533600.0, .E2 = 98084.012, .eta2 = 19589.3399},
      .gel = {.law = PALP_GEL_POLYTROPIC,
              .pressure = 101325.0,
              .a1 = 10.0,
              .a2 = 5360357.64,
              .a3 = 0.0,
              .support_modulus = 21574.3345,
              .support_viscosity = 6884.34588,
              .support_bulk_fraction = 0.997409179,
              .density = 950.0,
              .added_mass_fraction = 0.820983601},
      .dt = 0.01,
      .effects = PALP_EFFECT_ALL & ~(uint32_t)PALP_EFFECT_GRAVITY,
      .gravity = {0.0, 0.0, -9.81},
      .max_contacts = 8,
      .sleep_speed = 1e-5,
      .sleep_time = 0.5,
      .max_speed = 20.0,
      .finger_surface = PALP_FINGER_SURFACE_SMOOTH,
  };
  return d;
}

const char *palp_finger_linearise_name(int where) {
  return where == PALP_FINGER_LINEARISE_FREE ? "free" : where == PALP_FINGER_LINEARISE_CURRENT ? "current" : NULL;
}

int palp_finger_linearise_from_name(const char *name, int *out) {
  for (int s = PALP_FINGER_LINEARISE_FREE; s <= PALP_FINGER_LINEARISE_CURRENT; ++s)
    if (name && strcmp(name, palp_finger_linearise_name(s)) == 0) {
      *out = s;
      return PALP_OK;
    }
  return PALP_EINVAL;
}

const char *palp_finger_surface_name(int surface) {
  return surface == PALP_FINGER_SURFACE_FACETS ? "facets" : surface == PALP_FINGER_SURFACE_SMOOTH ? "smooth" : NULL;
}

int palp_finger_surface_from_name(const char *name, int *out) {
  for (int s = PALP_FINGER_SURFACE_FACETS; s <= PALP_FINGER_SURFACE_SMOOTH; ++s)
    if (name && strcmp(name, palp_finger_surface_name(s)) == 0) {
      *out = s;
      return PALP_OK;
    }
  return PALP_EINVAL;
}

static const char *const effect_names[] = {"membrane_elasticity", "membrane_viscosity", "gel_pressure",
                                           "gel_damping",         "gravity",            "force_feedback",
                                           "gel_support"};
#define PALP_EFFECT_COUNT 7

const char *palp_effect_name(palp_effect e) {
  for (int i = 0; i < PALP_EFFECT_COUNT; ++i)
    if (e == (palp_effect)(1u << i)) return effect_names[i];
  return NULL;
}

int palp_effect_from_name(const char *name, palp_effect *out) {
  for (int i = 0; i < PALP_EFFECT_COUNT; ++i)
    if (name && strcmp(name, effect_names[i]) == 0) {
      *out = (palp_effect)(1u << i);
      return PALP_OK;
    }
  return PALP_EINVAL;
}

static int has(const palp_world *w, palp_effect e) { return (w->def.effects & e) != 0; }

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- stages ------------------------------------------------------------- */

static void stage_loads(palp_world *w, double h) {
  (void)h;
  const int gravity = has(w, PALP_EFFECT_GRAVITY);
  for (int i = 0; i < w->mesh.vertex_count; ++i)
    w->force[i] = gravity ? v3_scale(w->def.gravity, w->mass[i]) : v3(0, 0, 0);
  for (int c = 0; c < w->def.max_contacts; ++c) {
    const contact *k = &w->contacts[c];
    if (k->kind != CONTACT_FORCE) continue;
    for (int q = 0; q < k->count; ++q)
      w->force[k->vertex[q]] = v3_add(w->force[k->vertex[q]], v3_scale(k->force, k->weight[q]));
  }
}

/* An AVX2 clone (three-operand instructions: ~18% fewer; no fused multiply-add, so the same bits).
 * Not under ThreadSanitizer: its instrumented ifunc resolvers run before its runtime is up and
 * crash at load (scripts/sanitize.sh), so a TSan build takes the portable code, the same bits. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static void stage_membrane_forces(palp_world *w, double h) {
  (void)h;
  const int visc = has(w, PALP_EFFECT_MEMBRANE_VISCOSITY);
  /* Locals and restrict, as in stage_membrane_state: the force stores (doubles) may
   * alias the Burgers coefficients in *w and the link arrays, which the compiler then
   * reloaded every link. The same operations in the same order: the same bits. */
  const palp_burgers bg = w->burgers;
  const double E_static = w->E_static;
  const int(*restrict link)[2] = (const int(*)[2])w->mesh.link;
  const double *restrict eps = w->eps, *restrict xsec = w->xsec;
  const double(*restrict xs)[2] = (const double(*)[2])w->xs;
  const palp_vec3 *restrict dir = w->dir;
  palp_vec3 *restrict force = w->force;
  const int nl = w->nlink;
  for (int l = 0; l < nl; ++l) {
    /* Stress at the end of the step if the strain stayed put [Pa]; the change of
     * strain over the step enters through the implicit matrix. */
    const double sigma = visc ? palp_burgers_predict(&bg, xs[l], eps[l]) : E_static * eps[l];
    const palp_vec3 f = v3_scale(dir[l], sigma * xsec[l]); /* [N], tension pulls the ends together */
    const int a = link[l][0], b = link[l][1];
    force[a] = v3_add(force[a], f);
    force[b] = v3_sub(force[b], f);
  }
}

/* dtheta_e = sum_k g_k . u_k [rad] of hinge e at the current positions. */
static inline double hinge_turn(const int *restrict v, const palp_vec3 *restrict g, const palp_vec3 *restrict pos,
                                const palp_vec3 *restrict rest) {
  double th = 0.0;
  for (int k = 0; k < 4; ++k) {
    const palp_vec3 p = pos[v[k]], r = rest[v[k]];
    th += g[k].x * (p.x - r.x) + g[k].y * (p.y - r.y) + g[k].z * (p.z - r.z);
  }
  return th;
}

/* Adds the hinges' forces f_k = -k_e dtheta_e g_k [N] to f; returns the largest
 * |dtheta_e| [rad]. The displacements are taken once per vertex (each vertex is in
 * ~12 hinges), and read through restrict locals: f is written while they are read,
 * and without restrict the compiler reloads every coefficient after each store. An
 * AVX2 clone (three-operand instructions, ~14% fewer per hinge; no fused multiply-add,
 * so the same bits). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static double bending_add(const palp_world *w, palp_vec3 *restrict f) {
  const palp_vec3 *restrict pos = w->pos, *restrict rest = w->mesh.rest;
  palp_vec3 *restrict u = w->ubuf;
  for (int i = 0; i < w->mesh.vertex_count; ++i)
    u[i] = (palp_vec3){pos[i].x - rest[i].x, pos[i].y - rest[i].y, pos[i].z - rest[i].z};
  const int(*restrict hinge)[4] = (const int(*)[4])w->hinge;
  const palp_vec3(*restrict hgrad)[4] = (const palp_vec3(*)[4])w->hgrad;
  const double *restrict hk = w->hk;
  const int nh = w->nhinge;
  double thmax = 0.0;
  for (int e = 0; e < nh; ++e) {
    const int *v = hinge[e];
    const palp_vec3 *g = hgrad[e];
    double th = 0.0; /* dtheta_e = sum_k g_k . u_k [rad] */
    for (int k = 0; k < 4; ++k) th += g[k].x * u[v[k]].x + g[k].y * u[v[k]].y + g[k].z * u[v[k]].z;
    const double m = -hk[e] * th; /* [N m] */
    for (int k = 0; k < 4; ++k) {
      palp_vec3 *fk = &f[v[k]];
      fk->x += g[k].x * m, fk->y += g[k].y * m, fk->z += g[k].z * m;
    }
    /* as fmax(thmax, |th|) (a NaN is passed over), without its libm call per hinge */
    if (fabs(th) > thmax) thmax = fabs(th);
  }
  return thmax;
}

/* The hinges' force on vertex i alone [N] (the feedback needs it at a few contact
 * vertices, not over the mesh). */
static palp_vec3 bending_at(const palp_world *w, int i) {
  palp_vec3 f = v3(0, 0, 0);
  for (int q = w->vhinge_start[i]; q < w->vhinge_start[i + 1]; ++q) {
    const int e = w->vhinge[q] >> 2, k = w->vhinge[q] & 3;
    const double m = -w->hk[e] * hinge_turn(w->hinge[e], w->hgrad[e], w->pos, w->mesh.rest);
    f = v3_add(f, v3_scale(w->hgrad[e][k], m));
  }
  return f;
}

/* The linearisation's own error at this step's share of the hinges (bending.h,
 * PALP_HINGE_CHECK_PERIOD), in a fixed turn so that replay counts the same steps:
 * |(theta(x) - theta(rest)) - sum_k g_k . u_k| [rad], the difference taken on the
 * circle. Hinges without stiffness (a released rim) carry no force and are skipped. */
static void bending_check(palp_world *w, double h) {
  const int nh = w->nhinge;
  int n = (int)ceil((double)nh * h / PALP_HINGE_CHECK_PERIOD);
  if (n > nh) n = nh;
  const palp_vec3 *x = w->pos;
  /* a miss the parameters' fingertip validation covered is not beyond it (palp.h) */
  const double limit = palp_world_hinge_range(&w->def);
  for (int q = 0; q < n; ++q) {
    const int e = w->hcheck_next;
    if (w->hk[e] > 0.0) {
      const int *v = w->hinge[e];
      const double lin = hinge_turn(v, w->hgrad[e], x, w->mesh.rest);
      const double tr = remainder(palp_hinge_angle(x[v[0]], x[v[1]], x[v[2]], x[v[3]]) - w->hrest[e], 6.283185307179586);
      const double err = fabs(tr - lin);
      const uint8_t beyond = !(err <= limit); /* a NaN counts */
      w->hbeyond_count += (int)beyond - (int)w->hbeyond[e];
      w->hbeyond[e] = beyond;
      if (!(err <= w->max_bend_err)) w->max_bend_err = err == err ? err : INFINITY;
    }
    if (++w->hcheck_next == nh) w->hcheck_next = 0;
  }
}

/* Explicit at x_n; its change over the step enters through h^2 K_b in the factor,
 * which makes the (linear) bending exactly implicit. */
static void stage_membrane_bending(palp_world *w, double h) {
  const double th = bending_add(w, w->force);
  if (th > w->step_max_bend) w->step_max_bend = th;
  bending_check(w, h);
}

static void stage_gel_forces(palp_world *w, double h) {
  double dp_dV, p;
  if (w->def.gel.law == PALP_GEL_POLYTROPIC) {
    p = palp_gel_polytropic(&w->def.gel, w->V0, w->V, &dp_dV);
    /* Implicit volume stiffness h^2 (-dp/dV) and damping h a2 on the g g^T mode. */
    w->c_rank1 = h * h * (-dp_dV) + (has(w, PALP_EFFECT_GEL_DAMPING) ? h * w->def.gel.a2 : 0.0);
  } else {
    p = w->p_abs - w->def.gel.pressure;
    const double k = w->def.gel.a1 * w->p_abs / w->V + (has(w, PALP_EFFECT_GEL_DAMPING) ? w->def.gel.a2 / h : 0.0);
    w->c_rank1 = h * h * k;
  }
  for (int i = 0; i < w->mesh.vertex_count; ++i) w->force[i] = v3_add(w->force[i], v3_scale(w->grad[i], p));
}

/* Area-weighted mean displacement [m] and velocity [m/s] of the free surface. */
static void support_means(const palp_world *w, palp_vec3 *um, palp_vec3 *vm) {
  palp_vec3 su = v3(0, 0, 0), sv = v3(0, 0, 0);
  double sa = 0.0;
  for (int r = 0; r < w->nfree; ++r) {
    const int i = w->vertex_of[r];
    const double a = w->mesh.vertex_area[i];
    su = v3_add(su, v3_scale(v3_sub(w->pos[i], w->mesh.rest[i]), a));
    sv = v3_add(sv, v3_scale(w->vel[i], a));
    sa += a;
  }
  *um = sa > 0.0 ? v3_scale(su, 1.0 / sa) : v3(0, 0, 0);
  *vm = sa > 0.0 ? v3_scale(sv, 1.0 / sa) : v3(0, 0, 0);
}

/* The relaxing support's stiffness over a step of h [Pa/m]: backward Euler on the
 * dashpot, q+ = (q + h/tau u+) / (1 + h/tau), makes its force at the step's end
 * -k_r A (u+ - q+) = -k_r tau / (tau + h) A (u+ - q): a spring of that stiffness
 * anchored at q, on the factor's diagonal like the support's own. */
static double relax_stiffness(const palp_world *w, double h) {
  const double kr = w->def.gel.support_relax_modulus, tr = w->def.gel.support_relax_time;
  return w->sq && kr > 0.0 ? kr * tr / (tr + h) : 0.0;
}

/* The stiffening support (docs/model.md, "The support stiffens near the base"). The
 * gel column between a free vertex and the base plane z = 0 is H [m] high at rest; a
 * vertex displaced by u [m] strains it by about e = |u| / H, in shear for a sideways
 * move and in compression for a downward one. The gel, bonded and incompressible, grows
 * stiffer as that strain grows, and the linear support cannot see it: beside its force
 * -k A u the vertex meets
 *   -k A s u,  s = beta e^p   [N],
 * the gradient of the energy k A beta |u|^(p+2) / ((p + 2) H^p) (so none is made), with
 * tangent k A s (I + p u^ u^^T). Its share vanishes with |u| (p >= 1), so the small-
 * strain fit is kept; near the rim, where H is small, it comes soonest. Whole-dome leans
 * (the support's bulk shift) are resisted too: near the base the gel cannot lean. */
static double stiffening_share(double beta, double p, double ulen, double H) {
  const double e = ulen / H;
  if (p == 2.0) return beta * e * e;
  if (p == 3.0) return beta * e * e * e; /* the two tried for the breast-tissue set: pow costs ~20 ns a vertex */
  return beta * pow(e, p);
}

/* Explicit here; the factor holds the tangent of its own state (build_matrix), and a
 * vertex whose tangent has moved from it by more than the mass term absorbs at the
 * factor's step, or by half the support's own stiffness there, asks for a rebuild as a
 * turned link does (by twice the mass margin: at once, see try_step). */
static void support_stiffening(palp_world *w, double h) {
  const double k = w->def.gel.support_modulus; /* [Pa/m] */
  const double beta = w->def.gel.support_stiffening, p = w->def.gel.support_stiffening_power;
  const double hf = w->h_factored > 0.0 ? w->h_factored : h;
  const double mslack = 1.0 / (1.5625 * hf * hf); /* [1/s^2]: x mass, the factor's quarter margin */
  int stale = 0, unsafe = 0;
  for (int r = 0; r < w->nfree; ++r) {
    const int i = w->vertex_of[r];
    const palp_vec3 u = v3_sub(w->pos[i], w->mesh.rest[i]), uf = w->fsu[i];
    const double ul = v3_len(u), ufl = v3_len(uf), H = w->sheight[i];
    const double sa = stiffening_share(beta, p, ul, H), sf = stiffening_share(beta, p, ufl, H);
    const double ka = k * w->sarea[i]; /* [N/m] */
    w->force[i] = v3_sub(w->force[i], v3_scale(u, ka * sa));
    /* |T(u) - T(u_f)|_F for T = s I + p s u^ u^^T (per k A): 3 ds^2 + 2 ds (b - b_f) + b^2 +
     * b_f^2 - 2 b b_f (u^ . u^_f)^2, ds = s - s_f, b = p s. */
    const double ds = sa - sf, b = p * sa, bf = p * sf;
    const double c = ul > 0.0 && ufl > 0.0 ? v3_dot(u, uf) / (ul * ufl) : 0.0;
    const double dT = ka * sqrt(fmax(0.0, 3.0 * ds * ds + 2.0 * ds * (b - bf) + b * b + bf * bf - 2.0 * b * bf * c * c));
    const double ms = w->mass[i] * mslack; /* [N/m] */
    stale |= dT > fmin(ms, 0.5 * ka * (1.0 + sf + bf));
    unsafe |= dT > 2.0 * ms;
  }
  if (stale) w->stale = 1;
  if (unsafe) w->unsafe |= PALP_UNSAFE_MARGIN;
}

static void stage_gel_support(palp_world *w, double h) {
  /* Elastic part explicit at x_n; the h^2 A k and h A c terms sit on the factor's
   * diagonal, which makes the whole support implicit. */
  const double k = w->def.gel.support_modulus; /* [Pa/m] */
  const double phi = w->def.gel.support_bulk_fraction;
  const int n = w->nfree;
  const int *restrict vertex_of = w->vertex_of;
  const palp_vec3 *restrict pos = w->pos, *restrict rest = w->mesh.rest, *restrict vel = w->vel;
  const double *restrict sarea = w->sarea, *restrict area = w->mesh.vertex_area;
  palp_vec3 *restrict force = w->force;
  /* With the bulk shift, the area-weighted sums of support_means in the same pass (the
   * same terms in the same order as support_means adds them). */
  palp_vec3 su = v3(0, 0, 0), sv = v3(0, 0, 0);
  double sa = 0.0;
  const palp_vec3 *sq = w->sq; /* the relaxing branch, anchored at its dashpots */
  const double kr = relax_stiffness(w, h);
  for (int r = 0; r < n; ++r) {
    const int i = vertex_of[r];
    const palp_vec3 u = v3_sub(pos[i], rest[i]);
    force[i] = v3_sub(force[i], v3_scale(u, k * sarea[i]));
    if (sq) force[i] = v3_sub(force[i], v3_scale(v3_sub(u, sq[i]), kr * sarea[i]));
    if (phi > 0.0) {
      const double a = area[i];
      su = v3_add(su, v3_scale(u, a));
      sv = v3_add(sv, v3_scale(vel[i], a));
      sa += a;
    }
  }
  if (phi > 0.0) {
    /* Bulk shift: the support resists u_i - phi u_mean (and v_i - phi v_mean), with
     * the means taken at the start of the step, explicitly; the implicit diagonal
     * h^2 A k + h A c stays (over-stiff, so it only damps). */
    const double c = has(w, PALP_EFFECT_GEL_DAMPING) ? w->def.gel.support_viscosity : 0.0; /* [Pa s/m] */
    const palp_vec3 um = sa > 0.0 ? v3_scale(su, 1.0 / sa) : v3(0, 0, 0); /* as support_means */
    const palp_vec3 vm = sa > 0.0 ? v3_scale(sv, 1.0 / sa) : v3(0, 0, 0);
    const palp_vec3 b = v3_add(v3_scale(um, phi * k), v3_scale(vm, phi * c)); /* [Pa] */
    for (int r = 0; r < n; ++r) {
      const int i = vertex_of[r];
      force[i] = v3_add(force[i], v3_scale(b, sarea[i]));
    }
  }
  if (w->sheight) support_stiffening(w, h);
}

static int refactor(palp_world *w, double h, int blend);
static void spares_prepare(palp_world *w, double h);
static void job_free(palp_factor_job *j);

/* The solve's largest squared speed: the fold v = !(x_k^2 <= v) ? x_k^2 : v over k from
 * v = 0 (a NaN square takes v's place, and a later square replaces it again). Without
 * a NaN that is the largest square, in any order, and the SSE2 path (every x86-64)
 * takes it two at a time; with one, the fold itself runs: the same result either way. */
static double max_square(const double *restrict x, int n) {
  double v = 0.0;
  int k = 0;
#if defined(__SSE2__)
  __m128d m = _mm_setzero_pd(), nan = _mm_setzero_pd();
  for (; k + 2 <= n; k += 2) {
    const __m128d a = _mm_loadu_pd(x + k), y = _mm_mul_pd(a, a);
    m = _mm_max_pd(y, m); /* without NaNs the larger; a NaN is caught below */
    nan = _mm_or_pd(nan, _mm_cmpunord_pd(y, y));
  }
  if (_mm_movemask_pd(nan)) {
    k = 0; /* a NaN: the fold, from the start */
  } else {
    double mm[2];
    _mm_storeu_pd(mm, m);
    v = mm[0] > mm[1] ? mm[0] : mm[1];
  }
#endif
  for (; k < n; ++k)
    if (!(x[k] * x[k] <= v)) v = x[k] * x[k]; /* NaN is kept: it fails the tests below */
  return v;
}

/* The new factor's weight a in this frame's blend, k / (N + 1) at its k-th frame; 1
 * outside a blend. */
static double blend_weight(const palp_world *w) {
  return w->blend_k > 0 ? w->blend_k / (w->def.refactor_blend + 1.0) : 1.0;
}

/* x <- A^{-1} x for width interleaved right-hand sides. During a blend (def.refactor_blend)
 * the inverse is B = a A_new^{-1} + (1 - a) A_old^{-1}, a rising from 1/(N + 1) to N/(N + 1)
 * over the N frames after a rebuild: a rebuild realigns the lagged tangent's axial
 * stiffness by up to 30 degrees at once, and the finger's force stepped with it (breast-
 * tissue dome slid at 1 kHz: 4.2% in one tick). B is what the whole step uses (the free
 * velocities, the gel's u and the finger's compliance columns), so the step is a
 * linearly implicit step with the matrix B^{-1}: symmetric positive definite, and above
 * any S that both factors are above (A >= S gives A^{-1} <= S^{-1}, so B <= S^{-1}),
 * hence as stable as the weaker of the two. */
static void factor_solve(palp_world *w, double *x, int width) {
  const double a = blend_weight(w), b = 1.0 - a;
  if (!(a < 1.0)) {
    palp_ldl_solve(&w->ldl, x, width, w->work);
    return;
  }
  const size_t n = (size_t)width * 3 * (size_t)w->nfree;
  memcpy(w->bx, x, sizeof(double) * n);
  palp_ldl_solve(&w->ldl_prev, w->bx, width, w->work);
  palp_ldl_solve(&w->ldl, x, width, w->work);
  for (size_t k = 0; k < n; ++k) x[k] = a * x[k] + b * w->bx[k];
}

static void stage_solve(palp_world *w, double h) {
  const int n = w->nfree;
  const int gel = has(w, PALP_EFFECT_GEL_PRESSURE);
  /* Refresh u = A^{-1} g when the gradient has moved by more than 2% of its norm
   * since u was computed. In between, the forces still use the current g; only the
   * Jacobian's rank-1 term uses g_u, and a stale direction keeps cos^2 > 0.999 of
   * the volume stiffness, far above the half that stability needs. */
  int refresh = 0;
  if (gel) {
    double dd = 0.0, gg = 0.0;
    for (int r = 0; r < n; ++r) {
      const palp_vec3 g = w->grad[w->vertex_of[r]];
      const double *gu = w->g_u + 3 * r;
      dd += (g.x - gu[0]) * (g.x - gu[0]) + (g.y - gu[1]) * (g.y - gu[1]) + (g.z - gu[2]) * (g.z - gu[2]);
      gg += v3_dot(g, g);
    }
    refresh = !w->u_valid || dd > 4e-4 * gg;
  }
  /* Unknowns are the 3n velocity components; a refresh solves for u alongside. */
  const int width = refresh ? 2 : 1;
  double *x = w->rhs;
  for (int r = 0; r < n; ++r) {
    const int i = w->vertex_of[r];
    const palp_vec3 b = v3_add(v3_scale(w->vel[i], w->mass[i]), v3_scale(w->force[i], h));
    const double bv[3] = {b.x, b.y, b.z};
    const double gv[3] = {w->grad ? w->grad[i].x : 0.0, w->grad ? w->grad[i].y : 0.0, w->grad ? w->grad[i].z : 0.0};
    for (int c = 0; c < 3; ++c) {
      x[width * (3 * r + c)] = bv[c];
      if (refresh) {
        x[width * (3 * r + c) + 1] = gv[c];
        w->g_u[3 * r + c] = gv[c];
      }
    }
  }
  factor_solve(w, x, width);
  if (refresh) {
    for (int k = 0; k < 3 * n; ++k) {
      w->u[k] = x[2 * k + 1];
      x[k] = x[2 * k]; /* compact the velocity column; k <= 2k keeps it in place */
    }
    w->u_valid = 1;
  }
  if (gel) {
    /* (A + c g g^T)^{-1} b = y - u c (g.y) / (1 + c g.u) with y = A^{-1} b, u = A^{-1} g. */
    double gy = 0.0, gu = 0.0;
    for (int k = 0; k < 3 * n; ++k) {
      gy += w->g_u[k] * x[k];
      gu += w->g_u[k] * w->u[k];
    }
    const double s = w->c_rank1 * gy / (1.0 + w->c_rank1 * gu);
    for (int k = 0; k < 3 * n; ++k) x[k] -= s * w->u[k];
    w->sm_coef = w->c_rank1 / (1.0 + w->c_rank1 * gu);
  } else {
    w->sm_coef = 0.0;
  }
  /* Nothing has moved yet: a solution that is not finite or faster than max_speed
   * is rejected here and the step retried in halves (palp_world_step_dt). At the
   * last halving a finite but too fast solution has its speeds capped at max_speed
   * (Box2D's per-step translation limit): a load far beyond the model then deforms
   * the phantom at a bounded rate instead of failing the session.
   * "Too fast" is tested on the largest velocity component, |v_c| > max_speed / sqrt 3
   * (max_square's one pass, SIMD): it never misses a vertex above max_speed (one of its
   * components is at least |v| / sqrt 3), but it also rejects one between max_speed / sqrt 3
   * and max_speed along an axis (palp.h, def.max_speed). Kept so: a per-vertex test would
   * change which steps are halved, and so the bits of logged sessions. The cap itself is per
   * vertex (|v| > max_speed), and clamped_steps counts only a sub-step that capped one (it
   * also counted those whose bound tripped with every vertex under max_speed, until
   * session 83: the health report and LM_CLAMPED_STEP said capped where nothing was). */
  const double v2max = max_square(x, 3 * n);
  const double vmax = w->def.max_speed; /* [m/s] */
  if (!isfinite(v2max)) {
    w->reject = 1;
    return;
  }
  if (!(v2max <= vmax * vmax / 3.0)) {
    if (!w->last_resort) {
      w->reject = 1;
      return;
    }
    int capped = 0;
    for (int r = 0; r < n; ++r) {
      double *v = x + 3 * r;
      const double s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      if (s2 > vmax * vmax) {
        const double f = vmax / sqrt(s2);
        v[0] *= f, v[1] *= f, v[2] *= f;
        capped = 1;
      }
    }
    w->clamped_steps += capped;
    return;
  }
  /* The step is linearised about x_n: a link that turns by more than 30 degrees or
   * changes its strain by more than 0.25 within it has left that linearisation (a
   * tensionless membrane pressed at one vertex has no transverse stiffness at x_n,
   * and one 10 ms step overshot ~3x). Such steps are retried in halves, each
   * relinearised with the tension built so far. Only checked when some vertex
   * moves by more than a tenth of the shortest link, so quiet steps pay nothing. */
  if (!w->last_resort && w->nlink && 3.0 * v2max * h * h > 0.01 * w->min_rest_len * w->min_rest_len) {
    /* Only links with a fast end can leave the linearisation, so only those are
     * checked (a pressing fingertip makes ~6 of 296 vertices fast in half the steps;
     * the check of every link was ~30k instructions). A vertex is slow when it moves
     * by h |v| <= s = 0.05 min_rest_len this step (fixed ones do not move). A link with
     * two slow ends changes by |dd| <= 2 s <= 0.1 L0 (L0 its rest length); with
     * -0.5 < eps < 1 its length at x_n is len0 > 0.5 L0 >= 5 |dd|, and dir and eps are
     * those of x_n (stage_membrane_state ends every step that moves the positions). So
     * it turns by sin(theta) <= |dd| / len0 <= 0.2 (c > 0, c^2 >= 0.96 len^2 > 0.75
     * len^2) and |deps| <= |dd| / L0 <= 0.1 < 0.25: the test below cannot reject it, far
     * beyond round-off, and skipping it leaves the outcome as it was. */
    uint8_t *restrict fast = w->vfast;
    const double s_lim = 0.05 * w->min_rest_len / h; /* [m/s] */
    for (int r = 0; r < n; ++r) {
      const double *v = x + 3 * r;
      fast[w->vertex_of[r]] = !(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= s_lim * s_lim); /* NaN: fast */
    }
    for (int l = 0; l < w->nlink; ++l) {
      const int a = w->mesh.link[l][0], b = w->mesh.link[l][1];
      if (!fast[a] && !fast[b] && w->eps[l] > -0.5 && w->eps[l] < 1.0) continue;
      const int ra = w->row_of[a], rb = w->row_of[b];
      palp_vec3 d = v3_sub(w->pos[b], w->pos[a]);
      if (rb >= 0) d = v3_add(d, v3_scale(v3(x[3 * rb], x[3 * rb + 1], x[3 * rb + 2]), h));
      if (ra >= 0) d = v3_sub(d, v3_scale(v3(x[3 * ra], x[3 * ra + 1], x[3 * ra + 2]), h));
      const double len = v3_len(d), c = v3_dot(d, w->dir[l]);
      const double deps = (len - w->rest_len[l]) / w->rest_len[l] - w->eps[l];
      if (c < 0.0 || c * c < 0.75 * len * len || fabs(deps) > 0.25) {
        w->reject = 2;
        break;
      }
    }
  }
}

static void stage_integrate(palp_world *w, double h) {
  for (int r = 0; r < w->nfree; ++r) {
    const int i = w->vertex_of[r];
    const double *x = w->rhs + 3 * r;
    w->vel[i] = v3(x[0], x[1], x[2]);
    w->pos[i] = v3_add(w->pos[i], v3_scale(w->vel[i], h));
  }
}

/* ---- fingers ------------------------------------------------------------ */

/* The 3 columns of f^{-1} at free row r into col, [3][n3] in single precision, through
 * solve [3 n3] and work (palp_ldl_work_size(n3, 3)). One function for the finger's pool,
 * a deferred job's columns and a blend's old ones: a column is the same bits whoever
 * makes it. */
static void factor_cols(const palp_ldl *f, int r, int n3, double *solve, double *work, float *col) {
  memset(solve, 0, sizeof(double) * 3 * (size_t)n3);
  for (int c = 0; c < 3; ++c) solve[3 * (3 * r + c) + c] = 1.0;
  palp_ldl_solve(f, solve, 3, work);
  for (int k = 0; k < n3; ++k)
    for (int c = 0; c < 3; ++c) col[(size_t)c * (size_t)n3 + (size_t)k] = (float)solve[3 * k + c];
}

/* The pool slot holding the 3 columns of A^{-1} (the factor, without the gel's
 * rank-1 term) at free row r, [3][n3] contiguous, computed on first use after a
 * refactorisation; the pool grows (up to every free row) only when every slot
 * serves this step. Returns the slot or -1 when out of memory. */
static int finger_slot(palp_world *w, int r) {
  finger_scratch *fs = w->fs;
  const int n3 = fs->n3;
  int s = fs->row_slot[r];
  if (s < 0) {
    int best = -1;
    for (int q = 0; q < fs->slots; ++q) {
      if (fs->slot_row[q] < 0) {
        best = q;
        break;
      }
      if (fs->slot_used[q] != fs->stamp && (best < 0 || fs->slot_used[q] < fs->slot_used[best])) best = q;
    }
    if (best < 0) {
      const int grown = fs->slots * 2 < w->nfree ? fs->slots * 2 : w->nfree;
      if (grown <= fs->slots) return -1;
      float *pool = realloc(fs->pool, sizeof(float) * 3 * (size_t)n3 * (size_t)grown);
      int *sr = realloc(fs->slot_row, sizeof(int) * (size_t)grown);
      int64_t *su = realloc(fs->slot_used, sizeof(int64_t) * (size_t)grown);
      if (pool) fs->pool = pool;
      if (sr) fs->slot_row = sr;
      if (su) fs->slot_used = su;
      if (!pool || !sr || !su) return -1;
      for (int q = fs->slots; q < grown; ++q) fs->slot_row[q] = -1, fs->slot_used[q] = 0;
      best = fs->slots;
      fs->slots = grown;
    }
    s = best;
    if (fs->slot_row[s] >= 0) fs->row_slot[fs->slot_row[s]] = -1;
    factor_cols(&w->ldl, r, n3, fs->solve, fs->work, fs->pool + (size_t)s * 3 * (size_t)n3);
    fs->slot_row[s] = r;
    fs->row_slot[r] = s;
  }
  fs->slot_used[s] = fs->stamp;
  return s;
}

/* Room for n doubles of the local compliance block (grown, never shrunk). 0 or -1. */
static int local_block_reserve(finger_scratch *fs, size_t n) {
  if (fs->G_cap >= n) return 0;
  double *G = realloc(fs->G, sizeof(double) * n);
  if (!G) return -1;
  fs->G = G;
  fs->G_cap = n;
  return 0;
}

static void zstore_clear(zstore *z);

static void finger_cols_invalidate(palp_world *w) {
  finger_scratch *fs = w->fs;
  if (!fs) return;
  zstore_clear(&fs->z); /* the paths' values and their pairs came from the old factor */
  fs->G_owner = -1; /* gathered from the old factor's columns */
  for (int q = 0; q < fs->slots; ++q) {
    if (fs->slot_row[q] >= 0) fs->row_slot[fs->slot_row[q]] = -1;
    fs->slot_row[q] = -1;
  }
}

/* Slot q of the replaced factor's columns for row r, the store grown when full; -1
 * when out of memory. */
static int prev_slot_take(palp_world *w, int r) {
  finger_scratch *fs = w->fs;
  if (fs->prev_count == fs->prev_slots) {
    const int grown = fs->prev_slots ? 2 * fs->prev_slots : 8;
    float *pool = realloc(fs->prev_pool, sizeof(float) * 3 * (size_t)fs->n3 * (size_t)grown);
    if (pool) fs->prev_pool = pool;
    int *sr = realloc(fs->prev_slot_row, sizeof(int) * (size_t)grown);
    if (sr) fs->prev_slot_row = sr;
    if (!pool || !sr) return -1;
    fs->prev_slots = grown;
  }
  const int q = fs->prev_count++;
  fs->prev_slot_row[q] = r;
  fs->prev_row_slot[r] = q;
  return q;
}

/* At the start of a blend, before the pool is invalidated: the columns the last step
 * used, which are the replaced factor's, kept for the blend (the rows a finger touches
 * next are mostly these; others are solved with ldl_prev when asked for). */
static void prev_cols_keep(palp_world *w) {
  finger_scratch *fs = w->fs;
  if (!fs) return;
  for (int q = 0; q < fs->prev_count; ++q) fs->prev_row_slot[fs->prev_slot_row[q]] = -1;
  fs->prev_count = 0;
  const size_t len = 3 * (size_t)fs->n3;
  for (int q = 0; q < fs->slots; ++q) {
    if (fs->slot_row[q] < 0 || fs->slot_used[q] != fs->stamp) continue;
    const int s = prev_slot_take(w, fs->slot_row[q]);
    if (s < 0) return;
    memcpy(fs->prev_pool + (size_t)s * len, fs->pool + (size_t)q * len, sizeof(float) * len);
  }
}

/* The slot of the replaced factor's 3 columns at free row r during a blend ([3][n3]
 * at prev_pool + slot 3 n3, as finger_slot makes them); -1 when out of memory (the
 * caller then uses the new factor's). A slot, not a pointer: taking one may move the
 * whole store (realloc), so pointers into it are formed only once every row of the
 * step has its slot. Pointers kept across such calls read freed memory, and the 1 kHz
 * slide then went differently from run to run (lost contact, thousands of rebuilds). */
static int prev_cols(palp_world *w, int r) {
  finger_scratch *fs = w->fs;
  const int n3 = fs->n3;
  int s = fs->prev_row_slot[r];
  if (s < 0) {
    s = prev_slot_take(w, r);
    if (s < 0) return -1;
    factor_cols(&w->ldl_prev, r, n3, fs->solve, fs->work, fs->prev_pool + (size_t)s * 3 * (size_t)n3);
  }
  return s;
}

/* The store's slots dropped (a new factor). */
static void zstore_clear(zstore *z) {
  for (int q = 0; q < z->used; ++q) z->row_slot[z->slot_row[q]] = -1;
  z->used = 0;
}

static void zstore_free(zstore *z) {
  free(z->row_slot), free(z->slot_row), free(z->stamp), free(z->len), free(z->path), free(z->val), free(z->pair);
  free(z->pair_ok), free(z->zw);
  memset(z, 0, sizeof *z);
}

/* An empty store for nb block columns, paths up to h long, over the world's etree. 0 or -1. */
static int zstore_init(zstore *z, int nb, int h, const int *blk, const int *parent) {
  if (z->row_slot) return 0;
  z->row_slot = malloc(sizeof(int) * (size_t)nb);
  z->zw = calloc(9 * (size_t)nb, sizeof(double));
  if (!z->row_slot || !z->zw) {
    zstore_free(z);
    return -1;
  }
  for (int r = 0; r < nb; ++r) z->row_slot[r] = -1;
  z->h = h, z->blk = blk, z->parent = parent;
  return 0;
}

/* The etree of the factor's block columns and each free row's block column, once per
 * world (every factor of a world has the same ordering and pattern), and the finger's
 * store. 0 or -1 when out of memory. */
static int zpaths_setup(palp_world *w) {
  finger_scratch *fs = w->fs;
  const int nb = w->ldl.nb;
  if (fs->zparent) return 0;
  int *blk = malloc(sizeof(int) * (size_t)nb), *par = malloc(sizeof(int) * (size_t)nb);
  if (!blk || !par || zstore_init(&fs->z, nb, blk && par ? palp_ldl_etree(&w->ldl, blk, par) : 0, blk, par) < 0) {
    free(blk), free(par);
    return -1;
  }
  fs->zblk = blk, fs->zparent = par;
  return 0;
}

/* The slot holding free row r's path values z = L^{-1} P e_{3r+c} (c = 0..2) under the
 * factor f, made on first use: the forward pass walks only the row's etree path, where
 * all of z is (every row of L's column J is an ancestor of J, so a unit right-hand
 * side's updates stay on its path). -1 when out of memory. */
static int finger_zslot(zstore *z, const palp_ldl *f, int r) {
  if (z->row_slot[r] >= 0) return z->row_slot[r];
  if (z->used == z->cap) {
    const int cap = z->cap ? 2 * z->cap : 32, h = z->h;
    int *sr = realloc(z->slot_row, sizeof(int) * (size_t)cap), *len = realloc(z->len, sizeof(int) * (size_t)cap);
    if (sr) z->slot_row = sr;
    if (len) z->len = len;
    int64_t *st = realloc(z->stamp, sizeof(int64_t) * (size_t)cap);
    if (st) z->stamp = st;
    int *path = realloc(z->path, sizeof(int) * (size_t)cap * (size_t)h);
    if (path) z->path = path;
    double *val = realloc(z->val, sizeof(double) * 9 * (size_t)cap * (size_t)h);
    if (val) z->val = val;
    double *pair = malloc(sizeof(double) * 9 * (size_t)cap * (size_t)cap);
    uint8_t *ok = calloc((size_t)cap * (size_t)cap, 1);
    if (!sr || !len || !st || !path || !val || !pair || !ok) {
      free(pair), free(ok);
      return -1;
    }
    for (int a = 0; a < z->used; ++a) /* the pairs move to the wider table */
      for (int b = 0; b < z->used; ++b)
        if (z->pair_ok[a * z->cap + b]) {
          ok[a * cap + b] = 1;
          memcpy(pair + 9 * ((size_t)a * cap + b), z->pair + 9 * ((size_t)a * z->cap + b), sizeof(double) * 9);
        }
    free(z->pair), free(z->pair_ok);
    z->pair = pair, z->pair_ok = ok, z->cap = cap;
  }
  const int s = z->used++;
  z->slot_row[s] = r;
  z->row_slot[r] = s;
  z->stamp[s] = 0;
  for (int b = 0; b < z->used; ++b) z->pair_ok[s * z->cap + b] = z->pair_ok[b * z->cap + s] = 0;
  z->len[s] = palp_ldl_unit_path(f, z->blk[r], z->parent, z->zw, z->path + (size_t)s * (size_t)z->h,
                                 z->val + 9 * (size_t)s * (size_t)z->h);
  return s;
}

/* The 3x3 block of A^{-1} between the vertices of slots a and b, out[3i + j] = A^{-1} at
 * (3 r_a + i, 3 r_b + j) = the sum over their common path of z_a D^{-1} z_b
 * (A = P^T L D L^T P), cached per pair (and its transpose for b, a) until the factor changes. */
static const double *zpair(zstore *z, const palp_ldl *f, int a, int b) {
  double *out = z->pair + 9 * ((size_t)a * z->cap + b);
  if (z->pair_ok[a * z->cap + b]) return out;
  double acc[9];
  palp_ldl_path_block(f, z->path + (size_t)a * z->h, z->val + 9 * (size_t)a * z->h, z->len[a],
                      z->path + (size_t)b * z->h, z->val + 9 * (size_t)b * z->h, z->len[b], acc);
  double *sym = z->pair + 9 * ((size_t)b * z->cap + a);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = acc[3 * i + j], sym[3 * j + i] = acc[3 * i + j];
  z->pair_ok[a * z->cap + b] = z->pair_ok[b * z->cap + a] = 1;
  return out;
}

/* x += c col over n entries: a finger's contact impulse spread by one compliance
 * column (up to ~60 columns of every unknown per finger per step, the finger
 * stage's largest cost). The columns are kept in single precision, like the factor
 * they come from (src/sparse_ldl.h): a server core steps many sessions in turn, so
 * they are read from beyond the caches, and half the bytes is most of the time
 * (docs/model.md). The AVX2 clone does the same widening, multiply and add per entry
 * (no fused multiply-add), so both clones give the same bits. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static void axpy(int n, double c, const float *restrict col, double *restrict x) {
  for (int q = 0; q < n; ++q) x[q] += c * (double)col[q];
}

/* x += c0 col0 + c1 col1 + c2 col2, added in that order per entry, as three axpy
 * calls would (the same bits), reading and writing x once: a contact inside a triangle
 * of the smooth surface loads three vertices, nine columns, where one at a vertex of the
 * facets loaded three. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static void axpy3(int n, const double c[3], const float *restrict col, size_t stride, double *restrict x) {
  const float *restrict c0 = col, *restrict c1 = col + stride, *restrict c2 = col + 2 * stride;
  for (int q = 0; q < n; ++q) x[q] = ((x[q] + c[0] * (double)c0[q]) + c[1] * (double)c1[q]) + c[2] * (double)c2[q];
}

/* Free position of vertex i after the solve, before contacts: x + h v_free [m]. */
static palp_vec3 free_pos(const palp_world *w, int i, double h) {
  const int r = w->row_of[i];
  if (r < 0) return w->pos[i];
  const double *v = w->rhs + 3 * r;
  return v3_add(w->pos[i], v3_scale(v3(v[0], v[1], v[2]), h));
}

static double seg_dist2(palp_vec3 p, palp_vec3 a, palp_vec3 b) {
  const palp_vec3 ab = v3_sub(b, a);
  const double L2 = v3_dot(ab, ab);
  double t = L2 > 0.0 ? v3_dot(v3_sub(p, a), ab) / L2 : 0.0;
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  const palp_vec3 d = v3_sub(p, v3_add(a, v3_scale(ab, t)));
  return v3_dot(d, d);
}

/* The unit area-weighted normal of vertex i's ring of dome triangles at positions x
 * (sum of the triangles' cross products, i.e. twice their vector areas). */
static palp_vec3 ring_normal(const palp_world *w, const finger_scratch *fs, int i, const palp_vec3 *x) {
  palp_vec3 s = v3(0, 0, 0);
  for (int q = fs->vtri_start[i]; q < fs->vtri_start[i + 1]; ++q) {
    const int *T = w->mesh.tri[fs->vtri[q]];
    s = v3_add(s, v3_cross(v3_sub(x[T[1]], x[T[0]]), v3_sub(x[T[2]], x[T[0]])));
  }
  const double l = v3_len(s);
  return l > 0.0 ? v3_scale(s, 1.0 / l) : v3(0, 0, 1);
}

/* Vertex i's normal for the smooth surface at the free positions: its rest normal
 * turned as its ring turned (finger.h), once per finger collection. */
static palp_vec3 smooth_normal(const palp_world *w, finger_scratch *fs, int i) {
  if (fs->nstamp[i] == fs->ncount) return fs->ncur[i];
  palp_vec3 s = v3(0, 0, 0);
  for (int q = fs->vtri_start[i]; q < fs->vtri_start[i + 1]; ++q) {
    const int t = fs->vtri[q];
    if (fs->tstamp[t] != fs->ncount) { /* each triangle once per collection */
      const int *T = w->mesh.tri[t];
      const palp_vec3 *x = fs->gpos, a = x[T[0]];
      fs->tcross[t] = v3_cross(v3_sub(x[T[1]], a), v3_sub(x[T[2]], a));
      fs->tstamp[t] = fs->ncount;
    }
    s = v3_add(s, fs->tcross[t]);
  }
  const double l = v3_len(s);
  const palp_vec3 m = l > 0.0 ? v3_scale(s, 1.0 / l) : fs->mrest[i];
  fs->ncur[i] = palp_normal_carry(fs->nrest[i], fs->mrest[i], m);
  fs->nstamp[i] = fs->ncount;
  return fs->ncur[i];
}

/* Collects the constraints of one finger (docs/haptics.md). Finger rows: dome
 * triangles near the proxy's path from its last position p0 to the device, one per
 * closest feature (face, edge or vertex: neighbouring triangles that share the
 * closest point would repeat it), each linearised at p0,
 *   g_t = |p0 - q_t| - R + n_t . (p - p0) - n_t . sum_a w_ta dx_a >= 0.
 * Base rows: the free vertices of those triangles near the base plane, z_a >= 0, so
 * that a finger pressing the surface down onto the base feels it. Constraint c's
 * surface-force direction J_c (force on the surface per unit multiplier) is
 * -w_ta n_t on the triangle's vertices, or e_z on the vertex. */
static int finger_collect(palp_world *w, contact *k, double h, double prev_tri_lam[][2], int nprev) {
  finger_scratch *fs = w->fs;
  const palp_mesh *m = &w->mesh;
  const int nv = m->vertex_count;
  const double R = k->fdef.radius;
  const palp_vec3 p0 = k->proxy, d = k->device;
  const double reach = R + fs->max_link + 1e-3; /* [m] */
  fs->ncount++; /* the free positions changed (the last finger's solve moved them) */
  /* Each vertex's free position once per collection: the candidates, the triangles and
   * the normals below read it ~3 times per vertex near the finger. */
  palp_vec3 *restrict fp = fs->fpos;
  for (int i = 0; i < nv; ++i) fp[i] = free_pos(w, i, h);
  /* The geometry (candidates, closest points, normals, rows) at the free positions, or
   * at the current ones with the free motion fp - gp added to each gap below
   * (def.finger_linearise): at rest under a finger the free step is the surface
   * springing back without it, most of the dent at 4 ms, and a gap linearised across
   * that moves the equilibrium. */
  const int at_x = w->def.finger_linearise == PALP_FINGER_LINEARISE_CURRENT;
  const palp_vec3 *gp = at_x ? w->pos : fp;
  fs->gpos = gp;
  /* Candidates: vertices near the proxy's path; then the triangles at them, marked in a
   * bitmap and visited in ascending order, as the scan of every dome triangle for one
   * with a candidate vertex visited them (~75 of 632 at 338 vertices). */
  uint8_t *restrict cand = fs->cand; /* byte stores alias anything: a restrict local */
  int *restrict clist = fs->clist;
  int ncand = 0;
  for (int i = 0; i < nv; ++i) {
    /* (at the current positions, a vertex whose free step brings it near counts too) */
    const int is = seg_dist2(gp[i], p0, d) < reach * reach || (at_x && seg_dist2(fp[i], p0, d) < reach * reach);
    cand[i] = (uint8_t)is;
    clist[ncand] = i;
    ncand += is;
  }
  uint64_t *restrict tbits = fs->tbits;
  for (int q = 0; q < ncand; ++q)
    for (int z = fs->vtri_start[clist[q]]; z < fs->vtri_start[clist[q] + 1]; ++z)
      tbits[fs->vtri[z] >> 6] |= (uint64_t)1 << (fs->vtri[z] & 63);
  int64_t key[PALP_FINGER_MAX_CON];
  int nc = 0;
  /* the marked triangles in ascending order, the bitmap cleared for the next collection */
  int *restrict tlist = fs->tlist, ntri = 0;
  const int nwords = m->dome_triangle_count / 64 + 1;
  for (int wd = 0; wd < nwords; ++wd) {
    for (uint64_t bits = tbits[wd]; bits; bits &= bits - 1) tlist[ntri++] = 64 * wd + __builtin_ctzll(bits);
    tbits[wd] = 0;
  }
  for (int z = 0; z < ntri; ++z) {
    const int t = tlist[z];
    const int *T = m->tri[t];
    if (w->row_of[T[0]] < 0 && w->row_of[T[1]] < 0 && w->row_of[T[2]] < 0) continue;
    const palp_vec3 a = gp[T[0]], b = gp[T[1]], c = gp[T[2]];
    double bary[3];
    palp_vec3 q = palp_tri_closest(p0, a, b, c, bary);
    const palp_vec3 face = v3_cross(v3_sub(b, a), v3_sub(c, a)); /* outward (CCW seen from outside) */
    const double fl = v3_len(face);
    if (!(fl > 0.0)) continue;
    palp_vec3 nf = v3_scale(face, 1.0 / fl);
    if (fs->patch) {
      /* The patch lies within patch_max of the facet, so its gap g0 >= |p0 - q| - R -
       * patch_max, and bt = g0 + n . (d - p0) >= g0 - |d - p0|: a triangle past both
       * bounds by the 1 mm below makes no row, and its patch is not searched. */
      double slack = 1e-3; /* at the current positions, plus the free step's largest motion here */
      for (int e = 0; at_x && e < 3; ++e) slack += v3_len(v3_sub(fp[T[e]], gp[T[e]]));
      if (v3_len(v3_sub(p0, q)) - R - fs->patch_max[t] - v3_len(v3_sub(d, p0)) > slack) continue;
      const palp_vec3 N[3] = {smooth_normal(w, fs, T[0]), smooth_normal(w, fs, T[1]), smooth_normal(w, fs, T[2])};
      q = palp_smooth_closest(p0, a, b, c, N, &fs->patch[t], bary, &nf);
    }
    const palp_vec3 pq = v3_sub(p0, q);
    const double dist = v3_len(pq);
    const palp_vec3 n = dist > 1e-9 ? v3_scale(pq, 1.0 / dist) : nf;
    if (v3_dot(n, nf) <= 0.0) continue; /* the proxy is behind this triangle: it cannot touch it */
    double g0 = dist - R;
    if (at_x) { /* the free step's motion at the closest point, through the row's weights */
      palp_vec3 dl = v3(0, 0, 0);
      for (int e = 0; e < 3; ++e)
        if (bary[e] != 0.0) dl = v3_add(dl, v3_scale(v3_sub(fp[T[e]], gp[T[e]]), bary[e]));
      g0 -= v3_dot(n, dl);
    }
    const double bt = g0 + v3_dot(n, v3_sub(d, p0)); /* gap with the proxy at the device, surface free [m] */
    if (bt > 1e-3 && g0 > 1e-3) continue;
    /* closest feature: a vertex (two zero weights), an edge (one) or the face */
    int zeros = 0, nz[3], nn = 0;
    for (int e = 0; e < 3; ++e)
      if (bary[e] == 0.0) zeros++;
      else nz[nn++] = T[e];
    int64_t kf = zeros == 2   ? nz[0]
                 : zeros == 1 ? (int64_t)nv + (int64_t)(nz[0] < nz[1] ? nz[0] : nz[1]) * nv +
                                    (nz[0] < nz[1] ? nz[1] : nz[0])
                              : -1 - (int64_t)t;
    int dup = 0;
    for (int q2 = 0; q2 < nc && !dup; ++q2) dup = key[q2] == kf;
    if (dup) continue;
    int slot = nc;
    if (nc == PALP_FINGER_MAX_CON / 2) {
      /* Full (half the rows stay for the base): replace the farthest from contact. */
      slot = 0;
      for (int q2 = 1; q2 < nc; ++q2)
        if (fs->b[q2] > fs->b[slot]) slot = q2;
      if (!(bt < fs->b[slot])) continue;
    } else {
      nc++;
    }
    key[slot] = kf;
    k->ctri[slot] = t;
    memcpy(k->cbary[slot], bary, sizeof bary);
    k->cn[slot] = n;
    k->cq[slot] = q;
    fs->b[slot] = bt;
    k->clam[slot] = 0.0;
    for (int q2 = 0; q2 < nprev; ++q2)
      if ((int64_t)prev_tri_lam[q2][0] == kf) k->clam[slot] = prev_tri_lam[q2][1]; /* warm start */
  }
  /* The table the phantom stands on stops the fingertip too: p_z >= R, a finger row
   * with no surface share (the device feels the table through the coupling). */
  if (nc < PALP_FINGER_MAX_CON / 2 && (p0.z - R < reach || d.z - R < reach)) {
    key[nc] = -(int64_t)2e12;
    k->ctri[nc] = -1 - nv;
    k->cn[nc] = v3(0, 0, 1);
    k->cq[nc] = v3(p0.x, p0.y, 0.0);
    fs->b[nc] = d.z - R;
    k->clam[nc] = 0.0;
    for (int q2 = 0; q2 < nprev; ++q2)
      if ((int64_t)prev_tri_lam[q2][0] == key[nc]) k->clam[nc] = prev_tri_lam[q2][1];
    nc++;
  }
  k->nfinger = nc;
  for (int q2 = 0; q2 < nc; ++q2) k->ckey[q2] = key[q2];
  /* Base rows for the free vertices of those triangles within 1 mm of the base. */
  for (int q2 = 0; q2 < k->nfinger && nc < PALP_FINGER_MAX_CON; ++q2)
    for (int e = 0; e < 3 && nc < PALP_FINGER_MAX_CON && k->ctri[q2] >= 0; ++e) {
      const int v = m->tri[k->ctri[q2]][e];
      if (w->row_of[v] < 0 || fs->cand[v] == 2) continue;
      const double z = fp[v].z; /* the base's gap: at the free positions either way */
      if (z > 1e-3) continue;
      fs->cand[v] = 2; /* once */
      k->ctri[nc] = -1 - v;
      k->cn[nc] = v3(0, 0, 0); /* no share in the finger's force */
      k->cq[nc] = gp[v];
      fs->b[nc] = z;
      k->ckey[nc] = -(int64_t)1e12 - v;
      k->clam[nc] = 0.0;
      for (int q3 = 0; q3 < nprev; ++q3)
        if ((int64_t)prev_tri_lam[q3][0] == k->ckey[nc]) k->clam[nc] = prev_tri_lam[q3][1];
      nc++;
    }
  return nc;
}

/* Constraint c's surface-force direction J_c as (vertex, 3-vector) entries, and each
 * entry's own barycentric weight b [-] (1 for a base row). The entries are packed: fixed
 * corners and corners of zero weight are left out, so entry e is not corner e, and
 * whoever weights an entry by the closest point's barycentric weights must take b[e],
 * not cbary[c][e] (the drift did, and read corner 0's zero weight for a vertex at
 * corner 2). */
static int constraint_j(const palp_world *w, const contact *k, int c, int *v, palp_vec3 *j, double *b) {
  if (k->ctri[c] == -1 - w->mesh.vertex_count) return 0; /* the table: no surface share */
  if (k->ctri[c] < 0) {
    v[0] = -1 - k->ctri[c];
    j[0] = v3(0, 0, 1);
    b[0] = 1.0;
    return 1;
  }
  int n = 0;
  for (int e = 0; e < 3; ++e) {
    const int vv = w->mesh.tri[k->ctri[c]][e];
    if (w->row_of[vv] < 0 || k->cbary[c][e] == 0.0) continue;
    v[n] = vv;
    b[n] = k->cbary[c][e];
    j[n++] = v3_scale(k->cn[c], -k->cbary[c][e]);
  }
  return n;
}

/* The pad's influence between two contact points q1, q2 on a fingertip of radius r [-]:
 *   P = 1 at one and the same feature, (1 - a) exp(-|q1 - q2|^2 / l^2) between two,
 *   l = r / 16 (0.5 mm on an 8 mm tip) on the facets, r / 6 on the smooth surface (below),
 *   a = 0.03.
 * Features pressing the pad at one place share its compression; features a millimetre
 * apart press it almost independently, as the spring per feature did (a wider kernel,
 * l = r / 4, also coupled the facets a sliding finger meets, and its force steps grew
 * from 2.6% to 4.0% of the force). P = a I + (1 - a) G with G the Gram matrix of a
 * Gaussian, a positive definite kernel, so the pad matrix is positive definite even when
 * features coincide (a vertex and the edge point next to it): the LCP and the
 * stiffness's Cholesky stay well posed, and coincident features act as one pad to
 * within a / 2 .. 3a / 4 of its compliance, where a spring each put them in parallel.
 * On the smooth surface the rows near a contact are one continuous surface seen from
 * neighbouring patches (a patch whose closest point is clamped to its edge, next to the
 * patch that holds the minimum): they sample one contact region of the pad, of radius
 * sqrt(2 R_eff delta) ~ 1.6 mm at 0.2 mm of pad compression (1 N; R_eff = 6.7 mm for an
 * 8 mm tip on the 40 mm dome), so they share its compression over l = r / 6 (1.3 mm).
 * At r / 16 the count of such rows within 0.5 mm, which depends on where the contact
 * sits on its triangle, set the pad's stiffness: sliding 1 mm below the sphere (long-term
 * dome, 5 mm/s) the force varied by 13.9%; r / 6 gives 4.6%, r / 4 3.7% but the worst
 * tick of model_finger's deep slide then came within 0.0002 N of its bound (r / 6: 0.0012 N). */
static double pad_share(palp_vec3 q1, palp_vec3 q2, double l, int same) {
  if (same) return 1.0;
  const double a = 0.03;
  const palp_vec3 d = v3_sub(q1, q2);
  return (1.0 - a) * exp(-v3_dot(d, d) / (l * l));
}

static void stage_fingers(palp_world *w, double h) {
  finger_scratch *fs = w->fs;
  if (!fs) return;
  const int n3 = fs->n3;
  double *x = w->rhs; /* free velocities [m/s], 3 per free row */
  fs->stamp++;
  for (int ci = 0; ci < w->def.max_contacts; ++ci) {
    contact *k = &w->contacts[ci];
    if (k->kind != CONTACT_FINGER) continue;
    const double kc = k->fdef.coupling_stiffness; /* [N/m] */
    const double pad_l = k->fdef.radius / (fs->patch ? 6.0 : 16.0); /* the pad's sharing length (pad_share) [m] */
    double prev[PALP_FINGER_MAX_CON][2];
    int nprev = 0;
    for (int q = 0; q < k->ncon; ++q)
      if (k->clam[q] > 0.0) prev[nprev][0] = (double)k->ckey[q], prev[nprev++][1] = k->clam[q];
    const int m = finger_collect(w, k, h, prev, nprev);
    memset(fs->cand, 0, (size_t)w->mesh.vertex_count);
    k->ncon = m;
    k->count = 0;
    k->total = v3(0, 0, 0);
    palp_local_model *lm = &k->lm;
    const palp_local_model lm_last = *lm; /* the last step's model: how well it predicted sets the drift */
    memset(lm, 0, sizeof *lm);
    lm->period = h;
    lm->device = k->device;
    if (!k->nfinger) {
      k->ncon = 0;
      k->proxy = k->device;
      lm->proxy = k->proxy;
      lm->normal = v3(0, 0, 1);
      continue;
    }
    /* Local vertices (every J entry) and their compliance columns. */
    int cv[PALP_FINGER_MAX_CON][3], cn_[PALP_FINGER_MAX_CON];
    palp_vec3 cj[PALP_FINGER_MAX_CON][3];
    double cb[PALP_FINGER_MAX_CON][3]; /* each entry's barycentric weight (constraint_j) */
    int nl = 0;
    for (int c = 0; c < m; ++c) {
      cn_[c] = constraint_j(w, k, c, cv[c], cj[c], cb[c]);
      for (int e = 0; e < cn_[c]; ++e)
        if (fs->vloc[cv[c][e]] < 0) fs->vloc[cv[c][e]] = nl, fs->lvert[nl++] = cv[c][e];
    }
    int slot[3 * PALP_FINGER_MAX_CON];
    int oom = 0;
    /* During a blend, the replaced factor's columns too (factor_solve): the compliance
     * is a colv + (1 - a) colp. */
    const double ba = blend_weight(w), bb = 1.0 - ba;
    const int blend = ba < 1.0;
    /* A nested-dissection factor (a net of 600 vertices and more, sparse_ldl.h), not
     * blending: the local compliance from the vertices' etree paths (finger_zslot,
     * zpair) and the correction by one more solve, instead of full columns
     * (docs/haptics.md, "The compliance by etree paths"). */
    const int zmode = w->ldl.nested && w->ldl.nb > 0 && !blend && !w->def.finger_columns;
    if (zmode) {
      oom |= zpaths_setup(w) < 0;
      /* Bounded: a finger that roams without a rebuild would fill the store (and its
       * pair table, cap^2 blocks) with every vertex it passed; past PALP_ZSTORE_KEEP
       * slots the store starts anew before this step takes its own. */
      if (!oom && fs->z.used + nl > PALP_ZSTORE_KEEP) zstore_clear(&fs->z);
      const int made = fs->z.used;
      for (int a = 0; a < nl && !oom; ++a) {
        oom |= (slot[a] = finger_zslot(&fs->z, &w->ldl, w->row_of[fs->lvert[a]])) < 0;
        if (slot[a] >= 0) fs->z.stamp[slot[a]] = fs->stamp;
      }
      w->finger_paths += fs->z.used - made;
    } else {
      for (int a = 0; a < nl; ++a) oom |= (slot[a] = finger_slot(w, w->row_of[fs->lvert[a]])) < 0;
    }
    const int L3 = 3 * nl;
    oom |= local_block_reserve(fs, (size_t)L3 * (size_t)L3) < 0;
    if (oom) { /* keep the step going without this finger's contact; counted */
      w->finger_unsolved++;
      for (int a = 0; a < nl; ++a) fs->vloc[fs->lvert[a]] = -1;
      k->ncon = 0;
      continue;
    }
    const float *colv[3 * PALP_FINGER_MAX_CON];
    for (int a = 0; a < nl; ++a) colv[a] = zmode ? NULL : fs->pool + (size_t)slot[a] * 3 * (size_t)n3;
    const float *colp[3 * PALP_FINGER_MAX_CON];
    if (blend) {
      int pslot[3 * PALP_FINGER_MAX_CON];
      for (int a = 0; a < nl; ++a) pslot[a] = prev_cols(w, w->row_of[fs->lvert[a]]);
      for (int a = 0; a < nl; ++a) /* every slot taken: the store no longer moves */
        colp[a] = pslot[a] < 0 ? colv[a] : fs->prev_pool + (size_t)pslot[a] * 3 * (size_t)n3;
    }
    /* The compliance among the local dofs, gathered once: G[3b + j][3a + i] = A^{-1}
     * at (local dof 3a + i, 3b + j). Read from the columns per constraint, each
     * vertex's entries were gathered once for every constraint it is in (~4x), from
     * columns that a server core's step finds out of the caches (docs/model.md). Kept
     * while the same finger has the same local vertices in the same order and the
     * factor has not changed (finger_cols_invalidate): a pressing fingertip keeps them
     * for most steps, and the gather is ~200 scattered cache lines of the columns. */
    if (blend || !(fs->G_owner == ci && fs->G_nl == nl && !memcmp(fs->G_lvert, fs->lvert, sizeof(int) * (size_t)nl))) {
      /* zmode: from the pairs' blocks, G[3b + j][3a + i] = A^{-1} at (3 r_a + i, 3 r_b + j) */
      for (int b = 0; b < nl && zmode; ++b)
        for (int a = 0; a < nl; ++a) {
          const double *blk = zpair(&fs->z, &w->ldl, slot[a], slot[b]);
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) fs->G[(size_t)(3 * b + j) * (size_t)L3 + 3 * a + i] = blk[3 * i + j];
        }
      for (int b = 0; b < nl && !zmode; ++b)
        for (int j = 0; j < 3; ++j) {
          const float *col = colv[b] + (size_t)j * (size_t)n3;
          double *g = fs->G + (size_t)(3 * b + j) * (size_t)L3;
          for (int a = 0; a < nl; ++a) {
            const int ra = w->row_of[fs->lvert[a]];
            g[3 * a] = (double)col[3 * ra], g[3 * a + 1] = (double)col[3 * ra + 1];
            g[3 * a + 2] = (double)col[3 * ra + 2];
          }
          if (blend) {
            const float *cp = colp[b] + (size_t)j * (size_t)n3;
            for (int a = 0; a < nl; ++a) {
              const int ra = w->row_of[fs->lvert[a]];
              for (int i = 0; i < 3; ++i) g[3 * a + i] = ba * g[3 * a + i] + bb * (double)cp[3 * ra + i];
            }
          }
        }
      fs->G_owner = blend ? -1 : ci, fs->G_nl = nl; /* a blended G serves this step only */
      memcpy(fs->G_lvert, fs->lvert, sizeof(int) * (size_t)nl);
    }
    /* y_c = A_full^{-1} J_c at the local dofs, with the gel's rank-1 term by
     * Sherman-Morrison: A_full^{-1} e_j = A^{-1} e_j - sm u u_j (A symmetric). The
     * coefficient and u in restrict locals: the stores to y may alias w->sm_coef, which
     * was reloaded for every entry and kept the loops scalar (same operations). */
    const double smc = w->sm_coef;
    const double *restrict uvec = w->u;
    for (int c = 0; c < m; ++c) {
      double *restrict yc = fs->y + (size_t)c * (size_t)(9 * PALP_FINGER_MAX_CON);
      memset(yc, 0, sizeof(double) * (size_t)L3);
      double uj = 0.0; /* u . J_c */
      for (int e = 0; e < cn_[c]; ++e) {
        const int r = w->row_of[cv[c][e]];
        const int b = fs->vloc[cv[c][e]];
        const double jv[3] = {cj[c][e].x, cj[c][e].y, cj[c][e].z};
        for (int j = 0; j < 3; ++j) {
          if (jv[j] == 0.0) continue;
          const double *restrict g = fs->G + (size_t)(3 * b + j) * (size_t)L3;
          for (int q = 0; q < L3; ++q) yc[q] += jv[j] * g[q];
          if (smc != 0.0) uj += jv[j] * uvec[3 * r + j];
        }
      }
      if (smc != 0.0) {
        const double su = smc * uj; /* as sm_coef * uj * u, left to right */
        for (int a = 0; a < nl; ++a) {
          const int ra = w->row_of[fs->lvert[a]];
          for (int i = 0; i < 3; ++i) yc[3 * a + i] -= su * uvec[3 * ra + i];
        }
      }
    }
    /* The pad's compliance between touched features (below) [m/N], each pair once: it is
     * symmetric bit for bit (q1 - q2 and q2 - q1 have the same squared length), and its
     * exp per pair was a tenth of the stage. fs->lwork is free until the LCP. */
    double *pad = fs->lwork;
    const int pad_on = k->fdef.pad_stiffness > 0.0;
    if (pad_on)
      for (int c = 0; c < k->nfinger; ++c)
        for (int dd = 0; dd <= c; ++dd)
          if (k->ctri[c] >= 0 && k->ctri[dd] >= 0)
            pad[c * m + dd] = pad[dd * m + c] = pad_share(k->cq[c], k->cq[dd], pad_l, c == dd) / k->fdef.pad_stiffness;
    /* W_cd = h^2 J_c . y_d (+ n_c . n_d / k_c between finger rows, the coupling) [m/N] */
    for (int c = 0; c < m; ++c) {
      const palp_vec3 ncc = k->cn[c];
      const int padc = pad_on && c < k->nfinger && k->ctri[c] >= 0; /* row c takes the pad's share */
      for (int dd = 0; dd < m; ++dd) {
        const double *yd = fs->y + (size_t)dd * (size_t)(9 * PALP_FINGER_MAX_CON);
        double s = 0.0;
        for (int e = 0; e < cn_[c]; ++e) {
          const int a = fs->vloc[cv[c][e]];
          s += v3_dot(cj[c][e], v3(yd[3 * a], yd[3 * a + 1], yd[3 * a + 2]));
        }
        double wcd = h * h * s + v3_dot(ncc, k->cn[dd]) / kc;
        /* The pad's compliance between touched features (not the table's): one layer on
         * the fingertip, so features pressing it at one place share its compression.
         * A spring per feature put the pads of features meeting at a point in parallel:
         * when a neighbour's closest point left a shared vertex for the edge next to it,
         * it became a constraint of its own already ~1 mm into the pad, and the force
         * stepped by +24% in 3 ms (long-term dome, 45 deg, 2.5 mm; docs/haptics.md). */
        if (padc && dd < k->nfinger && k->ctri[dd] >= 0) wcd += pad[c * m + dd];
        fs->W[c * m + dd] = wcd;
      }
    }
    if (palp_lcp_solve(m, fs->W, fs->b, k->clam, fs->lwork) < 0 &&
        palp_lcp_pgs(m, fs->W, fs->b, k->clam, 500, 1e-8) < 0)
      w->finger_unsolved++;
    /* Proxy and force; the surface's velocity correction dv = h A_full^{-1} sum_c lam_c J_c. */
    palp_vec3 F = v3(0, 0, 0), point = v3(0, 0, 0);
    double lsum = 0.0;
    for (int c = 0; c < k->nfinger; ++c) {
      F = v3_add(F, v3_scale(k->cn[c], k->clam[c]));
      point = v3_add(point, v3_scale(k->cq[c], k->clam[c]));
      lsum += k->clam[c];
    }
    k->total = F;
    k->proxy = v3_add(k->device, v3_scale(F, 1.0 / kc));
    memset(fs->lf, 0, sizeof(double) * (size_t)L3);
    for (int c = 0; c < m; ++c) {
      if (!(k->clam[c] > 0.0)) continue;
      for (int e = 0; e < cn_[c]; ++e) {
        const int a = fs->vloc[cv[c][e]];
        fs->lf[3 * a] += k->clam[c] * cj[c][e].x, fs->lf[3 * a + 1] += k->clam[c] * cj[c][e].y;
        fs->lf[3 * a + 2] += k->clam[c] * cj[c][e].z;
      }
      if (k->ctri[c] < 0) w->base_contacts++;
    }
    double uf = 0.0;
    double *zr = fs->solve; /* zmode: the correction's right-hand side, then A^{-1} of it */
    if (zmode) memset(zr, 0, sizeof(double) * (size_t)n3);
    for (int a = 0; a < nl; ++a) {
      const int ra = w->row_of[fs->lvert[a]];
      const double c3[3] = {h * fs->lf[3 * a], h * fs->lf[3 * a + 1], h * fs->lf[3 * a + 2]};
      const int fused = c3[0] != 0.0 && c3[1] != 0.0 && c3[2] != 0.0;
      if (zmode) {
        for (int j = 0; j < 3; ++j) {
          zr[3 * ra + j] = c3[j];
          uf += c3[j] * (smc != 0.0 ? uvec[3 * ra + j] : 0.0);
        }
        continue;
      }
      if (blend) {
        const double ca[3] = {ba * c3[0], ba * c3[1], ba * c3[2]}, cb[3] = {bb * c3[0], bb * c3[1], bb * c3[2]};
        for (int j = 0; j < 3; ++j)
          if (c3[j] != 0.0) {
            axpy(n3, ca[j], colv[a] + (size_t)j * (size_t)n3, x);
            axpy(n3, cb[j], colp[a] + (size_t)j * (size_t)n3, x);
          }
      } else if (fused) {
        axpy3(n3, c3, colv[a], (size_t)n3, x);
      }
      for (int j = 0; j < 3; ++j) {
        const double c = c3[j];
        if (c == 0.0) continue;
        if (!fused && !blend) axpy(n3, c, colv[a] + (size_t)j * (size_t)n3, x);
        uf += c * (smc != 0.0 ? uvec[3 * ra + j] : 0.0);
      }
    }
    if (zmode) {
      palp_ldl_solve(&w->ldl, zr, 1, fs->work);
      for (int q = 0; q < n3; ++q) x[q] += zr[q];
    }
    if (smc != 0.0) {
      const double su = smc * uf; /* as sm_coef * uf * u, left to right */
      double *restrict xr = x;
      for (int q = 0; q < n3; ++q) xr[q] -= su * uvec[q];
    }
    /* Per-vertex feedback: what the finger rows push on each vertex, reversed. */
    for (int c = 0; c < k->nfinger; ++c) {
      if (!(k->clam[c] > 0.0)) continue;
      for (int e = 0; e < cn_[c]; ++e) {
        const palp_vec3 f = v3_scale(cj[c][e], -k->clam[c]);
        int q = 0;
        while (q < k->count && k->vertex[q] != cv[c][e]) q++;
        if (q == k->count) {
          if (k->count == k->cap) continue;
          k->vertex[k->count] = cv[c][e], k->feedback[k->count++] = v3(0, 0, 0);
        }
        k->feedback[q] = v3_add(k->feedback[q], f);
      }
    }
    /* The local contact model (palp.h): K = N_A W_AA^{-1} N_A^T with the active set
     * held (base rows carry a zero normal: the device moves none of their gaps). */
    const int na = palp_contact_stiffness(m, fs->W, k->cn, k->clam, lm->stiffness, fs->lwork);
    lm->contact = lsum > 0.0 && na > 0;
    lm->force = F;
    lm->proxy = k->proxy;
    const double Fl = v3_len(F);
    lm->normal = Fl > 0.0 ? v3_scale(F, 1.0 / Fl) : k->cn[0];
    lm->depth = fmax(0.0, v3_dot(v3_sub(k->proxy, k->device), lm->normal));
    if (lsum > 0.0) {
      lm->point = v3_scale(point, 1.0 / lsum);
      /* drift: the surface's velocity at the contact after the step [m/s], sum_c lam_c
       * sum_v b_cv v_v / sum_c lam_c, each vertex by its own weight b_cv (a fixed corner's
       * velocity is 0 and it has no entry) */
      palp_vec3 vc = v3(0, 0, 0);
      for (int c = 0; c < k->nfinger; ++c) {
        if (!(k->clam[c] > 0.0)) continue;
        if (k->ctri[c] >= 0) lm->triangles++;
        for (int e = 0; e < cn_[c]; ++e) {
          const int r = w->row_of[cv[c][e]];
          vc = v3_add(vc, v3_scale(v3(x[3 * r], x[3 * r + 1], x[3 * r + 2]), k->clam[c] * cb[c][e]));
        }
      }
      lm->drift = palp_drift_observe(&lm_last, lm, v3_scale(vc, 1.0 / lsum), h, w->def.max_speed, &k->drift_corr);
      /* footprint: the lumped (one-third) areas of the vertices the finger touches [m^2] */
      for (int q = 0; q < k->count; ++q) lm->area += w->mesh.vertex_area[k->vertex[q]];
    } else {
      lm->point = k->cq[0];
    }
    for (int a = 0; a < nl; ++a) fs->vloc[fs->lvert[a]] = -1;
  }
}

/* The phantom sits on a rigid base: no vertex goes below z = 0 (a vertex pressed
 * there keeps its tangential motion and loses the downward one). */
static void stage_base(palp_world *w, double h) {
  (void)h;
  for (int r = 0; r < w->nfree; ++r) {
    const int i = w->vertex_of[r];
    if (w->pos[i].z >= 0.0) continue;
    w->pos[i].z = 0.0;
    if (w->vel[i].z < 0.0) w->vel[i].z = 0.0;
    w->base_contacts++;
  }
}

/* The link states from the links' vectors, components in dx, dy, dz [m]: directions,
 * strains, stresses (Burgers when visc) and the factor's stability test (see
 * stage_membrane_state). Split from the gather of the vectors so that it runs on whole
 * vectors of links: the square root and division per link, in the gathering loop, left
 * it scalar (-fno-math-errno lets the square root vectorise, src/CMakeLists.txt). Per
 * link the same operations in the same order as before, and the AVX2 clone does no
 * fused multiply-add, so every path gives the same bits. Returns 1 when a link left the
 * factor's stability region. */
/* The loop of link_states for visc 0 or 1 (a constant there: a branch inside the
 * loop would keep it from vectorising). */
static inline __attribute__((always_inline)) int link_states_loop(
    int nl, const double *restrict dx, const double *restrict dy, const double *restrict dz,
    const double *restrict rest_len, const double *restrict inv_rest, const double *restrict xsec,
    const double *restrict kx, const double *restrict fbeta, const double *restrict fslack,
    const palp_vec3 *restrict fdir, palp_vec3 *restrict dir, double *restrict eps_l, double *restrict sigma_l,
    double (*restrict xs)[2], const int visc, const palp_burgers *bgp, double E_static, double tangent,
    const int turn, double *restrict lturn) {
  const palp_burgers bg = *bgp;
  long long stale = 0, unsafe = 0; /* as wide as a double: GCC vectorises the OR of double comparisons only so */
  for (int l = 0; l < nl; ++l) {
    const double len = sqrt(dx[l] * dx[l] + dy[l] * dy[l] + dz[l] * dz[l]), inv_len = 1.0 / len;
    const palp_vec3 u = {dx[l] * inv_len, dy[l] * inv_len, dz[l] * inv_len};
    dir[l] = u;
    const double eps = (len - rest_len[l]) * inv_rest[l];
    const double sigma = visc ? palp_burgers_advance(&bg, xs[l], eps_l[l], eps) : E_static * eps;
    eps_l[l] = eps;
    sigma_l[l] = sigma;
    /* Leaving the factor's stability region (see refactor): turned by > 30 degrees,
     * or tension stiffness across the link above beta k (half the margin). */
    const double c = v3_dot(u, fdir[l]);
    const double ts = sigma * xsec[l] * inv_len, held = fbeta[l] * tangent * kx[l] + fslack[l];
    stale |= (c * c < 0.75) | (ts > held);
    /* Beyond the margin itself: tension stiffness above twice what the factor holds. A
     * deferred rebuild cannot wait for its due frame there: at 1 kHz the long-term dome,
     * slid at 50 mm/s, rang at the Nyquist rate during the 16 frames of the lag (force
     * steps of 30%; docs/haptics.md). A turn is judged at its vertices (turn_quotient):
     * the 45 deg limit it had here fired where the vertex held the turned stiffness
     * easily, and missed the stiff links that rang at 17 deg. */
    unsafe |= ts > 2.0 * held;
    if (turn) lturn[l] = tangent * kx[l] * (1.0 - c * c); /* a constant: the turn rule's worlds only */
  }
  return (stale != 0) | ((unsafe != 0) << 1);
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static int link_states(int nl, const double *restrict dx, const double *restrict dy, const double *restrict dz,
                       const double *restrict rest_len, const double *restrict inv_rest, const double *restrict xsec,
                       const double *restrict kx, const double *restrict fbeta, const double *restrict fslack,
                       const palp_vec3 *restrict fdir, palp_vec3 *restrict dir, double *restrict eps_l,
                       double *restrict sigma_l, double (*restrict xs)[2], int visc, const palp_burgers *bgp,
                       double E_static, double tangent, double *restrict lturn) {
  /* lturn NULL: no turn rule, and the loop stores nothing for it */
#define LINK_STATES(v, t)                                                                                        \
  link_states_loop(nl, dx, dy, dz, rest_len, inv_rest, xsec, kx, fbeta, fslack, fdir, dir, eps_l, sigma_l, xs, v, \
                   bgp, E_static, tangent, t, lturn)
  if (visc) return lturn ? LINK_STATES(1, 1) : LINK_STATES(1, 0);
  return lturn ? LINK_STATES(0, 1) : LINK_STATES(0, 0);
#undef LINK_STATES
}

/* Whether the turn rule applies (PALP_TURN_STALE): at haptic rates in worlds stepped as the
 * server steps them, a lag or a blend (see stage_membrane_state). */
static int turn_rule(const palp_world *w) { return w->soft_blk != NULL; }

/* After a factorisation: each free vertex's fsoft becomes the least over it and the
 * vertices it links to. A diagonal block holds a vertex moving alone, and neighbours
 * moving with it hold less (the long-term dome rang, up to 2.31%, with each vertex's sum
 * over its own block kept under 0.9; docs/haptics.md). vturn is the scratch. */
static void soft_neighbourhood(palp_world *w) {
  double *restrict m = w->vturn;
  const int(*restrict link)[2] = (const int(*)[2])w->mesh.link;
  for (int i = 0; i < w->mesh.vertex_count; ++i) m[i] = INFINITY;
  for (int r = 0; r < w->nfree; ++r) m[w->vertex_of[r]] = w->fsoft[r];
  for (int l = 0; l < w->nlink; ++l) {
    const int ra = w->row_of[link[l][0]], rb = w->row_of[link[l][1]];
    if (ra >= 0 && rb >= 0) {
      m[link[l][0]] = fmin(m[link[l][0]], w->fsoft[rb]);
      m[link[l][1]] = fmin(m[link[l][1]], w->fsoft[ra]);
    }
  }
  for (int r = 0; r < w->nfree; ++r) w->fsoft[r] = m[w->vertex_of[r]];
}

/* The largest turn quotient q (PALP_TURN_STALE): the links' turned stiffness k_l sin^2
 * summed at each free vertex, over the factor's softest stiffness there or at a vertex
 * it links to (soft_neighbourhood). */
static double turn_quotient(const palp_world *w) {
  /* No vertex sums more than link_degree times the largest turned stiffness: while that
   * is under the stale level at the softest vertex, nothing is summed. */
  double lmax = 0.0;
  for (int l = 0; l < w->nlink; ++l) lmax = w->lturn[l] > lmax ? w->lturn[l] : lmax;
  if (w->link_degree * lmax <= PALP_TURN_STALE * w->fsoft[w->nfree]) return 0.0;
  double *restrict acc = w->vturn;
  const int(*restrict link)[2] = (const int(*)[2])w->mesh.link;
  memset(acc, 0, sizeof(double) * (size_t)w->mesh.vertex_count);
  for (int l = 0; l < w->nlink; ++l) acc[link[l][0]] += w->lturn[l], acc[link[l][1]] += w->lturn[l];
  double q = 0.0;
  for (int r = 0; r < w->nfree; ++r) {
    const double qr = acc[w->vertex_of[r]] / w->fsoft[r];
    if (!(qr <= q)) q = qr; /* NaN is kept: it fails every test below */
  }
  return q;
}

static void stage_membrane_state(palp_world *w, double h) {
  (void)h;
  const int visc = has(w, PALP_EFFECT_MEMBRANE_VISCOSITY);
  const double tangent = visc ? w->burgers.tangent : w->E_static; /* [Pa] */
  const palp_vec3 *restrict pos = w->pos;
  const int(*restrict link)[2] = (const int(*)[2])w->mesh.link;
  const int nl = w->nlink;
  double *restrict dx = w->ld, *restrict dy = w->ld + nl, *restrict dz = w->ld + 2 * (size_t)nl;
  for (int l = 0; l < nl; ++l) {
    const palp_vec3 a = pos[link[l][0]], b = pos[link[l][1]];
    dx[l] = b.x - a.x, dy[l] = b.y - a.y, dz[l] = b.z - a.z;
  }
  const int leave = link_states(nl, dx, dy, dz, w->rest_len, w->inv_rest, w->xsec, w->kx, w->fbeta, w->fslack, w->fdir,
                                w->dir, w->eps, w->sigma, w->xs, visc, &w->burgers, w->E_static, tangent,
                                turn_rule(w) ? w->lturn : NULL);
  /* the largest strain, compared in link order as before (a max reduction would not vectorise anyway) */
  const double *restrict eps_l = w->eps;
  double max_strain = w->step_max_strain;
  for (int l = 0; l < nl; ++l)
    if (fabs(eps_l[l]) > max_strain) max_strain = fabs(eps_l[l]);
  w->step_max_strain = max_strain;
  if (leave & 1) w->stale = 1;
  if (leave & 2) w->unsafe |= PALP_UNSAFE_MARGIN;
  /* The turn rule at haptic rates in worlds stepped as the server steps them (a lag or
   * a blend): the library's default (rebuilt at once, no blend), which the evaluation,
   * the calibrations and the stored references use, keeps its rebuilds and its bits.
   * There an earlier rebuild moved a held press onto another of the model's equilibria
   * (0.2x cyst at 5 mm: 1.409 N against 1.365 N; docs/haptics.md). */
  if (turn_rule(w)) {
    const double q = turn_quotient(w);
    if (!(q <= PALP_TURN_STALE)) w->stale = 1;
    if (!(q <= PALP_TURN_UNSAFE)) w->unsafe |= PALP_UNSAFE_TURN;
  }
}

static void stage_gel_state(palp_world *w, double h) {
  const double V_prev = w->V;
  w->V = palp_gel_volume_gradient(&w->mesh, w->pos, w->grad);
  w->Vdot = (w->V - V_prev) / h;
  if (w->def.gel.law == PALP_GEL_POLYTROPIC) {
    w->p_gauge = palp_gel_polytropic(&w->def.gel, w->V0, w->V, NULL) -
                 (has(w, PALP_EFFECT_GEL_DAMPING) ? w->def.gel.a2 * w->Vdot : 0.0);
  } else {
    int dropped = 0;
    const double pn = palp_gel_literal_step(&w->def.gel, w->p_abs, w->p_abs_prev, w->V, V_prev, h, w->h_gel_prev,
                                            has(w, PALP_EFFECT_GEL_DAMPING), &dropped);
    w->gel_momentum_dropped += dropped;
    w->p_abs_prev = w->p_abs;
    w->p_abs = pn;
    w->h_gel_prev = h;
    w->p_gauge = pn - w->def.gel.pressure;
  }
}

/* The relaxing support's dashpots follow the step's displacements (see
 * relax_stiffness): q+ = (q + h/tau u+) / (1 + h/tau). */
static void stage_support_state(palp_world *w, double h) {
  const double a = h / w->def.gel.support_relax_time, b = 1.0 / (1.0 + a);
  for (int r = 0; r < w->nfree; ++r) {
    const int i = w->vertex_of[r];
    w->sq[i] = v3_scale(v3_add(w->sq[i], v3_scale(v3_sub(w->pos[i], w->mesh.rest[i]), a)), b);
  }
}

static void stage_feedback(palp_world *w, double h) {
  (void)h;
  const int gel = has(w, PALP_EFFECT_GEL_PRESSURE), support = has(w, PALP_EFFECT_GEL_SUPPORT);
  const double ks = w->def.gel.support_modulus; /* [Pa/m] */
  const double cs = has(w, PALP_EFFECT_GEL_DAMPING) ? w->def.gel.support_viscosity : 0.0; /* [Pa s/m] */
  const double phi = w->def.gel.support_bulk_fraction;
  /* The bulk shift's share of the support, with the means of the state the
   * feedback reports (the end of the step). */
  palp_vec3 bulk = v3(0, 0, 0); /* [Pa] */
  if (support && phi > 0.0) {
    palp_vec3 um, vm;
    support_means(w, &um, &vm);
    bulk = v3_add(v3_scale(um, phi * ks), v3_scale(vm, phi * cs));
  }
  for (int c = 0; c < w->def.max_contacts; ++c) {
    contact *k = &w->contacts[c];
    if (k->kind != CONTACT_FORCE) continue; /* a finger's force comes from its contact solve */
    k->total = v3(0, 0, 0);
    for (int q = 0; q < k->count; ++q) {
      const int i = k->vertex[q];
      /* The force of membrane and gel on the vertex is what the finger feels. */
      palp_vec3 f = v3(0, 0, 0);
      for (int e = w->vlink_start[i]; e < w->vlink_start[i + 1]; ++e) {
        const int l = abs(w->vlink[e]) - 1;
        /* tension sigma a pulls the first end towards the second, along dir */
        const palp_vec3 fl = v3_scale(w->dir[l], w->sigma[l] * w->xsec[l]);
        f = w->vlink[e] > 0 ? v3_add(f, fl) : v3_sub(f, fl);
      }
      if (gel) f = v3_add(f, v3_scale(w->grad[i], w->p_gauge));
      if (w->nhinge) f = v3_add(f, bending_at(w, i));
      if (support) {
        const palp_vec3 u = v3_sub(w->pos[i], w->mesh.rest[i]);
        f = v3_sub(f, v3_scale(v3_add(v3_scale(u, ks), v3_scale(w->vel[i], cs)), w->sarea[i]));
        if (phi > 0.0) f = v3_add(f, v3_scale(bulk, w->sarea[i]));
        if (w->sq) f = v3_sub(f, v3_scale(v3_sub(u, w->sq[i]), w->def.gel.support_relax_modulus * w->sarea[i]));
        if (w->sheight) {
          const double s = stiffening_share(w->def.gel.support_stiffening, w->def.gel.support_stiffening_power,
                                            v3_len(u), w->sheight[i]);
          f = v3_sub(f, v3_scale(u, ks * s * w->sarea[i]));
        }
      }
      k->feedback[q] = f;
      k->total = v3_add(k->total, f);
    }
  }
}

/* ---- creation ------------------------------------------------------------- */

static int validate(const palp_world_def *d) {
  const palp_membrane_params *m = &d->membrane;
  const palp_gel_params *g = &d->gel;
  if (!(d->dt > 0.0 && d->dt <= PALP_WORLD_MAX_DT) || !isfinite(d->dt)) return PALP_EINVAL;
  if (d->max_contacts < 0 || d->max_contacts > 64) return PALP_EINVAL;
  if (d->refactor_lag < 0 || d->refactor_lag > 1000) return PALP_EINVAL;
  if (d->refactor_blend < 0 || d->refactor_blend > 1000) return PALP_EINVAL;
  /* the bounds also refuse inf and NaN */
  if (!(m->thickness > 0.0 && m->thickness <= PALP_THICKNESS_MAX_M) ||
      !(m->density > 0.0 && m->density <= PALP_DENSITY_MAX_KG_M3))
    return PALP_EINVAL;
  if (d->effects & ~(uint32_t)PALP_EFFECT_ALL) return PALP_EINVAL;
  if (!(m->bending_stiffness >= 0.0 && m->bending_stiffness <= PALP_BENDING_MAX_N_M)) return PALP_EINVAL;
  if (!(m->rim_hinge_release >= 0.0 && m->rim_hinge_release <= 1.0)) return PALP_EINVAL;
  if (!(m->skin_bending_stiffness >= 0.0 && m->skin_bending_stiffness <= m->bending_stiffness)) return PALP_EINVAL;
  if ((d->effects & PALP_EFFECT_MEMBRANE_VISCOSITY) && !(d->effects & PALP_EFFECT_MEMBRANE_ELASTICITY))
    return PALP_EINVAL;
  if ((d->effects & PALP_EFFECT_GEL_DAMPING) && !(d->effects & (PALP_EFFECT_GEL_PRESSURE | PALP_EFFECT_GEL_SUPPORT)))
    return PALP_EINVAL;
  if (d->effects & PALP_EFFECT_GEL_SUPPORT) {
    if (!(g->support_modulus > 0.0 && g->support_modulus <= PALP_SUPPORT_MODULUS_MAX)) return PALP_EINVAL;
    if (!(g->support_viscosity >= 0.0 && g->support_viscosity <= PALP_SUPPORT_VISCOSITY_MAX)) return PALP_EINVAL;
    if (!(g->support_bulk_fraction >= 0.0 && g->support_bulk_fraction <= 1.0)) return PALP_EINVAL;
    if (!(g->support_relax_modulus >= 0.0 && g->support_relax_modulus <= PALP_SUPPORT_MODULUS_MAX)) return PALP_EINVAL;
    if (g->support_relax_modulus > 0.0 &&
        !(g->support_relax_time > 0.0 && g->support_relax_time <= PALP_SUPPORT_RELAX_TIME_MAX))
      return PALP_EINVAL;
    if (!(g->support_stiffening >= 0.0 && g->support_stiffening <= 1e3)) return PALP_EINVAL;
    if (g->support_stiffening > 0.0 && !(g->support_stiffening_power >= 1.0 && g->support_stiffening_power <= 8.0))
      return PALP_EINVAL;
    if (!(g->support_base_reach >= 0.0 && g->support_base_reach <= 1.0)) return PALP_EINVAL;
  }
  if (d->effects & PALP_EFFECT_MEMBRANE_ELASTICITY) {
    if (!(m->E1 > 0.0 && m->E2 > 0.0) || !isfinite(m->E1) || !isfinite(m->E2)) return PALP_EINVAL;
    if ((d->effects & PALP_EFFECT_MEMBRANE_VISCOSITY) &&
        (!(m->eta1 > 0.0 && m->eta2 > 0.0) || !isfinite(m->eta1) || !isfinite(m->eta2)))
      return PALP_EINVAL;
  }
  if (d->effects & PALP_EFFECT_GEL_PRESSURE) {
    if (!(g->pressure > 0.0 && g->pressure <= PALP_GEL_PRESSURE_MAX_PA) || !(g->a1 > 0.0 && g->a1 <= PALP_GEL_A1_MAX))
      return PALP_EINVAL;
    if (!(g->a2 >= 0.0 && g->a2 <= PALP_GEL_A2_MAX) || !isfinite(g->a3)) return PALP_EINVAL;
    if (g->law != PALP_GEL_POLYTROPIC && g->law != PALP_GEL_PAPER_LITERAL) return PALP_EINVAL;
    /* The literal law's momentum term a3 (p_{i-1} - p_{i-2}) / (h h_prev) is stable only
     * for -1/2 < a3 / (h h_prev) < 1 (palp_gel_literal_valid): refused where the world's
     * own step cannot meet it. Shorter steps (a rejected step's halves, palp_world_step_dt)
     * leave the term out where they break it, and count those frames
     * (health.gel_momentum_dropped). */
    if (g->law == PALP_GEL_PAPER_LITERAL && !palp_gel_literal_valid(g->a3, d->dt, d->dt)) return PALP_EINVAL;
  }
  if (!(g->density > 0.0 && g->density <= PALP_DENSITY_MAX_KG_M3) || !(g->added_mass_fraction >= 0.0) ||
      !(g->added_mass_fraction <= 1.0)) /* at most the whole gel */
    return PALP_EINVAL;
  if (!v3_isfinite(d->gravity) || !(d->sleep_speed >= 0.0) || !(d->sleep_time >= 0.0)) return PALP_EINVAL;
  if (!(d->max_speed > 0.0)) return PALP_EINVAL;
  if (!palp_finger_surface_name(d->finger_surface)) return PALP_EINVAL;
  if (!palp_finger_linearise_name(d->finger_linearise)) return PALP_EINVAL;
  if (d->lesion_count < 0 || d->lesion_count > PALP_MAX_LESIONS) return PALP_EINVAL;
  if (d->validated_count < 0 || d->validated_count > PALP_MAX_VALIDATED) return PALP_EINVAL;
  for (int k = 0; k < d->validated_count; ++k) /* polar angles ascending in [0, pi/2], depths > 0 */
    if (!(d->validated_polar[k] >= 0.0 && d->validated_polar[k] <= 0.5 * PALP_PI + 1e-12) ||
        (k > 0 && !(d->validated_polar[k] > d->validated_polar[k - 1])) || !(d->validated_depth[k] > 0.0) ||
        !isfinite(d->validated_depth[k]))
      return PALP_EINVAL;
  /* [rad]; stated only with the validation it belongs to (a logged scene writes it there) */
  if (!(d->validated_hinge_error >= 0.0 && d->validated_hinge_error <= 1.0) ||
      (d->validated_hinge_error > 0.0 && d->validated_count == 0))
    return PALP_EINVAL;
  for (int l = 0; l < d->lesion_count; ++l) {
    const palp_lesion *L = &d->lesion[l];
    /* inside the dome and clear of its base; a finite, positive stiffness ratio */
    if (!v3_isfinite(L->center) || !(L->radius > 0.0) || !(L->stiffness_ratio > 0.0) || !isfinite(L->stiffness_ratio) ||
        !(v3_len(L->center) + L->radius < d->mesh.radius) || !(L->center.z - L->radius > 0.0))
      return PALP_EINVAL;
  }
  return PALP_OK;
}

/* Timing slots: the factor's upkeep, then the pipeline's stages in order. */
enum { STAGE_REFACTOR = 0, STAGE_FIRST = 1 };

/* Adds dt [s] to a timing slot: `last` sums every part of the current frame (both halves
 * of a split step, a rejected attempt's stages), `total` every frame. */
static void stage_time_add(palp_world *w, int slot, double dt) {
  w->timings.last[slot] += dt;
  w->timings.total[slot] += dt;
}

static void build_pipeline(palp_world *w) {
  int n = 0;
  w->stages[n++] = (stage){"loads", stage_loads};
  if (w->nlink) w->stages[n++] = (stage){"membrane_forces", stage_membrane_forces};
  if (w->nhinge) w->stages[n++] = (stage){"membrane_bending", stage_membrane_bending};
  if (has(w, PALP_EFFECT_GEL_PRESSURE)) w->stages[n++] = (stage){"gel_forces", stage_gel_forces};
  if (has(w, PALP_EFFECT_GEL_SUPPORT)) w->stages[n++] = (stage){"gel_support", stage_gel_support};
  w->stages[n++] = (stage){"solve", stage_solve};
  w->stages[n++] = (stage){"fingers", stage_fingers};
  w->stages[n++] = (stage){"integrate", stage_integrate};
  w->stages[n++] = (stage){"base", stage_base};
  if (w->nlink) w->stages[n++] = (stage){"membrane_state", stage_membrane_state};
  if (has(w, PALP_EFFECT_GEL_PRESSURE)) w->stages[n++] = (stage){"gel_state", stage_gel_state};
  if (w->sq) w->stages[n++] = (stage){"support_state", stage_support_state};
  if (has(w, PALP_EFFECT_FORCE_FEEDBACK)) w->stages[n++] = (stage){"feedback", stage_feedback};
  w->stage_count = n;
  memset(&w->timings, 0, sizeof w->timings);
  /* The factor's upkeep is timed too, first as it runs first: a due job installed (or
   * computed) and a blend advanced before the step, a rebuild or a job request and the
   * Burgers coefficients inside it. Left out, a rebuild step's stages summed to 16% of
   * its wall time (0.088 of 0.55 ms). */
  w->timings.name[STAGE_REFACTOR] = "refactor";
  for (int s = 0; s < n; ++s) w->timings.name[STAGE_FIRST + s] = w->stages[s].name;
}

static void *xcalloc(size_t n, size_t size, int *fail) {
  void *p = calloc(n ? n : 1, size);
  if (!p) *fail = 1;
  return p;
}

/* A half-edge (a -> b) of triangle t, keyed by its unordered ends. */
typedef struct half_edge {
  int lo, hi, a, b, opp, t;
} half_edge;
static int half_edge_cmp(const void *x, const void *y) {
  const half_edge *p = x, *q = y;
  if (p->lo != q->lo) return p->lo < q->lo ? -1 : 1;
  if (p->hi != q->hi) return p->hi < q->hi ? -1 : 1;
  return (p->t > q->t) - (p->t < q->t);
}

/* The lesion support scale set for vertex i (1 without lesions, exactly). */
static double lesion_scale(const palp_world *w, int i) {
  const double a = w->mesh.vertex_area[i];
  return a > 0.0 ? w->sarea[i] / a : 1.0;
}

static double tri_area(const palp_vec3 *x, const int *T) {
  return 0.5 * v3_len(v3_cross(v3_sub(x[T[1]], x[T[0]]), v3_sub(x[T[2]], x[T[0]])));
}

/* One hinge per edge shared by two triangles with a free vertex among its four. The
 * base's triangles count: at the rim the dome meets the rigid base at a hinge whose
 * only free vertex is the dome triangle's wing, which clamps the skin's slope there
 * (the phantom is bonded to its base); such a hinge takes twice the dome triangle's
 * area, as if mirrored, since the base's long slivers say nothing of the skin. */
static int build_hinges(palp_world *w) {
  const palp_mesh *m = &w->mesh;
  const int nt = m->triangle_count;
  half_edge *he = malloc(sizeof *he * (size_t)(3 * nt));
  if (!he) return PALP_ENOMEM;
  for (int t = 0; t < nt; ++t)
    for (int q = 0; q < 3; ++q) {
      const int a = m->tri[t][q], b = m->tri[t][(q + 1) % 3];
      he[3 * t + q] = (half_edge){a < b ? a : b, a < b ? b : a, a, b, m->tri[t][(q + 2) % 3], t};
    }
  qsort(he, (size_t)(3 * nt), sizeof *he, half_edge_cmp);
  int cap = 0;
  for (int i = 0; i + 1 < 3 * nt; ++i)
    if (he[i].lo == he[i + 1].lo && he[i].hi == he[i + 1].hi) cap++;
  w->hinge = malloc(sizeof *w->hinge * (size_t)(cap ? cap : 1));
  w->hgrad = malloc(sizeof *w->hgrad * (size_t)(cap ? cap : 1));
  w->hk = malloc(sizeof *w->hk * (size_t)(cap ? cap : 1));
  w->hrest = malloc(sizeof *w->hrest * (size_t)(cap ? cap : 1));
  w->hbeyond = calloc((size_t)(cap ? cap : 1), 1);
  w->vhinge_start = calloc((size_t)m->vertex_count + 1, sizeof(int));
  w->vhinge = malloc(sizeof(int) * (size_t)(4 * cap + 1));
  w->ubuf = malloc(sizeof *w->ubuf * (size_t)m->vertex_count);
  if (!w->hinge || !w->hgrad || !w->hk || !w->hrest || !w->hbeyond || !w->vhinge_start || !w->vhinge || !w->ubuf) {
    free(he);
    return PALP_ENOMEM;
  }
  const double D = w->def.membrane.bending_stiffness;          /* [N m] */
  const double Ds = w->def.membrane.skin_bending_stiffness;   /* [N m], the skin's own share of D */
  for (int i = 0; i + 1 < 3 * nt; ++i) {
    const half_edge *p = &he[i], *q = &he[i + 1];
    if (p->lo != q->lo || p->hi != q->hi) continue;
    /* p runs a -> b with wing c; q, the neighbour, b -> a with wing d. */
    const int v[4] = {p->a, p->b, p->opp, q->opp};
    if (m->fixed[v[0]] && m->fixed[v[1]] && m->fixed[v[2]] && m->fixed[v[3]]) continue;
    palp_vec3 g[4];
    if (palp_hinge_gradient(m->rest[v[0]], m->rest[v[1]], m->rest[v[2]], m->rest[v[3]], g)) continue;
    const int pd = p->t < m->dome_triangle_count, qd = q->t < m->dome_triangle_count;
    if (!pd && !qd) continue;
    const double area = (pd ? tri_area(m->rest, m->tri[p->t]) : 0.0) + (qd ? tri_area(m->rest, m->tri[q->t]) : 0.0);
    const double e2 = v3_dot(v3_sub(m->rest[v[1]], m->rest[v[0]]), v3_sub(m->rest[v[1]], m->rest[v[0]]));
    const int e = w->nhinge++;
    memcpy(w->hinge[e], v, sizeof v);
    memcpy(w->hgrad[e], g, sizeof g);
    w->hrest[e] = palp_hinge_angle(m->rest[v[0]], m->rest[v[1]], m->rest[v[2]], m->rest[v[3]]);
    /* The gel's part of D sees a lesion as the support under the edge's ends does (their
     * scales were set before the hinges: sarea / vertex_area), a stiff one and a soft one
     * alike. Until the support's cyst strained as Eshelby's sphere (src/lesion.c) the series
     * scale made a 0.2x cyst 0.38x and the split doubled its softening, so a cyst kept D;
     * with Eshelby's 0.84 the split brings the long-term cyst from 0.2 of the level-4 FE's
     * loss to 0.6-1.0 of it (docs/haptics.md). Without lesions s is 1 and D is kept exactly,
     * so lesion-free worlds keep their bits. */
    const double s = 0.5 * (lesion_scale(w, v[0]) + lesion_scale(w, v[1]));
    const double De = Ds > 0.0 && s != 1.0 ? Ds + (D - Ds) * s : D;
    w->hk[e] = palp_hinge_stiffness(De, e2, pd && qd ? area : 2.0 * area);
    if (!(pd && qd)) w->hk[e] *= 1.0 - w->def.membrane.rim_hinge_release; /* a rim edge: see palp.h */
  }
  free(he);
  for (int e = 0; e < w->nhinge; ++e)
    for (int k = 0; k < 4; ++k) w->vhinge_start[w->hinge[e][k] + 1]++;
  for (int i = 0; i < m->vertex_count; ++i) w->vhinge_start[i + 1] += w->vhinge_start[i];
  int *fill = malloc(sizeof(int) * (size_t)m->vertex_count);
  if (!fill) return PALP_ENOMEM;
  memcpy(fill, w->vhinge_start, sizeof(int) * (size_t)m->vertex_count);
  for (int e = 0; e < w->nhinge; ++e)
    for (int k = 0; k < 4; ++k) w->vhinge[fill[w->hinge[e][k]]++] = 4 * e + k;
  free(fill);
  return PALP_OK;
}

palp_world *palp_world_create(const palp_world_def *def, int *err) {
  int e = validate(def);
  if (e) {
    if (err) *err = e;
    return NULL;
  }
  palp_world *w = calloc(1, sizeof *w);
  if (!w) {
    if (err) *err = PALP_ENOMEM;
    return NULL;
  }
  w->def = *def;
  e = palp_mesh_create(&def->mesh, &w->mesh);
  if (e) {
    free(w);
    if (err) *err = e;
    return NULL;
  }
  const int nv = w->mesh.vertex_count;
  int fail = 0;
  w->pos = xcalloc((size_t)nv, sizeof *w->pos, &fail);
  w->vel = xcalloc((size_t)nv, sizeof *w->vel, &fail);
  w->force = xcalloc((size_t)nv, sizeof *w->force, &fail);
  w->mass = xcalloc((size_t)nv, sizeof *w->mass, &fail);
  w->sarea = xcalloc((size_t)nv, sizeof *w->sarea, &fail);
  if ((def->effects & PALP_EFFECT_GEL_SUPPORT) && def->gel.support_relax_modulus > 0.0)
    w->sq = xcalloc((size_t)nv, sizeof *w->sq, &fail);
  if ((def->effects & PALP_EFFECT_GEL_SUPPORT) && def->gel.support_stiffening > 0.0) {
    w->sheight = xcalloc((size_t)nv, sizeof *w->sheight, &fail);
    w->fsu = xcalloc((size_t)nv, sizeof *w->fsu, &fail);
  }
  w->row_of = xcalloc((size_t)nv, sizeof *w->row_of, &fail);
  w->vertex_of = xcalloc((size_t)nv, sizeof *w->vertex_of, &fail);
  w->contacts = xcalloc((size_t)def->max_contacts, sizeof *w->contacts, &fail);
  if (fail) goto nomem;
  memcpy(w->pos, w->mesh.rest, sizeof *w->pos * (size_t)nv);
  double free_area = 0.0; /* [m^2] */
  for (int i = 0; i < nv; ++i) {
    /* The support's column runs from the surface to the dome's centre, cut short by the
     * base by support_base_reach (palp.h): R - f (R - z_i), floored at 1 mm. */
    const double rl = v3_len(w->mesh.rest[i]);
    const palp_vec3 nrm = rl > 0.0 ? v3_scale(w->mesh.rest[i], 1.0 / rl) : v3(0, 0, 1);
    const double fb = (def->effects & PALP_EFFECT_GEL_SUPPORT) ? def->gel.support_base_reach : 0.0;
    const double cl = fb > 0.0 ? fmax(rl - fb * (rl - w->mesh.rest[i].z), 1e-3) : rl; /* [m]; rl: the scale is 1 */
    w->sarea[i] = w->mesh.vertex_area[i] *
                  palp_support_column_scale(def->lesion, def->lesion_count, w->mesh.rest[i], nrm, cl, rl);
    /* The gel under a vertex is squeezed against the base plane z = 0; floored at 1 mm
     * (the rim's ring lies on it and is fixed; the next ring is ~2.6 mm up). */
    if (w->sheight) w->sheight[i] = fmax(w->mesh.rest[i].z, 1e-3);
    w->mass[i] = def->membrane.density * def->membrane.thickness * w->mesh.vertex_area[i]; /* [kg] */
    w->row_of[i] = w->mesh.fixed[i] ? -1 : w->nfree;
    if (!w->mesh.fixed[i]) w->vertex_of[w->nfree++] = i, free_area += w->mesh.vertex_area[i];
  }
  if (def->gel.added_mass_fraction > 0.0 && free_area > 0.0) {
    /* m_i += f rho_gel V0 A_i / A_free [kg]: the rim is clamped, so its share goes to the free vertices */
    const double per_area = def->gel.added_mass_fraction * def->gel.density * palp_mesh_volume(&w->mesh, w->mesh.rest) / free_area;
    for (int r = 0; r < w->nfree; ++r) w->mass[w->vertex_of[r]] += per_area * w->mesh.vertex_area[w->vertex_of[r]];
  }
  w->rhs = xcalloc((size_t)w->nfree * 6, sizeof(double), &fail);
  w->work = xcalloc(palp_ldl_work_size(3 * w->nfree, 2), sizeof(double), &fail); /* the step's solve: 1 or 2 wide */
  if (def->refactor_blend > 0) w->bx = xcalloc((size_t)w->nfree * 6, sizeof(double), &fail);
  if (fail) goto nomem;

  if (has(w, PALP_EFFECT_MEMBRANE_ELASTICITY)) {
    const int nl = w->mesh.link_count;
    w->nlink = nl;
    w->rest_len = xcalloc((size_t)nl, sizeof(double), &fail);
    w->inv_rest = xcalloc((size_t)nl, sizeof(double), &fail);
    w->ld = xcalloc(3 * (size_t)nl, sizeof(double), &fail);
    w->vfast = xcalloc((size_t)nv, 1, &fail);
    w->kx = xcalloc((size_t)nl, sizeof(double), &fail);
    w->xsec = xcalloc((size_t)nl, sizeof(double), &fail);
    w->eps = xcalloc((size_t)nl, sizeof(double), &fail);
    w->dir = xcalloc((size_t)nl, sizeof *w->dir, &fail);
    w->sigma = xcalloc((size_t)nl, sizeof(double), &fail);
    w->fdir = xcalloc((size_t)nl, sizeof *w->fdir, &fail);
    w->fbeta = xcalloc((size_t)nl, sizeof(double), &fail);
    w->link_mass = xcalloc((size_t)nl, sizeof(double), &fail);
    w->fslack = xcalloc((size_t)nl, sizeof(double), &fail);
    /* The turn rule's data, only where it applies (turn_rule): its sums of the factor's
     * diagonal blocks then run with each factorisation. */
    if ((def->refactor_lag > 0 || def->refactor_blend > 0) && def->dt <= PALP_HAPTIC_MAX_DT) {
      w->soft_blk = xcalloc(6 * (size_t)nv, sizeof(double), &fail);
      w->fsoft = xcalloc((size_t)nv + 1, sizeof(double), &fail);
      w->lturn = xcalloc((size_t)nl, sizeof(double), &fail);
      w->vturn = xcalloc((size_t)nv, sizeof(double), &fail);
    }
    if (has(w, PALP_EFFECT_MEMBRANE_VISCOSITY)) w->xs = xcalloc((size_t)nl, sizeof *w->xs, &fail);
    if (fail) goto nomem;
    /* Each link carries the membrane over the area of its two triangles: a spring
     * k = E t (A_l + A_r) / L0^2 reproduces an isotropic membrane's modulus on an
     * equilateral lattice (Van Gelder 1998), so the cross-section is t (A_l + A_r) / L0. */
    double *tri_area_sum = xcalloc((size_t)nl, sizeof(double), &fail);
    if (fail) goto nomem;
    for (int t = 0; t < w->mesh.dome_triangle_count; ++t) {
      const int *T = w->mesh.tri[t];
      const double area = tri_area(w->pos, T);
      for (int q = 0; q < 3; ++q) {
        int a = T[q], b = T[(q + 1) % 3];
        if (a > b) {
          int s = a;
          a = b, b = s;
        }
        /* binary search: links are sorted by (first, second) */
        int lo = 0, hi = nl - 1;
        while (lo <= hi) {
          const int mid = (lo + hi) / 2;
          const int *L = w->mesh.link[mid];
          if (L[0] == a && L[1] == b) {
            tri_area_sum[mid] += area;
            break;
          }
          if (L[0] < a || (L[0] == a && L[1] < b)) lo = mid + 1;
          else hi = mid - 1;
        }
      }
    }
    for (int l = 0; l < nl; ++l) {
      const palp_vec3 d = v3_sub(w->pos[w->mesh.link[l][1]], w->pos[w->mesh.link[l][0]]);
      w->rest_len[l] = v3_len(d);
      w->dir[l] = v3_scale(d, 1.0 / w->rest_len[l]);
      w->xsec[l] = def->membrane.thickness * tri_area_sum[l] / w->rest_len[l];
      w->inv_rest[l] = 1.0 / w->rest_len[l];
      w->kx[l] = w->xsec[l] / w->rest_len[l];
      if (l == 0 || w->rest_len[l] < w->min_rest_len) w->min_rest_len = w->rest_len[l];
    }
    free(tri_area_sum);
    int *deg = xcalloc((size_t)nv, sizeof(int), &fail);
    if (fail) goto nomem;
    for (int l = 0; l < nl; ++l) deg[w->mesh.link[l][0]]++, deg[w->mesh.link[l][1]]++;
    for (int i = 0; i < nv; ++i) w->link_degree = deg[i] > w->link_degree ? deg[i] : w->link_degree;
    for (int l = 0; l < nl; ++l) {
      double m = INFINITY; /* [kg] a fixed end adds nothing to the free end's margin */
      for (int q = 0; q < 2; ++q) {
        const int v = w->mesh.link[l][q];
        if (!w->mesh.fixed[v]) m = fmin(m, w->mass[v] / deg[v]);
      }
      w->link_mass[l] = isfinite(m) ? m : 0.0;
    }
    free(deg);
    w->E_static = def->membrane.E1 * def->membrane.E2 / (def->membrane.E1 + def->membrane.E2);
    if (def->membrane.bending_stiffness > 0.0 && build_hinges(w)) goto nomem;
  }

  if (has(w, PALP_EFFECT_GEL_PRESSURE)) {
    w->grad = xcalloc((size_t)nv, sizeof *w->grad, &fail);
    w->u = xcalloc((size_t)w->nfree * 3, sizeof(double), &fail);
    w->g_u = xcalloc((size_t)w->nfree * 3, sizeof(double), &fail);
    if (fail) goto nomem;
    w->V0 = w->V = palp_gel_volume_gradient(&w->mesh, w->pos, w->grad);
    w->p_abs = w->p_abs_prev = def->gel.pressure;
    w->h_gel_prev = def->dt; /* p_abs - p_abs_prev = 0: any step length gives no momentum */
  } else {
    w->V0 = w->V = palp_mesh_volume(&w->mesh, w->pos);
  }
  if (has(w, PALP_EFFECT_FORCE_FEEDBACK)) {
    w->vlink_start = xcalloc((size_t)nv + 1, sizeof(int), &fail);
    w->vlink = xcalloc((size_t)(2 * w->nlink), sizeof(int), &fail);
    if (fail) goto nomem;
    for (int l = 0; l < w->nlink; ++l) w->vlink_start[w->mesh.link[l][0] + 1]++, w->vlink_start[w->mesh.link[l][1] + 1]++;
    for (int i = 0; i < nv; ++i) w->vlink_start[i + 1] += w->vlink_start[i];
    int *fill = xcalloc((size_t)nv, sizeof(int), &fail);
    if (fail) goto nomem;
    for (int l = 0; l < w->nlink; ++l) {
      const int a = w->mesh.link[l][0], b = w->mesh.link[l][1];
      w->vlink[w->vlink_start[a] + fill[a]++] = l + 1;
      w->vlink[w->vlink_start[b] + fill[b]++] = -(l + 1);
    }
    free(fill);
  }
  e = refactor(w, def->dt, 0);
  if (e) {
    palp_world_destroy(w);
    if (err) *err = e;
    return NULL;
  }
  spares_prepare(w, def->dt);
  build_pipeline(w);
  w->awake = 1;
  if (err) *err = PALP_OK;
  return w;
nomem:
  palp_world_destroy(w);
  if (err) *err = PALP_ENOMEM;
  return NULL;
}

/* A finger contact's constraint rows (palp_world_add_finger_def), all or none. */
static void finger_rows_free(contact *k) {
  free(k->ctri), free(k->cbary), free(k->cn), free(k->cq), free(k->clam), free(k->ckey);
  k->ctri = NULL, k->cbary = NULL, k->cn = NULL, k->cq = NULL, k->clam = NULL, k->ckey = NULL;
}

/* The finger scratch, also one that finger_scratch_create left half made. */
static void finger_scratch_free(finger_scratch *fs) {
  if (!fs) return;
  free(fs->pool), free(fs->slot_row), free(fs->slot_used), free(fs->row_slot), free(fs->solve), free(fs->work);
  free(fs->G), free(fs->prev_pool), free(fs->prev_row_slot), free(fs->prev_slot_row);
  zstore_free(&fs->z);
  free(fs->zblk), free(fs->zparent);
  free(fs->vloc), free(fs->lvert), free(fs->G_lvert), free(fs->lf), free(fs->y), free(fs->W), free(fs->b), free(fs->lwork);
  free(fs->cand), free(fs->fpos), free(fs->patch), free(fs->patch_max), free(fs->nrest), free(fs->mrest), free(fs->ncur);
  free(fs->nstamp), free(fs->vtri_start), free(fs->vtri), free(fs->clist), free(fs->tbits), free(fs->tlist), free(fs->tcross), free(fs->tstamp), free(fs);
}

void palp_world_destroy(palp_world *w) {
  if (!w) return;
  for (int c = 0; w->contacts && c < w->def.max_contacts; ++c) {
    free(w->contacts[c].vertex);
    free(w->contacts[c].weight);
    free(w->contacts[c].feedback);
    finger_rows_free(&w->contacts[c]);
  }
  finger_scratch_free(w->fs);
  free(w->contacts);
  free(w->pos), free(w->vel), free(w->force), free(w->mass), free(w->sarea), free(w->sq), free(w->sheight), free(w->fsu), free(w->row_of), free(w->vertex_of);
  free(w->rest_len), free(w->inv_rest), free(w->ld), free(w->vfast), free(w->kx), free(w->xsec), free(w->eps), free(w->dir), free(w->xs);
  free(w->sigma), free(w->fdir), free(w->fbeta), free(w->link_mass), free(w->fslack);
  free(w->fsoft), free(w->lturn), free(w->vturn), free(w->soft_blk);
  free(w->hinge), free(w->hgrad), free(w->hk), free(w->hrest), free(w->hbeyond), free(w->vhinge_start), free(w->vhinge), free(w->ubuf);
  free(w->grad), free(w->u), free(w->g_u), free(w->vlink_start), free(w->vlink);
  free(w->rhs), free(w->work), free(w->bx);
  palp_ldl_free(&w->ldl);
  palp_ldl_free(&w->ldl_prev);
  free(w->rti), free(w->rtj), free(w->rtx);
  job_free(w->job);
  free(w->gp), free(w->gi);
  palp_mesh_destroy(&w->mesh);
  free(w);
}

/* Builds and factors A = M + h^2 K~ over the free degrees of freedom (3 per free
 * vertex) for step h, with the lagged tangent of each link,
 *   K~_l = k_l [d d^T + beta_l (I - d d^T)],  k_l = E_alg a_l / L0_l [N/m],
 * d its current direction and beta_l = max(beta_min, 2 rho_l), where
 * rho_l = (sigma_l a_l / L_l) / k_l is the tension's stiffness across the link
 * relative to k_l. A linearly implicit step stays stable while K~ holds at least
 * half of the true stiffness in every mode, so the factor serves until a link turns
 * by more than 30 degrees or its tension outgrows beta_l (checked every step in
 * stage_membrane_state). An isotropic k_l I would never need rebuilding, but it
 * adds stiffness across the links, which damped a pressed patch by ~90%. */
#define PALP_BETA_MIN 0.001
static int set_burgers(palp_world *w, double h) {
  if (!has(w, PALP_EFFECT_MEMBRANE_VISCOSITY) || h == w->h_burgers) return PALP_OK;
  const palp_membrane_params *m = &w->def.membrane;
  const int e = palp_burgers_init(&w->burgers, m->E1, m->eta1, m->E2, m->eta2, h);
  if (!e) w->h_burgers = h;
  return e;
}

/* The lower triangle of A = M + h^2 K~ as triplets (nnz returned), with the link
 * data the factor will be checked against (fdir, fbeta, fslack) for the current
 * state. Needs the Burgers coefficients for h (set_burgers). */
/* The smallest eigenvalue of the symmetric 3x3 [a0 a1 a2; a1 a3 a4; a2 a4 a5]
 * (the trigonometric form: the three are q + 2 p cos(phi + 2 pi k / 3)). */
static double sym3_min_eig(const double a[6]) {
  const double p1 = a[1] * a[1] + a[2] * a[2] + a[4] * a[4];
  const double q = (a[0] + a[3] + a[5]) / 3.0;
  if (p1 == 0.0) return fmin(a[0], fmin(a[3], a[5]));
  const double b0 = a[0] - q, b3 = a[3] - q, b5 = a[5] - q;
  const double p = sqrt((b0 * b0 + b3 * b3 + b5 * b5 + 2.0 * p1) / 6.0);
  const double c0 = b0 / p, c1 = a[1] / p, c2 = a[2] / p, c3 = b3 / p, c4 = a[4] / p, c5 = b5 / p;
  const double det = c0 * (c3 * c5 - c4 * c4) - c1 * (c1 * c5 - c4 * c2) + c2 * (c1 * c4 - c3 * c2);
  const double phi = acos(fmax(-1.0, fmin(1.0, det / 2.0))) / 3.0;
  return q + 2.0 * p * cos(phi + 2.0 * 3.14159265358979323846 / 3.0);
}

/* fsoft[r] = the smallest eigenvalue of A's diagonal block at free row r, over h^2
 * [N/m]: what the factor holds at that vertex in its softest direction, mass term
 * included (turn_quotient); fsoft[nf] their least. Summed from the triplets (the
 * duplicates as the factor sums them; each block's lower triangle is all it has) into
 * blk [6 nf]. Run with the factorisation (palp_factor_job_run, refactor): ~30 us at 338
 * vertices, which a rebuild request on the tick need not pay. */
static void soft_stiffness(int nf, double h, int nnz, const int *ti, const int *tj, const double *tx, double *blk,
                           double *fsoft) {
  static const int idx[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  memset(blk, 0, sizeof(double) * 6 * (size_t)nf);
  for (int k = 0; k < nnz; ++k)
    if (ti[k] / 3 == tj[k] / 3) blk[6 * (ti[k] / 3) + idx[ti[k] % 3][tj[k] % 3]] += tx[k];
  fsoft[nf] = INFINITY;
  for (int r = 0; r < nf; ++r) {
    fsoft[r] = sym3_min_eig(blk + 6 * r) / (h * h);
    if (!(fsoft[r] >= fsoft[nf])) fsoft[nf] = fsoft[r]; /* NaN too: then every step sums */
  }
}

static int build_matrix(const palp_world *w, double h, int *ti, int *tj, double *tx, palp_vec3 *fdir,
                        double *fbeta, double *fslack, palp_vec3 *fsu) {
  const double E = has(w, PALP_EFFECT_MEMBRANE_VISCOSITY) ? w->burgers.tangent : w->E_static; /* [Pa] */
  int nnz = 0;
  /* Lower triangle of each 3x3 diagonal block (duplicates are summed). */
  const double ks = has(w, PALP_EFFECT_GEL_SUPPORT) ? w->def.gel.support_modulus : 0.0; /* [Pa/m] */
  const double cs = has(w, PALP_EFFECT_GEL_SUPPORT) && has(w, PALP_EFFECT_GEL_DAMPING) ? w->def.gel.support_viscosity : 0.0;
  const double kr = relax_stiffness(w, h); /* [Pa/m]; 0 without the relaxing support */
  for (int r = 0; r < w->nfree; ++r)
    for (int i = 0; i < 3; ++i) {
      const int v = w->vertex_of[r];
      ti[nnz] = tj[nnz] = 3 * r + i;
      tx[nnz++] = w->mass[v] + (kr > 0.0 ? (h * h * (ks + kr) + h * cs) : (h * h * ks + h * cs)) * w->sarea[v];
    }
  if (w->sheight) { /* only with the support on, whose modulus is > 0 (validate) */
    /* The stiffening support's tangent h^2 k A s (I + p u^ u^^T) at this state (see
     * support_stiffening), and the u it was built with. */
    const double beta = w->def.gel.support_stiffening, p = w->def.gel.support_stiffening_power;
    for (int r = 0; r < w->nfree; ++r) {
      const int v = w->vertex_of[r];
      const palp_vec3 u = v3_sub(w->pos[v], w->mesh.rest[v]);
      const double ul = v3_len(u), g = h * h * ks * w->sarea[v] * stiffening_share(beta, p, ul, w->sheight[v]); /* [kg] */
      const double uv[3] = {ul > 0.0 ? u.x / ul : 0.0, ul > 0.0 ? u.y / ul : 0.0, ul > 0.0 ? u.z / ul : 0.0};
      fsu[v] = u;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j <= i; ++j)
          ti[nnz] = 3 * r + i, tj[nnz] = 3 * r + j, tx[nnz++] = g * ((i == j ? 1.0 : 0.0) + p * uv[i] * uv[j]);
    }
  }
  for (int l = 0; l < w->nlink; ++l) {
    const double k = E * w->xsec[l] / w->rest_len[l]; /* [N/m] */
    const palp_vec3 d = w->dir[l];
    const double dv[3] = {d.x, d.y, d.z};
    const double len = w->rest_len[l] * (1.0 + w->eps[l]);
    const double rho = fmax(0.0, w->sigma[l] * w->xsec[l] / len) / k;
    const double beta = fmax(PALP_BETA_MIN, 2.0 * rho);
    fdir[l] = d;
    fbeta[l] = beta;
    /* The mass term stabilises too: the 1-D condition h^2 k <= 4 m + 2 h^2 k~ leaves
     * 4 m / h^2 of transverse stiffness beyond 2 k~; half of it, shared among the
     * links at a vertex, for the longest step this factor serves (1.25 h). At 10 ms it
     * is ~1% of a link's stiffness; at 1 ms it spares most tension-growth rebuilds. */
    fslack[l] = 2.0 * w->link_mass[l] / (1.5625 * h * h);
    const int ra = w->row_of[w->mesh.link[l][0]], rb = w->row_of[w->mesh.link[l][1]];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) {
        const double b = h * h * k * ((1.0 - beta) * dv[i] * dv[j] + (i == j ? beta : 0.0));
        if (ra >= 0) ti[nnz] = 3 * ra + i, tj[nnz] = 3 * ra + j, tx[nnz++] = b;
        if (rb >= 0) ti[nnz] = 3 * rb + i, tj[nnz] = 3 * rb + j, tx[nnz++] = b;
      }
    if (ra >= 0 && rb >= 0) {
      const int hi = ra > rb ? ra : rb, lo = ra > rb ? rb : ra;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          ti[nnz] = 3 * hi + i, tj[nnz] = 3 * lo + j,
          tx[nnz++] = -h * h * k * ((1.0 - beta) * dv[i] * dv[j] + (i == j ? beta : 0.0));
    }
  }
  /* Bending: h^2 k_e g_p g_q^T between the hinge's free vertices (constant). */
  for (int e = 0; e < w->nhinge; ++e) {
    const double kh = h * h * w->hk[e]; /* [N m s^2] */
    for (int p = 0; p < 4; ++p) {
      const int rp = w->row_of[w->hinge[e][p]];
      if (rp < 0) continue;
      const double gp[3] = {w->hgrad[e][p].x, w->hgrad[e][p].y, w->hgrad[e][p].z};
      for (int q = 0; q <= p; ++q) {
        const int rq = w->row_of[w->hinge[e][q]];
        if (rq < 0) continue;
        const double gq[3] = {w->hgrad[e][q].x, w->hgrad[e][q].y, w->hgrad[e][q].z};
        if (rp == rq) {
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j <= i; ++j) ti[nnz] = 3 * rp + i, tj[nnz] = 3 * rp + j, tx[nnz++] = kh * gp[i] * gp[j];
        } else {
          const int hi = rp > rq ? rp : rq, lo = rp > rq ? rq : rp;
          const double *gh = rp > rq ? gp : gq, *gl = rp > rq ? gq : gp;
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) ti[nnz] = 3 * hi + i, tj[nnz] = 3 * lo + j, tx[nnz++] = kh * gh[i] * gl[j];
        }
      }
    }
  }
  return nnz;
}

/* Entries of A's lower triangle as triplets: 3 masses per free vertex (and 6 for the
 * stiffening support's block), 2 x 6 + 9 per link, 4 x 6 + 6 x 9 per hinge. */
static int nnz_bound(const palp_world *w) {
  return (w->sheight ? 9 : 3) * w->nfree + 21 * w->nlink + 78 * w->nhinge;
}

/* The free-vertex graph (CSC, both triangles) that orders the 3x3 blocks; built
 * once and kept, because a deferred job's factor analyses it too. */
static int build_graph(palp_world *w) {
  const int nf = w->nfree;
  /* Both directions of every coupled pair of free rows: the links', and each
   * hinge's six (its wings are coupled only through it); duplicates removed. */
  const size_t cap = 2 * (size_t)w->nlink + 12 * (size_t)w->nhinge + 1;
  int(*pr)[2] = malloc(sizeof *pr * cap);
  w->gp = calloc((size_t)nf + 1, sizeof(int));
  w->gi = malloc(sizeof(int) * cap);
  if (!pr || !w->gp || !w->gi) {
    free(pr);
    return PALP_ENOMEM;
  }
  size_t np = 0;
  for (int l = 0; l < w->nlink; ++l) {
    const int ra = w->row_of[w->mesh.link[l][0]], rb = w->row_of[w->mesh.link[l][1]];
    if (ra >= 0 && rb >= 0) pr[np][0] = ra, pr[np++][1] = rb, pr[np][0] = rb, pr[np++][1] = ra;
  }
  for (int e = 0; e < w->nhinge; ++e)
    for (int p = 0; p < 4; ++p)
      for (int q = 0; q < 4; ++q) {
        const int rp = w->row_of[w->hinge[e][p]], rq = w->row_of[w->hinge[e][q]];
        if (p != q && rp >= 0 && rq >= 0) pr[np][0] = rp, pr[np++][1] = rq;
      }
  /* stable counting sort by row */
  for (size_t k = 0; k < np; ++k) w->gp[pr[k][0] + 1]++;
  for (int r = 0; r < nf; ++r) w->gp[r + 1] += w->gp[r];
  int *fill = malloc(sizeof(int) * (size_t)(nf ? nf : 1));
  if (!fill) {
    free(pr);
    return PALP_ENOMEM;
  }
  memcpy(fill, w->gp, sizeof(int) * (size_t)nf);
  for (size_t k = 0; k < np; ++k) w->gi[fill[pr[k][0]]++] = pr[k][1];
  /* Duplicates out, first occurrences kept in place: without hinges the graph is
   * exactly the links' in their order, so the ordering, the factor and the bits of
   * every earlier session log stay the same. fill[] marks the row last seen. */
  for (int r = 0; r < nf; ++r) fill[r] = -1;
  int out = 0;
  for (int r = 0; r < nf; ++r) {
    const int s = w->gp[r], t = w->gp[r + 1];
    w->gp[r] = out;
    for (int k = s; k < t; ++k)
      if (fill[w->gi[k]] != r) fill[w->gi[k]] = r, w->gi[out++] = w->gi[k];
  }
  w->gp[nf] = out;
  free(fill), free(pr);
  return PALP_OK;
}

static void factor_installed(palp_world *w, double h) {
  w->h_factored = h;
  w->u_valid = 0;
  w->stale = 0;
  w->unsafe = 0;
  w->refactors++;
}

/* A blend (factor_solve) from the factor now in ldl_prev to the one just made. */
static void blend_start(palp_world *w) { w->blend_k = 1; }

static void blend_stop(palp_world *w) { w->blend_k = 0; }

/* At the start of each frame of a blend: the next weight, and u made anew from the blended
 * inverse (and once more after its end). The finger's gathered compliance needs nothing
 * here: stage_fingers gathers it anew in every frame of a blend and keeps none of it. */
static void blend_advance(palp_world *w) {
  if (++w->blend_k > w->def.refactor_blend) blend_stop(w);
  w->u_valid = 0;
}

/* Synchronous rebuild: at creation, when the step size leaves the factor's range, and
 * for a lagged tangent not deferred (blended in when blend, def.refactor_blend > 0 and
 * the step size is the factor's). A deferred job still pending is dropped at its due
 * frame (it describes an older state than this factor). */
static int refactor(palp_world *w, double h, int blend) {
  int e = set_burgers(w, h);
  if (e) return e;
  if (!w->gp) {
    e = build_graph(w);
    if (e) return e;
  }
  if (!w->rti) { /* the pattern's bound does not change after creation */
    const size_t nnz_max = (size_t)nnz_bound(w);
    w->rti = malloc(sizeof(int) * nnz_max), w->rtj = malloc(sizeof(int) * nnz_max);
    w->rtx = malloc(sizeof(double) * nnz_max);
    if (!w->rti || !w->rtj || !w->rtx) {
      free(w->rti), free(w->rtj), free(w->rtx);
      w->rti = w->rtj = NULL, w->rtx = NULL;
      return PALP_ENOMEM;
    }
  }
  int *ti = w->rti, *tj = w->rtj;
  double *tx = w->rtx;
  const int nnz = build_matrix(w, h, ti, tj, tx, w->fdir, w->fbeta, w->fslack, w->fsu);
  if (w->soft_blk) {
    soft_stiffness(w->nfree, h, nnz, ti, tj, tx, w->soft_blk, w->fsoft);
    soft_neighbourhood(w);
  }
  blend = blend && w->bx && w->ldl.n > 0 && h == w->h_factored;
  if (blend) {
    /* the factor being replaced to ldl_prev; the new one into the storage ldl_prev had
     * (its analysis reused after the first blend) */
    prev_cols_keep(w);
    const palp_ldl t = w->ldl;
    w->ldl = w->ldl_prev;
    w->ldl_prev = t;
  }
  w->factor_analyses += !w->ldl.symbolic;
  e = palp_ldl_factor_blocks(&w->ldl, w->nfree, w->gp, w->gi, nnz, ti, tj, tx);
  if (e) {
    if (blend) {
      const palp_ldl t = w->ldl;
      w->ldl = w->ldl_prev;
      w->ldl_prev = t;
    }
    return e;
  }
  finger_cols_invalidate(w);
  factor_installed(w, h);
  if (blend) blend_start(w);
  else blend_stop(w);
  if (w->job_state != JOB_NONE) w->job_obsolete = 1;
  return PALP_OK;
}

/* ---- deferred refactorisation (docs/haptics.md) -------------------------- */

/* Everything a lagged-tangent rebuild needs, owned by the job while a host holds
 * it: the matrix built at the requesting frame, a spare factor (with its own
 * CHOLMOD workspace) and the finger compliance columns the new factor will be
 * asked for first. The world's graph (gp, gi) is shared read-only: it never changes
 * after creation. */
struct palp_factor_job {
  int nf, nnz, n3;
  const int *gp, *gi;
  int *ti, *tj;
  double *tx;
  double h;
  palp_ldl ldl;
  int ncols, cols_cap; /* columns to precompute; capacity of cols in slots */
  int *col_row;        /* [cols_cap] free row of each */
  float *cols;         /* [cols_cap][3][n3], the finger pool's layout */
  double *solve, *work; /* [3 n3] */
  palp_vec3 *fdir;     /* [nlink] the new factor's link data (world-only) */
  double *fbeta, *fslack;
  double *fsoft, *soft_blk; /* [nf + 1], [6 nf] with the turn rule (turn_rule), else NULL */
  palp_vec3 *fsu; /* [nvertex] the stiffening support's u (NULL without it) */
  int rc;
  int analysed; /* the last run met its factor's storage unanalysed (counted at install) */
  /* With a nested-dissection factor: the paths (and their pairs) of the latest finger
   * step's vertices under the new factor, swapped into the finger's store at install. */
  zstore z;
  int nz, nz_cap;
  int *zrows; /* [nz_cap] */
};

static void job_free(palp_factor_job *j) {
  if (!j) return;
  free(j->ti), free(j->tj), free(j->tx), free(j->col_row), free(j->cols), free(j->solve), free(j->work);
  free(j->fdir), free(j->fbeta), free(j->fslack), free(j->fsu), free(j->fsoft), free(j->soft_blk);
  zstore_free(&j->z);
  free(j->zrows);
  palp_ldl_free(&j->ldl);
  free(j);
}

static palp_factor_job *job_alloc(const palp_world *w) {
  palp_factor_job *j = calloc(1, sizeof *j);
  if (!j) return NULL;
  const int nnz_max = nnz_bound(w);
  j->nf = w->nfree;
  j->n3 = 3 * w->nfree;
  j->gp = w->gp;
  j->gi = w->gi;
  j->ti = malloc(sizeof(int) * (size_t)nnz_max);
  j->tj = malloc(sizeof(int) * (size_t)nnz_max);
  j->tx = malloc(sizeof(double) * (size_t)nnz_max);
  j->solve = malloc(sizeof(double) * 3 * (size_t)(j->n3 ? j->n3 : 1));
  j->work = malloc(sizeof(double) * palp_ldl_work_size(j->n3, 3));
  const size_t nl = (size_t)(w->nlink ? w->nlink : 1);
  j->fdir = malloc(sizeof(palp_vec3) * nl);
  j->fbeta = malloc(sizeof(double) * nl);
  j->fslack = malloc(sizeof(double) * nl);
  if (w->soft_blk) {
    j->fsoft = malloc(sizeof(double) * ((size_t)w->nfree + 1));
    j->soft_blk = malloc(sizeof(double) * 6 * (size_t)(w->nfree ? w->nfree : 1));
  }
  if (w->sheight) j->fsu = calloc((size_t)w->mesh.vertex_count, sizeof(palp_vec3));
  if (!j->ti || !j->tj || !j->tx || !j->solve || !j->work || !j->fdir || !j->fbeta || !j->fslack ||
      (w->soft_blk && (!j->fsoft || !j->soft_blk)) ||
      (w->sheight && !j->fsu)) {
    job_free(j);
    return NULL;
  }
  return j;
}

int palp_factor_job_run(palp_factor_job *j) {
  if (!j) return PALP_EINVAL;
  /* before the factorisation, which may reorder the triplets */
  if (j->soft_blk) soft_stiffness(j->nf, j->h, j->nnz, j->ti, j->tj, j->tx, j->soft_blk, j->fsoft);
  j->analysed = !j->ldl.symbolic;
  j->rc = palp_ldl_factor_blocks(&j->ldl, j->nf, j->gp, j->gi, j->nnz, j->ti, j->tj, j->tx);
  if (j->rc) return j->rc;
  /* The same function as finger_slot's, so a column is the same bits whoever makes it. */
  for (int q = 0; q < j->ncols; ++q)
    factor_cols(&j->ldl, j->col_row[q], j->n3, j->solve, j->work, j->cols + (size_t)q * 3 * (size_t)j->n3);
  /* The same functions as the finger's, so a path and a pair are the same bits whoever makes them. */
  zstore_clear(&j->z);
  int ok = 1;
  for (int q = 0; q < j->nz && ok; ++q) ok = finger_zslot(&j->z, &j->ldl, j->zrows[q]) >= 0;
  for (int a = 0; a < j->z.used && ok; ++a)
    for (int b = a; b < j->z.used; ++b) zpair(&j->z, &j->ldl, a, b);
  if (!ok) zstore_clear(&j->z); /* out of memory: the tick makes them */
  return PALP_OK;
}

/* A rebuild requested by the step at frame f: the matrix of the current state, to be
 * installed at the start of frame f + refactor_lag. Returns 0 or PALP_ENOMEM (the
 * caller then rebuilds at once). */
static int job_request(palp_world *w, double h) {
  if (!w->job) {
    w->job = job_alloc(w);
    if (!w->job) return PALP_ENOMEM;
  }
  palp_factor_job *j = w->job;
  j->h = h;
  j->nnz = build_matrix(w, h, j->ti, j->tj, j->tx, j->fdir, j->fbeta, j->fslack, j->fsu);
  j->ncols = 0;
  const finger_scratch *fs = w->fs;
  if (fs && fs->slots > 0) {
    if (j->cols_cap < fs->slots) {
      float *c = realloc(j->cols, sizeof(float) * 3 * (size_t)j->n3 * (size_t)fs->slots);
      int *cr = realloc(j->col_row, sizeof(int) * (size_t)fs->slots);
      if (c) j->cols = c;
      if (cr) j->col_row = cr;
      if (c && cr) j->cols_cap = fs->slots;
    }
    /* The columns of the latest step's contact vertices: the next steps ask for them. */
    for (int q = 0; q < fs->slots && j->ncols < j->cols_cap; ++q)
      if (fs->slot_row[q] >= 0 && fs->slot_used[q] == fs->stamp) j->col_row[j->ncols++] = fs->slot_row[q];
  }
  j->nz = 0;
  if (fs && fs->zparent && fs->z.used > 0 && zstore_init(&j->z, w->nfree, fs->z.h, fs->zblk, fs->zparent) == 0) {
    /* the same for the paths, on a nested-dissection factor (stage_fingers) */
    if (j->nz_cap < fs->z.used) {
      int *zr = realloc(j->zrows, sizeof(int) * (size_t)fs->z.used);
      if (zr) j->zrows = zr, j->nz_cap = fs->z.used;
    }
    for (int q = 0; q < fs->z.used && j->nz < j->nz_cap; ++q)
      if (fs->z.stamp[q] == fs->stamp) j->zrows[j->nz++] = fs->z.slot_row[q];
  }
  j->rc = 0;
  w->job_state = JOB_REQUESTED;
  w->job_obsolete = 0;
  w->job_due = w->frame + w->def.refactor_lag;
  return PALP_OK;
}

/* At the start of the due frame: the job's factor replaces the world's. */
static int job_install(palp_world *w) {
  palp_factor_job *j = w->job;
  const int obsolete = w->job_obsolete;
  w->job_state = JOB_NONE;
  w->job_obsolete = 0;
  w->factor_analyses += j->analysed;
  j->analysed = 0;
  if (obsolete) return PALP_OK;
  if (j->rc) return refactor(w, j->h, 0); /* the same matrix, factored here: still deterministic */
  const int blend = w->def.refactor_blend > 0 && w->bx && j->h == w->h_factored;
  if (blend) prev_cols_keep(w);
  const palp_ldl old = w->ldl;
  w->ldl = j->ldl;
  if (blend) {
    j->ldl = w->ldl_prev; /* the next job's spare; the replaced factor serves the blend */
    w->ldl_prev = old;
  } else {
    j->ldl = old; /* kept as the next job's spare: its analysis is reused */
  }
  memcpy(w->fdir, j->fdir, sizeof(palp_vec3) * (size_t)w->nlink);
  memcpy(w->fbeta, j->fbeta, sizeof(double) * (size_t)w->nlink);
  memcpy(w->fslack, j->fslack, sizeof(double) * (size_t)w->nlink);
  if (w->soft_blk) {
    memcpy(w->fsoft, j->fsoft, sizeof(double) * ((size_t)w->nfree + 1));
    soft_neighbourhood(w);
  }
  if (w->fsu) memcpy(w->fsu, j->fsu, sizeof(palp_vec3) * (size_t)w->mesh.vertex_count);
  finger_cols_invalidate(w);
  finger_scratch *fs = w->fs;
  if (fs && j->nz > 0 && j->z.used > 0) { /* the job's paths and pairs, of the factor just installed */
    const zstore t = fs->z;
    fs->z = j->z;
    j->z = t;
    for (int q = 0; q < fs->z.used; ++q) fs->z.stamp[q] = fs->stamp;
    w->finger_paths += fs->z.used;
  }
  if (fs && j->ncols > 0 && j->cols_cap > 0) {
    /* Swap the pools: the job's buffer has the finger pool's layout. */
    if (j->cols_cap < fs->slots) {
      float *c = realloc(j->cols, sizeof(float) * 3 * (size_t)j->n3 * (size_t)fs->slots);
      int *cr = realloc(j->col_row, sizeof(int) * (size_t)fs->slots);
      if (c) j->cols = c;
      if (cr) j->col_row = cr;
      if (c && cr) j->cols_cap = fs->slots;
    }
    if (j->cols_cap >= fs->slots) {
      float *pool = fs->pool;
      fs->pool = j->cols;
      j->cols = pool;
      /* fs->slots stays: the swapped-in buffer holds at least that many slots; the
       * old pool (now the job's) had exactly fs->slots. */
      j->cols_cap = fs->slots;
      for (int q = 0; q < j->ncols; ++q) {
        fs->slot_row[q] = j->col_row[q];
        fs->row_slot[j->col_row[q]] = q;
        fs->slot_used[q] = fs->stamp;
      }
    }
  }
  factor_installed(w, j->h);
  if (blend) blend_start(w);
  else blend_stop(w);
  return PALP_OK;
}

/* The spare factors a lagged world swaps in (the job's, and ldl_prev with a blend),
 * analysed at creation. A factor's first use orders and analyses the matrix (AMD,
 * CHOLMOD's symbolic and numeric passes, the block map, then the block pass: several
 * times a refactorisation's cost), and a server helper that met it at a session's
 * first rebuild missed the lag: every session waited once, for up to 20 ms, and so did
 * every other session of its tick group (docs/server.md, "Rebuilds off the tick path").
 * The results do not change: each factorisation ends in the block pass over the same
 * pattern and ordering (palp_ldl_factor_blocks), whatever the spare held before.
 * Failing here is not an error: the spare is then analysed at its first use. */
static void spares_prepare(palp_world *w, double h) {
  if (w->def.refactor_lag <= 0) return;
  if (!w->job) w->job = job_alloc(w);
  palp_factor_job *j = w->job;
  if (!j) return;
  /* the current state's matrix, as job_request makes it, run as a helper runs a job
   * (no columns); nothing is requested, so the world never installs it */
  j->h = h;
  j->nnz = build_matrix(w, h, j->ti, j->tj, j->tx, j->fdir, j->fbeta, j->fslack, j->fsu);
  j->ncols = 0;
  (void)palp_factor_job_run(j);
  w->factor_analyses += j->analysed;
  j->analysed = 0;
  if (w->def.refactor_blend > 0 && w->bx) {
    w->factor_analyses += !w->ldl_prev.symbolic;
    (void)palp_ldl_factor_blocks(&w->ldl_prev, j->nf, j->gp, j->gi, j->nnz, j->ti, j->tj, j->tx);
  }
}

int palp_world_refactor_blend_for(double dt) {
  /* ~8 ms: half the lag, so a blend ends before the next job can be installed; at
   * 1 kHz the breast-tissue slide's 4.2% step becomes eight of ~0.5% (docs/haptics.md).
   * Only for physics at 500 Hz or faster: at slower rates the station blends each new
   * model over its period of several haptic ticks already, and a blend of 2 frames at
   * 250 Hz showed no gain in the 4 ms slide for its cost (a second solve per frame). */
  if (!(dt > 0.0) || dt > PALP_HAPTIC_MAX_DT) return 0;
  const double k = ceil(0.008 / dt - 1e-9);
  return k < 1.0 ? 1 : k > 1000.0 ? 1000 : (int)k;
}

int palp_world_refactor_lag_for(double dt) {
  /* ~16 ms: a job costs ~0.5 ms of factorisation and ~1 ms of finger columns, and
   * jobs come in bursts; at 8 ms, 32 sessions at 250 Hz still waited 1.4-8 ms for
   * a third of their jobs (docs/server.md). 2 frames at 100 Hz. */
  if (!(dt > 0.0)) return 0;
  const double k = ceil(0.016 / dt - 1e-9);
  return k < 1.0 ? 1 : k > 1000.0 ? 1000 : (int)k;
}

palp_factor_job *palp_world_factor_claim(palp_world *w) {
  if (!w || w->job_state != JOB_REQUESTED) return NULL;
  w->job_state = JOB_CLAIMED;
  return w->job;
}

int palp_world_factor_done(palp_world *w, palp_factor_job *j) {
  if (!w || !j || j != w->job || w->job_state != JOB_CLAIMED) return PALP_EINVAL;
  w->job_state = JOB_DONE;
  return PALP_OK;
}

int64_t palp_world_factor_due(const palp_world *w) {
  return w && w->job_state == JOB_CLAIMED ? w->job_due : -1;
}

/* ---- stepping ----------------------------------------------------------- */

/* path: also a finger whose proxy's path to its device (the segment finger_collect searches)
 * passes near the surface. Asked only of a sleeping world (session 83 review): a device set from
 * 30 mm above the pole to 20 mm inside the dome, no vertex within reach of either point, left the
 * world asleep and the finger without a contact (an awake world pressed 27 mm there). An awake
 * world keeps the device-point test: after each of its steps a finger without force has its proxy
 * at its device (stage_fingers), so its sleep decision is the same either way, and the wake of
 * palp_world_set_finger_device (which restarts its quiet time) stays as it was. */
static int has_load(const palp_world *w, int path) {
  /* Gravity is a load like any other (docs/model.md lists it under loads): a sagging dome
   * creeps on through its Maxwell dashpots, and put to sleep its sag stayed at 4.28 um
   * where it reaches 7.12 um in 120 s awake (session 81). */
  if (has(w, PALP_EFFECT_GRAVITY) && v3_dot(w->def.gravity, w->def.gravity) > 0.0) return 1;
  for (int c = 0; c < w->def.max_contacts; ++c) {
    const contact *k = &w->contacts[c];
    if (k->kind == CONTACT_FORCE && v3_dot(k->force, k->force) > 0.0) return 1;
    if (k->kind == CONTACT_FINGER) {
      /* Pressing, or touching: a sphere on a facet is at most about half a link from
       * the facet's nearest vertex, so a device farther than that hovers. */
      if (v3_dot(k->total, k->total) > 0.0) return 1;
      const double reach = k->fdef.radius + 0.5 * (w->fs ? w->fs->max_link : 0.0);
      const int moved = path && (k->proxy.x != k->device.x || k->proxy.y != k->device.y || k->proxy.z != k->device.z);
      for (int r = 0; r < w->nfree; ++r) {
        const palp_vec3 p = w->pos[w->vertex_of[r]];
        if (v3_len(v3_sub(p, k->device)) < reach) return 1;
        if (moved && seg_dist2(p, k->proxy, k->device) < reach * reach) return 1;
      }
    }
  }
  return 0;
}

/* The fastest internal creep or recovery [m/s]: each link's Maxwell flow |sigma| / eta1 and
 * Kelvin recovery |sigma - E2 x2| / eta2 times its rest length, and each free vertex's
 * relaxing support dashpot |u - q| / tau_r. The vertices can be slower than the sleep speed
 * while these still move the state on (a released dome recovering through its Kelvin arms
 * and its support's dashpots): sleeping then froze the breast-tissue dome's residual dent. */
static double internal_rate(const palp_world *w) {
  double r = 0.0;
  if (w->xs) {
    const double E2 = w->def.membrane.E2, i1 = 1.0 / w->def.membrane.eta1, i2 = 1.0 / w->def.membrane.eta2;
    for (int l = 0; l < w->nlink; ++l) {
      const double s = w->sigma[l], L = w->rest_len[l];
      const double v = L * fmax(fabs(s) * i1, fabs(s - E2 * w->xs[l][1]) * i2);
      if (!(v <= r)) r = v; /* NaN is kept: it keeps the world awake */
    }
  }
  if (w->sq) {
    const double itau = 1.0 / w->def.gel.support_relax_time;
    for (int k = 0; k < w->nfree; ++k) {
      const int i = w->vertex_of[k];
      const double v = v3_len(v3_sub(v3_sub(w->pos[i], w->mesh.rest[i]), w->sq[i])) * itau;
      if (!(v <= r)) r = v;
    }
  }
  return r;
}

static int has_finger(const palp_world *w) {
  for (int c = 0; c < w->def.max_contacts; ++c)
    if (w->contacts[c].kind == CONTACT_FINGER) return 1;
  return 0;
}

/* One attempt at a step of h; PALP_EAGAIN-like 1 when the solve was rejected
 * (nothing but the force arrays has changed then). */
static int try_step(palp_world *w, double h, int last_resort) {
  /* One clock read per stage boundary, each stage's end the next one's start: a read costs
   * ~25 ns on a VM's kvm-clock, and two per stage were ~2% of the paper's 25 us step. */
  double t0 = now_s();
  /* The factor built for h_f serves steps up to 1.25 h_f: the implicit stiffness is
   * then at least (1/1.25)^2 = 64% of what h needs, above the half that stability
   * requires; shorter steps only damp a little more. Beyond, or after a lagged-
   * tangent trigger, rebuild. The Burgers step is always exact for h. */
  /* Deferred only with a finger down (the haptic sessions the lag is for): under
   * heavy force loads rebuilds come every step or two, mostly inside halved steps
   * that rebuild at once anyway, and a helper computing jobs that are dropped only
   * competes with the ticks for the cores (measured: server_malformed's flood). */
  const int defer = w->def.refactor_lag > 0 && has_finger(w);
  const int resize = h > 1.25 * w->h_factored || h < 0.5 * w->h_factored;
  /* A factor beyond its margin is not kept for the lag at haptic physics rates (def.dt of
   * PALP_HAPTIC_MAX_DT or less): waiting let the long-term dome ring at 1 kHz, 30% of the
   * force (docs/haptics.md). At 250 Hz the margin is reached a frame or two after most
   * requests, and rebuilding then on the tick cost the demo's strip search (breast-tissue
   * dome) 1,289 such rebuilds and 1,118 late ticks in 123 s, against 5 late without, for a
   * gain seen only in the next-step prediction of the paper's flowing phantom. */
  const int margin = defer && w->unsafe && w->def.dt <= PALP_HAPTIC_MAX_DT; /* the rate's, not a halved step's */
  if (resize || (w->stale && (!defer || margin))) {
    /* Blended in unless the old factor is beyond its margin (or built for another h):
     * one near it for turned links (PALP_UNSAFE_TURN) is still stable, and a rebuild at
     * once unblended stepped the breast-tissue dome's force by up to 6.8% in a tick.
     * Keeping an unsafe factor for its last 2 frames made no difference at 1 kHz. */
    if (!resize && margin) w->margin_rebuilds++;
    int e = refactor(w, h, !resize && !(w->unsafe & PALP_UNSAFE_MARGIN));
    if (e) return e;
  } else if (w->stale && w->job_state == JOB_NONE) {
    /* Deferred: the old factor serves refactor_lag more frames (a lagged tangent is
     * already an approximation, and the trigger keeps half the stability margin). */
    if (job_request(w, h)) {
      int e = refactor(w, h, 1);
      if (e) return e;
    }
  }
  int e = set_burgers(w, h);
  if (e) return e;
  w->reject = 0;
  w->last_resort = last_resort;
  w->step_max_strain = 0.0;
  w->step_max_bend = 0.0;
  {
    const double t1 = now_s();
    stage_time_add(w, STAGE_REFACTOR, t1 - t0);
    t0 = t1;
  }
  for (int s = 0; s < w->stage_count; ++s) {
    w->stages[s].fn(w, h);
    const double t1 = now_s();
    stage_time_add(w, STAGE_FIRST + s, t1 - t0);
    t0 = t1;
    if (w->reject) return 1; /* rejected in the solve, before anything moved */
  }
  w->t += h;
  if (w->step_max_strain > 0.5) w->frame_large_strain = 1;
  if (w->step_max_strain > w->max_strain) w->max_strain = w->step_max_strain;
  if (w->hbeyond_count > 0) w->frame_large_bend = 1;
  if (w->step_max_bend > w->max_bend) w->max_bend = w->step_max_bend;
  return PALP_OK;
}

/* After a whole step (not its halves): a fingertip in contact pressed deeper than the
 * parameters were validated against the FE there (def.validated_*), its centre's depth
 * below the undeformed sphere at its polar angle, as palp-fem finger measures it. */
static void validated_check(palp_world *w) {
  double worst = 0.0; /* [m] */
  for (int ci = 0; ci < w->def.max_contacts; ++ci) {
    const contact *k = &w->contacts[ci];
    if (k->kind != CONTACT_FINGER || !k->lm.contact) continue;
    const palp_vec3 p = k->proxy;
    const double depth = w->def.mesh.radius + k->fdef.radius - v3_len(p);
    const double over = depth - palp_world_validated_depth(&w->def, atan2(sqrt(p.x * p.x + p.y * p.y), p.z));
    if (over > worst) worst = over;
  }
  if (worst > 0.0) w->beyond_validated_steps++;
  if (worst > w->max_beyond_validated) w->max_beyond_validated = worst;
}

/* Retries a rejected step as two halves, down to h/16, where only a non-finite
 * solution fails (stage_solve caps speeds and accepts inaccuracy there). */
#define PALP_MAX_HALVINGS 4
static int step_split(palp_world *w, double h, int depth) {
  int e = try_step(w, h, depth >= PALP_MAX_HALVINGS);
  if (e <= 0) return e;
  if (depth >= PALP_MAX_HALVINGS) return PALP_EUNSTABLE;
  w->substeps++;
  e = step_split(w, 0.5 * h, depth + 1);
  if (e) return e;
  return step_split(w, 0.5 * h, depth + 1);
}

int palp_world_step_dt(palp_world *w, double h) {
  if (!w) return PALP_EINVAL;
  if (w->broken) return PALP_EUNSTABLE;
  if (!(h > 0.0 && h <= 0.1) || !isfinite(h)) return PALP_EINVAL;
  /* A sleeping world without a load only advances its clock, due job or not (as before). */
  const int sleeping = !w->awake && !has_load(w, 1);
  /* A due job not handed back: refused before anything changes (the blend's weight, u, the
   * timings, the wake), so that the host's retry after palp_world_factor_done steps the very
   * world a host on time stepped. The blend was advanced first until session 83: a job that
   * fell due inside a blend (a margin rebuild made while it was pending) was blended one frame
   * ahead on the retry, and the late host's world diverged from its replay. */
  if (!sleeping && w->job_state == JOB_CLAIMED && w->frame >= w->job_due) return PALP_EBUSY;
  /* `last` is this frame's: zero while asleep (nothing is computed), else summed below */
  memset(w->timings.last, 0, sizeof w->timings.last);
  if (!w->awake) {
    if (sleeping) {
      w->t += h;
      w->frame++;
      return PALP_OK;
    }
    w->awake = 1;
    w->quiet = 0.0;
  }
  if (w->blend_k > 0 || (w->job_state != JOB_NONE && w->frame >= w->job_due)) {
    const double t0 = now_s();
    if (w->blend_k > 0) blend_advance(w);
    if (w->job_state != JOB_NONE && w->frame >= w->job_due) {
      /* Installed at its due frame whoever computed it: replay gets the same bits (a claimed
       * one was handed back: refused above). */
      if (w->job_state == JOB_REQUESTED && !w->job_obsolete) palp_factor_job_run(w->job);
      const int e = job_install(w);
      if (e) return e;
    }
    stage_time_add(w, STAGE_REFACTOR, now_s() - t0);
  }
  const double t_end = w->t + h;
  w->frame_large_strain = w->frame_large_bend = 0;
  int e = step_split(w, h, 0);
  if (e) {
    w->broken = (e == PALP_EUNSTABLE);
    return e;
  }
  w->t = t_end; /* halves sum to h exactly in binary, but keep the clock exact anyway */
  w->frame++;
  w->timings.steps++; /* frames stepped, however split: the totals' divisor */
  w->large_strain_steps += w->frame_large_strain;
  w->large_bend_steps += w->frame_large_bend;
  if (w->def.validated_count > 0) validated_check(w);

  /* Finite check and sleep: one pass over the free velocities. */
  double vmax2 = 0.0, vsum = 0.0;
  for (int r = 0; r < w->nfree; ++r) {
    const palp_vec3 v = w->vel[w->vertex_of[r]];
    const double v2 = v3_dot(v, v);
    vsum += v2;
    if (v2 > vmax2) vmax2 = v2;
  }
  if (!isfinite(vsum)) {
    w->broken = 1;
    return PALP_EUNSTABLE;
  }
  if (w->def.sleep_time > 0.0 && vmax2 < w->def.sleep_speed * w->def.sleep_speed && !has_load(w, 0) &&
      internal_rate(w) < w->def.sleep_speed) {
    w->quiet += h;
    if (w->quiet >= w->def.sleep_time) {
      w->awake = 0;
      for (int i = 0; i < w->mesh.vertex_count; ++i) w->vel[i] = v3(0, 0, 0);
    }
  } else {
    w->quiet = 0.0;
  }
  return PALP_OK;
}

int palp_world_step(palp_world *w) { return w ? palp_world_step_dt(w, w->def.dt) : PALP_EINVAL; }

/* ---- contacts ----------------------------------------------------------- */

static int free_slot(palp_world *w) {
  for (int c = 0; c < w->def.max_contacts; ++c)
    if (w->contacts[c].kind == CONTACT_NONE) return c;
  return PALP_EFULL;
}

static int ensure_cap(contact *k, int cap) {
  if (k->cap >= cap) return PALP_OK;
  int *v = realloc(k->vertex, sizeof(int) * (size_t)cap);
  if (v) k->vertex = v;
  double *wt = realloc(k->weight, sizeof(double) * (size_t)cap);
  if (wt) k->weight = wt;
  palp_vec3 *fb = realloc(k->feedback, sizeof(palp_vec3) * (size_t)cap);
  if (fb) k->feedback = fb;
  if (!v || !wt || !fb) return PALP_ENOMEM;
  k->cap = cap;
  return PALP_OK;
}

int palp_world_add_contact(palp_world *w, const palp_contact_def *def) {
  if (!w || !def) return PALP_EINVAL;
  const int c = free_slot(w);
  if (c < 0) return c;
  contact *k = &w->contacts[c];
  int e = ensure_cap(k, w->mesh.vertex_count);
  if (e) return e;
  const int n = palp_contact_weights(&w->mesh, w->mesh.rest, def, k->vertex, k->weight, k->cap);
  if (n < 0) return n;
  k->kind = CONTACT_FORCE;
  k->count = n;
  k->force = v3(0, 0, 0);
  k->total = v3(0, 0, 0);
  memset(k->feedback, 0, sizeof *k->feedback * (size_t)n);
  return c;
}

static contact *get_contact(palp_world *w, int c, int kind) {
  if (!w || c < 0 || c >= w->def.max_contacts) return NULL;
  contact *k = &w->contacts[c];
  return (kind == CONTACT_NONE ? k->kind != CONTACT_NONE : k->kind == kind) ? k : NULL;
}

int palp_world_set_contact_force(palp_world *w, int c, palp_vec3 f) {
  contact *k = get_contact(w, c, CONTACT_FORCE);
  if (!k) return PALP_ERANGE;
  if (!v3_isfinite(f)) return PALP_EINVAL;
  if (f.x != k->force.x || f.y != k->force.y || f.z != k->force.z) palp_world_wake(w);
  k->force = f;
  return PALP_OK;
}

palp_finger_def palp_finger_default_def(void) {
  return (palp_finger_def){.radius = 0.008, .coupling_stiffness = 2000.0, .pad_stiffness = 5000.0};
}

/* The finger scratch, made whole or not at all: w->fs is set only once every array is
 * there, since every later call (and every step) takes a set w->fs as complete. Until
 * 2026-12-06 it was set first, so after one failed allocation the next add_finger
 * returned a finger and the step dereferenced the missing arrays (a server adds the
 * finger again at the next touch: one failed allocation crashed every session). */
static int finger_scratch_fill(palp_world *w, finger_scratch *fs);
static int finger_scratch_create(palp_world *w) {
  if (w->fs) return PALP_OK;
  finger_scratch *fs = calloc(1, sizeof *fs);
  if (!fs) return PALP_ENOMEM;
  const int e = finger_scratch_fill(w, fs);
  if (e) {
    finger_scratch_free(fs);
    return e;
  }
  w->fs = fs;
  return PALP_OK;
}

static int finger_scratch_fill(palp_world *w, finger_scratch *fs) {
  const int nv = w->mesh.vertex_count, M = PALP_FINGER_MAX_CON;
  fs->n3 = 3 * w->nfree;
  fs->slots = w->nfree < 32 ? w->nfree : 32;
  int fail = 0;
  fs->pool = xcalloc((size_t)fs->slots * 3 * (size_t)fs->n3, sizeof(float), &fail);
  fs->slot_row = xcalloc((size_t)fs->slots, sizeof(int), &fail);
  fs->slot_used = xcalloc((size_t)fs->slots, sizeof(int64_t), &fail);
  fs->row_slot = xcalloc((size_t)w->nfree, sizeof(int), &fail);
  fs->prev_row_slot = xcalloc((size_t)w->nfree, sizeof(int), &fail);
  fs->solve = xcalloc(3 * (size_t)fs->n3, sizeof(double), &fail);
  fs->work = xcalloc(palp_ldl_work_size(fs->n3, 3), sizeof(double), &fail);
  fs->vloc = xcalloc((size_t)nv, sizeof(int), &fail);
  fs->lvert = xcalloc(3 * (size_t)M, sizeof(int), &fail);
  fs->G_lvert = xcalloc(3 * (size_t)M, sizeof(int), &fail);
  fs->G_owner = -1;
  fs->lf = xcalloc(9 * (size_t)M, sizeof(double), &fail);
  fs->y = xcalloc((size_t)M * 9 * (size_t)M, sizeof(double), &fail);
  fs->W = xcalloc((size_t)M * (size_t)M, sizeof(double), &fail);
  fs->b = xcalloc((size_t)M, sizeof(double), &fail);
  fs->lwork = xcalloc((size_t)M * (size_t)M + 3 * (size_t)M, sizeof(double), &fail);
  fs->cand = xcalloc((size_t)nv, 1, &fail);
  fs->fpos = xcalloc((size_t)nv, sizeof(palp_vec3), &fail);
  if (fail) return PALP_ENOMEM; /* freed by the caller */
  for (int q = 0; q < fs->slots; ++q) fs->slot_row[q] = -1;
  for (int r = 0; r < w->nfree; ++r) fs->row_slot[r] = fs->prev_row_slot[r] = -1;
  for (int i = 0; i < nv; ++i) fs->vloc[i] = -1;
  for (int l = 0; l < w->mesh.link_count; ++l) {
    const palp_vec3 d = v3_sub(w->mesh.rest[w->mesh.link[l][1]], w->mesh.rest[w->mesh.link[l][0]]);
    fs->max_link = fmax(fs->max_link, v3_len(d));
  }
  {
    const int nt = w->mesh.dome_triangle_count;
    fs->vtri_start = xcalloc((size_t)nv + 1, sizeof(int), &fail);
    fs->vtri = xcalloc(3 * (size_t)nt + 1, sizeof(int), &fail);
    fs->clist = xcalloc((size_t)nv, sizeof(int), &fail);
    fs->tbits = xcalloc((size_t)nt / 64 + 1, sizeof(uint64_t), &fail);
    fs->tlist = xcalloc((size_t)nt + 1, sizeof(int), &fail);
    int *fill = xcalloc((size_t)nv + 1, sizeof(int), &fail);
    if (fail) {
      free(fill);
      return PALP_ENOMEM;
    }
    for (int t = 0; t < nt; ++t)
      for (int e = 0; e < 3; ++e) fs->vtri_start[w->mesh.tri[t][e] + 1]++;
    for (int i = 0; i < nv; ++i) fs->vtri_start[i + 1] += fs->vtri_start[i];
    for (int t = 0; t < nt; ++t) /* each vertex's triangles in ascending order */
      for (int e = 0; e < 3; ++e) fs->vtri[fs->vtri_start[w->mesh.tri[t][e]] + fill[w->mesh.tri[t][e]]++] = t;
    free(fill);
  }
  if (w->def.finger_surface == PALP_FINGER_SURFACE_SMOOTH) {
    const int nt = w->mesh.dome_triangle_count;
    fs->patch = xcalloc((size_t)nt, sizeof *fs->patch, &fail);
    fs->patch_max = xcalloc((size_t)nt, sizeof(double), &fail);
    fs->nrest = xcalloc((size_t)nv, sizeof(palp_vec3), &fail);
    fs->mrest = xcalloc((size_t)nv, sizeof(palp_vec3), &fail);
    fs->ncur = xcalloc((size_t)nv, sizeof(palp_vec3), &fail);
    fs->nstamp = xcalloc((size_t)nv, sizeof(int64_t), &fail);
    fs->tcross = xcalloc((size_t)nt, sizeof(palp_vec3), &fail);
    fs->tstamp = xcalloc((size_t)nt, sizeof(int64_t), &fail);
    if (fail) return PALP_ENOMEM;
    for (int t = 0; t < nt; ++t) fs->tstamp[t] = -1;
    palp_rest_normals(&w->mesh, fs->nrest);
    for (int i = 0; i < nv; ++i) {
      fs->nstamp[i] = -1;
      fs->mrest[i] = ring_normal(w, fs, i, w->mesh.rest);
    }
    for (int t = 0; t < nt; ++t) {
      const int *T = w->mesh.tri[t];
      const palp_vec3 X[3] = {w->mesh.rest[T[0]], w->mesh.rest[T[1]], w->mesh.rest[T[2]]};
      const palp_vec3 Nt[3] = {fs->nrest[T[0]], fs->nrest[T[1]], fs->nrest[T[2]]};
      /* a degenerate triangle keeps a zero patch: its facet */
      palp_smooth_patch_init(&fs->patch[t], X, Nt);
      fs->patch_max[t] = palp_smooth_patch_max_offset(&fs->patch[t], X, Nt);
    }
  }
  return PALP_OK;
}

/* Solid angle of triangle (a, b, c) seen from p (Van Oosterom & Strackee 1983). */
static double solid_angle(palp_vec3 p, palp_vec3 a, palp_vec3 b, palp_vec3 c) {
  a = v3_sub(a, p), b = v3_sub(b, p), c = v3_sub(c, p);
  const double la = v3_len(a), lb = v3_len(b), lc = v3_len(c);
  const double num = v3_dot(a, v3_cross(b, c));
  const double den = la * lb * lc + v3_dot(a, b) * lc + v3_dot(a, c) * lb + v3_dot(b, c) * la;
  return 2.0 * atan2(num, den);
}

/* 1 when a sphere at p of radius R overlaps the closed surface or lies inside it. */
static int sphere_in_phantom(const palp_world *w, palp_vec3 p, double R) {
  double omega = 0.0;
  for (int t = 0; t < w->mesh.triangle_count; ++t) {
    const int *T = w->mesh.tri[t];
    double bary[3];
    const palp_vec3 q = palp_tri_closest(p, w->pos[T[0]], w->pos[T[1]], w->pos[T[2]], bary);
    if (v3_len(v3_sub(p, q)) < R) return 1;
    omega += solid_angle(p, w->pos[T[0]], w->pos[T[1]], w->pos[T[2]]);
  }
  return fabs(omega) > 2.0 * PALP_PI; /* winding number above 1/2 */
}

int palp_world_add_finger_def(palp_world *w, const palp_finger_def *def, palp_vec3 device) {
  if (!w || !def || !v3_isfinite(device) || !(def->radius > 0.0) || !isfinite(def->radius) ||
      !(def->coupling_stiffness > 0.0) || !isfinite(def->coupling_stiffness) || !(def->pad_stiffness >= 0.0) ||
      !isfinite(def->pad_stiffness))
    return PALP_EINVAL;
  const int c = free_slot(w);
  if (c < 0) return c;
  int e = finger_scratch_create(w);
  if (e) return e;
  contact *k = &w->contacts[c];
  e = ensure_cap(k, w->mesh.vertex_count);
  if (e) return e;
  if (!k->ctri) {
    const size_t M = PALP_FINGER_MAX_CON;
    k->ctri = calloc(M, sizeof *k->ctri);
    k->cbary = calloc(M, sizeof *k->cbary);
    k->cn = calloc(M, sizeof *k->cn);
    k->cq = calloc(M, sizeof *k->cq);
    k->clam = calloc(M, sizeof *k->clam);
    k->ckey = calloc(M, sizeof *k->ckey);
    /* all or none: a set ctri is taken as all six there (the next add_finger, the step) */
    if (!k->ctri || !k->cbary || !k->cn || !k->cq || !k->clam || !k->ckey) {
      finger_rows_free(k);
      return PALP_ENOMEM;
    }
  }
  k->kind = CONTACT_FINGER;
  k->fdef = *def;
  /* nfinger too: a slot a pressing finger left keeps its rows, and palp_world_finger_contacts
   * (and the state hash) read the old finger's until the first step (review, 2026-12-06) */
  k->count = k->ncon = k->nfinger = 0;
  k->device = k->proxy = device;
  /* The proxy must start outside the phantom: a device placed inside it starts its
   * proxy above the surface on the ray from the base's centre, and the first steps
   * bring it down onto the surface with the coupling. */
  if (sphere_in_phantom(w, device, def->radius)) {
    palp_vec3 dir = v3(device.x, device.y, fmax(device.z, 0.0));
    const double dl = v3_len(dir);
    dir = dl > 1e-9 ? v3_scale(dir, 1.0 / dl) : v3(0, 0, 1);
    double rmax = 0.0;
    for (int i = 0; i < w->mesh.vertex_count; ++i) rmax = fmax(rmax, v3_len(w->pos[i]));
    k->proxy = v3_scale(dir, rmax + def->radius + 1e-3);
  }
  k->total = v3(0, 0, 0);
  memset(&k->lm, 0, sizeof k->lm); /* no contact: the drift observer starts afresh (palp_drift_observe) */
  k->lm.device = device, k->lm.proxy = k->proxy, k->lm.normal = v3(0, 0, 1), k->lm.period = w->def.dt;
  palp_world_wake(w);
  return c;
}

int palp_world_set_finger_device(palp_world *w, int c, palp_vec3 device) {
  contact *k = get_contact(w, c, CONTACT_FINGER);
  if (!k) return PALP_ERANGE;
  if (!v3_isfinite(device)) return PALP_EINVAL;
  if (device.x != k->device.x || device.y != k->device.y || device.z != k->device.z) {
    k->device = device;
    if (has_load(w, !w->awake)) palp_world_wake(w);
  }
  return PALP_OK;
}

int palp_world_add_finger(palp_world *w, palp_vec3 center, double radius) {
  palp_finger_def d = palp_finger_default_def();
  d.radius = radius;
  return palp_world_add_finger_def(w, &d, center);
}

int palp_world_set_finger(palp_world *w, int c, palp_vec3 center, double radius) {
  contact *k = get_contact(w, c, CONTACT_FINGER);
  if (!k) return PALP_ERANGE;
  if (!v3_isfinite(center) || !(radius > 0.0) || !isfinite(radius)) return PALP_EINVAL;
  k->fdef.radius = radius;
  return palp_world_set_finger_device(w, c, center);
}

int palp_world_finger_local_model(const palp_world *w, int c, palp_local_model *out) {
  const contact *k = get_contact((palp_world *)w, c, CONTACT_FINGER);
  if (!k || !out) return PALP_ERANGE;
  *out = k->lm;
  out->time = w->t;
  return PALP_OK;
}

double palp_world_support_scale(const palp_world *w, int i) {
  if (!w || i < 0 || i >= w->mesh.vertex_count || !(w->mesh.vertex_area[i] > 0.0)) return 1.0;
  return w->sarea[i] / w->mesh.vertex_area[i];
}

int palp_world_finger_contacts(const palp_world *w, int c, int *triangles, double *force, int cap) {
  const contact *k = get_contact((palp_world *)w, c, CONTACT_FINGER);
  if (!k) return PALP_ERANGE;
  int n = 0;
  for (int q = 0; q < k->nfinger; ++q) {
    if (!(k->clam[q] > 0.0) || k->ctri[q] < 0) continue;
    if (n < cap) {
      if (triangles) triangles[n] = k->ctri[q];
      if (force) force[n] = k->clam[q];
    }
    n++;
  }
  return n;
}

int palp_world_remove_contact(palp_world *w, int c) {
  contact *k = get_contact(w, c, CONTACT_NONE);
  if (!k) return PALP_ERANGE;
  k->kind = CONTACT_NONE;
  k->count = 0;
  palp_world_wake(w);
  return PALP_OK;
}

int palp_world_contact_feedback(const palp_world *w, int c, palp_vec3 *total) {
  const contact *k = get_contact((palp_world *)w, c, CONTACT_NONE);
  if (!k) return PALP_ERANGE;
  if (!(w->def.effects & PALP_EFFECT_FORCE_FEEDBACK)) return PALP_EINVAL;
  if (total) *total = k->total;
  return PALP_OK;
}

int palp_world_contact_vertices(const palp_world *w, int c, int *vertices, palp_vec3 *feedback, int cap) {
  const contact *k = get_contact((palp_world *)w, c, CONTACT_NONE);
  if (!k) return PALP_ERANGE;
  const int n = k->count < cap ? k->count : cap;
  const int fb = (w->def.effects & PALP_EFFECT_FORCE_FEEDBACK) != 0;
  for (int q = 0; q < n; ++q) {
    if (vertices) vertices[q] = k->vertex[q];
    if (feedback) feedback[q] = fb ? k->feedback[q] : v3(0, 0, 0);
  }
  return k->count;
}

/* ---- queries ------------------------------------------------------------ */

const palp_mesh *palp_world_mesh(const palp_world *w) { return &w->mesh; }
const palp_vec3 *palp_world_positions(const palp_world *w) { return w->pos; }
const palp_vec3 *palp_world_velocities(const palp_world *w) { return w->vel; }
double palp_world_time(const palp_world *w) { return w->t; }
int64_t palp_world_frame(const palp_world *w) { return w->frame; }
double palp_world_volume(const palp_world *w) {
  return (w->def.effects & PALP_EFFECT_GEL_PRESSURE) ? w->V : palp_mesh_volume(&w->mesh, w->pos);
}
double palp_world_rest_volume(const palp_world *w) { return w->V0; }
double palp_world_pressure(const palp_world *w) { return w->p_gauge; }
int palp_world_is_awake(const palp_world *w) { return w->awake; }
void palp_world_wake(palp_world *w) {
  w->awake = 1;
  w->quiet = 0.0;
}
const palp_world_def *palp_world_get_def(const palp_world *w) { return &w->def; }

/* FNV-1a over 64-bit words (the state is arrays of doubles): one multiply per 8
 * bytes instead of per byte, so hashing every frame at 1 kHz stays cheap. */
static uint64_t fnv1a64(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = data;
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    memcpy(&w, p + i, 8);
    h ^= w;
    h *= 1099511628211ull;
  }
  for (; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

/* palp_world_state_hash's fold: FNV-1a's (h ^ w) P with each word mixed first. In fnv1a64 a bit k
 * of a word reaches only bits k and above of h (P is odd), so the top bit, a double's sign, only
 * flips h's top bit, and two such flips cancel: two worlds whose pole velocity differed in the
 * signs of vx and vy hashed equal (session 83 review). Mixed, a changed word changes about half
 * the bits of what is folded in. A tail shorter than a word is folded zero-padded. */
static uint64_t mixfold(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = data;
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    memcpy(&w, p + i, 8);
    h = (h ^ palp_rng_mix(w)) * 1099511628211ull;
  }
  if (i < n) {
    uint64_t w = 0;
    memcpy(&w, p + i, n - i);
    h = (h ^ palp_rng_mix(w)) * 1099511628211ull;
  }
  return h;
}

/* What the logged hash covers, folded by fold (fnv1a64 for palp_world_hash, mixfold for the state
 * hash): one list, so the two cannot drift apart. Word by word, V, p_abs and t folded one after the
 * other are the words of an array of the three. */
static uint64_t fold_logged(const palp_world *w, uint64_t h, uint64_t (*fold)(uint64_t, const void *, size_t)) {
  const size_t nv = (size_t)w->mesh.vertex_count;
  h = fold(h, w->pos, sizeof *w->pos * nv);
  h = fold(h, w->vel, sizeof *w->vel * nv);
  if (w->nlink) h = fold(h, w->eps, sizeof(double) * (size_t)w->nlink);
  if (w->xs) h = fold(h, w->xs, sizeof *w->xs * (size_t)w->nlink);
  if (w->sq) h = fold(h, w->sq, sizeof *w->sq * nv);
  h = fold(h, &w->V, sizeof w->V);
  h = fold(h, &w->p_abs, sizeof w->p_abs);
  h = fold(h, &w->t, sizeof w->t);
  return fold(h, &w->frame, sizeof w->frame);
}

uint64_t palp_world_hash(const palp_world *w) { return fold_logged(w, 14695981039346656037ull, fnv1a64); }

/* A factor's numbers: its 3x3 blocks and diagonal (the block form the solves use), or its
 * scalar L and 1/D. The ordering is the analysis's, the same for every factor of a world. */
static uint64_t ldl_hash(uint64_t h, const palp_ldl *f) {
  if (f->nb > 0) {
    h = mixfold(h, f->blk, sizeof(float) * 9 * (size_t)f->bcolp[f->nb]);
    h = mixfold(h, f->bdiag, sizeof(double) * 3 * (size_t)f->nb);
  } else if (f->n > 0) {
    h = mixfold(h, f->val, sizeof(double) * (size_t)f->colp[f->n]);
  }
  if (f->n > 0) h = mixfold(h, f->dinv, sizeof(double) * (size_t)f->n);
  return h;
}

static uint64_t vec3_hash(uint64_t h, palp_vec3 v) {
  const double d[3] = {v.x, v.y, v.z};
  return mixfold(h, d, sizeof d);
}

/* A contact: its load or finger, what it touched and fed back, and the finger's local
 * model and drift observer. Field by field: the structs' padding is not state. */
static uint64_t contact_hash(uint64_t h, const contact *k) {
  const int head[3] = {k->kind, k->count, k->kind == CONTACT_FINGER ? k->ncon : 0};
  h = mixfold(h, head, sizeof head);
  if (k->kind == CONTACT_NONE) return h;
  h = mixfold(h, k->vertex, sizeof(int) * (size_t)k->count);
  h = mixfold(h, k->feedback, sizeof(palp_vec3) * (size_t)k->count);
  h = vec3_hash(h, k->total);
  if (k->kind == CONTACT_FORCE) {
    h = mixfold(h, k->weight, sizeof(double) * (size_t)k->count);
    return vec3_hash(h, k->force);
  }
  const double fd[3] = {k->fdef.radius, k->fdef.coupling_stiffness, k->fdef.pad_stiffness};
  h = mixfold(h, fd, sizeof fd);
  h = vec3_hash(vec3_hash(h, k->device), k->proxy);
  const size_t n = (size_t)k->ncon;
  h = mixfold(h, &k->nfinger, sizeof k->nfinger);
  h = mixfold(h, k->ctri, sizeof(int) * n);
  h = mixfold(h, k->cbary, sizeof(double[3]) * n);
  h = mixfold(h, k->cn, sizeof(palp_vec3) * n);
  h = mixfold(h, k->cq, sizeof(palp_vec3) * n);
  h = mixfold(h, k->clam, sizeof(double) * n); /* the next step's warm start (with ckey) */
  h = mixfold(h, k->ckey, sizeof(int64_t) * n);
  const palp_local_model *m = &k->lm; /* the next step's drift observer reads it */
  const int mi[2] = {m->contact, m->triangles};
  h = mixfold(h, mi, sizeof mi);
  const double md[3] = {m->period, m->area, m->depth}; /* its time is the world's (set when queried) */
  h = mixfold(h, md, sizeof md);
  h = mixfold(h, m->stiffness, sizeof m->stiffness);
  const palp_vec3 mv[6] = {m->device, m->proxy, m->normal, m->force, m->drift, m->point};
  for (int q = 0; q < 6; ++q) h = vec3_hash(h, mv[q]);
  return vec3_hash(h, k->drift_corr);
}

uint64_t palp_world_state_hash(const palp_world *w) {
  const size_t nv = (size_t)w->mesh.vertex_count, nl = (size_t)w->nlink;
  uint64_t h = fold_logged(w, 14695981039346656037ull, mixfold); /* what palp_world_hash covers, here mixed */
  /* the links' state beyond their strains: directions and stresses (the feedback's) */
  if (nl) {
    h = mixfold(h, w->dir, sizeof(palp_vec3) * nl);
    h = mixfold(h, w->sigma, sizeof(double) * nl);
  }
  /* the gel: the literal law's previous pressure and step, the reported pressure and rate,
   * and the solve's kept A^{-1} g (reused while the gradient turns little) */
  const double gel[4] = {w->p_abs_prev, w->h_gel_prev, w->p_gauge, w->Vdot};
  h = mixfold(h, gel, sizeof gel);
  if (w->u) {
    h = mixfold(h, &w->u_valid, sizeof w->u_valid);
    if (w->u_valid) {
      h = mixfold(h, w->u, sizeof(double) * 3 * (size_t)w->nfree);
      h = mixfold(h, w->g_u, sizeof(double) * 3 * (size_t)w->nfree);
    }
  }
  /* the installed tangent: its factor, what the steps check it against, whether it must
   * be rebuilt; a blend's replaced factor; a deferred rebuild's matrix */
  h = mixfold(h, &w->h_factored, sizeof w->h_factored);
  h = ldl_hash(h, &w->ldl);
  if (nl) {
    h = mixfold(h, w->fdir, sizeof(palp_vec3) * nl);
    h = mixfold(h, w->fbeta, sizeof(double) * nl);
    h = mixfold(h, w->fslack, sizeof(double) * nl);
  }
  if (w->fsu) h = mixfold(h, w->fsu, sizeof(palp_vec3) * nv);
  if (w->fsoft) h = mixfold(h, w->fsoft, sizeof(double) * ((size_t)w->nfree + 1));
  const int flags[5] = {w->stale, w->unsafe, w->blend_k, w->job_state != JOB_NONE, w->job_obsolete};
  h = mixfold(h, flags, sizeof flags);
  if (w->blend_k > 0) h = ldl_hash(h, &w->ldl_prev);
  if (w->job_state != JOB_NONE) {
    /* who computes it (the state a host moves it through) does not change its bits */
    const palp_factor_job *j = w->job;
    h = mixfold(h, &w->job_due, sizeof w->job_due);
    h = mixfold(h, &j->h, sizeof j->h);
    h = mixfold(h, &j->nnz, sizeof j->nnz);
    h = mixfold(h, j->ti, sizeof(int) * (size_t)j->nnz);
    h = mixfold(h, j->tj, sizeof(int) * (size_t)j->nnz);
    h = mixfold(h, j->tx, sizeof(double) * (size_t)j->nnz);
    if (nl) {
      h = mixfold(h, j->fdir, sizeof(palp_vec3) * nl);
      h = mixfold(h, j->fbeta, sizeof(double) * nl);
      h = mixfold(h, j->fslack, sizeof(double) * nl);
    }
    if (j->fsu) h = mixfold(h, j->fsu, sizeof(palp_vec3) * nv);
  }
  /* sleep */
  const int wake[2] = {w->awake, w->broken};
  h = mixfold(h, wake, sizeof wake);
  h = mixfold(h, &w->quiet, sizeof w->quiet);
  /* contacts */
  for (int c = 0; c < w->def.max_contacts; ++c) h = contact_hash(h, &w->contacts[c]);
  return h;
}

void palp_world_get_health(const palp_world *w, palp_world_health *out) {
  out->substeps = w->substeps;
  out->refactors = w->refactors;
  out->large_strain_steps = w->large_strain_steps;
  out->max_strain = w->max_strain;
  out->clamped_steps = w->clamped_steps;
  out->margin_rebuilds = w->margin_rebuilds;
  out->factor_analyses = w->factor_analyses;
  out->finger_paths = w->finger_paths;
  out->base_contacts = w->base_contacts;
  out->finger_unsolved = w->finger_unsolved;
  out->large_bend_steps = w->large_bend_steps;
  out->max_bend = w->max_bend;
  out->max_bend_error = w->max_bend_err;
  out->beyond_validated_steps = w->beyond_validated_steps;
  out->max_beyond_validated = w->max_beyond_validated;
  out->gel_momentum_dropped = w->gel_momentum_dropped;
}

double palp_world_hinge_range(const palp_world_def *def) {
  return fmax(PALP_HINGE_LINEAR_ERR_MAX, def->validated_hinge_error);
}

double palp_world_validated_depth(const palp_world_def *def, double polar) {
  const int n = def->validated_count;
  if (n <= 0) return INFINITY;
  const double *a = def->validated_polar, *d = def->validated_depth;
  if (!(polar > a[0])) return d[0];
  for (int k = 1; k < n; ++k)
    if (polar <= a[k]) return d[k - 1] + (d[k] - d[k - 1]) * (polar - a[k - 1]) / (a[k] - a[k - 1]);
  return d[n - 1];
}

void palp_world_timings(const palp_world *w, palp_stage_timings *out) {
  *out = w->timings;
  out->refactors = w->refactors;
  out->factor_nnz = w->ldl.n ? w->ldl.colp[w->ldl.n] : 0;
  out->unknowns = w->ldl.n;
}
