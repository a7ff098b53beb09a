/* test_validate.c - every contact check, with expected outcomes worked out by hand. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "palp_log.h"
#include "validate.h"

static int failures;

static palp_vec3 rest[3] = {{0, 0, 0.04}, {0.04, 0, 0}, {0, 0.04, 0}};

static palp_srv_limits limits(palp_srv_force_policy policy) {
  return (palp_srv_limits){.session_id = 5, .max_force = 10.0, .absurd_force = 1000.0, .force_policy = policy, .finger_radius_min = 0.002,
                           .finger_radius_max = 0.03, .phantom_radius = 0.04, .vertex_count = 3, .rest = rest};
}

static palp_Contact force_contact(void) {
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = 5;
  c.finger = 1;
  c.seq = 9;
  c.mode = palp_CONTACT_FORCE;
  c.distribution = 3;
  c.vertex = -1;
  c.center = (palp_Vec3){0, 0, 0.04};
  c.force = (palp_Vec3){0, 0, -3};
  return c;
}

static void expect(const char *what, const palp_Contact *c, palp_srv_force_policy policy, int want_rc,
                   palp_srv_reject_reason want_reason, palp_srv_contact *out) {
  palp_srv_limits lim = limits(policy);
  palp_srv_contact tmp;
  palp_srv_reject_reason r = PALP_SRV_REJ_COUNT;
  int rc = palp_srv_validate_contact(c, &lim, out ? out : &tmp, &r);
  int ok = rc == want_rc && (want_rc == PALP_SRV_ACCEPT || r == want_reason);
  fprintf(stderr, "%s %-40s rc %d reason %s (want rc %d %s)\n", ok ? "ok  " : "FAIL", what, rc,
          rc == PALP_SRV_ACCEPT ? "-" : palp_srv_reject_name(r), want_rc,
          want_rc == PALP_SRV_ACCEPT ? "-" : palp_srv_reject_name(want_reason));
  failures += !ok;
}

int main(void) {
  palp_srv_contact out;
  palp_Contact c = force_contact();
  expect("valid force contact", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, &out);
  failures += !(out.finger == 1 && out.seq == 9 && out.distribution == 3 && out.force.z == -3);

  c = force_contact(); c.center.x = NAN;
  expect("NaN centre", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_NONFINITE, NULL);
  c = force_contact(); c.force.y = INFINITY;
  expect("infinite force", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_NONFINITE, NULL);
  c = force_contact(); c.session_id = 6;
  expect("other session's id", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_UNKNOWN_SESSION, NULL);
  c = force_contact(); c.finger = 4;
  expect("finger 4 of 0..3", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_FINGER, NULL);
  c = force_contact(); c.mode = (palp_ContactMode)7;
  expect("mode 7", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_MODE, NULL);
  c = force_contact(); c.distribution = 0;
  expect("distribution 0", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_DISTRIBUTION, NULL);
  c = force_contact(); c.distribution = 5;
  expect("distribution 5", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_DISTRIBUTION, NULL);
  /* pi R^2 = 5.03e-3 m^2 is the largest patch. */
  c = force_contact(); c.patch_area = 6e-3;
  expect("patch larger than pi R^2", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_DISTRIBUTION, NULL);
  c = force_contact(); c.vertex = 3;
  expect("vertex 3 of 3", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_VERTEX, NULL);
  c = force_contact(); c.vertex = 1; c.center = (palp_Vec3){NAN, 0, 0};
  expect("vertex 1 (centre ignored but NaN)", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_NONFINITE, NULL);
  c = force_contact(); c.vertex = 1;
  expect("vertex 1 puts the centre on it", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, &out);
  failures += !(out.center.x == 0.04 && out.center.z == 0);
  /* 2R = 0.08 m is the reach: 0.081 is out, 0.079 in. */
  c = force_contact(); c.center = (palp_Vec3){0.081, 0, 0};
  expect("centre 0.081 m from the origin", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_OUT_OF_REACH, NULL);
  c = force_contact(); c.center = (palp_Vec3){0.079, 0, 0};
  expect("centre 0.079 m from the origin", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, NULL);

  /* (30, 0, -40) N has |F| = 50 N; clamped to 10 N it is (6, 0, -8) N. */
  c = force_contact(); c.force = (palp_Vec3){30, 0, -40};
  expect("50 N clamped to 10 N", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_CLAMPED, PALP_SRV_REJ_FORCE_LIMIT, &out);
  int ok = fabs(out.force.x - 6) < 1e-12 && fabs(out.force.z + 8) < 1e-12 && out.force.y == 0;
  fprintf(stderr, "%s clamped force (%g, %g, %g) N, want (6, 0, -8) within 1e-12\n", ok ? "ok  " : "FAIL",
          out.force.x, out.force.y, out.force.z);
  failures += !ok;
  expect("50 N rejected under reject policy", &c, PALP_SRV_FORCE_REJECT, PALP_SRV_REJECT, PALP_SRV_REJ_FORCE_LIMIT, NULL);
  c = force_contact(); c.force = (palp_Vec3){6, 0, -8};
  expect("exactly 10 N is allowed", &c, PALP_SRV_FORCE_REJECT, PALP_SRV_ACCEPT, 0, NULL);

  /* Absurd forces (limit 1000 N here) are refused whatever the policy, never scaled:
   * 1e300 N used to overflow |F| to infinity and be "clamped" to 0 N. */
  c = force_contact(); c.force = (palp_Vec3){0, 0, -1e300};
  expect("1e300 N rejected as absurd (clamp policy)", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_ABSURD_FORCE, NULL);
  c = force_contact(); c.force = (palp_Vec3){1e300, 1e300, 1e300};
  expect("(1e300, 1e300, 1e300) N rejected as absurd", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_ABSURD_FORCE, NULL);
  c = force_contact(); c.force = (palp_Vec3){0, 600, -800}; /* |F| = 1000 N exactly: clamped, not absurd */
  expect("1000 N is clamped, not absurd", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_CLAMPED, PALP_SRV_REJ_FORCE_LIMIT, &out);
  ok = fabs(out.force.y - 6) < 1e-12 && fabs(out.force.z + 8) < 1e-12;
  fprintf(stderr, "%s 1000 N clamped to (%g, %g, %g) N, want (0, 6, -8) within 1e-12\n", ok ? "ok  " : "FAIL",
          out.force.x, out.force.y, out.force.z);
  failures += !ok;
  c = force_contact(); c.force = (palp_Vec3){0, 600.001, -800};
  expect("1000.0005 N rejected as absurd", &c, PALP_SRV_FORCE_REJECT, PALP_SRV_REJECT, PALP_SRV_REJ_ABSURD_FORCE, NULL);
  c = force_contact(); c.force = (palp_Vec3){4e-320, 0, -3e-320}; /* subnormal: no division by zero */
  expect("subnormal force accepted", &c, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, NULL);

  palp_Contact f;
  memset(&f, 0, sizeof f);
  f.session_id = 5;
  f.mode = palp_CONTACT_FINGER;
  f.center = (palp_Vec3){0, 0, 0.05};
  f.radius = 0.01;
  expect("valid finger", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, &out);
  f.radius = 0.001;
  expect("finger radius 1 mm < 2 mm", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_RADIUS, NULL);
  f.radius = 2.0;
  expect("finger radius 2 m", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_BAD_RADIUS, NULL);
  f.radius = NAN;
  expect("finger radius NaN", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_NONFINITE, NULL);
  f.radius = 0.01;
  f.center = (palp_Vec3){0, 0, 40.0}; /* mm sent as m */
  expect("finger 40 m away", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_REJECT, PALP_SRV_REJ_OUT_OF_REACH, NULL);
  f.center = (palp_Vec3){0, 0, 0.2}; /* hovering 16 cm above: fine */
  expect("finger hovering 0.2 m away", &f, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, NULL);

  palp_Contact r;
  memset(&r, 0, sizeof r);
  r.session_id = 5;
  r.mode = palp_CONTACT_RELEASE;
  r.center.x = NAN; /* ignored on release */
  expect("release ignores the other fields", &r, PALP_SRV_FORCE_CLAMP, PALP_SRV_ACCEPT, 0, NULL);

  /* Network strings for the text log (session 75): control bytes, DEL and the backslash as \xNN,
   * UTF-8 kept, and a cut never halves an escape. */
  {
    char o[64];
    const struct {
      const char *in, *want;
      size_t len;
    } pr[] = {{"a\nINFO forged", "a\\x0aINFO forged", 64},
              {"\x1b[2J\r\x7f", "\\x1b[2J\\x0d\\x7f", 64},
              {"back\\slash", "back\\x5cslash", 64},
              {"Jos\xc3\xa9", "Jos\xc3\xa9", 64},
              {"T\xc2\x9b" "2J\xc2\xa0", "T\\xc2\\x9b2J\xc2\xa0", 64}, /* a C1 CSI escaped, U+00A0 kept */
              {"ab\ncd", "ab", 6},      /* "ab\x0a" needs 7 bytes with its NUL: cut before the escape */
              {"ab\ncd", "ab\\x0a", 7}, /* ... which fits in 7 */
              {NULL, "", 4}};
    for (size_t i = 0; i < sizeof pr / sizeof pr[0]; i++) {
      palp_log_printable(pr[i].in, o, pr[i].len);
      const int ok = strcmp(o, pr[i].want) == 0;
      fprintf(stderr, "%s printable #%zu: \"%s\" (want \"%s\", %zu bytes)\n", ok ? "ok  " : "FAIL", i, o, pr[i].want,
              pr[i].len);
      failures += !ok;
    }
  }

  fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
