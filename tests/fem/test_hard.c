/* Hard cases for the FEM reference (issue 7): each stays finite and bounded, keeps
 * the gel's volume, returns toward rest after release, and finishes in bounded
 * time; where the solver must cut its step back it counts it, and where it cannot
 * continue it fails with a clear message and a negative code, never NaN.
 *
 * Coarse meshes only (level 1; level 2 for 40 frames where a case needs it) and the
 * long-term C10 reading (sub-millimetre to millimetre response, fast) unless a case
 * needs the other. Usage: test_fem_hard CASE SCENE_JSON. Every bound comes from
 * physics and is stated in its message: displacement below the radius 40 mm, the
 * enclosed volume of the mapped surface within 1% of rest (the gel's K/mu >= 1e5),
 * recovery to a stated fraction of the peak a stated time after release. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fem_internal.h" /* the model itself, for the FE volume and kinetic energy */
#include "fem_test.h"
#include "palp.h"
#include "palp_fem.h"

static const double R = 0.04; /* [m] phantom radius */
static const char *scene_path = "config/paper_step.json";

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static palp_vec3 on_sphere(double polar_deg, double az_deg) {
  const double t = polar_deg * 3.14159265358979323846 / 180.0, p = az_deg * 3.14159265358979323846 / 180.0;
  return (palp_vec3){R * sin(t) * cos(p), R * sin(t) * sin(p), R * cos(t)};
}

static double vnorm(palp_vec3 a) { return sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

/* The paper's scene with one contact replaced: `dist` at (polar, azimuth) [deg],
 * a step of F [N] on [0, t_off) with no ramp, `frames` 10 ms frames. */
static int base_scene(palp_scene *s, int frames) {
  char err[256];
  const int rc = palp_scene_load(scene_path, s, err, sizeof err);
  if (rc) fprintf(stderr, "scene %s: %s\n", scene_path, err);
  s->frames = frames;
  return rc;
}

static void set_contact(palp_scene *s, int i, palp_distribution dist, double polar, double az, double F, double t_on,
                        double t_off) {
  palp_scene_contact *c = &s->contact[i];
  const palp_scene_contact keep = s->contact[0];
  *c = keep; /* patch area etc. as in the paper's scene */
  c->def.distribution = dist;
  c->def.center = on_sphere(polar, az);
  c->direction = (palp_vec3){0, 0, 0}; /* inward normal at the centre */
  c->profile.kind = PALP_PROFILE_STEP;
  c->profile.magnitude = F;
  c->profile.t_on = t_on;
  c->profile.t_off = t_off;
  if (s->contact_count < i + 1) s->contact_count = i + 1;
}

static palp_fem_config fast_config(int level) {
  palp_fem_config c = palp_fem_default_config();
  c.c10_reading = PALP_FEM_C10_LONG_TERM;
  c.mesh.level = level;
  c.cache_dir[0] = 0; /* compute, never read a cached answer */
  /* the volume checks need material points of the FE surface: the point map samples
   * them, the patch map (the default) averages each vertex's one-ring */
  c.load_map = PALP_FEM_LOAD_POINT;
  return c;
}

/* What a run measured. Displacements are over all real-time vertices [m]; volume
 * change |V(rest + u) / V(rest) - 1| of the mapped surface (palp_mesh_volume). */
typedef struct measured {
  int rc;
  char err[256];
  int finite;          /* every displacement and feedback finite */
  double peak;         /* max over frames of the largest vertex displacement */
  double top_peak;     /* max |top displacement| */
  double max_dv;       /* max over frames of the relative volume change */
  double dent;         /* at the frame of the peak: sum |u . n| A_v, the volume the dent sweeps [m^3] */
  double dv_at_peak;   /* |V - V0| at that frame [m^3] */
  double min_z;        /* lowest z of any deformed vertex [m]; the base plane is z = 0 */
  double wall;         /* [s] */
  palp_fem_result r;   /* kept for case-specific checks; destroyed by done() */
} measured;

static double frame_max(const palp_fem_result *r, int f) {
  double mx = 0.0;
  for (int v = 0; v < r->vertex_count; ++v) {
    const double d = vnorm(r->disp[(size_t)f * (size_t)r->vertex_count + (size_t)v]);
    if (!(d <= mx)) mx = d; /* NaN propagates */
  }
  return mx;
}

static measured run(const palp_fem_config *cfg, const palp_scene *s) {
  measured m;
  memset(&m, 0, sizeof m);
  const double t0 = now();
  m.rc = palp_fem_run(cfg, s, &m.r, NULL, NULL, m.err, sizeof m.err);
  m.wall = now() - t0;
  if (m.rc) return m;
  palp_mesh mesh;
  if (palp_mesh_create(&s->world.mesh, &mesh)) {
    m.rc = PALP_EINVAL;
    snprintf(m.err, sizeof m.err, "test: real-time mesh");
    return m;
  }
  const int nv = m.r.vertex_count;
  palp_vec3 *pos = malloc((size_t)nv * sizeof *pos);
  const double V0 = palp_mesh_volume(&mesh, mesh.rest);
  m.finite = 1;
  m.min_z = INFINITY;
  int fpeak = 0;
  for (int f = 0; f < m.r.frames; ++f) {
    const palp_vec3 *u = m.r.disp + (size_t)f * (size_t)nv;
    for (int v = 0; v < nv; ++v) {
      pos[v] = (palp_vec3){mesh.rest[v].x + u[v].x, mesh.rest[v].y + u[v].y, mesh.rest[v].z + u[v].z};
      if (!isfinite(u[v].x) || !isfinite(u[v].y) || !isfinite(u[v].z)) m.finite = 0;
      if (!(pos[v].z >= m.min_z)) m.min_z = pos[v].z;
    }
    for (int k = 0; k < m.r.contact_vertex_count; ++k) {
      const palp_vec3 fb = m.r.feedback[(size_t)f * (size_t)m.r.contact_vertex_count + (size_t)k];
      if (!isfinite(fb.x) || !isfinite(fb.y) || !isfinite(fb.z)) m.finite = 0;
    }
    const double dmax = frame_max(&m.r, f);
    if (!(dmax <= m.peak)) m.peak = dmax, fpeak = f;
    const double top = vnorm(m.r.top_disp[f]);
    if (!(top <= m.top_peak)) m.top_peak = top;
    const double dv = fabs(palp_mesh_volume(&mesh, pos) / V0 - 1.0);
    if (!(dv <= m.max_dv)) m.max_dv = dv;
  }
  /* The dent at the peak: sum over dome vertices of |u . n| times the vertex's
   * lumped area; incompressibility means the bulge elsewhere makes up for it. */
  {
    const palp_vec3 *u = m.r.disp + (size_t)fpeak * (size_t)nv;
    for (int v = 0; v < nv; ++v) {
      const palp_vec3 n = mesh.rest[v];
      const double ln = vnorm(n);
      pos[v] = (palp_vec3){n.x + u[v].x, n.y + u[v].y, n.z + u[v].z};
      if (ln > 0) m.dent += fabs((u[v].x * n.x + u[v].y * n.y + u[v].z * n.z) / ln) * mesh.vertex_area[v];
    }
    m.dv_at_peak = fabs(palp_mesh_volume(&mesh, pos) - V0);
  }
  free(pos);
  palp_mesh_destroy(&mesh);
  return m;
}

static void done(measured *m) {
  if (m->rc == 0) palp_fem_result_destroy(&m->r);
}

/* Largest vertex displacement at time t [s] (the frame ending at t). */
static double disp_at(const measured *m, double t) {
  const double period = m->r.frames > 0 ? m->r.time[0] : 0.01;
  int f = (int)lround(t / period) - 1;
  if (f < 0) f = 0;
  if (f >= m->r.frames) f = m->r.frames - 1;
  return frame_max(&m->r, f);
}

static void report(const char *name, const measured *m) {
  if (m->rc) {
    printf("%-44s error %d (%s) after %.2f s\n", name, m->rc, m->err, m->wall);
    return;
  }
  printf("%-44s peak %.4f mm (top %.4f mm), final %.4f mm, max volume change %.4f%% (dV/dent %.3f), lowest z "
         "%.3f mm, steps %ld, Newton %ld, cut-backs %ld, factorisations %ld, wall %.2f s\n",
         name, 1e3 * m->peak, 1e3 * m->top_peak, 1e3 * frame_max(&m->r, m->r.frames - 1), 100 * m->max_dv,
         m->dent > 0 ? m->dv_at_peak / m->dent : 0.0, 1e3 * m->min_z, m->r.steps, m->r.newton_iterations,
         m->r.cutbacks, m->r.factorizations, m->wall);
}

/* The common bar: the run succeeded, everything finite, the peak below the radius,
 * the enclosed volume within 1% of rest, and at `t_check` (after release) the
 * largest displacement below `frac` of the peak. */
static void stable(const char *name, const measured *m, double t_check, double frac) {
  report(name, m);
  CHECK(m->rc == 0, "%s: run failed with %d: %s", name, m->rc, m->err);
  if (m->rc) return;
  CHECK(m->finite && isfinite(m->peak), "%s: every displacement and feedback finite", name);
  CHECK(m->peak > 0 && m->peak < R, "%s: peak displacement %.3f mm in (0, radius 40 mm)", name, 1e3 * m->peak);
  CHECK(m->max_dv < 0.01, "%s: enclosed volume within 1%% of rest (max %.4f%%)", name, 100 * m->max_dv);
  /* The phantom sits on its clamped base: no material point may pass below the
   * base plane (tolerance 0.1 mm, a tenth of the finest FE cell's size). */
  CHECK(m->min_z > -1e-4, "%s: no vertex below the base plane (lowest z %.3f mm, tolerance -0.1 mm)", name,
        1e3 * m->min_z);
  const double d = disp_at(m, t_check);
  CHECK(d < frac * m->peak, "%s: at %.2f s displacement %.4f mm below %.0f%% of the peak %.4f mm", name, t_check,
        1e3 * d, 100 * frac, 1e3 * m->peak);
}

/* ---- cases -------------------------------------------------------------------- */

/* Ten times the paper's force (30 N), a step with no ramp, uniform over 5.2 cm^2;
 * held 0.5 s, then 1 s free. Besides the 1% bar, incompressibility: the volume
 * change at the peak is below 25% of the volume the dent sweeps (a compressible
 * solid would lose most of it; K/mu = 1e5 predicts ~0.1%). Back within 10% of the
 * peak 1 s after release (the slowest creep time tau2 / g_inf = 0.5 s gives
 * exp(-2) = 14% for the creep part alone; the elastic part returns at once). */
static void case_force30(void) {
  palp_scene s;
  if (base_scene(&s, 150)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.5);
  const palp_fem_config cfg = fast_config(1);
  measured m = run(&cfg, &s);
  stable("30 N uniform step, no ramp, level 1", &m, 1.5, 0.10);
  if (m.rc == 0)
    CHECK(m.dv_at_peak < 0.05 * m.dent, "30 N: |dV| %.3g m^3 below 5%% of the dent's swept volume %.3g m^3",
          m.dv_at_peak, m.dent);
  done(&m);
}

/* A point load: 3 N on one real-time vertex (distribution single), held 0.5 s,
 * level 1 and 2. It must either run (finite, bounded, back within 10% 1 s after
 * release) or fail cleanly: a negative code and a message, not NaN. */
static void case_point(void) {
  for (int level = 1; level <= 2; ++level) {
    palp_scene s;
    if (base_scene(&s, level == 1 ? 150 : 50)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
    set_contact(&s, 0, PALP_DIST_SINGLE, 30, 40, 3.0, 0.0, level == 1 ? 0.5 : 0.1);
    const palp_fem_config cfg = fast_config(level);
    measured m = run(&cfg, &s);
    char name[64];
    snprintf(name, sizeof name, "3 N single vertex, level %d", level);
    if (m.rc) {
      report(name, &m);
      CHECK(m.rc < 0 && m.err[0], "%s: a failure must carry a negative code and a message", name);
    } else {
      /* level 2 (50 frames, affordable) runs 0.4 s after a 0.1 s hold: below 50% of
       * the peak (slowest creep time 0.5 s: exp(-0.8) = 45% of the creep part) */
      stable(name, &m, level == 1 ? 1.5 : 0.5, level == 1 ? 0.10 : 0.50);
    }
    done(&m);
  }
}

/* Contact at the fixed base's rim: 86 deg polar, 4 deg above the clamped base,
 * where part of the patch lies on clamped vertices. 3 N Gaussian and 30 N uniform. */
static void case_rim(void) {
  const struct {
    palp_distribution d;
    double F;
    const char *name;
  } c[2] = {{PALP_DIST_GAUSSIAN, 3.0, "3 N gaussian at the rim (86 deg), level 1"},
            {PALP_DIST_UNIFORM, 30.0, "30 N uniform at the rim (86 deg), level 1"}};
  for (int i = 0; i < 2; ++i) {
    palp_scene s;
    if (base_scene(&s, 150)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
    set_contact(&s, 0, c[i].d, 86, 0, c[i].F, 0.0, 0.5);
    const palp_fem_config cfg = fast_config(1);
    measured m = run(&cfg, &s);
    stable(c[i].name, &m, 1.5, 0.10);
    done(&m);
  }
}

/* The load and the feedback next to the clamp (since session 82): at 86 deg polar a
 * contact's surface map reaches the lowest ring of elements, whose base nodes are
 * clamped. The FE must still receive the scene's whole force (the real-time model,
 * whose contact vertices are never clamped, does), nothing may be loaded onto a
 * clamped node, and the feedback must be the finger's force, not the clamp's
 * reaction. 3 N Gaussian held from t = 0, level 1, both load maps:
 *  - the nodal load the run applies (palp_fem_run_load at t = 0.5 s) sums over the
 *    free nodes (a load on a clamped DOF is ignored by the residual) to F d
 *    within 1% of F, d the inward radial normal at the real-time vertex nearest the
 *    centre (scene.c's rule for a contact without a direction); exactly zero on every
 *    clamped node;
 *  - the summed feedback at t = 1.0 s (near equilibrium: inertia of the creep is
 *    negligible) equals -F d within 5% of F (before the fix: 80 deg off, 3.1 N). */
static void case_rimload(void) {
  const palp_fem_load_map maps[2] = {PALP_FEM_LOAD_POINT, PALP_FEM_LOAD_PATCH};
  for (int i = 0; i < 2; ++i) {
    const char *mname = maps[i] == PALP_FEM_LOAD_POINT ? "point" : "patch";
    palp_scene s;
    if (base_scene(&s, 100)) {
      CHECK(0, "scene %s", scene_path);
      return;
    }
    const double F = 3.0;
    set_contact(&s, 0, PALP_DIST_GAUSSIAN, 86, 0, F, 0.0, 10.0);
    palp_fem_config cfg = fast_config(1);
    cfg.load_map = maps[i];
    /* the expected direction, from the real-time mesh alone */
    palp_mesh rt;
    if (palp_mesh_create(&s.world.mesh, &rt)) {
      CHECK(0, "real-time mesh");
      return;
    }
    const palp_vec3 pc = rt.rest[palp_mesh_nearest_vertex(&rt, rt.rest, s.contact[0].def.center)];
    const double lc = vnorm(pc);
    const double d[3] = {-pc.x / lc, -pc.y / lc, -pc.z / lc};
    palp_mesh_destroy(&rt);
    /* the load delivered */
    palp_fem_mesh fm;
    double *fext = NULL;
    char err[256];
    int rc = palp_fem_run_load(&cfg, &s, 0.5, &fm, &fext, err, sizeof err);
    CHECK(rc == 0, "%s map: palp_fem_run_load: %s", mname, err);
    if (rc) return;
    double sum[3] = {0, 0, 0}, on_clamp = 0.0;
    int clamped_touched = 0;
    for (int a = 0; a < fm.node_count; ++a)
      for (int k = 0; k < 3; ++k) {
        if (fm.fixed[a]) on_clamp += fabs(fext[3 * a + k]); /* the residual ignores it: lost */
        else sum[k] += fext[3 * a + k];
      }
    /* the case is meaningful only if the map does reach the base's ring of nodes */
    for (int e = 0; e < fm.element_count; ++e)
      for (int c = 0; c < 8; ++c) {
        const int a = fm.hex[e][c];
        if (!fm.fixed[a]) continue;
        for (int c2 = 0; c2 < 8; ++c2)
          if (fext[3 * fm.hex[e][c2]] != 0.0 || fext[3 * fm.hex[e][c2] + 2] != 0.0) clamped_touched = 1;
      }
    const double miss = sqrt((sum[0] - F * d[0]) * (sum[0] - F * d[0]) + (sum[1] - F * d[1]) * (sum[1] - F * d[1]) +
                             (sum[2] - F * d[2]) * (sum[2] - F * d[2]));
    printf("rim load (%s map): delivered (%.4f %.4f %.4f) N, scene F d = (%.4f %.4f %.4f) N, |diff| %.2e N, on "
           "clamped nodes %.2e N\n",
           mname, sum[0], sum[1], sum[2], F * d[0], F * d[1], F * d[2], miss, on_clamp);
    CHECK(clamped_touched, "%s map: the 86 deg contact loads an element with clamped nodes (else the case tests "
          "nothing)", mname);
    CHECK(miss <= 0.01 * F, "%s map: delivered load within 1%% of the scene's %.1f N (|diff| %.4f N)", mname, F, miss);
    CHECK(on_clamp == 0.0, "%s map: no load on clamped nodes (%.3g N)", mname, on_clamp);
    free(fext);
    palp_fem_mesh_destroy(&fm);
    /* the feedback */
    measured m = run(&cfg, &s);
    report(mname, &m);
    CHECK(m.rc == 0, "%s map: run failed: %s", mname, m.err);
    if (m.rc == 0) {
      const int f = 99; /* t = 1.0 s */
      double fb[3] = {0, 0, 0};
      for (int k = 0; k < m.r.contact_vertex_count; ++k) {
        const palp_vec3 v = m.r.feedback[(size_t)f * (size_t)m.r.contact_vertex_count + (size_t)k];
        fb[0] += v.x, fb[1] += v.y, fb[2] += v.z;
      }
      const double e = sqrt((fb[0] + F * d[0]) * (fb[0] + F * d[0]) + (fb[1] + F * d[1]) * (fb[1] + F * d[1]) +
                            (fb[2] + F * d[2]) * (fb[2] + F * d[2]));
      printf("rim feedback (%s map) at 1.0 s: (%.4f %.4f %.4f) N, expected -F d = (%.4f %.4f %.4f) N, |diff| %.4f N\n",
             mname, fb[0], fb[1], fb[2], -F * d[0], -F * d[1], -F * d[2], e);
      CHECK(e <= 0.05 * F, "%s map: summed feedback within 5%% of -F d (|diff| %.4f N, bound %.3f N)", mname, e,
            0.05 * F);
    }
    done(&m);
  }
}

/* Several fingers at once: three contacts of different kinds and times (3 N
 * gaussian at 20 deg from 0 to 0.5 s, 3 N uniform at 35 deg from 0.1 to 0.4 s,
 * 2 N single at 50 deg from 0.2 to 0.5 s). While all three press, each contact's
 * summed feedback pushes the finger back with its applied force within 10% (near
 * equilibrium: the creep transient is mostly over, inertia is negligible). */
static void case_multi(void) {
  palp_scene s;
  if (base_scene(&s, 150)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_GAUSSIAN, 20, 0, 3.0, 0.0, 0.5);
  set_contact(&s, 1, PALP_DIST_UNIFORM, 35, 120, 3.0, 0.1, 0.4);
  set_contact(&s, 2, PALP_DIST_SINGLE, 50, 240, 2.0, 0.2, 0.5);
  const palp_fem_config cfg = fast_config(1);
  measured m = run(&cfg, &s);
  stable("three contacts at once, level 1", &m, 1.5, 0.10);
  if (m.rc == 0) {
    const int f = 34; /* t = 0.35 s: all three on */
    double push[3] = {0, 0, 0};
    for (int k = 0; k < m.r.contact_vertex_count; ++k) {
      const int c = m.r.contact_of[k];
      const palp_vec3 fb = m.r.feedback[(size_t)f * (size_t)m.r.contact_vertex_count + (size_t)k];
      const palp_vec3 n = s.contact[c].def.center;
      push[c] += (fb.x * n.x + fb.y * n.y + fb.z * n.z) / vnorm(n);
    }
    printf("  outward feedback at 0.35 s: %.3f / %.3f / %.3f N (applied 3 / 3 / 2 N)\n", push[0], push[1], push[2]);
    const double applied[3] = {3.0, 3.0, 2.0};
    for (int c = 0; c < 3; ++c)
      CHECK(fabs(push[c] - applied[c]) < 0.1 * applied[c],
            "contact %d: outward feedback %.3f N within 10%% of the applied %.1f N", c, push[c], applied[c]);
  }
  done(&m);
}

/* Relaxation times far shorter than the step: both Prony taus 0.1 ms at a 10 ms
 * step (dt / tau = 100). The recursive update is unconditionally stable; the
 * creep times tau / g_inf become ~10 ms, so 0.3 s after release the phantom is
 * back within 5% of its peak. */
static void case_fasttau(void) {
  palp_scene s;
  if (base_scene(&s, 100)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 3.0, 0.0, 0.5);
  palp_fem_config cfg = fast_config(1);
  for (int k = 0; k < cfg.gel.prony_count; ++k) cfg.gel.tau[k] = 1e-4;
  for (int k = 0; k < cfg.membrane.prony_count; ++k) cfg.membrane.tau[k] = 1e-4;
  measured m = run(&cfg, &s);
  stable("Prony taus 0.1 ms at a 10 ms step, level 1", &m, 0.8, 0.05);
  done(&m);
}

/* A very stiff membrane (C10 x 100: 70 MPa relaxed) on a very soft gel (C10 / 100:
 * 103 Pa relaxed, K/mu = 1e7): 3 N uniform held 0.5 s. */
static void case_stiffsoft(void) {
  for (int inst = 0; inst <= 1; ++inst) {
    palp_scene s;
    if (base_scene(&s, 150)) {
      CHECK(0, "scene %s", scene_path);
      return;
    }
    set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 3.0, 0.0, 0.5);
    palp_fem_config cfg = fast_config(1);
    cfg.membrane.c10 *= 100.0;
    cfg.gel.c10 /= 100.0;
    /* the instantaneous reading: gel relaxed C10 = 1.03 Pa, K/mu = 1e9 */
    if (inst) cfg.c10_reading = PALP_FEM_C10_INSTANTANEOUS;
    measured m = run(&cfg, &s);
    stable(inst ? "stiff membrane x100, soft gel /100, instantaneous" : "stiff membrane x100, soft gel /100, long-term",
           &m, 1.5, 0.10);
    done(&m);
  }
}

/* Hard steps at dt = frame period (a step larger than the frame is not allowed):
 * (1) 30 N with no ramp on level 2 under the long-term reading, held 0.2 s, 40
 *     frames: completes; without cut-backs exactly one step per frame; 0.2 s after
 *     release below 50% of the peak (slowest creep time 0.5 s: exp(-0.4) = 67% of
 *     the creep part, the elastic part returns at once).
 * (2) 30 N with no ramp on level 1 under the instantaneous reading (relaxed gel
 *     mu = 206 Pa under 58 kPa of pressure: the tangent goes indefinite, see
 *     docs/fem.md), held 0.2 s, 30 frames: the 10 ms step cannot be solved in 12
 *     Newton iterations, so the solver must cut back (and count it), then finish
 *     with every value finite, the displacement below the diameter and the volume
 *     kept within 1%. The displacement is not checked after release (the run ends 0.1 s
 *     after it, far inside the creep time). */
static void case_cutback(void) {
  palp_scene s;
  if (base_scene(&s, 40)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.2);
  palp_fem_config cfg = fast_config(2);
  cfg.dt = 0.0; /* one step per 10 ms frame */
  measured m = run(&cfg, &s);
  stable("30 N step at dt = 10 ms, level 2", &m, 0.4, 0.5);
  if (m.rc == 0)
    CHECK(m.r.steps >= m.r.frames && (m.r.cutbacks > 0 || m.r.steps == m.r.frames),
          "one step per frame unless cut back: %ld steps for %d frames, %ld cut-backs", m.r.steps, m.r.frames,
          m.r.cutbacks);
  done(&m);

  palp_scene s1;
  if (base_scene(&s1, 30)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s1, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.2);
  palp_fem_config inst = fast_config(1);
  inst.c10_reading = PALP_FEM_C10_INSTANTANEOUS;
  measured b = run(&inst, &s1);
  report("30 N step, instantaneous reading, level 1", &b);
  CHECK(b.rc == 0, "instantaneous 30 N: completes (%d: %s)", b.rc, b.err);
  if (b.rc == 0) {
    /* Far outside the faithful range (the pole sinks by ~3/4 of the 40 mm height and
     * the gel flows sideways), so the bound is the phantom's diameter, 80 mm: no
     * material point may leave a region twice the phantom's size. */
    CHECK(b.finite && b.peak > 0 && b.peak < 2 * R,
          "instantaneous 30 N: finite, peak %.2f mm below the diameter 80 mm", 1e3 * b.peak);
    CHECK(b.max_dv < 0.01, "instantaneous 30 N: enclosed volume within 1%% of rest (max %.4f%%)", 100 * b.max_dv);
    CHECK(b.r.cutbacks > 0 && b.r.steps > b.r.frames,
          "instantaneous 30 N: the hard step is cut back and counted (%ld cut-backs, %ld steps for %d frames)",
          b.r.cutbacks, b.r.steps, b.r.frames);
  }
  done(&b);
}

/* The cut-back path gives the same answer, and a solver that cannot go on says so:
 * (1) 30 N step at level 1 (long-term), 60 frames, with max_newton = 2 instead of
 *     12: some steps of the unramped load need 3 iterations, so they are cut back
 *     (counted), and the top peak agrees with the unrestricted run within 2%
 *     (max_newton was 4 while a step took 3-5 iterations; since the solve of the
 *     second iterate aims at the tolerance, most take 2 and none needed 5)
 *     (halved steps change the time discretisation, not the equilibrium).
 * (2) the same with 1 Newton iteration and no cut-back: fails at once with a
 *     negative code and a message naming the time, never NaN, never hangs. */
static void case_newton(void) {
  palp_scene s;
  if (base_scene(&s, 60)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.2);
  const palp_fem_config full = fast_config(1);
  palp_fem_config tight = full;
  tight.max_newton = 2;
  measured a = run(&full, &s), b = run(&tight, &s);
  report("30 N, max_newton 12, level 1", &a);
  report("30 N, max_newton 2, level 1", &b);
  CHECK(a.rc == 0 && b.rc == 0, "both runs complete (%d: %s; %d: %s)", a.rc, a.err, b.rc, b.err);
  if (a.rc == 0 && b.rc == 0) {
    CHECK(a.finite && b.finite, "finite");
    CHECK(b.r.cutbacks > 0 && b.r.steps > b.r.frames, "max_newton 2: steps cut back and counted (%ld, %ld steps)",
          b.r.cutbacks, b.r.steps);
    CHECK(fabs(b.top_peak - a.top_peak) < 0.02 * a.top_peak,
          "cut-back run's top peak %.4f mm within 2%% of the unrestricted %.4f mm", 1e3 * b.top_peak,
          1e3 * a.top_peak);
  }
  done(&a);
  done(&b);

  palp_scene s1;
  if (base_scene(&s1, 10)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s1, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.2);
  palp_fem_config starved = fast_config(1);
  starved.max_newton = 1;
  starved.max_cutbacks = 0;
  measured c = run(&starved, &s1);
  report("30 N, 1 Newton iteration, no cut-back", &c);
  CHECK(c.rc < 0 && c.err[0] && strstr(c.err, "t = "),
        "starved solver: fails with a negative code (%d) and a message naming the time (\"%s\")", c.rc, c.err);
  done(&c);
}

/* Steps of another size: the FE step must divide the 10 ms frame.
 * (1) dt = 3 ms does not: refused up front with PALP_EINVAL and a message, no run.
 * (2) 30 N step, level 1, held 0.3 s, at dt = 10 ms and dt = 5 ms: the displacement
 *     at the end of the hold (0.3 s, a creep state: creep times 0.2-0.5 s >> dt)
 *     agrees within 5% between the two, and both stay finite and keep their volume.
 *     The ringing right after the unramped step is not compared: its period is a
 *     few ms, so each dt samples it differently. */
static void case_dt(void) {
  palp_scene s;
  if (base_scene(&s, 40)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 30.0, 0.0, 0.3);
  palp_fem_config bad = fast_config(1);
  bad.dt = 0.003;
  measured x = run(&bad, &s);
  report("dt = 3 ms (does not divide 10 ms)", &x);
  CHECK(x.rc == PALP_EINVAL && strstr(x.err, "divide"), "dt = 3 ms refused with PALP_EINVAL (%d) and a message (\"%s\")",
        x.rc, x.err);
  done(&x);

  palp_fem_config c10 = fast_config(1), c5 = fast_config(1);
  c5.dt = 0.005;
  measured a = run(&c10, &s), b = run(&c5, &s);
  report("30 N, dt = 10 ms, level 1", &a);
  report("30 N, dt = 5 ms, level 1", &b);
  CHECK(a.rc == 0 && b.rc == 0, "both complete (%s; %s)", a.err, b.err);
  if (a.rc == 0 && b.rc == 0) {
    const double da = vnorm(a.r.top_disp[29]), db = vnorm(b.r.top_disp[29]);
    printf("  top displacement at 0.30 s: %.4f mm (10 ms) vs %.4f mm (5 ms)\n", 1e3 * da, 1e3 * db);
    CHECK(a.finite && b.finite && a.max_dv < 0.01 && b.max_dv < 0.01, "finite, volume within 1%% (%.4f%%, %.4f%%)",
          100 * a.max_dv, 100 * b.max_dv);
    CHECK(fabs(da - db) < 0.05 * db, "top displacement at 0.3 s: 10 ms %.4f mm within 5%% of 5 ms %.4f mm", 1e3 * da,
          1e3 * db);
  }
  done(&a);
  done(&b);
}

/* The FE solid itself (not the mapped surface): a 30 N vertical load with no ramp
 * on the level-1 model's surface nodes around the pole (weights exp(-r^2 / s^2),
 * s = 1 cm, summing to exactly 30 N), held 0.2 s, then 0.3 s free, dt = 10 ms,
 * under both readings. Measured at every step: the deformed FE volume (sum over
 * hexahedra of the 2x2x2-Gauss integral of det(dx/dxi), exact for trilinear
 * hexahedra) and the kinetic energy 1/2 sum m_a |v_a|^2.
 *   - volume within 0.1% of the undeformed mesh: J - 1 = p / K, and even 200 kPa
 *     of pressure (30 N on 1.5 cm^2) against K = 2 GPa gives 1e-4;
 *   - finite; long-term: the top node's displacement below the radius and no node
 *     below the base plane z = 0 (tolerance 0.1 mm);
 *   - energy: once released, the Prony series dissipates and average-acceleration
 *     Newmark adds none; the motion left is creep, whose velocity decays at least
 *     as fast as the slowest creep time 0.5 s allows, so the kinetic energy (its
 *     square) 0.3 s after release is below exp(-2 x 0.3 / 0.5) = 30% of its peak
 *     after release;
 *   - long-term reading: the top node back below 50% of its peak 0.3 s after release
 *     (slowest creep time 0.5 s). The instantaneous reading's creep is not over
 *     then (its displacement is ~60x larger for the same creep times), and 30 N
 *     is far outside its faithful range: the bound is the diameter, 80 mm. Its
 *     lowest node is printed, not asserted: the model has no contact with the
 *     support, and this load pushes the pole through the base plane (see the
 *     "Hard cases" section of docs/fem.md). */
static double fe_volume(const palp_fem_mesh *mesh, const double *u) {
  double vol = 0.0;
  for (int e = 0; e < mesh->element_count; ++e)
    for (int g = 0; g < 8; ++g) {
      double dN[8][3], J[3][3] = {{0}};
      palp_fem_hex_dshape(palp_fem_gauss[g], dN);
      for (int a = 0; a < 8; ++a) {
        const int n = mesh->hex[e][a];
        for (int i = 0; i < 3; ++i)
          for (int k = 0; k < 3; ++k) J[i][k] += (mesh->x[n][i] + u[3 * n + i]) * dN[a][k];
      }
      vol += J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
             J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    }
  return vol;
}

static void case_fevolume(void) {
  for (int inst = 0; inst <= 1; ++inst) {
    palp_fem_config cfg = fast_config(1);
    if (inst) cfg.c10_reading = PALP_FEM_C10_INSTANTANEOUS;
    palp_fem_mesh mesh;
    palp_fem_model m;
    if (palp_fem_mesh_create(&cfg.mesh, &mesh)) {
      CHECK(0, "mesh");
      return;
    }
    if (palp_fem_model_create(&m, &mesh, &cfg) || palp_fem_model_finalize(&m)) {
      CHECK(0, "model: %s", m.err);
      palp_fem_mesh_destroy(&mesh);
      return;
    }
    const double t0 = now();
    double *f = calloc((size_t)m.ndof, sizeof(double)), *zero = calloc((size_t)m.ndof, sizeof(double));
    const palp_fem_set *surf = palp_fem_mesh_find_set(&mesh, "SURFACE", 0);
    double wsum = 0.0;
    const double sw = 0.01; /* [m] */
    for (int i = 0; surf && i < surf->count; ++i) {
      const double *x = mesh.x[surf->items[i]];
      if (!mesh.fixed[surf->items[i]]) wsum += exp(-(x[0] * x[0] + x[1] * x[1]) / (sw * sw));
    }
    for (int i = 0; surf && i < surf->count; ++i) {
      const double *x = mesh.x[surf->items[i]];
      if (!mesh.fixed[surf->items[i]]) f[3 * surf->items[i] + 2] = -30.0 * exp(-(x[0] * x[0] + x[1] * x[1]) / (sw * sw)) / wsum;
    }
    double V0 = 0.0;
    {
      double *u0 = calloc((size_t)m.ndof, sizeof(double));
      V0 = fe_volume(&mesh, u0);
      free(u0);
    }
    double max_dv = 0.0, top_peak = 0.0, ke_peak = 0.0, ke_end = 0.0, ke_tail = 0.0, top_end = 0.0, zmin = INFINITY;
    int rc = 0, finite = 1;
    const int hold = 20, total = 50;
    for (int k = 0; k < total && rc == 0; ++k) {
      rc = palp_fem_step(&m, k < hold ? f : zero, 0.01);
      if (rc) break;
      const double dv = fabs(fe_volume(&mesh, m.u) / V0 - 1.0);
      if (!(dv <= max_dv)) max_dv = dv;
      double ke = 0.0;
      for (int d = 0; d < m.ndof; ++d) {
        ke += 0.5 * m.mass[d / 3] * m.v[d] * m.v[d];
        if (!isfinite(m.u[d]) || !isfinite(m.v[d])) finite = 0;
      }
      const int tn = mesh.top_node;
      const double top = sqrt(m.u[3 * tn] * m.u[3 * tn] + m.u[3 * tn + 1] * m.u[3 * tn + 1] + m.u[3 * tn + 2] * m.u[3 * tn + 2]);
      if (!(top <= top_peak)) top_peak = top;
      if (k >= hold && !(ke <= ke_peak)) ke_peak = ke;
      ke_end = ke, top_end = top;
      if (k >= total - 10) ke_tail += ke / 10.0; /* mean over the last 10 steps (0.1 s) */
      for (int n = 0; n < mesh.node_count; ++n)
        if (!(mesh.x[n][2] + m.u[3 * n + 2] >= zmin)) zmin = mesh.x[n][2] + m.u[3 * n + 2];
    }
    const char *name = inst ? "FE solid, 30 N at the pole, instantaneous" : "FE solid, 30 N at the pole, long-term";
    printf("%-44s top peak %.4f mm, 0.3 s after release %.4f mm, max FE volume change %.2e, kinetic energy after "
           "release peak %.3g J, at the end %.3g J, lowest node z %.3f mm, steps %ld, cut-backs %ld, wall %.2f s\n",
           name, 1e3 * top_peak, 1e3 * top_end, max_dv, ke_peak, ke_end, 1e3 * zmin, m.steps, m.cutbacks,
           now() - t0);
    CHECK(rc == 0, "%s: every step completes (%d: %s)", name, rc, m.err);
    if (rc == 0) {
      CHECK(finite && top_peak > 0 && top_peak < (inst ? 2 * R : R), "%s: finite, top peak %.3f mm below the %s",
            name, 1e3 * top_peak, inst ? "diameter 80 mm" : "radius 40 mm");
      if (!inst)
        CHECK(zmin > -1e-4, "%s: no node below the base plane (lowest z %.3f mm, tolerance -0.1 mm)", name,
              1e3 * zmin);
      CHECK(max_dv < 1e-3, "%s: FE volume within 0.1%% of the undeformed mesh (max %.2e)", name, max_dv);
      /* Long-term: the ringing decays with the creep. Instantaneous (the pole pushed
       * 18 mm through the base, outside the faithful range): the kinetic energy
       * hovers at 2-5e-5 J after a spike at release whose height, and the last
       * step's sample of the 2-3-step ringing, change 2x with round-off (23%, 31%,
       * 52% of the spike for three builds with identical formulas), so the 30%
       * decay is asserted only for the long-term reading; both must not gain
       * energy: the mean over the last 0.1 s below the post-release peak. */
      if (!inst)
        CHECK(ke_end < 0.3 * ke_peak, "%s: kinetic energy 0.3 s after release %.3g J below 30%% of its peak %.3g J",
              name, ke_end, ke_peak);
      CHECK(ke_tail < ke_peak, "%s: mean kinetic energy of the last 0.1 s %.3g J below its post-release peak %.3g J",
            name, ke_tail, ke_peak);
      if (!inst)
        CHECK(top_end < 0.5 * top_peak, "%s: 0.3 s after release %.4f mm below 50%% of the peak %.4f mm", name,
              1e3 * top_end, 1e3 * top_peak);
    }
    free(f);
    free(zero);
    palp_fem_model_destroy(&m);
    palp_fem_mesh_destroy(&mesh);
  }
}

/* A longer run without drift: 400 frames at level 1, the paper's 3 N press twice
 * (keyframes: press 0-1 s, release, press 2-3 s, release). The displacement 1 s
 * after the second release is within 2% of the first press's peak of the one 1 s
 * after the first release, and both are below 5% of the peak. */
static void case_twice(void) {
  palp_scene s;
  if (base_scene(&s, 400)) {
    CHECK(0, "scene %s", scene_path);
    return;
  }
  set_contact(&s, 0, PALP_DIST_UNIFORM, 30, 40, 3.0, 0.0, 1.0);
  palp_profile *p = &s.contact[0].profile;
  const double kt[] = {0.0, 0.999, 1.0, 1.999, 2.0, 2.999, 3.0};
  const double kf[] = {3.0, 3.0, 0.0, 0.0, 3.0, 3.0, 0.0};
  p->kind = PALP_PROFILE_KEYFRAMES;
  p->key_count = 7;
  for (int i = 0; i < 7; ++i) p->key_t[i] = kt[i], p->key_f[i] = kf[i];
  const palp_fem_config cfg = fast_config(1);
  measured m = run(&cfg, &s);
  stable("3 N pressed twice, 400 frames, level 1", &m, 4.0, 0.05);
  if (m.rc == 0) {
    const double d1 = disp_at(&m, 2.0), d2 = disp_at(&m, 4.0);
    double p1 = 0.0, p2 = 0.0;
    for (int f = 0; f < 200; ++f) p1 = fmax(p1, frame_max(&m.r, f));
    for (int f = 200; f < 400; ++f) p2 = fmax(p2, frame_max(&m.r, f));
    printf("  first press peak %.4f mm, 1 s after release %.5f mm; second %.4f mm, %.5f mm\n", 1e3 * p1, 1e3 * d1,
           1e3 * p2, 1e3 * d2);
    CHECK(fabs(d2 - d1) < 0.02 * p1, "rest state drift %.5f mm below 2%% of the peak %.4f mm", 1e3 * fabs(d2 - d1),
          1e3 * p1);
    CHECK(fabs(p2 - p1) < 0.02 * p1, "second peak %.4f mm within 2%% of the first %.4f mm", 1e3 * p2, 1e3 * p1);
  }
  done(&m);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s force30|point|rim|rimload|multi|fasttau|stiffsoft|cutback|newton|dt|fevolume|twice [SCENE]\n", argv[0]);
    return 2;
  }
  if (argc > 2) scene_path = argv[2];
  static const struct {
    const char *name;
    void (*fn)(void);
  } cases[] = {{"force30", case_force30}, {"point", case_point},         {"rim", case_rim}, {"rimload", case_rimload},
               {"multi", case_multi},     {"fasttau", case_fasttau},     {"stiffsoft", case_stiffsoft},
               {"cutback", case_cutback}, {"newton", case_newton},   {"dt", case_dt}, {"fevolume", case_fevolume}, {"twice", case_twice}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
    if (!strcmp(argv[1], cases[i].name)) {
      const double t0 = now();
      cases[i].fn();
      printf("case %s: %.2f s wall, %s\n", argv[1], now() - t0, fem_failures ? "FAILED" : "passed");
      return fem_failures ? 1 : 0;
    }
  fprintf(stderr, "unknown case \"%s\"\n", argv[1]);
  return 2;
}
