/*
 * episode.h - when to tell the trainee that a condition began and that it is over.
 *
 * A condition sampled now and then (the force on her hand limited, the phantom pressed
 * beyond the model's valid range) is announced at once when it begins and as over only
 * once it has stayed clear for a hold time. A press held at the limit dips under it for a
 * tick now and then; announcing each dip made "FORCE LIMITED" and "back under the limit"
 * alternate 20 ms apart. Pure: no I/O, no clock of its own (times are the caller's) [s].
 */
#ifndef PALP_CLI_EPISODE_H
#define PALP_CLI_EPISODE_H

typedef struct palp_cli_episode {
  double hold;        /* [s] clear this long before the episode is over */
  int shown;          /* an episode was announced and is not over */
  double began;       /* when the announced episode began [s] */
  double last_on;     /* when the condition was last seen [s] */
  double clear_since; /* when it was first seen clear since last_on [s]; < 0 while on */
} palp_cli_episode;

/* The station's holds [s]: the force limit's (a press at the limit dips under it for a tick),
 * and the valid range's (the skin's check revisits each hinge every 0.2 s). */
#define PALP_CLI_LIMIT_HOLD_S 0.25
#define PALP_CLI_RANGE_HOLD_S 0.5

enum { PALP_CLI_EPISODE_QUIET = 0, PALP_CLI_EPISODE_BEGAN = 1, PALP_CLI_EPISODE_OVER = 2 };

/* An episode tracker that needs `hold` [s] clear before an episode is over. */
palp_cli_episode palp_cli_episode_make(double hold);

/* The condition at time t [s] (times never go back): PALP_CLI_EPISODE_BEGAN when it is
 * on and no episode is shown, PALP_CLI_EPISODE_OVER when it has been clear for the hold
 * (then began, last_on and clear_since still describe the episode that ended), else
 * PALP_CLI_EPISODE_QUIET. */
int palp_cli_episode_update(palp_cli_episode *e, double t, int on);

#endif
