/*
 * fem_cache.c - FE reference results on disk, keyed by a hash of every input.
 *
 * One file per key, <dir>/<16 hex digits>.femr: a fixed header (magic, layout
 * version, key, sizes, run statistics) followed by the arrays in native byte
 * order (the cache is local to the machine that computed it). A result is
 * written to a temporary file, flushed and renamed, so a crash never leaves a
 * truncated entry under a valid name; a file that does not match its header is
 * treated as a miss and recomputed.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fem_internal.h"

#define MAGIC "PALPFEMR"
#define LAYOUT 1u

typedef struct header {
  char magic[8];
  uint32_t layout;
  uint32_t pad;
  uint64_t key;
  int32_t frames, vertex_count, top_vertex, contact_vertex_count;
  int32_t node_count, element_count, dof_count, pad2;
  int64_t steps, newton_iterations, cutbacks, factorizations, pcg_iterations;
  double wall_seconds;
} header;

static int mkdirs(const char *dir) {
  char p[1024];
  if (snprintf(p, sizeof p, "%s", dir) >= (int)sizeof p) return PALP_EINVAL;
  for (char *c = p + 1; *c; ++c)
    if (*c == '/') {
      *c = 0;
      if (mkdir(p, 0777) != 0 && errno != EEXIST) return PALP_EIO;
      *c = '/';
    }
  if (mkdir(p, 0777) != 0 && errno != EEXIST) return PALP_EIO;
  return PALP_OK;
}

static void path_of(const char *dir, uint64_t key, char *out, size_t cap) {
  snprintf(out, cap, "%s/%016llx.femr", dir, (unsigned long long)key);
}

int palp_fem_cache_store(const char *dir, const palp_fem_result *r) {
  if (!dir || !dir[0]) return PALP_EINVAL;
  int rc = mkdirs(dir);
  if (rc) return rc;
  char path[1100], tmp[1200];
  path_of(dir, r->key, path, sizeof path);
  snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
  FILE *f = fopen(tmp, "wb");
  if (!f) return PALP_EIO;
  header h;
  memset(&h, 0, sizeof h);
  memcpy(h.magic, MAGIC, 8);
  h.layout = LAYOUT;
  h.key = r->key;
  h.frames = r->frames, h.vertex_count = r->vertex_count, h.top_vertex = r->top_vertex;
  h.contact_vertex_count = r->contact_vertex_count;
  h.node_count = r->node_count, h.element_count = r->element_count, h.dof_count = r->dof_count;
  h.steps = r->steps, h.newton_iterations = r->newton_iterations, h.cutbacks = r->cutbacks;
  h.factorizations = r->factorizations, h.pcg_iterations = r->pcg_iterations;
  h.wall_seconds = r->wall_seconds;
  const size_t F = (size_t)r->frames, V = (size_t)r->vertex_count, C = (size_t)r->contact_vertex_count;
  int ok = fwrite(&h, sizeof h, 1, f) == 1;
  ok = ok && fwrite(r->time, sizeof(double), F, f) == F;
  ok = ok && fwrite(r->disp, sizeof(palp_vec3), F * V, f) == F * V;
  ok = ok && fwrite(r->top_disp, sizeof(palp_vec3), F, f) == F;
  ok = ok && (C == 0 || fwrite(r->contact_vertex, sizeof(int), C, f) == C);
  ok = ok && (C == 0 || fwrite(r->contact_of, sizeof(int), C, f) == C);
  ok = ok && (C == 0 || fwrite(r->feedback, sizeof(palp_vec3), F * C, f) == F * C);
  ok = ok && fflush(f) == 0 && fsync(fileno(f)) == 0;
  ok = (fclose(f) == 0) && ok;
  if (!ok || rename(tmp, path) != 0) {
    remove(tmp);
    return PALP_EIO;
  }
  return PALP_OK;
}

int palp_fem_cache_load(const char *dir, uint64_t key, palp_fem_result *out) {
  if (!dir || !dir[0]) return PALP_EINVAL;
  char path[1100];
  path_of(dir, key, path, sizeof path);
  FILE *f = fopen(path, "rb");
  if (!f) return PALP_EIO;
  header h;
  memset(out, 0, sizeof *out);
  int ok = fread(&h, sizeof h, 1, f) == 1 && memcmp(h.magic, MAGIC, 8) == 0 && h.layout == LAYOUT && h.key == key &&
           h.frames > 0 && h.vertex_count > 0 && h.contact_vertex_count >= 0 && h.frames < (1 << 24) &&
           h.vertex_count < (1 << 24);
  if (ok) {
    const size_t F = (size_t)h.frames, V = (size_t)h.vertex_count, C = (size_t)h.contact_vertex_count;
    out->time = malloc(sizeof(double) * F);
    out->disp = malloc(sizeof(palp_vec3) * F * V);
    out->top_disp = malloc(sizeof(palp_vec3) * F);
    out->contact_vertex = malloc(sizeof(int) * (C ? C : 1));
    out->contact_of = malloc(sizeof(int) * (C ? C : 1));
    out->feedback = malloc(sizeof(palp_vec3) * (C ? F * C : 1));
    ok = out->time && out->disp && out->top_disp && out->contact_vertex && out->contact_of && out->feedback;
    ok = ok && fread(out->time, sizeof(double), F, f) == F;
    ok = ok && fread(out->disp, sizeof(palp_vec3), F * V, f) == F * V;
    ok = ok && fread(out->top_disp, sizeof(palp_vec3), F, f) == F;
    ok = ok && (C == 0 || fread(out->contact_vertex, sizeof(int), C, f) == C);
    ok = ok && (C == 0 || fread(out->contact_of, sizeof(int), C, f) == C);
    ok = ok && (C == 0 || fread(out->feedback, sizeof(palp_vec3), F * C, f) == F * C);
    ok = ok && fgetc(f) == EOF;
    out->frames = h.frames, out->vertex_count = h.vertex_count, out->top_vertex = h.top_vertex;
    out->contact_vertex_count = h.contact_vertex_count;
    out->node_count = h.node_count, out->element_count = h.element_count, out->dof_count = h.dof_count;
    out->steps = h.steps, out->newton_iterations = h.newton_iterations, out->cutbacks = h.cutbacks;
    out->factorizations = h.factorizations, out->pcg_iterations = h.pcg_iterations;
    out->wall_seconds = h.wall_seconds;
    out->key = key;
    out->from_cache = 1;
  }
  fclose(f);
  if (!ok) {
    palp_fem_result_destroy(out);
    return PALP_EIO;
  }
  return PALP_OK;
}

void palp_fem_result_destroy(palp_fem_result *r) {
  if (!r) return;
  free(r->time);
  free(r->disp);
  free(r->top_disp);
  free(r->contact_vertex);
  free(r->contact_of);
  free(r->feedback);
  memset(r, 0, sizeof *r);
}
