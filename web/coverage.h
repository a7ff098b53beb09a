/*
 * coverage.h - the force gauge's pressure bands (palp_web_): how palp-web bands a press outside an
 * exercise (inside one, the exercise's bands, palp_band_of). The coverage map the bands mark is the
 * library's (palp_coverage.h), which the stations share; its bands are PALP_BAND_* (light 0 .. deep
 * 2), these PALP_WEB_BAND_* (none 0, light 1 .. deep 3): the hub passes band - 1.
 */
#ifndef PALP_WEB_COVERAGE_H
#define PALP_WEB_COVERAGE_H

#include <stddef.h>
#include <stdint.h>

/* Pressure bands of the force gauge [N]: light below light_max, medium up to medium_max, deep
 * above; a force below touch_min is resting on the skin, not palpating (docs/web.md). */
typedef struct palp_web_bands {
  double touch_min;
  double light_max;
  double medium_max;
} palp_web_bands;

enum { PALP_WEB_BAND_NONE = 0, PALP_WEB_BAND_LIGHT = 1, PALP_WEB_BAND_MEDIUM = 2, PALP_WEB_BAND_DEEP = 3 };

palp_web_bands palp_web_bands_default(void);
/* 0 when touch_min >= 0 and touch_min < light_max < medium_max (all finite), else PALP_EINVAL. */
int palp_web_bands_check(const palp_web_bands *b);
/* The band of a force magnitude [N]. */
int palp_web_band(const palp_web_bands *b, double force);
const char *palp_web_band_name(int band);

#endif
