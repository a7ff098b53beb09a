/* bending.c - linearised hinge bending (see bending.h). */
#include "bending.h"

#include "vec3.h"

double palp_hinge_angle(palp_vec3 a, palp_vec3 b, palp_vec3 c, palp_vec3 d) {
  const palp_vec3 e = v3_sub(b, a);
  const palp_vec3 n1 = v3_cross(e, v3_sub(c, a)); /* triangle (a, b, c) */
  const palp_vec3 n2 = v3_cross(v3_sub(d, a), e); /* triangle (b, a, d), same orientation */
  const double el = v3_len(e);
  return atan2(v3_dot(v3_cross(n2, n1), e) / el, v3_dot(n1, n2)); /* the sign of the gradient below */
}

int palp_hinge_gradient(palp_vec3 a, palp_vec3 b, palp_vec3 c, palp_vec3 d, palp_vec3 g[4]) {
  /* Bridson, Marino & Fedkiw (2003), "Simulation of clothing with folds and
   * wrinkles", with their x1 = c, x2 = d (the wings), x3 = a, x4 = b (the edge):
   * n1 = (c - a) x (c - b), n2 = (d - b) x (d - a) (twice the areas, unnormalised),
   *   dtheta/dc = |e| n1 / |n1|^2,  dtheta/dd = |e| n2 / |n2|^2,
   *   dtheta/da = ((c - b).e^) n1 / |n1|^2 + ((d - b).e^) n2 / |n2|^2,
   *   dtheta/db = -((c - a).e^) n1 / |n1|^2 - ((d - a).e^) n2 / |n2|^2. */
  const palp_vec3 e = v3_sub(b, a);
  const double el = v3_len(e);
  const palp_vec3 n1 = v3_cross(v3_sub(c, a), v3_sub(c, b));
  const palp_vec3 n2 = v3_cross(v3_sub(d, b), v3_sub(d, a));
  const double q1 = v3_dot(n1, n1), q2 = v3_dot(n2, n2);
  if (!(el > 0.0 && q1 > 0.0 && q2 > 0.0)) return -1;
  const palp_vec3 m1 = v3_scale(n1, 1.0 / q1), m2 = v3_scale(n2, 1.0 / q2); /* [1/m^2] */
  const palp_vec3 eh = v3_scale(e, 1.0 / el);
  g[2] = v3_scale(m1, el);
  g[3] = v3_scale(m2, el);
  g[0] = v3_add(v3_scale(m1, v3_dot(v3_sub(c, b), eh)), v3_scale(m2, v3_dot(v3_sub(d, b), eh)));
  g[1] = v3_scale(v3_add(v3_scale(m1, v3_dot(v3_sub(c, a), eh)), v3_scale(m2, v3_dot(v3_sub(d, a), eh))), -1.0);
  return 0;
}

double palp_hinge_stiffness(double D, double edge_len2, double area_sum) {
  return area_sum > 0.0 ? D * edge_len2 / area_sum : 0.0;
}
