/*
 * eval_fem.h - bridge from the FEM reference's result to an evaluation record.
 * Kept apart from eval.h so the statistics and calibration code (and their
 * tests) do not depend on the FEM library.
 */
#ifndef PALP_EVAL_FEM_H
#define PALP_EVAL_FEM_H

#include "eval.h"
#include "palp_fem.h"

/* Copies a FEM result into a record; the rim flags come from the scene's
 * real-time mesh (the vertices the result is mapped to). */
int palp_eval_record_from_fem(const palp_fem_result *r, const palp_scene *s, palp_eval_record *out, char *err,
                              size_t errlen);

#endif
