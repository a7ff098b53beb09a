/* What a logged frame says about the world, computed in one place so that the server's log and
 * the replay agree to the bit (same operations in the same order). Links the model library. */
#include <math.h>
#include <stdio.h>

#include "palp_db.h"

void palp_db_frame_summarize(const palp_world *w, palp_db_frame *f) {
  const palp_mesh *m = palp_world_mesh(w);
  const palp_vec3 *x = palp_world_positions(w);
  /* Displacement of vertex i: |x_i - X_i|, X the rest position [m]. */
  double max2 = 0.0;
  for (int i = 0; i < m->vertex_count; i++) {
    const double dx = x[i].x - m->rest[i].x, dy = x[i].y - m->rest[i].y, dz = x[i].z - m->rest[i].z;
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > max2) max2 = d2;
  }
  const int t = m->top_vertex;
  const double tx = x[t].x - m->rest[t].x, ty = x[t].y - m->rest[t].y, tz = x[t].z - m->rest[t].z;
  /* Contact force: |sum over live contacts of the feedback force| [N]; contact ids are small
   * integers below max_contacts, and a free id reports an error. */
  palp_vec3 sum = {0, 0, 0};
  const int slots = palp_world_get_def(w)->max_contacts;
  for (int c = 0; c < slots; c++) {
    palp_vec3 fb;
    if (palp_world_contact_feedback(w, c, &fb) == 0) {
      sum.x += fb.x;
      sum.y += fb.y;
      sum.z += fb.z;
    }
  }
  f->frame = palp_world_frame(w);
  f->sim_time_s = palp_world_time(w);
  f->top_disp_m = sqrt(tx * tx + ty * ty + tz * tz);
  f->max_disp_m = sqrt(max2);
  f->volume_m3 = palp_world_volume(w);
  f->pressure_pa = palp_world_pressure(w);
  f->contact_force_n = sqrt(sum.x * sum.x + sum.y * sum.y + sum.z * sum.z);
  f->state_hash = palp_world_hash(w);
}

palp_world *palp_db_world_from_scene(const char *scene_json, double dt_s, int *err, char *msg,
                                     size_t msglen) {
  palp_scene sc;
  char perr[256] = "";
  int rc = palp_scene_parse(scene_json ? scene_json : "", &sc, perr, sizeof perr);
  if (rc) {
    if (msg && msglen) snprintf(msg, msglen, "scene: %s", perr[0] ? perr : palp_strerror(rc));
    if (err) *err = rc;
    return NULL;
  }
  /* The server steps at its tick rate, whatever the scene says. Its rebuild lag is in the
   * logged scene (time.refactor_lag_steps; absent in logs made before the lag existed, which
   * were stepped without one), so replay defers exactly as the session did; likewise its
   * blend of rebuilt tangents (time.refactor_blend_steps). */
  if (dt_s > 0) sc.world.dt = dt_s;
  palp_world *w = palp_scene_create_world(&sc, &rc);
  if (!w) {
    if (msg && msglen) snprintf(msg, msglen, "world: %s", palp_strerror(rc));
    if (err) *err = rc;
    return NULL;
  }
  /* The scene's scripted contacts are the offline tools' business; a session's contacts come
   * from the station and are all in the log. */
  for (int c = 0; c < sc.contact_count; c++) palp_world_remove_contact(w, c);
  if (err) *err = 0;
  return w;
}
