/* consumer.c - a program outside palp, built against the INSTALLED model library
 * (through pkg-config and through find_package) by tests/install/install_prefix.sh.
 * It loads the installed paper scene, presses for 1 s with the scene's own 3 N
 * contact and checks what the README states for that experiment: the dome is
 * dented (peak displacement tens of mm: 26.8 mm at the pole) and keeps its volume
 * (within 0.13%; asserted here within 1%). Prints "consumer ok" on success. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <palp.h>
#include <input.h> /* the device-driver interface is installed too */

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: consumer SCENE.json\n");
    return 2;
  }
  palp_scene sc;
  char err[256] = "";
  int rc = palp_scene_load(argv[1], &sc, err, sizeof err);
  if (rc < 0) {
    fprintf(stderr, "consumer: %s: %s\n", argv[1], err[0] ? err : palp_strerror(rc));
    return 1;
  }
  palp_world *w = palp_scene_create_world(&sc, &rc);
  if (!w) {
    fprintf(stderr, "consumer: cannot create the world: %s\n", palp_strerror(rc));
    return 1;
  }
  const palp_mesh *m = palp_world_mesh(w);
  const int n = m->vertex_count;
  double max_disp = 0;
  const int steps = (int)lround(1.0 / sc.world.dt);
  for (int k = 0; k < steps; k++) {
    if ((rc = palp_scene_apply(&sc, w, palp_world_time(w))) < 0 || (rc = palp_world_step(w)) < 0) {
      fprintf(stderr, "consumer: step %d: %s\n", k, palp_strerror(rc));
      return 1;
    }
    const palp_vec3 *p = palp_world_positions(w);
    for (int i = 0; i < n; i++) {
      double dx = p[i].x - m->rest[i].x, dy = p[i].y - m->rest[i].y, dz = p[i].z - m->rest[i].z;
      double d = sqrt(dx * dx + dy * dy + dz * dz);
      if (d > max_disp) max_disp = d;
    }
  }
  const double dv = fabs(palp_world_volume(w) / palp_world_rest_volume(w) - 1.0);
  const int cmd_ok = sizeof(palp_cli_cmd) > 0; /* input.h compiles against the installed palp.h */
  printf("consumer: %d vertices, %d steps of %.4g s, peak displacement %.2f mm, volume change %.3f%%\n", n, steps,
         sc.world.dt, max_disp * 1e3, dv * 100);
  int ok = cmd_ok && max_disp > 0.005 && max_disp < 0.06 && dv < 0.01;
  palp_world_destroy(w);
  if (!ok) {
    fprintf(stderr, "consumer: FAIL (want peak displacement in (5, 60) mm and volume change < 1%%)\n");
    return 1;
  }
  printf("consumer ok\n");
  return 0;
}
