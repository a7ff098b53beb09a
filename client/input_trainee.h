/*
 * input_trainee.h - the scripted trainees (trainee.h) as a position-driven device
 * (input_trainee.c, issue 13). Not installed: palp-client's own.
 */
#ifndef PALP_CLI_INPUT_TRAINEE_H
#define PALP_CLI_INPUT_TRAINEE_H

#include "input.h"
/* --input sim:expert[,spacing_mm=8,hold_s=0.12,threshold=0.12,rate_hz=250] and
 * sim:novice[,presses=5,depth_mm=3,seed=7,rate_hz=250]: client/trainee.c's scripts in
 * real time at the phantom's physics rate, marking lumps with the device's button. */
#include "trainee.h"
typedef enum palp_cli_trainee_kind { PALP_CLI_TRAINEE_EXPERT = 1, PALP_CLI_TRAINEE_NOVICE = 2 } palp_cli_trainee_kind;
typedef struct palp_cli_trainee_def {
  palp_cli_trainee_kind kind;
  palp_cli_expert_cfg expert;
  int presses;            /* novice */
  double depth;           /* novice press depth [m] */
  unsigned seed;          /* novice */
  double radius;          /* fingertip [m] */
  double physics_rate_hz; /* the script's step rate: the phantom's */
} palp_cli_trainee_def;
palp_cli_trainee_def palp_cli_trainee_default_def(palp_cli_trainee_kind kind);
int palp_cli_trainee_parse(const char *spec, palp_cli_trainee_def *out, char *err, size_t errlen);
int palp_cli_trainee_input(const palp_cli_trainee_def *def, palp_cli_input *out);

#endif
