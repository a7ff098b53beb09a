/*
 * episode.c - announce a condition at once, and as over after a hold clear (episode.h).
 */
#include "episode.h"

palp_cli_episode palp_cli_episode_make(double hold) {
  return (palp_cli_episode){.hold = hold, .shown = 0, .began = 0.0, .last_on = 0.0, .clear_since = -1.0};
}

int palp_cli_episode_update(palp_cli_episode *e, double t, int on) {
  if (on) {
    e->last_on = t, e->clear_since = -1.0;
    if (e->shown) return PALP_CLI_EPISODE_QUIET;
    e->shown = 1, e->began = t;
    return PALP_CLI_EPISODE_BEGAN;
  }
  if (!e->shown) return PALP_CLI_EPISODE_QUIET;
  if (e->clear_since < 0.0) e->clear_since = t;
  /* from the first look that saw it clear: the caller's looks are its only evidence */
  if (t - e->clear_since < e->hold) return PALP_CLI_EPISODE_QUIET;
  e->shown = 0;
  return PALP_CLI_EPISODE_OVER;
}
