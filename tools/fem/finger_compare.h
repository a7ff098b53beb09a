/* finger_compare.h - `palp-fem finger` (finger_compare.c). */
#ifndef PALP_FEM_FINGER_COMPARE_H
#define PALP_FEM_FINGER_COMPARE_H
#include "palp_fem.h"
/* The pole_lesion site's lesion: 10 mm across, its centre lesion_depth [m] under the
 * pole (0.010 in the case), lesion_ratio times the gel's stiffness (5).
 * fe_from: NULL, or a CSV written by this function whose FE columns are used
 * instead of solving; max_depths: 0, or the number of depths per curve; < 0: every depth
 * and no force-matched table (its real-time curve to 30 mm costs most of the time);
 * max_force [N]: each FE curve stops at the first depth whose force passes it (5 N: the
 * issue's range; more to check a deep press, e.g. the exercises' deep band). */
int palp_fem_finger_compare(const palp_fem_config *cfg, const palp_scene *scene, const char *csv, const char *only,
                            double lesion_depth, double lesion_ratio, const char *fe_from, int max_depths,
                            int force_table, double max_force, char *err, size_t errlen);
#endif
