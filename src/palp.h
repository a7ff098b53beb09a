/*
 * palp.h - the real-time viscoelastic breast-phantom model (Widmer & Hu 2011).
 *
 * A world is created from a def struct, stepped at a fixed time step through a
 * pipeline of named stages, and queried for its state. Units are SI throughout
 * (m, kg, s, N, Pa); convert at the edges. Functions return 0 or a negative
 * PALP_E* code. The library holds no globals: every piece of state hangs off a
 * palp_world, which its creator owns and destroys.
 *
 * This header never pulls in DDS, SQLite or any I/O library.
 */
#ifndef PALP_H
#define PALP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- errors ------------------------------------------------------------ */
enum {
  PALP_OK = 0,
  PALP_EINVAL = -1,    /* an argument or parameter is out of its domain */
  PALP_ENOMEM = -2,    /* allocation failed */
  PALP_ERANGE = -3,    /* an index (vertex, contact) is out of range */
  PALP_EPARSE = -4,    /* a scene or parameter file is malformed */
  PALP_EIO = -5,       /* a file could not be read or written */
  PALP_EUNSTABLE = -6, /* the state became non-finite; the world refuses to step */
  PALP_EFULL = -7,     /* no free contact slot */
  PALP_ESOLVER = -8,   /* the sparse factorisation failed */
  PALP_EBUSY = -9      /* a deferred refactorisation a host claimed is due but not handed back */
};
const char *palp_strerror(int err);

typedef struct palp_vec3 {
  double x, y, z;
} palp_vec3;

/* ---- mesh --------------------------------------------------------------- */
/* A hemisphere of radius `radius` [m] on the plane z = 0, pole at +z. The dome
 * holds `vertex_count` vertices on latitude rings; the rim ring lies on z = 0 and
 * is fixed. The flat base is closed with triangles between rim vertices only, so
 * the surface is a closed, consistently outward-oriented triangle mesh. */
/* The largest mesh palp_mesh_create makes and a scene may ask for (mesh.vertex_count), and so
 * the largest a palp-server publishes in its catalogue: the catalogue's readers take no larger
 * (palp_dds_phantom_check, idl/, for the stations and palp-recorder; palp-web's bound). One
 * constant, so that no reader refuses a mesh a server can publish (2026-12-06). A closed mesh
 * of V vertices has 2V - 4 triangles. */
#define PALP_MESH_MAX_VERTICES 200000

typedef struct palp_mesh_def {
  double radius;    /* [m], default 0.04 (8.0 cm diameter) */
  int vertex_count; /* default 338; any value from 19 to PALP_MESH_MAX_VERTICES */
} palp_mesh_def;

typedef struct palp_mesh {
  int vertex_count;
  int triangle_count; /* dome triangles first, then base triangles */
  int dome_triangle_count;
  int link_count; /* unique edges with at least one free end */
  int ring_count; /* latitude rings below the pole; ring_count is the rim */
  palp_vec3 *rest;  /* [vertex_count] rest positions [m] */
  int (*tri)[3];    /* [triangle_count] counter-clockwise seen from outside */
  int (*link)[2];   /* [link_count] vertex pairs, first < second */
  uint8_t *fixed;   /* [vertex_count] 1 for rim (base) vertices */
  int *ring_start;  /* [ring_count + 2] first vertex of each ring; pole is ring 0 */
  double *vertex_area; /* [vertex_count] lumped (one-third) dome area [m^2] */
  int top_vertex;   /* the pole */
} palp_mesh;

palp_mesh_def palp_mesh_default_def(void);
int palp_mesh_create(const palp_mesh_def *def, palp_mesh *out);
void palp_mesh_destroy(palp_mesh *mesh);
/* Enclosed volume by the divergence theorem, V = sum_t x_a . (x_b x x_c) / 6 [m^3]. */
double palp_mesh_volume(const palp_mesh *mesh, const palp_vec3 *pos);
/* Index of the dome vertex nearest to a point [m]. */
int palp_mesh_nearest_vertex(const palp_mesh *mesh, const palp_vec3 *pos, palp_vec3 p);

/* ---- contact loads ------------------------------------------------------- */
/* The paper's four force distributions. */
typedef enum palp_distribution {
  PALP_DIST_SINGLE = 1,          /* I: all force on one vertex */
  PALP_DIST_UNIFORM = 2,         /* II: uniform pressure over a patch */
  PALP_DIST_GAUSSIAN = 3,        /* III: 2D Gaussian peaked at the patch centre */
  PALP_DIST_GAUSSIAN_OFFSET = 4  /* IV: 2D Gaussian peaked off-centre (distal finger) */
} palp_distribution;

typedef struct palp_contact_def {
  palp_distribution distribution;
  palp_vec3 center;       /* a point on or near the surface [m]; snapped to the nearest vertex */
  double patch_area;      /* [m^2], default 5.2e-4 (5.2 cm^2) */
  double sigma_fraction;  /* Gaussian sigma as a fraction of the patch radius, default 0.5 */
  double offset_fraction; /* IV: peak offset as a fraction of the patch radius, default 0.5 */
  palp_vec3 offset_dir;   /* IV: direction of the offset (projected on the tangent plane) */
} palp_contact_def;

palp_contact_def palp_contact_default_def(palp_distribution d, palp_vec3 center);

/* Per-vertex weights of a distribution on a mesh: fills vertices[] and weights[]
 * (sum of weights = 1) and returns how many (<= cap), or a negative error.
 * Shared by the real-time model and the FEM reference so both load the same points. */
int palp_contact_weights(const palp_mesh *mesh, const palp_vec3 *pos, const palp_contact_def *def,
                         int *vertices, double *weights, int cap);

/* ---- force profiles ------------------------------------------------------ */
typedef enum palp_profile_kind {
  PALP_PROFILE_STEP = 1,     /* magnitude during [t_on, t_off), else 0; no ramp */
  PALP_PROFILE_RAMP = 2,     /* 0 -> magnitude over [t_on, t_off], then held */
  PALP_PROFILE_SINE = 3,     /* offset + magnitude sin(2 pi f (t - t_on)) during [t_on, t_off) */
  PALP_PROFILE_KEYFRAMES = 4 /* piecewise linear through (t_i, f_i); held after the last */
} palp_profile_kind;

#define PALP_PROFILE_MAX_KEYS 64
typedef struct palp_profile {
  palp_profile_kind kind;
  double magnitude; /* [N] */
  double t_on, t_off; /* [s] */
  double frequency; /* [Hz], sine only */
  double offset;    /* [N], sine only */
  int key_count;
  double key_t[PALP_PROFILE_MAX_KEYS]; /* [s] */
  double key_f[PALP_PROFILE_MAX_KEYS]; /* [N] */
} palp_profile;

/* The paper's 3 N step held for 2 s, then released. */
palp_profile palp_profile_paper_step(void);
double palp_profile_eval(const palp_profile *p, double t);

/* ---- material and world -------------------------------------------------- */
/* Burgers element (Maxwell spring E1 + dashpot eta1, in series with a Kelvin
 * spring E2 || dashpot eta2), Eq. 1 of the paper, in stress-strain form. Each link
 * carries it over an effective cross-section thickness * (adjacent area) / rest length. */
typedef struct palp_membrane_params {
  double thickness; /* [m], 2 mm (Table I) */
  double density;   /* [kg/m^3], 950 (Table I) */
  double E1;        /* Maxwell spring [Pa] */
  double eta1;      /* Maxwell dashpot [Pa s] */
  double E2;        /* Kelvin spring [Pa] */
  double eta2;      /* Kelvin dashpot [Pa s] */
  /* The skin's bending stiffness D = E t^3 / (12 (1 - nu^2)) [N m], as linearised
   * hinges on the triangles' edges (docs/model.md); 0, the default, is the paper's
   * membrane, which carries a load only by stretching. */
  double bending_stiffness;
  /* How far the rim lets the skin rotate: the hinges on the rim's edges (a dome
   * triangle against the clamped base) keep (1 - rim_hinge_release) of their
   * stiffness. 0, the default, clamps the skin's slope at the base; 1 pins it. The
   * hinges carry an effective D several times the skin's own (they stand in for the
   * gel's shear coupling too), and clamping that D at the rim stiffens the dome near
   * it beyond the FE's (docs/materials.md, "The rim"). */
  double rim_hinge_release;
  /* The skin's own share of bending_stiffness [N m], 0 <= D_skin <= D; 0, the
   * default, leaves every hinge at D. The fitted D is several times the skin's plate
   * stiffness E t^3 / (12 (1 - nu^2)): the rest stands in for the gel under the
   * coarse net, so that part sees a lesion as the support does. With D_skin > 0 a
   * hinge over a lesion carries D_skin + (D - D_skin) s, s the mean of its edge's
   * two vertices' lesion support scales (palp_lesion_support_scale; below 1 over a soft
   * cyst); without lesions s = 1 and the hinge is exactly D (docs/haptics.md,
   * "The hinges see the lesion"). */
  double skin_bending_stiffness;
} palp_membrane_params;

typedef enum palp_gel_law {
  /* p = P [(V0/V)^a1 - 1] - a2 dV/dt: Eq. 3's a1 term integrated exactly, a2 as
   * damping of the volume rate; a3 unused. See docs/model.md. */
  PALP_GEL_POLYTROPIC = 0,
  /* Eq. 3 as printed, read incrementally frame to frame (see docs/model.md). */
  PALP_GEL_PAPER_LITERAL = 1
} palp_gel_law;

typedef struct palp_gel_params {
  palp_gel_law law;
  double pressure; /* P: reference internal pressure [Pa], balanced by the outside at rest */
  double a1;       /* polytropic exponent [-]; bulk modulus = a1 P */
  double a2;       /* volume-rate damping [Pa s / m^3] */
  double a3;       /* literal law only: pressure momentum [s^2] */
  /* Gel support (an elastic foundation under the membrane, docs/model.md): the
   * gel's shear stiffness, which a uniform pressure cannot represent, resists each
   * vertex's displacement u with a traction k u + c du/dt over its lumped area. */
  double support_modulus;   /* k [Pa/m] */
  double support_viscosity; /* c [Pa s/m], applied with gel damping */
  /* phi in [0, 1]: the support resists each vertex's displacement relative to phi
   * times the free surface's area-weighted mean displacement (the gel body's bulk
   * shift), -k A_i (u_i - phi u_mean) - c A_i (v_i - phi v_mean); 0 anchors every
   * vertex to its rest position (docs/model.md, "The gel body may shift"). */
  double support_bulk_fraction; /* [-] */
  /* The support's relaxing share (a Maxwell branch beside the spring; 0: none): a
   * displacement held still is resisted by k + k_r at first and by k after a few
   * relax times, as a gel with a Prony term relaxes (the breast-tissue profile's
   * FEM creeps over its tau = 0.5 s term under a held load). Each free vertex
   * carries the branch's dashpot position q: force -k_r A (u - q), dq/dt = (u - q) /
   * tau_r, implicit (docs/model.md, "The support relaxes"). */
  double support_relax_modulus; /* k_r [Pa/m] */
  double support_relax_time;    /* tau_r [s], > 0 when k_r > 0 */
  /* The support stiffens as the gel column under a vertex is strained (0: linear, bit
   * for bit as before). A free vertex displaced by u, over the gel's height H above the
   * base at its rest position, meets -k A (1 + beta (|u| / H)^p) u: the bonded,
   * incompressible gel's confinement near the base, which a linear foundation cannot
   * see (docs/model.md, "The support stiffens near the base"). p >= 1 keeps the
   * tangent continuous at u = 0. */
  double support_stiffening;       /* beta [-], in [0, 1000] */
  double support_stiffening_power; /* p [-], in [1, 8] when beta > 0 (scene files: 2 by default) */
  /* How far the bonded base cuts the support's column, f in [0, 1] (0: not at all, bit for
   * bit as before). The support under a vertex is a column along its inward normal whose
   * compliance is weighted by a fingertip's Boussinesq stress (palp_support_column_scale);
   * the column runs to the dome's centre, length R, but the gel is bonded to the base
   * z = 0, which lies z_i under vertex i: near the rim the base is inside the stress bulb
   * and stiffens the gel (the FE fingertip at 70 deg). The column's length is
   * R - f (R - z_i) (floored at 1 mm) and its compliance is set against the pole's:
   * k_i / k = S(R) / S(length) (docs/model.md, "The base cuts the support's column"). */
  double support_base_reach; /* f [-] */
  /* The gel moves with the membrane, so its inertia belongs to the surface
   * vertices: each free vertex carries added_mass_fraction of the gel's mass
   * density V0, shared by lumped area (docs/model.md, "Vertex weights"). */
  double density;             /* [kg/m^3], Table II: 950 */
  double added_mass_fraction; /* [-] in [0, 1]: 0 = membrane mass only, 1 = the whole gel */
} palp_gel_params;

/* Upper bounds of the membrane's and the gel's values, refused beyond by palp_world_create
 * (in the effects that use them) and by the scene parser: generous (each far above any
 * tissue, gel or silicone value and the shipped sets, config/params/), but finite, and
 * where measured stable: beyond them a scene read from a handed-over session log made a
 * dome that never moved, or one that stepped "ok" to V/V0 = -1.8 (pressure 1e30 Pa). */
#define PALP_THICKNESS_MAX_M 0.1   /* skin ~2 mm (shipped 2 mm); 10 cm is a wall, not a skin */
#define PALP_DENSITY_MAX_KG_M3 2.5e4 /* membrane and gel: above osmium's 22.6e3 (shipped 950) */
#define PALP_GEL_PRESSURE_MAX_PA 1e7 /* 100 atmospheres: a pressure vessel (shipped 101,325) */
/* 30x the shipped 10 and ~40x the Tait exponent of water (~7): (V0/V)^a1 stays finite for
 * V > V0/10. 1e3 made the default dome non-finite in 4 frames under 30 N at the pole,
 * where 300 stepped it (session 81). */
#define PALP_GEL_A1_MAX 300.0
/* [Pa s/m^3]: the volume mode's damping time a2 V0 / (a1 P) is ~1.3 s at the shipped dome
 * (V0 1.34e-4 m^3, a1 P 1.0e6 Pa): a gel whose volume no longer follows a press; 1,400x
 * the shipped 7.1e6 (100x is the calibrator's reach). */
#define PALP_GEL_A2_MAX 1e10
/* [Pa/m], support_modulus and support_relax_modulus: a GPa gel (the membrane's modulus
 * bound in scenes) over a 1 mm column (the smallest dome's radius); shipped <= 3.3e6. */
#define PALP_SUPPORT_MODULUS_MAX 1e12
/* [Pa s/m]: 1e14 Pa s (the membrane's viscosity bound in scenes) over 1 mm; shipped <= 6e5. */
#define PALP_SUPPORT_VISCOSITY_MAX 1e17
/* [s]: 11.6 days, far beyond any session: the branch no longer relaxes (shipped <= 0.54 s). */
#define PALP_SUPPORT_RELAX_TIME_MAX 1e6
/* [N m], membrane.bending_stiffness (and so skin_bending_stiffness, at most it): 250x the
 * largest shipped D (0.040 N m, params/paper_long_term_level2.json; the others <= 0.02), so
 * beyond the calibrator's reach from it (100x its start), and ~3e4x a skin's own plate
 * (~3e-4 N m). Unbounded until session 83: at 1e30 a 3 N press at the pole moved nothing and
 * every step said "ok" (no halving, no cap, no health counter); 1e3 still dented it 0.013 mm. */
#define PALP_BENDING_MAX_N_M 10.0

/* The literal law's momentum term a3 (p_{i-1} - p_{i-2}) / (h h_prev) [Pa], a3 [s^2], h
 * this frame's step and h_prev the last one's [s], is stable only for
 *   -1/2 < a3 / (h h_prev) < 1
 * (docs/model.md, "Inside gel"): 1 when (a3, h, h_prev) lies inside. A world refuses a
 * def.dt outside it; steps it meets outside (a rejected step's halves, palp_world_step_dt)
 * leave the term out and count (palp_world_health.gel_momentum_dropped). */
int palp_gel_literal_valid(double a3, double h, double h_prev);
/* The step [s] at and below which a3 leaves that range at a fixed step: sqrt(a3) for
 * a3 > 0, sqrt(-2 a3) for a3 < 0, 0 for a3 = 0 (any step). */
double palp_gel_literal_min_step(double a3);

typedef enum palp_effect {
  PALP_EFFECT_MEMBRANE_ELASTICITY = 1u << 0,
  PALP_EFFECT_MEMBRANE_VISCOSITY = 1u << 1, /* needs elasticity */
  PALP_EFFECT_GEL_PRESSURE = 1u << 2,
  PALP_EFFECT_GEL_DAMPING = 1u << 3, /* needs gel pressure or gel support */
  PALP_EFFECT_GRAVITY = 1u << 4,
  PALP_EFFECT_FORCE_FEEDBACK = 1u << 5,
  PALP_EFFECT_GEL_SUPPORT = 1u << 6,
  PALP_EFFECT_ALL = (1u << 7) - 1u
} palp_effect;

/* Names as used in scene files: "membrane_elasticity", ... ; NULL if unknown. */
const char *palp_effect_name(palp_effect e);
int palp_effect_from_name(const char *name, palp_effect *out);

/* A lesion: a sphere of different stiffness inside the gel (docs/haptics.md,
 * "Lesions"). The gel support under each vertex is a column from the surface to the
 * dome's centre whose compliance is weighted by the stress a fingertip-sized load
 * puts at each depth (Boussinesq, a uniformly loaded circle of radius c: sigma_z(z) /
 * p = 1 - z^3 / (c^2 + z^2)^{3/2}); a lesion cut by the column replaces the gel's
 * compliance over its chord by q of it, so the vertex's support stiffens by
 *   k_i / k = C0 / (C0 - (1 - q) C_chord),  C = integral of sigma_z / p dz.
 * A stiff lesion (ratio >= 1) is loaded in series by the column above it: q = 1/ratio.
 * Load goes round a soft one (ratio < 1), and q is the strain it takes in a matrix that
 * strains by 1 (Eshelby's sphere in an incompressible matrix): q = 1 / (1 + beta (ratio - 1)),
 * beta = 2 (4 - 5 nu) / (15 (1 - nu)) = 0.4 at nu = 0.5. */
#define PALP_MAX_LESIONS 8
#define PALP_MAX_VALIDATED 8 /* entries of palp_world_def.validated_* */
#define PALP_LESION_CONTACT_SCALE 0.008 /* c [m]: the fingertip the training is for */
#define PALP_LESION_SOFT_BETA 0.4       /* beta: Eshelby's shear factor at nu = 0.5 */
typedef struct palp_lesion {
  palp_vec3 center;       /* [m], inside the dome, clear of the base */
  double radius;          /* [m] */
  double stiffness_ratio; /* E_lesion / E_gel [-], > 0 (> 1: a hard lump; < 1: a soft cyst) */
} palp_lesion;

/* The longest fixed step a world is created with [s]: palp_world_create refuses more, as it
 * has since the first model (ten times the paper's 0.01 s). A server's physics rate must
 * therefore be >= 1 / this = 10 Hz; its config refuses less, naming the key. */
#define PALP_WORLD_MAX_DT 0.1

typedef struct palp_world_def {
  palp_mesh_def mesh;
  palp_membrane_params membrane;
  palp_gel_params gel;
  double dt;          /* fixed step [s]: 0.01 as in the paper, 0.001 for haptics */
  uint32_t effects;   /* PALP_EFFECT_* mask */
  palp_vec3 gravity;  /* [m/s^2], default (0, 0, -9.81) */
  int max_contacts;   /* force-driven contacts and fingers together, default 8 */
  double sleep_speed; /* below this vertex speed [m/s] with no load the world may sleep, default 1e-5 */
  double sleep_time;  /* [s] of quiet before sleeping, default 0.5 */
  double max_speed;   /* a solved vertex speed above this [m/s] (default 20) means the
                         step cannot be trusted: it is retried as two half steps. Tested
                         per component, |v_x|, |v_y| or |v_z| > max_speed / sqrt 3 (one
                         cheap pass; it catches every vertex above max_speed, and also
                         one moving along an axis at 0.58-1 max_speed); at the last
                         halving only vertices above max_speed itself are capped */
  int refactor_lag;   /* frames a lagged-tangent rebuild waits before it is installed (0,
                         the default: at once); see palp_world_factor_claim */
  int refactor_blend; /* frames over which a rebuilt tangent takes over from the one it
                         replaces (0, the default: at once); palp_world_refactor_blend_for */
  int lesion_count;   /* 0..PALP_MAX_LESIONS; lesions act through the gel support */
  palp_lesion lesion[PALP_MAX_LESIONS];
  /* The surface a finger meets (docs/haptics.md, "The smooth contact surface"): the
   * flat triangles, whose facets lie up to ~0.19 mm inside the tissue's sphere between
   * vertices (338 vertices), or a smooth (Phong) patch over each triangle from the rest
   * normals, exact at rest and carried with the deformation. Forces still act on the
   * triangles' vertices by barycentric weights. */
  int finger_surface; /* palp_finger_surface */
  /* Where a fingertip's contact is linearised each step (docs/haptics.md, "The held
   * force depends on the physics step"): at the step's free positions x + h v_free
   * (the default, and a scene's without the key: the long-term set was fitted and
   * validated with it; the held force then depends on the step: breast tissue, 3 mm,
   * 12% lower at 4 ms than the step-independent value), or at the current positions
   * with the free motion carried into the gap (the held force the same at every step;
   * the breast-tissue scenes and their set since 2026-11-29). */
  int finger_linearise; /* palp_finger_linearise */
  /* 1: a finger's compliance from full columns of A^{-1} even on a nested-dissection
   * factor, where by default (0) it is made from the vertices' etree paths and the
   * correction by one more solve (docs/haptics.md, "The compliance by etree paths"): the
   * same quantities to rounding; kept as the reference the paths are tested against. */
  int finger_columns;
  /* Where the parameters were validated against the FE reference with a fingertip
   * (docs/model.md, "Valid range"): up to which indentation [m] of the fingertip (its
   * centre's depth below the undeformed sphere, R + r - |c|) its force stayed within 15%
   * of the FE's, at the polar angle [rad] of the fingertip's centre; polar angles
   * ascending, linear in between, the end values beyond (palp_world_validated_depth). A
   * step whose fingertip presses deeper counts in health.beyond_validated_steps. 0
   * entries: the parameters make no such statement, and nothing is counted. */
  int validated_count; /* 0..PALP_MAX_VALIDATED */
  double validated_polar[PALP_MAX_VALIDATED]; /* [rad] */
  double validated_depth[PALP_MAX_VALIDATED]; /* [m] */
  /* The largest miss of a linearised hinge turn from its true turn [rad] that the
   * fingertip presses of that validation reached within their validated depths, their
   * force still within 15% of the FE's there (docs/model.md, "Valid range"). A hinge
   * counts as beyond its linear range (health.large_bend_steps) from
   * max(PALP_HINGE_LINEAR_ERR_MAX = 0.1 rad, this): a miss the validation covered is not
   * reported as leaving it. 0 (the default, and a set or logged scene without the key):
   * 0.1 rad. */
  double validated_hinge_error;
} palp_world_def;

/* The indentation [m] up to which def's parameters were validated at polar angle
 * polar [rad] (def.validated_*), or +inf when they state none. */
double palp_world_validated_depth(const palp_world_def *def, double polar);

/* The miss of a linearised hinge turn from its true turn [rad] beyond which a step counts
 * in health.large_bend_steps: max(0.1 rad, def.validated_hinge_error). */
double palp_world_hinge_range(const palp_world_def *def);

typedef enum palp_finger_surface {
  PALP_FINGER_SURFACE_FACETS = 0, /* the flat triangles (how every session before 2026-11-27 was stepped) */
  PALP_FINGER_SURFACE_SMOOTH = 1  /* Phong patches over the triangles */
} palp_finger_surface;
/* Names as used in scene files ("facets", "smooth"); NULL if unknown. */
const char *palp_finger_surface_name(int surface);
int palp_finger_surface_from_name(const char *name, int *out);
typedef enum palp_finger_linearise {
  PALP_FINGER_LINEARISE_FREE = 0,   /* the free positions (the default) */
  PALP_FINGER_LINEARISE_CURRENT = 1 /* the current positions, the free motion in the gap */
} palp_finger_linearise;
/* Names as used in scene files ("free", "current"); NULL if unknown. */
const char *palp_finger_linearise_name(int where);
int palp_finger_linearise_from_name(const char *name, int *out);

palp_world_def palp_world_default_def(void);

typedef struct palp_world palp_world;

/* Validates def and builds the world; on failure returns NULL and sets *err. */
palp_world *palp_world_create(const palp_world_def *def, int *err);
void palp_world_destroy(palp_world *w);

/* Advances one fixed step of def.dt. A sleeping world returns at once. */
int palp_world_step(palp_world *w);
/* Advances by an arbitrary dt [s] (jittery clocks); refactors the solver when dt changes. */
int palp_world_step_dt(palp_world *w, double dt);

/* Deferred refactorisation (docs/haptics.md). With def.refactor_lag = k > 0 a
 * lagged-tangent rebuild that the step at frame f asks for is built from that
 * frame's state and installed at the start of frame f + k, whoever computes it: the
 * results depend on the inputs only (replay needs the same k). Until then the old
 * factor serves. A host may compute it on another thread so that it costs the tick
 * nothing: after a step, claim the job; run it anywhere (it touches only its own
 * memory); hand it back on the stepping thread before stepping frame
 * palp_world_factor_due (a due job not handed back makes the step fail with
 * PALP_EBUSY and change nothing: hand it back and step again). Unclaimed jobs are computed by the step at their due frame. Only
 * rebuilds while a finger is down are deferred; force-driven loads rebuild at once. */
typedef struct palp_factor_job palp_factor_job;
palp_factor_job *palp_world_factor_claim(palp_world *w); /* the job just requested, or NULL */
int palp_factor_job_run(palp_factor_job *job);          /* any thread; 0 or a negative error */
int palp_world_factor_done(palp_world *w, palp_factor_job *job);
int64_t palp_world_factor_due(const palp_world *w); /* frame a claimed job is due at, -1 none */
/* The lag the server and replay use at a physics step dt [s]: about 16 ms of frames. */
int palp_world_refactor_lag_for(double dt);
/* The blend a server sets for steps of dt [s] (def.refactor_blend, docs/haptics.md,
 * "Rebuilds blended in"): ~8 ms of frames at physics rates of 500 Hz or more (8 at
 * 1 kHz, 4 at 500 Hz); 0 at slower rates, whose models the station blends over its
 * haptic ticks, and for a dt that is not positive. */
int palp_world_refactor_blend_for(double dt);

/* Force-driven contact: returns a contact id >= 0 or a negative error. The force
 * vector [N] is spread over the distribution's vertices by their weights. */
int palp_world_add_contact(palp_world *w, const palp_contact_def *def);
int palp_world_set_contact_force(palp_world *w, int contact, palp_vec3 force);
/* Position-driven finger (docs/haptics.md). The trainee's hand moves a device
 * point; the simulated fingertip, the proxy ("god object"), is a rigid sphere of
 * the finger's radius that collides with the surface's deforming triangles and
 * never passes through them. A virtual coupling spring k_c joins proxy and device:
 * in free space the proxy sits on the device; pressed into the phantom, the device
 * goes beneath the surface, the proxy stays on it, and the finger's force is
 * k_c (proxy - device), which the step solves together with the surface's motion
 * (contact forces over the touched triangles, spread by barycentric weights). The
 * coupling bounds the stiffness a device is asked to render by k_c. */
typedef struct palp_finger_def {
  double radius;             /* fingertip sphere [m], default 0.008 */
  double coupling_stiffness; /* k_c, proxy to device [N/m], default 2000 */
  /* The pad's local compliance at each surface feature it touches [N/m], default
   * 5000; 0 makes the pad rigid. A finger's pulp conforms to what it presses, so a
   * facet entering contact takes its load over a fraction of a millimetre instead of
   * in one tick (docs/haptics.md). */
  double pad_stiffness;
} palp_finger_def;
palp_finger_def palp_finger_default_def(void);
/* Returns a contact id >= 0 or a negative error; the proxy starts at the device. */
int palp_world_add_finger_def(palp_world *w, const palp_finger_def *def, palp_vec3 device);
/* Moves the device point [m] (the next step uses it). */
int palp_world_set_finger_device(palp_world *w, int contact, palp_vec3 device);
/* Shorthands with the default coupling: center is the device point [m]. */
int palp_world_add_finger(palp_world *w, palp_vec3 center, double radius);
int palp_world_set_finger(palp_world *w, int contact, palp_vec3 center, double radius);

/* The local contact model of a finger after the last step: what a station's 1 kHz
 * haptic loop needs to render the phantom between the server's physics steps
 * without a round trip (multi-rate rendering, docs/haptics.md). Near the state it
 * describes, the force on the device at position x and time t is
 *   F(x, t) = force - K (x - device - drift (t - time)),
 * K = stiffness (= -dF/dx, symmetric, positive semi-definite, at most k_c), while
 * the normal component stays pushing (F . normal > 0); otherwise the finger is free
 * (F = 0). drift is the surface's own motion at the contact: a device that follows
 * it feels an unchanged force (the step's surface velocity there, corrected by an
 * observer of the last model's prediction error: palp_drift_observe, finger.h). */
typedef struct palp_local_model {
  double time;            /* world time at the end of the step it describes [s] */
  double period;          /* the step [s]: the next model is due this much later */
  int contact;            /* 1 when the fingertip touches the surface */
  int triangles;          /* triangles in contact */
  palp_vec3 device;       /* device point the step used [m] */
  palp_vec3 proxy;        /* fingertip centre, on or outside the surface [m] */
  palp_vec3 normal;       /* unit contact normal, from the surface towards the proxy */
  palp_vec3 force;        /* force of the phantom on the finger [N] */
  double stiffness[3][3]; /* K [N/m] */
  palp_vec3 drift;        /* [m/s] */
  double area;            /* contact footprint (touched triangles, barycentric share) [m^2] */
  double depth;           /* device beneath the proxy along the normal [m], >= 0 */
  palp_vec3 point;        /* force-weighted contact point on the surface [m] */
} palp_local_model;
int palp_world_finger_local_model(const palp_world *w, int contact, palp_local_model *out);

/* Force of a local model at device point x [m], `age` [s] after its time. */
palp_vec3 palp_local_model_force(const palp_local_model *m, palp_vec3 x, double age);

/* Where a finger touches: the touched triangles and each one's contact force on the
 * surface [N] (normal, outward from the finger); fills up to cap, returns the count. */
/* The gel support's per-vertex stiffening by the lesions, k_i / k [-]; 1 where none. */
double palp_world_support_scale(const palp_world *w, int vertex);
/* The same factor for a point on the surface with outward unit normal (no world needed). */
double palp_lesion_support_scale(const palp_lesion *lesions, int count, palp_vec3 surface_point, palp_vec3 normal,
                                 double column_length);
/* The support's stiffness scale of a column of column_length [m] against a full column of
 * full_length [m] (the pole's, the dome's radius), lesions included: S(full) / C(column),
 * C the column's Boussinesq-weighted compliance with the lesions' chords (lesion.c); equal to
 * palp_lesion_support_scale when the two lengths are equal. Overlapping lesions count once where
 * they overlap (the stiffest there); at most PALP_MAX_LESIONS lesions are read. */
double palp_support_column_scale(const palp_lesion *lesions, int count, palp_vec3 surface_point, palp_vec3 normal,
                                 double column_length, double full_length);

int palp_world_finger_contacts(const palp_world *w, int contact, int *triangles, double *force, int cap);
int palp_world_remove_contact(palp_world *w, int contact);

/* Force the phantom exerts back on the contact [N] (sum over its vertices), and per
 * vertex: fills up to cap entries, returns the count. Needs PALP_EFFECT_FORCE_FEEDBACK. */
int palp_world_contact_feedback(const palp_world *w, int contact, palp_vec3 *total);
int palp_world_contact_vertices(const palp_world *w, int contact, int *vertices, palp_vec3 *feedback,
                                int cap);

const palp_mesh *palp_world_mesh(const palp_world *w);
const palp_vec3 *palp_world_positions(const palp_world *w); /* [vertex_count] [m] */
const palp_vec3 *palp_world_velocities(const palp_world *w); /* [m/s] */
double palp_world_time(const palp_world *w);      /* simulated time [s] */
int64_t palp_world_frame(const palp_world *w);    /* steps taken, sleeping ones included */
double palp_world_volume(const palp_world *w);    /* [m^3] */
double palp_world_rest_volume(const palp_world *w);
double palp_world_pressure(const palp_world *w);  /* gauge gel pressure [Pa] */
int palp_world_is_awake(const palp_world *w);
void palp_world_wake(palp_world *w);
const palp_world_def *palp_world_get_def(const palp_world *w);

/* What the world had to do to stay faithful, and where it was pushed beyond its
 * model. Counters accumulate from creation. */
typedef struct palp_world_health {
  int64_t substeps;           /* steps retried as two half steps (velocity non-finite or
                                 above max_speed after the solve, or a link turned by
                                 > 30 deg / strained by > 0.25 within the step) */
  int64_t refactors;          /* factorisations: step size changes beyond the factor's
                                 stability margin, lagged-tangent rebuilds */
  int64_t large_strain_steps; /* steps (frames: a split step counts once) with a link
                                 strained beyond +-50%, where a linear Burgers law on
                                 engineering strain is a poor model */
  double max_strain;          /* largest |link strain| seen [-] */
  int64_t base_contacts;      /* vertex-steps held at the rigid base plane z = 0 */
  int64_t finger_unsolved;    /* finger contact solves that ended without converging */
  int64_t large_bend_steps;   /* steps (frames, as above) while a hinge's linearised turn missed its true
                                 turn by more than 0.1 rad (src/bending.h), or by more
                                 than def.validated_hinge_error where that is larger,
                                 where the linearised bending is a poor model (only with
                                 membrane.bending_stiffness > 0; each hinge checked
                                 once per 0.2 s of simulated time) */
  double max_bend;            /* largest linearised hinge turn from rest seen [rad] */
  int64_t clamped_steps;      /* sub-steps at the last halving (h/16) in which some vertex's
                                 velocity was capped at max_speed rather than failing the world
                                 (not those accepted uncapped, session 83): a load
                                 far beyond the model (e.g. 30 N on one vertex of a soft
                                 phantom) */
  double max_bend_error;      /* largest |true - linearised| hinge turn seen [rad] */
  int64_t margin_rebuilds;    /* deferred rebuilds (def.refactor_lag) made at once because the
                                 factor reached its stability margin before its due frame */
  int64_t beyond_validated_steps; /* steps with a fingertip in contact pressed deeper than
                                 the parameters were validated against the FE there
                                 (def.validated_*) */
  double max_beyond_validated; /* largest such excess of indentation [m] */
  int64_t factor_analyses;    /* factor storages ordered and analysed at their first use
                                 (AMD, CHOLMOD's symbolic pass, the block map: several
                                 refactorisations' cost). A lagged world (def.refactor_lag)
                                 analyses its spares at creation, so that no rebuild made
                                 off the tick meets one: 2 at creation (3 with
                                 def.refactor_blend), none later */
  int64_t finger_paths;       /* vertices whose finger compliance was made by their etree
                                 paths (a nested-dissection factor: nets of 600 vertices
                                 and more, sparse_ldl.h), on the tick or by a deferred job;
                                 0 where full compliance columns serve */
  int64_t gel_momentum_dropped; /* frames (steps or their halves) of the literal gel law
                                 (PALP_GEL_PAPER_LITERAL) whose momentum term a3 (p_{i-1} -
                                 p_{i-2}) / (h h_prev) was left out because h, h_prev were
                                 outside palp_gel_literal_valid, where it would amplify every
                                 change of pressure: a halved step, or palp_world_step_dt
                                 shorter than def.dt; the law there is the literal one
                                 without a3 (docs/model.md) */
} palp_world_health;
void palp_world_get_health(const palp_world *w, palp_world_health *out);

/* FNV-1a, in 64-bit words, over the phantom's recorded state: positions, velocities,
 * link strains, Burgers and support-relaxation states, gel volume and pressure, time and
 * frame. It is logged with every frame (db/palp_db.h) and `palp-review replay` compares
 * it, so it keeps its definition. It is a 64-bit checksum, not a proof: each word is folded
 * as h = (h ^ w) P with P odd, so a word's bit k reaches only bits k and above of h, and
 * some differences cancel, e.g. the signs of two doubles flipped (the pole's vx and vy:
 * equal hashes, session 83 review). A replay compares every frame, and a lasting
 * divergence shows in the next frame's hash. Equal hashes say nothing of the rest of the
 * world either: it leaves out state a later step reads (the literal gel law's previous
 * pressure and step, the fingers' proxies, warm starts, local models and drift observers,
 * the installed tangent, a blend or a pending rebuild, the sleep timer), so two worlds
 * can hash equal and diverge later; where that matters, palp_world_state_hash. */
uint64_t palp_world_hash(const palp_world *w);
/* A hash over everything of the world's state that a later step or query reads: the
 * above, and the links' directions and stresses, the literal gel's previous pressure and
 * step, the reported gel pressure and rate, the solve's kept A^{-1} g, the installed
 * tangent (its factor's numbers, the link data it is checked against, whether it must be
 * rebuilt), a blend's replaced factor, a pending rebuild's matrix, the sleep state, and
 * every contact (loads, fingers' devices, proxies, constraint rows and their warm-start
 * forces, feedback, local models, drift observers). Each word is mixed (the splitmix64
 * finaliser) before FNV-1a's fold, so that a changed bit, the sign's too, changes about
 * half the bits folded in, and differences cancel only by chance (~2^-64; since session
 * 83: it was the logged hash's fold, and the sign pairs above cancelled in it too). Two
 * worlds built from the same def with equal state hashes are bit-identical in all of it
 * (but for that chance), so they step and answer alike.
 * Left out: caches whose contents are the same bits whoever fills them (the finger's
 * compliance columns, Burgers coefficients), scratch, the health counters and the
 * timings. Not logged, and not for every tick: ~53 us at 338 vertices, ~0.45 ms at
 * 1,300 (the factor's numbers; palp_world_hash: 6 and 24 us). */
uint64_t palp_world_state_hash(const palp_world *w);

/* A fingerprint of this process's math library as the model calls it (exp, expm1, pow, atan2, sin,
 * cos, acos over fixed arguments; src/numerics.c). Two machines with the same build replay each
 * other's sessions bit for bit only if their fingerprints are equal: glibc picks its FMA/AVX2 or
 * baseline code at run time, and they differ in the last bit. Session logs keep it ("numerics" in
 * a session's params, palp-server since session 81). ~0.2 ms. */
uint64_t palp_numerics_fingerprint(void);

/* Per-stage timings of the last step and accumulated totals [s]. name[0] is "refactor",
 * the factor's upkeep (a due rebuild installed or computed, a blend advanced, a rebuild or
 * its request, the Burgers coefficients), then the pipeline's stages in order; unused
 * slots have a NULL name. `last` is the last palp_world_step_dt call's, summed over the
 * halves of a split step and any rejected attempt (all zero for a sleeping step), so
 * that its sum is nearly the call's wall time; `total` sums every call. */
#define PALP_STAGE_COUNT 14
typedef struct palp_stage_timings {
  const char *name[PALP_STAGE_COUNT];
  double last[PALP_STAGE_COUNT];
  double total[PALP_STAGE_COUNT];
  int64_t steps;     /* frames stepped awake (a split step counts once): total's divisor */
  int64_t refactors; /* factorisations so far (step size changes, lagged tangent rebuilds) */
  int factor_nnz;    /* off-diagonal entries of the current L */
  int unknowns;      /* size of the implicit system */
} palp_stage_timings;
void palp_world_timings(const palp_world *w, palp_stage_timings *out);

/* ---- scenes (JSON) --------------------------------------------------------- */
#define PALP_SCENE_MAX_CONTACTS 8
typedef struct palp_scene_contact {
  palp_contact_def def;
  palp_vec3 direction; /* unit force direction; zero means the inward normal at the centre */
  palp_profile profile; /* magnitude over time [N] */
} palp_scene_contact;

typedef struct palp_scene {
  char name[64];
  /* The FEM material profile the real-time parameters were calibrated against
   * ("paper_long_term", "paper_instantaneous", "breast_tissue"; docs/materials.md), from
   * the scene's "material" or else its parameter file's; "" when neither says. The model
   * does not use it: it tells the evaluation which reference the scene answers to. */
  char material[32];
  palp_world_def world;
  int frames;           /* output frames */
  double frame_period;  /* [s] between output frames (>= world.dt, a multiple of it) */
  int contact_count;
  palp_scene_contact contact[PALP_SCENE_MAX_CONTACTS];
} palp_scene;

/* Loads a scene. A "parameters" entry names a JSON file (relative to the scene) that gives
 * the "membrane" and "gel" objects (the scene then has none of its own). Unknown keys are
 * refused, in the scene and in its parameter file. On error returns a negative code and writes a message naming the
 * offending field (e.g. "membrane.E1: expected a number") into err. */
int palp_scene_load(const char *path, palp_scene *out, char *err, size_t errlen);
/* Parses scene text that comes from no file of the caller's: a session log's scene, which
 * is untrusted (a handed-over database). It must carry its "membrane" and "gel" itself; a
 * "parameters" file reference is refused (reading it could hang on a FIFO or probe files). */
int palp_scene_parse(const char *json, palp_scene *out, char *err, size_t errlen);
/* Parses trusted scene text (a tool's or a test's own) as if it were a scene file in dir
 * (NULL: "."): its "parameters" are read relative to dir. */
int palp_scene_parse_in(const char *json, const char *dir, palp_scene *out, char *err, size_t errlen);
/* The fully resolved scene as self-contained JSON (parameters inlined), so a logged
 * session can be rebuilt exactly; malloc'd, the caller frees it. NULL on failure. */
char *palp_scene_to_json(const palp_scene *s);
/* Creates the world and its contacts; contact ids are 0..contact_count-1. */
palp_world *palp_scene_create_world(const palp_scene *s, int *err);
/* Applies every contact's profile at time t [s] (call before each step). */
int palp_scene_apply(const palp_scene *s, palp_world *w, double t);
/* The start [s] of substep q (0..frame_period/dt - 1) of frame f: f * frame_period + q * world.dt,
 * the FE reference's clock. The offline tools apply the profiles at it, not at palp_world_time,
 * which sums dt step by step: 0.01 summed ten times is 0.09999999999999999, and a step edge at
 * 0.1 s loaded the real-time model one step longer than the FEM (session 82's review). */
double palp_scene_step_time(const palp_scene *s, long f, int q);

#ifdef __cplusplus
}
#endif
#endif
