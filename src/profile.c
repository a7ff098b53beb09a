/* profile.c - force magnitude over time [N] for scripted contacts. */
#include <math.h>

#include "palp.h"
#include "vec3.h"

palp_profile palp_profile_paper_step(void) {
  /* 3 N, the largest force the haptic device sustains, for 2 s with no ramp. */
  palp_profile p = {.kind = PALP_PROFILE_STEP, .magnitude = 3.0, .t_on = 0.0, .t_off = 2.0};
  return p;
}

double palp_profile_eval(const palp_profile *p, double t) {
  switch (p->kind) {
  case PALP_PROFILE_STEP:
    return (t >= p->t_on && t < p->t_off) ? p->magnitude : 0.0;
  case PALP_PROFILE_RAMP:
    if (t < p->t_on) return 0.0;
    if (t >= p->t_off || p->t_off <= p->t_on) return p->magnitude;
    return p->magnitude * (t - p->t_on) / (p->t_off - p->t_on);
  case PALP_PROFILE_SINE:
    if (t < p->t_on || t >= p->t_off) return 0.0;
    return p->offset + p->magnitude * sin(2.0 * PALP_PI * p->frequency * (t - p->t_on));
  case PALP_PROFILE_KEYFRAMES: {
    const int n = p->key_count;
    if (n <= 0) return 0.0;
    if (t <= p->key_t[0]) return p->key_f[0];
    for (int i = 1; i < n; ++i)
      if (t < p->key_t[i]) {
        const double s = (t - p->key_t[i - 1]) / (p->key_t[i] - p->key_t[i - 1]);
        return p->key_f[i - 1] + s * (p->key_f[i] - p->key_f[i - 1]);
      }
    return p->key_f[n - 1];
  }
  }
  return 0.0;
}
