/* coverage.c - the force gauge's pressure bands (coverage.h); the coverage map itself is the
 * library's (src/coverage.c), shared with the stations. */
#include "coverage.h"

#include <math.h>

#include "palp.h" /* PALP_E* codes */

palp_web_bands palp_web_bands_default(void) {
  return (palp_web_bands){.touch_min = 0.2, .light_max = 1.0, .medium_max = 3.0};
}

int palp_web_bands_check(const palp_web_bands *b) {
  if (!b || !isfinite(b->touch_min) || !isfinite(b->light_max) || !isfinite(b->medium_max)) return PALP_EINVAL;
  return b->touch_min >= 0 && b->touch_min < b->light_max && b->light_max < b->medium_max ? 0 : PALP_EINVAL;
}

int palp_web_band(const palp_web_bands *b, double f) {
  if (!(f >= b->touch_min)) return PALP_WEB_BAND_NONE; /* NaN too */
  if (f < b->light_max) return PALP_WEB_BAND_LIGHT;
  if (f <= b->medium_max) return PALP_WEB_BAND_MEDIUM;
  return PALP_WEB_BAND_DEEP;
}

const char *palp_web_band_name(int band) {
  switch (band) {
  case PALP_WEB_BAND_LIGHT: return "light";
  case PALP_WEB_BAND_MEDIUM: return "medium";
  case PALP_WEB_BAND_DEEP: return "deep";
  default: return "none";
  }
}
