/* finger_compare.h - `palp-fem finger` (finger_compare.c). */
#ifndef PALP_FEM_FINGER_COMPARE_H
#define PALP_FEM_FINGER_COMPARE_H
#include "palp_fem.h"
int palp_fem_finger_compare(const palp_fem_config *cfg, const palp_scene *scene, const char *csv, const char *only, char *err,
                            size_t errlen);
#endif
