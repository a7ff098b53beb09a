/* World calls that log themselves as the replay contract (db/palp_db.h) says: the log records
 * exactly the calls that succeeded, at the frame they took effect, and each applied input wakes
 * the world (the model wakes itself on some changes but not on a moved finger; the server wakes
 * it after every input, and replay must do the same). Waking is idempotent, so one wake after a
 * group of inputs at one frame is the same as one after each. */
#include <string.h>

#include "palp_db.h"

static palp_db_contact input(const palp_world *world, int slot, palp_db_contact_op op, palp_db_contact_kind kind) {
  palp_db_contact c;
  memset(&c, 0, sizeof c);
  c.frame = palp_world_frame(world);
  c.sim_time_s = palp_world_time(world);
  c.slot = slot;
  c.op = op;
  c.kind = kind;
  return c;
}

int palp_db_world_add_contact(palp_db_writer *w, palp_db_session s, palp_world *world,
                              const palp_contact_def *def, palp_vec3 force_n) {
  int id = palp_world_add_contact(world, def);
  if (id < 0) return id;
  int rc = palp_world_set_contact_force(world, id, force_n);
  if (rc < 0) { /* a non-finite force: undo, so the world and the log agree that nothing happened */
    palp_world_remove_contact(world, id);
    return rc;
  }
  palp_world_wake(world); /* contract: every applied input wakes the world */
  if (w) {
    palp_db_contact c = input(world, id, PALP_DB_OP_ADD, PALP_DB_KIND_FORCE);
    c.def = *def;
    c.force_n = force_n;
    palp_db_log_contact(w, s, &c);
  }
  return id;
}

int palp_db_world_set_contact_force(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                                    palp_vec3 force_n) {
  int rc = palp_world_set_contact_force(world, id, force_n);
  if (rc == 0) palp_world_wake(world);
  if (rc == 0 && w) {
    palp_db_contact c = input(world, id, PALP_DB_OP_UPDATE, PALP_DB_KIND_FORCE);
    c.force_n = force_n;
    palp_db_log_contact(w, s, &c);
  }
  return rc;
}

int palp_db_world_add_finger(palp_db_writer *w, palp_db_session s, palp_world *world, palp_vec3 center_m,
                             double radius_m) {
  int id = palp_world_add_finger(world, center_m, radius_m);
  if (id >= 0) palp_world_wake(world);
  if (id >= 0 && w) {
    palp_db_contact c = input(world, id, PALP_DB_OP_ADD, PALP_DB_KIND_FINGER);
    c.center_m = center_m;
    c.radius_m = radius_m;
    palp_db_log_contact(w, s, &c);
  }
  return id;
}

int palp_db_world_set_finger(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                             palp_vec3 center_m, double radius_m) {
  int rc = palp_world_set_finger(world, id, center_m, radius_m);
  if (rc == 0) palp_world_wake(world);
  if (rc == 0 && w) {
    palp_db_contact c = input(world, id, PALP_DB_OP_UPDATE, PALP_DB_KIND_FINGER);
    c.center_m = center_m;
    c.radius_m = radius_m;
    palp_db_log_contact(w, s, &c);
  }
  return rc;
}

int palp_db_world_remove_contact(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                                 palp_db_contact_kind kind) {
  int rc = palp_world_remove_contact(world, id);
  if (rc == 0) palp_world_wake(world);
  if (rc == 0 && w) {
    palp_db_contact c = input(world, id, PALP_DB_OP_REMOVE, kind);
    palp_db_log_contact(w, s, &c);
  }
  return rc;
}

int palp_db_world_step(palp_db_writer *w, palp_db_session s, palp_world *world, palp_db_frame *out) {
  int rc = palp_world_step(world);
  if (rc != 0) return rc;
  if (w || out) {
    palp_db_frame f;
    palp_db_frame_summarize(world, &f);
    if (w) palp_db_log_frame(w, s, &f);
    if (out) *out = f;
  }
  return 0;
}
