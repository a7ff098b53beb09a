/*
 * fem_finger.h - the fingertip and the lesions in the FE reference (docs/fem.md,
 * "The finger" and "Lesions"): a rigid sphere pressed by position against the
 * outer surface with frictionless penalty contact, and stiff inclusions as a
 * per-element C10 multiplier. Internal to palp_fem (like fem_internal.h).
 */
#ifndef PALP_FEM_FINGER_H
#define PALP_FEM_FINGER_H

#include "fem_internal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Frictionless contact of a rigid sphere with the surface faces, enforced by an
 * augmented Lagrangian (penalty plus Uzawa multiplier updates until the
 * penetration is below gap_tol) on the gap at (quad + 1)^2 points of every face (composite Simpson) (a surface
 * integral of the contact pressure p = -penalty * gap, gap < 0), so the force is
 * consistent with the faces' areas rather than lumped at nodes. */
typedef struct palp_fem_finger {
  double radius;    /* [m], 0.008 */
  double penalty;   /* [N/m^3] pressure per metre of penetration, 1e10 by default */
  int quad;         /* Simpson intervals per face direction (even, 2..16), 8 */
  double center[3]; /* [m] sphere centre (set before each solve) */
  double gap_tol;   /* [m] augmented-Lagrangian target: penetration at most this, 1e-6 */
  int max_augment;  /* augmentations per position, 30 */
  double *lam;      /* [face_count * (quad + 1)^2] contact pressure multipliers [Pa] */
  double *last_p;   /* the pressure of the last assembly at each point [Pa] */
  int face_count;
  int (*face)[4];   /* outward-oriented quads the sphere may touch */
  /* from the last assembly */
  double force[3];  /* force of the phantom on the finger [N] */
  double min_gap;   /* smallest gap over the Gauss points and face nodes [m] (< 0: penetration) */
  double max_pressure; /* [Pa] */
  int active;       /* points in contact */
  long augmentations; /* multiplier updates so far */
  /* predict 1: each new centre's Newton starts from the secant extrapolation of the
   * last two converged states (u_k + a (u_k - u_k-1), a the ratio of the centre's
   * moves; the first press starts from its own state), not from u_k, whose surface the moved
   * sphere then overlaps by the whole step (fem_finger.c) */
  int predict;
  double *u_prev;   /* [ndof] the converged state before the last one (predict; NULL before the first press) */
  double *u_save;   /* [ndof] scratch: the last converged state while a prediction is tried */
  double c_prev[3]; /* [m] the centre u_prev was converged at */
  long predictions; /* starts extrapolated so far */
} palp_fem_finger;

/* faces NULL: every outer surface face of the mesh (palp_fem_surface_faces).
 * radius <= 0 and penalty <= 0 take the defaults. */
int palp_fem_finger_init(palp_fem_finger *f, const palp_fem_mesh *mesh, const int (*faces)[4], int face_count,
                         double radius, double penalty);
void palp_fem_finger_destroy(palp_fem_finger *f);
/* Installs the contact as the model's extra assembly term. */
void palp_fem_finger_attach(palp_fem_finger *f, palp_fem_model *m);

/* Quasi-static press by position: for each centre in turn, the static equilibrium
 * of the relaxed solid (dt = INFINITY: the long-term modulus) with the sphere there,
 * augmented (lambda <- max(0, lambda - eps g), re-solved) until no point penetrates
 * more than gap_tol or max_augment updates were made.
 * A centre whose solve fails is approached in halved sub-steps (up to 6 levels).
 * force[k] (may be NULL) gets the force on the finger [N], min_gap[k] the smallest gap. */
int palp_fem_finger_press(palp_fem_model *m, palp_fem_finger *f, const double (*centers)[3], int count,
                          double (*force)[3], double *min_gap);

/* Lesions as stiffer gel: scale[e] = 1 + phi_e (s - 1) for gel elements, phi_e the
 * volume fraction of element e inside the lesion sphere (sampled at 6^3 points of
 * the reference element); membrane elements stay 1. scale has element_count entries.
 * Returns the number of elements touched. */
int palp_fem_lesion_scale(const palp_fem_mesh *mesh, const palp_lesion *lesions, int count, double *scale);

/* A force-depth curve: the sphere (radius [m]) pressed along -n (n the outward unit
 * normal at the site) into the relaxed dome of cfg/mesh with its C10 scaled by the
 * lesions, its centre at (R + radius - depth[k]) n for the dome radius R, each depth in
 * turn (palp_fem_finger_press). force[k] is the force on the finger along n [N],
 * min_gap[k] (may be NULL) the smallest gap. Stops after the first depth whose force
 * passes fmax [N]. progress (may be NULL) is called with ud after each depth: a fine
 * level takes minutes a depth, and a run cut short keeps what it printed. Returns the
 * depths done (0..count; fewer when a press failed, with its reason in err) or -1
 * when the model cannot be built. */
typedef void (*palp_fem_finger_progress_fn)(void *ud, int k, double depth, double force, double min_gap,
                                             long newton);
int palp_fem_finger_curve(const palp_fem_config *cfg, const palp_fem_mesh *mesh, const palp_lesion *lesions,
                          int lesion_count, const double n[3], double radius, const double *depth, int count,
                          double fmax, double *force, double *min_gap, long *newton,
                          palp_fem_finger_progress_fn progress, void *ud, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
