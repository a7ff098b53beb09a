/*
 * fem_run.c - a scene through the FE reference, recorded like the real-time model.
 *
 * Loads: each scene contact's vertices and weights come from palp_contact_weights
 * on the real-time dome (palp_mesh_create of scene->world.mesh), its direction is
 * scene.c's (given, or the inward radial normal at the vertex nearest the centre),
 * and its magnitude palp_profile_eval at the start of every step, exactly as
 * palp_scene_apply feeds the real-time world before each of its steps. Vertex v's
 * force F_v = lambda_v F(t) d goes to the four FE nodes of its surface map with
 * the bilinear weights w_va.
 *
 * Output every frame_period: displacement of every real-time vertex, u_v =
 * sum_a w_va u_a, the top vertex's, and the force feedback at each contact vertex:
 * the force the phantom exerts on the finger, minus the internal nodal force
 * (M a + f_int = f_ext), shared back among the vertices that load a node in
 * proportion to their load weights:
 *   fb_k = - sum_a s_ka f_int,a,   s_ka = w_ka lambda_k / sum_j w_ja lambda_j,
 * so that in static equilibrium (f_int = f_ext on loaded nodes) fb_k = -F_k for a
 * contact whose vertices push in one direction.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fem_internal.h"

static double wall(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define H(x) h = palp_fem_fnv(h, &(x), sizeof(x))
static uint64_t hash_material(uint64_t h, const palp_fem_material *m) {
  H(m->density);
  H(m->c10);
  H(m->d1);
  H(m->prony_count);
  for (int k = 0; k < m->prony_count; ++k) {
    H(m->g[k]);
    H(m->tau[k]);
  }
  return h;
}

uint64_t palp_fem_run_key(const palp_fem_config *cfg, const palp_fem_mesh *mesh, const palp_scene *s) {
  uint64_t h = PALP_FEM_FNV_SEED;
  const int version = PALP_FEM_CODE_VERSION;
  H(version);
  /* the mesh itself (covers generated and imported meshes alike) */
  h = palp_fem_fnv(h, mesh->x, sizeof *mesh->x * (size_t)mesh->node_count);
  h = palp_fem_fnv(h, mesh->hex, sizeof *mesh->hex * (size_t)mesh->element_count);
  h = palp_fem_fnv(h, mesh->region, (size_t)mesh->element_count);
  h = palp_fem_fnv(h, mesh->fixed, (size_t)mesh->node_count);
  h = hash_material(h, &cfg->membrane);
  h = hash_material(h, &cfg->gel);
  H(cfg->c10_reading);
  H(cfg->dt);
  H(cfg->newmark_beta);
  H(cfg->newmark_gamma);
  H(cfg->newton_rtol);
  H(cfg->newton_atol);
  H(cfg->max_newton);
  H(cfg->max_cutbacks);
  H(cfg->full_newton);
  H(cfg->pcg_refactor);
  H(cfg->threads);
  H(cfg->factor_lag);
  if (cfg->load_map != PALP_FEM_LOAD_POINT) H(cfg->load_map); /* point runs keep their keys */
  if (cfg->hht_alpha != 0.0) { /* so do Newmark runs; HHT's keys carry its tolerance floor */
    const double hht_floor = PALP_FEM_HHT_FLOOR;
    H(cfg->hht_alpha);
    H(hht_floor);
  }
  /* the scene: real-time mesh, timing, contacts */
  H(s->world.mesh.radius);
  H(s->world.mesh.vertex_count);
  H(s->frames);
  H(s->frame_period);
  H(s->world.dt);
  H(s->contact_count);
  for (int c = 0; c < s->contact_count; ++c) {
    const palp_scene_contact *k = &s->contact[c];
    H(k->def.distribution);
    H(k->def.center);
    H(k->def.patch_area);
    H(k->def.sigma_fraction);
    H(k->def.offset_fraction);
    H(k->def.offset_dir);
    H(k->direction);
    H(k->profile.kind);
    H(k->profile.magnitude);
    H(k->profile.t_on);
    H(k->profile.t_off);
    H(k->profile.frequency);
    H(k->profile.offset);
    H(k->profile.key_count);
    for (int i = 0; i < k->profile.key_count && i < PALP_PROFILE_MAX_KEYS; ++i) {
      H(k->profile.key_t[i]);
      H(k->profile.key_f[i]);
    }
  }
  return h;
}
#undef H

typedef struct run_ws {
  palp_fem_mesh mesh;
  palp_mesh rt;
  palp_fem_map map;
  palp_fem_model model;
  int have_mesh, have_rt, have_map, have_model;
  int total;        /* contact vertices */
  int *cv;          /* contact vertex (real-time index) */
  int *cof;         /* its contact */
  double *lambda;   /* its load weight */
  double *scale;    /* 1 / (its map's weight on free nodes) when the map touches the clamp, else 1 */
  palp_vec3 dir[PALP_SCENE_MAX_CONTACTS];
  double *den;      /* [node_count] sum_j w_ja scale_j lambda_j over free nodes */
  double *fext;
} run_ws;

static void ws_free(run_ws *w) {
  if (w->have_model) palp_fem_model_destroy(&w->model);
  if (w->have_map) palp_fem_map_destroy(&w->map);
  if (w->have_rt) palp_mesh_destroy(&w->rt);
  if (w->have_mesh) palp_fem_mesh_destroy(&w->mesh);
  free(w->cv);
  free(w->cof);
  free(w->lambda);
  free(w->scale);
  free(w->den);
  free(w->fext);
}

int palp_fem_check_radius(const palp_fem_mesh *mesh, double scene_radius, char *err, size_t errlen) {
  double r2 = 0.0;
  for (int i = 0; i < mesh->node_count; ++i) {
    const double *x = mesh->x[i];
    const double q = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    if (q > r2) r2 = q;
  }
  const double r = sqrt(r2);
  if (!(scene_radius > 0.0) || !(fabs(r - scene_radius) <= PALP_FEM_RADIUS_TOL * scene_radius)) {
    snprintf(err, errlen,
             "FE dome radius %.6g m vs the scene's %.6g m (more than %.0f%% apart): the FE mesh must be the scene's "
             "dome, in metres (a mesh written in mm is 1000x too large); set mesh.radius or the scene's radius_m",
             r, scene_radius, 100 * PALP_FEM_RADIUS_TOL);
    return PALP_EINVAL;
  }
  return PALP_OK;
}

/* The FE mesh of the config (generated or read from cfg->inp_path). */
static int ws_mesh(run_ws *w, const palp_fem_config *cfg, char *err, size_t errlen) {
  int rc;
  if (cfg->inp_path[0]) rc = palp_fem_inp_read(cfg->inp_path, &w->mesh, err, errlen);
  else {
    rc = palp_fem_mesh_create(&cfg->mesh, &w->mesh);
    if (rc) snprintf(err, errlen, "mesh: invalid definition (level %d)", cfg->mesh.level);
  }
  if (!rc) w->have_mesh = 1;
  if (!rc && w->mesh.element_count > PALP_FEM_MAX_ELEMENTS) {
    snprintf(err, errlen, "FE mesh of %d hexahedra: above the %d allowed (it would need roughly %.0f GB; level 8's "
             "87,040 took 5 GB)", w->mesh.element_count, PALP_FEM_MAX_ELEMENTS,
             palp_fem_memory_estimate_gb((double)w->mesh.element_count));
    rc = PALP_EINVAL;
  }
  return rc;
}

/* The real-time dome, the surface map and every contact vertex with its load weight.
 *
 * Clamped FE nodes carry no load (since session 82): a map weight on a base node
 * would put that share of the vertex's force into the clamp, where the residual
 * ignores it, and its f_int there is the support's reaction, not the finger's force.
 * A contact vertex whose map touches the base (a patch or face in the lowest ring of
 * elements) has its weights renormalised over its free nodes, so the FE receives
 * the scene's whole force, as the real-time model (whose contact vertices are never
 * clamped) does; one whose map has no free node is refused. Vertices clear of the
 * base keep their weights bit for bit (scale 1). */
static int ws_loads(run_ws *w, const palp_fem_config *cfg, const palp_scene *scene, char *err, size_t errlen) {
  if (scene->contact_count < 0 || scene->contact_count > PALP_SCENE_MAX_CONTACTS) { /* w->dir's bound, checked here */
    snprintf(err, errlen, "scene: at most %d contacts", PALP_SCENE_MAX_CONTACTS);
    return PALP_EINVAL;
  }
  int rc = palp_fem_check_radius(&w->mesh, scene->world.mesh.radius, err, errlen);
  if (rc) return rc;
  rc = palp_mesh_create(&scene->world.mesh, &w->rt);
  if (rc) {
    snprintf(err, errlen, "real-time mesh: %s", palp_strerror(rc));
    return rc;
  }
  w->have_rt = 1;
  rc = cfg->load_map == PALP_FEM_LOAD_PATCH ? palp_fem_map_create_patch(&w->mesh, &w->rt, &w->map)
                                             : palp_fem_map_create(&w->mesh, w->rt.rest, w->rt.vertex_count, &w->map);
  if (rc) {
    snprintf(err, errlen, "surface map: a real-time vertex misses the FE surface (%s); do the geometries match?",
             palp_strerror(rc));
    return rc;
  }
  w->have_map = 1;
  const int V = w->rt.vertex_count;
  const uint8_t *fixed = w->mesh.fixed;
  int total = 0;
  int *tmpv = malloc(sizeof(int) * (size_t)V);
  double *tmpw = malloc(sizeof(double) * (size_t)V);
  w->cv = malloc(sizeof(int) * (size_t)V * (size_t)(scene->contact_count + 1));
  w->cof = malloc(sizeof(int) * (size_t)V * (size_t)(scene->contact_count + 1));
  w->lambda = malloc(sizeof(double) * (size_t)V * (size_t)(scene->contact_count + 1));
  w->scale = malloc(sizeof(double) * (size_t)V * (size_t)(scene->contact_count + 1));
  w->den = calloc((size_t)w->mesh.node_count, sizeof(double));
  w->fext = calloc((size_t)w->mesh.node_count * 3, sizeof(double));
  if (!tmpv || !tmpw || !w->cv || !w->cof || !w->lambda || !w->scale || !w->den || !w->fext) rc = PALP_ENOMEM;
  for (int c = 0; !rc && c < scene->contact_count; ++c) {
    const palp_scene_contact *sc = &scene->contact[c];
    const int n = palp_contact_weights(&w->rt, w->rt.rest, &sc->def, tmpv, tmpw, V);
    if (n < 0) {
      rc = n;
      snprintf(err, errlen, "contact %d: no load weights (%s)", c, palp_strerror(n));
      break;
    }
    palp_vec3 d = sc->direction;
    double len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (len == 0.0) { /* as palp_scene_apply: inward radial normal at the centre vertex */
      const int v = palp_mesh_nearest_vertex(&w->rt, w->rt.rest, sc->def.center);
      d = (palp_vec3){-w->rt.rest[v].x, -w->rt.rest[v].y, -w->rt.rest[v].z};
      len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    }
    if (!(len > 0.0) || !isfinite(len)) {
      rc = PALP_EINVAL;
      snprintf(err, errlen, "contact %d: no usable force direction", c);
      break;
    }
    w->dir[c] = (palp_vec3){d.x / len, d.y / len, d.z / len};
    for (int i = 0; i < n && !rc; ++i, ++total) {
      const int v = tmpv[i];
      double wfree = 0.0;
      int touches = 0;
      for (int a = w->map.start[v]; a < w->map.start[v + 1]; ++a) {
        if (fixed[w->map.node[a]]) touches = 1;
        else wfree += w->map.w[a];
      }
      if (touches && !(wfree > 1e-9)) {
        rc = PALP_EINVAL;
        snprintf(err, errlen, "contact %d: real-time vertex %d maps onto clamped FE nodes only; its load would go into "
                 "the clamp", c, v);
        break;
      }
      w->cv[total] = v;
      w->cof[total] = c;
      w->lambda[total] = tmpw[i];
      w->scale[total] = touches ? 1.0 / wfree : 1.0;
      for (int a = w->map.start[v]; a < w->map.start[v + 1]; ++a)
        if (!fixed[w->map.node[a]]) w->den[w->map.node[a]] += w->map.w[a] * w->scale[total] * tmpw[i];
    }
  }
  w->total = total;
  free(tmpv);
  free(tmpw);
  if (rc == PALP_ENOMEM) snprintf(err, errlen, "out of memory");
  return rc;
}

/* The nodal load at time t (the profile at the start of the step) into w->fext;
 * clamped nodes get none (ws_loads). */
static void ws_fext(run_ws *w, const palp_scene *scene, double t) {
  memset(w->fext, 0, sizeof(double) * 3 * (size_t)w->mesh.node_count);
  for (int k = 0; k < w->total; ++k) {
    const int c = w->cof[k], v = w->cv[k];
    const double mag = palp_profile_eval(&scene->contact[c].profile, t) * w->lambda[k];
    const double fv[3] = {mag * w->dir[c].x, mag * w->dir[c].y, mag * w->dir[c].z};
    for (int a = w->map.start[v]; a < w->map.start[v + 1]; ++a) {
      const int node = w->map.node[a];
      if (w->mesh.fixed[node]) continue;
      const double wa = w->map.w[a] * w->scale[k];
      for (int d = 0; d < 3; ++d) w->fext[3 * node + d] += wa * fv[d];
    }
  }
}

int palp_fem_run_load(const palp_fem_config *cfg, const palp_scene *scene, double t, palp_fem_mesh *mesh,
                      double **fext, char *err, size_t errlen) {
  char dummy[8];
  if (!err) err = dummy, errlen = sizeof dummy;
  err[0] = 0;
  *fext = NULL;
  memset(mesh, 0, sizeof *mesh);
  if (!cfg || !scene) return PALP_EINVAL;
  run_ws w;
  memset(&w, 0, sizeof w);
  int rc = ws_mesh(&w, cfg, err, errlen);
  if (!rc) rc = ws_loads(&w, cfg, scene, err, errlen);
  if (!rc) {
    ws_fext(&w, scene, t);
    *fext = w.fext, w.fext = NULL;
    *mesh = w.mesh, w.have_mesh = 0;
  }
  ws_free(&w);
  return rc;
}

int palp_fem_run(const palp_fem_config *cfg, const palp_scene *scene, palp_fem_result *out, palp_fem_progress_fn cb,
                 void *ud, char *err, size_t errlen) {
  char dummy[8];
  if (!err) err = dummy, errlen = sizeof dummy;
  err[0] = 0;
  memset(out, 0, sizeof *out);
  if (!cfg || !scene) return PALP_EINVAL;
  int rc = palp_fem_config_validate(cfg, err, errlen);
  if (rc) return rc;
  if (scene->frames < 1 || !(scene->frame_period > 0.0) || scene->contact_count < 0 ||
      scene->contact_count > PALP_SCENE_MAX_CONTACTS) {
    snprintf(err, errlen, "scene: needs frames >= 1, frame_period > 0 and at most %d contacts",
             PALP_SCENE_MAX_CONTACTS);
    return PALP_EINVAL;
  }
  const double period = scene->frame_period;
  const double dt = cfg->dt > 0.0 ? cfg->dt : period;
  const int sub = (int)lround(period / dt);
  if (sub < 1 || fabs(sub * dt - period) > 1e-9 * period) {
    snprintf(err, errlen, "dt = %g s must divide the frame period %g s", dt, period);
    return PALP_EINVAL;
  }
  run_ws w;
  memset(&w, 0, sizeof w);
  const double t_start = wall();
  rc = ws_mesh(&w, cfg, err, errlen);
  if (!rc) rc = ws_loads(&w, cfg, scene, err, errlen);
  if (rc) {
    ws_free(&w);
    return rc;
  }
  /* A run with a contact vertex whose map touches the clamp was computed differently
   * before session 82 (load and feedback at the clamped nodes): its key gets a marker so
   * such cache entries are recomputed, while every other key, and PALP_FEM_CODE_VERSION
   * (which stored guard references carry: docs/fem.md), stay as they were. */
  uint64_t key = palp_fem_run_key(cfg, &w.mesh, scene);
  for (int k = 0; k < w.total; ++k)
    if (w.scale[k] != 1.0) {
      static const char rule[] = "no load at clamped nodes (session 82)";
      key = palp_fem_fnv(key, rule, sizeof rule);
      break;
    }
  if (cfg->cache_dir[0] && palp_fem_cache_load(cfg->cache_dir, key, out) == 0) {
    ws_free(&w);
    return PALP_OK;
  }
  const int V = w.rt.vertex_count;
  const int total = w.total;
  rc = palp_fem_model_create(&w.model, &w.mesh, cfg);
  if (!rc) {
    w.have_model = 1;
    rc = palp_fem_model_finalize(&w.model);
  }
  if (rc) {
    snprintf(err, errlen, "model: %s", w.model.err[0] ? w.model.err : palp_strerror(rc));
    ws_free(&w);
    return rc;
  }
  /* the first numeric factorisation belongs to the setup, not to the first frame
   * (same bits: palp_fem_model_prefactor) */
  rc = palp_fem_model_prefactor(&w.model, dt);
  if (rc) {
    snprintf(err, errlen, "model: first factorisation: %s", w.model.err[0] ? w.model.err : palp_strerror(rc));
    ws_free(&w);
    return rc;
  }
  const double sec_setup = wall() - t_start;
  const int F = scene->frames;
  out->frames = F;
  out->vertex_count = V;
  out->top_vertex = w.rt.top_vertex;
  out->contact_vertex_count = total;
  out->time = malloc(sizeof(double) * (size_t)F);
  out->disp = malloc(sizeof(palp_vec3) * (size_t)F * (size_t)V);
  out->top_disp = malloc(sizeof(palp_vec3) * (size_t)F);
  out->contact_vertex = malloc(sizeof(int) * (size_t)(total ? total : 1));
  out->contact_of = malloc(sizeof(int) * (size_t)(total ? total : 1));
  out->feedback = malloc(sizeof(palp_vec3) * (size_t)F * (size_t)(total ? total : 1));
  if (!out->time || !out->disp || !out->top_disp || !out->contact_vertex || !out->contact_of || !out->feedback) {
    palp_fem_result_destroy(out);
    ws_free(&w);
    snprintf(err, errlen, "out of memory");
    return PALP_ENOMEM;
  }
  memcpy(out->contact_vertex, w.cv, sizeof(int) * (size_t)total);
  memcpy(out->contact_of, w.cof, sizeof(int) * (size_t)total);
  palp_fem_model *m = &w.model;
  if (cb && cb(ud, 0, F, 0.0)) { /* setup done */
    snprintf(err, errlen, "cancelled before frame 1");
    rc = PALP_EINVAL;
  }
  for (int f = 0; f < F && !rc; ++f) {
    for (int s = 0; s < sub && !rc; ++s) {
      const double t = f * period + s * dt; /* the profile at the start of the step */
      ws_fext(&w, scene, t);
      rc = palp_fem_step(m, w.fext, dt);
      if (rc) snprintf(err, errlen, "frame %d: %s", f, m->err[0] ? m->err : palp_strerror(rc));
    }
    if (rc) break;
    out->time[f] = (f + 1) * period;
    for (int v = 0; v < V; ++v) {
      double u[3] = {0, 0, 0};
      for (int a = w.map.start[v]; a < w.map.start[v + 1]; ++a)
        for (int d = 0; d < 3; ++d) u[d] += w.map.w[a] * m->u[3 * w.map.node[a] + d];
      out->disp[(size_t)f * (size_t)V + (size_t)v] = (palp_vec3){u[0], u[1], u[2]};
    }
    out->top_disp[f] = out->disp[(size_t)f * (size_t)V + (size_t)w.rt.top_vertex];
    for (int k = 0; k < total; ++k) {
      const int v = w.cv[k];
      double fb[3] = {0, 0, 0};
      for (int a = w.map.start[v]; a < w.map.start[v + 1]; ++a) {
        const int node = w.map.node[a];
        if (w.mesh.fixed[node] || !(w.den[node] > 0.0)) continue; /* f_int at the clamp is its reaction */
        const double share = w.map.w[a] * w.scale[k] * w.lambda[k] / w.den[node];
        for (int d = 0; d < 3; ++d) fb[d] -= share * m->fint[3 * node + d];
      }
      out->feedback[(size_t)f * (size_t)total + (size_t)k] = (palp_vec3){fb[0], fb[1], fb[2]};
    }
    if (cb && cb(ud, f + 1, F, out->time[f])) {
      snprintf(err, errlen, "cancelled at frame %d", f + 1);
      rc = PALP_EINVAL;
    }
  }
  out->node_count = w.mesh.node_count;
  out->element_count = w.mesh.element_count;
  out->dof_count = m->nfree;
  out->steps = m->steps;
  out->newton_iterations = m->newton_iterations;
  out->cutbacks = m->cutbacks;
  out->factorizations = m->factorizations;
  out->pcg_iterations = m->pcg_iterations;
  out->sec_assemble = m->sec_assemble, out->sec_factor = m->sec_factor;
  out->sec_solve = m->sec_solve, out->sec_krylov = m->sec_krylov;
  out->assemblies = m->assemblies, out->tangent_assemblies = m->tangent_assemblies, out->solves = m->solves;
  out->wall_seconds = wall() - t_start;
  out->sec_setup = sec_setup;
  out->background_factorizations = m->bg_factorizations;
  out->sec_factor_wait = m->sec_wait;
  out->key = key;
  ws_free(&w);
  if (rc) {
    palp_fem_result_destroy(out);
    return rc;
  }
  if (cfg->cache_dir[0] && palp_fem_cache_store(cfg->cache_dir, out) != 0)
    snprintf(err, errlen, "warning: could not write the cache entry under %s", cfg->cache_dir);
  return PALP_OK;
}
