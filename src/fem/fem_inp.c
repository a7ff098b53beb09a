/*
 * fem_inp.c - Abaqus .inp exchange of the hexahedral mesh.
 *
 * Written: *HEADING, *NODE (ids 1..N, coordinates in m with 17 significant
 * digits, so a round trip is exact), *ELEMENT TYPE=C3D8 (ids 1..E), then every
 * node and element set. Read: the same keywords from any C3D8-family file
 * (C3D8, C3D8R, C3D8H, C3D8I ...; other element types are refused with a message),
 * arbitrary ids, continuation lines, "GENERATE" sets; other keywords (materials,
 * steps, ...) are skipped. Lines starting with "**" are comments.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem_internal.h"
#include "palp_input_file.h"

int palp_fem_inp_write(const palp_fem_mesh *m, const char *path, const char *heading) {
  char tmp[1024];
  if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp) return PALP_EINVAL;
  FILE *f = fopen(tmp, "w");
  if (!f) return PALP_EIO;
  fprintf(f, "*HEADING\n%s\n** units: m, kg, s; written by palp-fem\n", heading ? heading : "palp phantom");
  fprintf(f, "*NODE\n");
  for (int n = 0; n < m->node_count; ++n)
    fprintf(f, "%d, %.17g, %.17g, %.17g\n", n + 1, m->x[n][0], m->x[n][1], m->x[n][2]);
  fprintf(f, "*ELEMENT, TYPE=C3D8\n");
  for (int e = 0; e < m->element_count; ++e) {
    fprintf(f, "%d", e + 1);
    for (int a = 0; a < 8; ++a) fprintf(f, ", %d", m->hex[e][a] + 1);
    fprintf(f, "\n");
  }
  for (int s = 0; s < m->set_count; ++s) {
    const palp_fem_set *set = &m->sets[s];
    fprintf(f, "*%s, %s=%s\n", set->is_element ? "ELSET" : "NSET", set->is_element ? "ELSET" : "NSET", set->name);
    for (int i = 0; i < set->count; ++i)
      fprintf(f, "%d%s", set->items[i] + 1, (i % 16 == 15 || i == set->count - 1) ? "\n" : ", ");
  }
  const int bad = ferror(f);
  if (fclose(f) != 0 || bad) {
    remove(tmp);
    return PALP_EIO;
  }
  if (rename(tmp, path) != 0) {
    remove(tmp);
    return PALP_EIO;
  }
  return PALP_OK;
}

/* ---- reading -------------------------------------------------------------- */
typedef struct id_index {
  long id;
  int index;
} id_index;

static int cmp_id(const void *a, const void *b) {
  const long x = ((const id_index *)a)->id, y = ((const id_index *)b)->id;
  return (x > y) - (x < y);
}

static int lookup(const id_index *t, int n, long id) {
  int lo = 0, hi = n - 1;
  while (lo <= hi) {
    const int mid = (lo + hi) / 2;
    if (t[mid].id < id) lo = mid + 1;
    else if (t[mid].id > id) hi = mid - 1;
    else return t[mid].index;
  }
  return -1;
}

typedef struct raw_set {
  char name[32];
  int is_element;
  long *ids;
  int count, cap;
} raw_set;

typedef struct reader {
  double (*x)[3];
  long *node_id;
  int nn, ncap;
  long (*conn)[8];
  long *elem_id;
  int ne, ecap;
  raw_set *sets;
  int nsets, setcap;
  long members; /* set members over all sets together */
} reader;

/* Bounds on what a file may ask for (memory and time stay bounded whatever it says):
 * ids are whole numbers 1..INP_ID_MAX (Abaqus' own limit is 999,999,999); nodes,
 * elements, and set members counted over all sets together, are at most INP_COUNT_MAX
 * each; there are at most INP_SETS_MAX distinct sets. The members are capped in total,
 * not per set: a per-set cap let each of a few kB of distinct "GENERATE 1, 999999999, 100"
 * sets allocate 80 MB. The set cap bounds set_named's linear search (and the mesh's own
 * one-at-a-time set list); palp's meshes have 5 sets, Abaqus files from other tools tens. */
#define INP_ID_MAX 999999999.0
#define INP_COUNT_MAX 10000000
#define INP_SETS_MAX 1024
#define INP_COORD_MAX_M 1e3                /* [m]: a phantom is centimetres across */
#define INP_FILE_MAX ((size_t)1 << 28)    /* 256 MiB: the level-3 dome's file is ~10 MB */

/* An id read as a double: a whole number in 1..INP_ID_MAX, else an error. (Casting 1e19
 * to an integer is undefined behaviour and made distinct ids collide.) */
static int as_id(double v, long *out) {
  if (!(v >= 1 && v <= INP_ID_MAX) || v != floor(v)) return PALP_EPARSE;
  *out = (long)v;
  return 0;
}

static int push_id(reader *r, raw_set *s, long id) {
  if (r->members >= INP_COUNT_MAX) return PALP_EINVAL;
  if (s->count == s->cap) {
    const int cap = s->cap ? 2 * s->cap : 64;
    long *p = realloc(s->ids, sizeof(long) * (size_t)cap);
    if (!p) return PALP_ENOMEM;
    s->ids = p, s->cap = cap;
  }
  s->ids[s->count++] = id;
  r->members++;
  return 0;
}

/* Value of "KEY=value" among the keyword's parameters (case-insensitive), or NULL. */
static const char *param(const char *line, const char *key, char *out, size_t cap) {
  const size_t kl = strlen(key);
  for (const char *p = strchr(line, ','); p; p = strchr(p + 1, ',')) {
    const char *q = p + 1;
    while (*q == ' ' || *q == '\t') ++q;
    size_t i = 0;
    while (i < kl && q[i] && toupper((unsigned char)q[i]) == key[i]) ++i;
    if (i != kl) continue;
    q += kl;
    while (*q == ' ') ++q;
    if (*q != '=') {
      if (out && cap) out[0] = 0;
      return out; /* a flag such as GENERATE */
    }
    ++q;
    while (*q == ' ') ++q;
    size_t n = 0;
    while (*q && *q != ',' && *q != '\n' && *q != '\r' && n + 1 < cap) out[n++] = (char)toupper((unsigned char)*q++);
    while (n > 0 && out[n - 1] == ' ') --n;
    out[n] = 0;
    return out;
  }
  return NULL;
}

static void reader_free(reader *r) {
  free(r->x);
  free(r->node_id);
  free(r->conn);
  free(r->elem_id);
  for (int s = 0; s < r->nsets; ++s) free(r->sets[s].ids);
  free(r->sets);
}

/* The set of that name, created if new: 0, PALP_EINVAL past INP_SETS_MAX sets, PALP_ENOMEM. */
static int set_named(reader *r, const char *name, int is_element, raw_set **out) {
  for (int s = 0; s < r->nsets; ++s)
    if (r->sets[s].is_element == is_element && strcmp(r->sets[s].name, name) == 0) {
      *out = &r->sets[s];
      return 0;
    }
  if (r->nsets >= INP_SETS_MAX) return PALP_EINVAL;
  if (r->nsets == r->setcap) {
    const int cap = r->setcap ? 2 * r->setcap : 16;
    raw_set *p = realloc(r->sets, sizeof *p * (size_t)cap);
    if (!p) return PALP_ENOMEM;
    r->sets = p, r->setcap = cap;
  }
  raw_set *s = &r->sets[r->nsets++];
  memset(s, 0, sizeof *s);
  snprintf(s->name, sizeof s->name, "%s", name);
  s->is_element = is_element;
  *out = s;
  return 0;
}

/* Parses up to max comma-separated numbers; returns how many, -1 on junk. */
static int numbers(const char *line, double *v, int max) {
  int n = 0;
  const char *p = line;
  while (*p) {
    while (*p == ' ' || *p == '\t' || *p == ',') ++p;
    if (!*p || *p == '\n' || *p == '\r') break;
    if (n == max) return -1;
    char *end;
    errno = 0;
    v[n] = strtod(p, &end);
    if (end == p || errno == ERANGE || !isfinite(v[n])) return -1;
    ++n;
    p = end;
    while (*p == ' ' || *p == '\t') ++p;
    if (*p && *p != ',' && *p != '\n' && *p != '\r') return -1;
  }
  return n;
}

/* The first (1-based) of the 2x2x2 Gauss points of element e whose Jacobian determinant
 * is not positive, or 0. */
static int inverted_gauss_point(const palp_fem_mesh *mesh, int e) {
  for (int g = 0; g < 8; ++g) {
    double dN[8][3], J[3][3];
    if (!(palp_fem_hex_jacobian(mesh, e, g, dN, J) > 0.0)) return g + 1;
  }
  return 0;
}

int palp_fem_inp_read(const char *path, palp_fem_mesh *out, char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  /* Read whole and checked first (palp_input_file_read): a regular file (a FIFO hung the reader),
   * bounded, and without a NUL byte, which fgets took for a line's end and was then reported as "line
   * longer than 4095 characters" (session 81). */
  char *text = NULL, why[200];
  size_t len = 0;
  const int rd = palp_input_file_read(path, INP_FILE_MAX, &text, &len, why, sizeof why);
  if (rd) {
    snprintf(err, errlen, "%s: %s", path, why);
    return rd == PALP_ENOMEM ? rd : PALP_EIO;
  }
  FILE *f = len ? fmemopen(text, len, "r") : NULL;
  if (!f) {
    free(text);
    snprintf(err, errlen, "%s: %s", path, len ? "cannot read" : "empty");
    return len ? PALP_EIO : PALP_EPARSE;
  }
  reader r;
  memset(&r, 0, sizeof r);
  enum { NONE, NODE, ELEMENT, SET } mode = NONE;
  raw_set *cur = NULL;
  int generate = 0, lineno = 0, rc = 0;
  char line[4096];
  double pend[16];
  int npend = 0; /* element data continued over lines */
  while (!rc && fgets(line, sizeof line, f)) {
    ++lineno;
    if (!strchr(line, '\n') && !feof(f)) {
      snprintf(err, errlen, "%s:%d: line longer than %zu characters", path, lineno, sizeof line - 1);
      rc = PALP_EPARSE;
      break;
    }
    const char *s = line;
    while (*s == ' ' || *s == '\t') ++s;
    if (*s == 0 || *s == '\n' || *s == '\r' || (s[0] == '*' && s[1] == '*')) continue;
    if (*s == '*') {
      if (npend) {
        snprintf(err, errlen, "%s:%d: element data cut short", path, lineno);
        rc = PALP_EPARSE;
        break;
      }
      char kw[32];
      size_t k = 0;
      ++s;
      while (*s && *s != ',' && *s != '\n' && *s != '\r' && k + 1 < sizeof kw) kw[k++] = (char)toupper((unsigned char)*s++);
      while (k > 0 && kw[k - 1] == ' ') --k;
      kw[k] = 0;
      char val[64];
      mode = NONE;
      cur = NULL;
      if (strcmp(kw, "NODE") == 0) mode = NODE;
      else if (strcmp(kw, "ELEMENT") == 0) {
        if (!param(line, "TYPE", val, sizeof val) || strncmp(val, "C3D8", 4) != 0) {
          snprintf(err, errlen, "%s:%d: element type %s not supported (8-node hexahedra C3D8* only)", path, lineno,
                   param(line, "TYPE", val, sizeof val) ? val : "(none)");
          rc = PALP_EPARSE;
          break;
        }
        mode = ELEMENT;
        if (param(line, "ELSET", val, sizeof val) && val[0] && (rc = set_named(&r, val, 1, &cur)) == PALP_EINVAL)
          snprintf(err, errlen, "%s:%d: more than %d sets", path, lineno, INP_SETS_MAX);
      } else if (strcmp(kw, "NSET") == 0 || strcmp(kw, "ELSET") == 0) {
        const int is_el = kw[0] == 'E';
        if (!param(line, is_el ? "ELSET" : "NSET", val, sizeof val) || !val[0]) {
          snprintf(err, errlen, "%s:%d: *%s without a name", path, lineno, kw);
          rc = PALP_EPARSE;
          break;
        }
        if ((rc = set_named(&r, val, is_el, &cur)) == PALP_EINVAL)
          snprintf(err, errlen, "%s:%d: more than %d sets", path, lineno, INP_SETS_MAX);
        char flag[8];
        generate = param(line, "GENERATE", flag, sizeof flag) != NULL;
        mode = SET;
      }
      continue;
    }
    double v[16];
    const int n = numbers(s, v, 16);
    if (mode == NONE) continue;
    if (n < 0) {
      snprintf(err, errlen, "%s:%d: expected comma-separated numbers", path, lineno);
      rc = PALP_EPARSE;
      break;
    }
    if (mode == NODE) {
      if (n != 4 && n != 3) {
        snprintf(err, errlen, "%s:%d: a node needs an id and 3 coordinates", path, lineno);
        rc = PALP_EPARSE;
        break;
      }
      long nid;
      if (as_id(v[0], &nid)) {
        snprintf(err, errlen, "%s:%d: node id %.17g is not a whole number in 1..%.0f", path, lineno, v[0], INP_ID_MAX);
        rc = PALP_EPARSE;
        break;
      }
      /* A phantom is centimetres across: a coordinate beyond 1 km (or not finite) is a wrong file,
       * not a mesh, and its volumes overflowed to "degenerate (zero volume)" (session 81). */
      for (int c = 1; c < n; ++c)
        if (!(fabs(v[c]) <= INP_COORD_MAX_M)) {
          snprintf(err, errlen, "%s:%d: node %ld: coordinate %.17g is not a finite number within +-%.0f m", path,
                   lineno, nid, v[c], INP_COORD_MAX_M);
          rc = PALP_EPARSE;
          break;
        }
      if (rc) break;
      if (r.nn >= INP_COUNT_MAX) {
        snprintf(err, errlen, "%s:%d: more than %d nodes", path, lineno, INP_COUNT_MAX);
        rc = PALP_EINVAL;
        break;
      }
      if (r.nn == r.ncap) {
        r.ncap = r.ncap ? 2 * r.ncap : 1024;
        void *a = realloc(r.x, sizeof *r.x * (size_t)r.ncap), *b = realloc(r.node_id, sizeof(long) * (size_t)r.ncap);
        if (a) r.x = a;
        if (b) r.node_id = b;
        if (!a || !b) {
          rc = PALP_ENOMEM;
          break;
        }
      }
      r.node_id[r.nn] = nid;
      r.x[r.nn][0] = v[1], r.x[r.nn][1] = v[2], r.x[r.nn][2] = n == 4 ? v[3] : 0.0;
      r.nn++;
    } else if (mode == ELEMENT) {
      for (int i = 0; i < n && npend < 16; ++i) pend[npend++] = v[i];
      if (npend < 9) continue;
      if (npend > 9) {
        snprintf(err, errlen, "%s:%d: a C3D8 element needs an id and 8 nodes", path, lineno);
        rc = PALP_EPARSE;
        break;
      }
      long eid, conn[8];
      int bad = as_id(pend[0], &eid) ? 0 : -1;
      for (int a = 0; a < 8 && bad < 0; ++a)
        if (as_id(pend[a + 1], &conn[a])) bad = a + 1;
      if (bad >= 0) {
        snprintf(err, errlen, "%s:%d: element %s %.17g is not a whole number in 1..%.0f", path, lineno,
                 bad == 0 ? "id" : "node", pend[bad], INP_ID_MAX);
        rc = PALP_EPARSE;
        break;
      }
      if (r.ne >= INP_COUNT_MAX) {
        snprintf(err, errlen, "%s:%d: more than %d elements", path, lineno, INP_COUNT_MAX);
        rc = PALP_EINVAL;
        break;
      }
      if (r.ne == r.ecap) {
        r.ecap = r.ecap ? 2 * r.ecap : 1024;
        void *a = realloc(r.conn, sizeof *r.conn * (size_t)r.ecap), *b = realloc(r.elem_id, sizeof(long) * (size_t)r.ecap);
        if (a) r.conn = a;
        if (b) r.elem_id = b;
        if (!a || !b) {
          rc = PALP_ENOMEM;
          break;
        }
      }
      r.elem_id[r.ne] = eid;
      for (int a = 0; a < 8; ++a) r.conn[r.ne][a] = conn[a];
      if (cur && (rc = push_id(&r, cur, eid)) == PALP_EINVAL)
        snprintf(err, errlen, "%s:%d: more than %d set members (all sets together)", path, lineno, INP_COUNT_MAX);
      r.ne++;
      npend = 0;
    } else if (mode == SET) {
      long a = 0, b = 0, step = 1;
      if (generate) {
        /* Whole numbers, step >= 1, at most INP_COUNT_MAX members in all sets: a fractional
         * step (cast to 0) or a 1e12 range used to loop while memory grew without bound. */
        if (n < 2 || n > 3 || as_id(v[0], &a) || as_id(v[1], &b) || (n == 3 && as_id(v[2], &step)) || a > b) {
          snprintf(err, errlen, "%s:%d: GENERATE needs whole numbers start <= end in 1..%.0f[, step >= 1]", path,
                   lineno, INP_ID_MAX);
          rc = PALP_EPARSE;
          break;
        }
        if ((b - a) / step + 1 > INP_COUNT_MAX - r.members) {
          snprintf(err, errlen, "%s:%d: GENERATE %ld..%ld step %ld makes more than %d set members (all sets together)",
                   path, lineno, a, b, step, INP_COUNT_MAX);
          rc = PALP_EINVAL;
          break;
        }
        for (long id = a; !rc && id <= b; id += step) rc = push_id(&r, cur, id);
      } else
        for (int i = 0; !rc && i < n; ++i) {
          if (as_id(v[i], &a)) {
            snprintf(err, errlen, "%s:%d: set member %.17g is not a whole number in 1..%.0f", path, lineno, v[i],
                     INP_ID_MAX);
            rc = PALP_EPARSE;
            break;
          }
          if ((rc = push_id(&r, cur, a)) == PALP_EINVAL)
            snprintf(err, errlen, "%s:%d: more than %d set members (all sets together)", path, lineno, INP_COUNT_MAX);
        }
    }
  }
  fclose(f);
  free(text);
  if (!rc && (r.nn == 0 || r.ne == 0)) {
    snprintf(err, errlen, "%s: no *NODE or no C3D8 *ELEMENT data", path);
    rc = PALP_EPARSE;
  }
  id_index *nt = NULL, *et = NULL;
  if (!rc) {
    nt = malloc(sizeof *nt * (size_t)r.nn);
    et = malloc(sizeof *et * (size_t)r.ne);
    out->x = malloc(sizeof *out->x * (size_t)r.nn);
    out->hex = malloc(sizeof *out->hex * (size_t)r.ne);
    out->region = calloc((size_t)r.ne, 1);
    out->fixed = calloc((size_t)r.nn, 1);
    if (!nt || !et || !out->x || !out->hex || !out->region || !out->fixed) rc = PALP_ENOMEM;
  }
  if (!rc) {
    for (int i = 0; i < r.nn; ++i) nt[i] = (id_index){r.node_id[i], i};
    for (int i = 0; i < r.ne; ++i) et[i] = (id_index){r.elem_id[i], i};
    qsort(nt, (size_t)r.nn, sizeof *nt, cmp_id);
    qsort(et, (size_t)r.ne, sizeof *et, cmp_id);
    for (int i = 1; i < r.nn && !rc; ++i)
      if (nt[i].id == nt[i - 1].id) {
        snprintf(err, errlen, "%s: node id %ld defined twice", path, nt[i].id);
        rc = PALP_EPARSE;
      }
    for (int i = 1; i < r.ne && !rc; ++i)
      if (et[i].id == et[i - 1].id) {
        snprintf(err, errlen, "%s: element id %ld defined twice", path, et[i].id);
        rc = PALP_EPARSE;
      }
  }
  if (!rc) {
    out->node_count = r.nn;
    out->element_count = r.ne;
    memcpy(out->x, r.x, sizeof *out->x * (size_t)r.nn);
    for (int e = 0; e < r.ne && !rc; ++e)
      for (int a = 0; a < 8; ++a) {
        const int idx = lookup(nt, r.nn, r.conn[e][a]);
        if (idx < 0) {
          snprintf(err, errlen, "%s: element %ld uses undefined node %ld", path, r.elem_id[e], r.conn[e][a]);
          rc = PALP_EPARSE;
          break;
        }
        out->hex[e][a] = idx;
      }
  }
  /* A node no element uses (a reference or leftover node, common in Abaqus files) would
   * get three free equations with no stiffness and no mass: a singular tangent, reported
   * as a solver failure. Refused here, naming the first few (since session 82). */
  if (!rc) {
    uint8_t *used = calloc((size_t)r.nn, 1);
    if (!used) rc = PALP_ENOMEM;
    for (int e = 0; !rc && e < r.ne; ++e)
      for (int a = 0; a < 8; ++a) used[out->hex[e][a]] = 1;
    int unused = 0;
    char ids[160] = "";
    for (int i = 0; !rc && i < r.nn; ++i)
      if (!used[i] && unused++ < 8) {
        const size_t n = strlen(ids);
        snprintf(ids + n, sizeof ids - n, "%s%ld", n ? ", " : "", r.node_id[i]);
      }
    if (!rc && unused) {
      snprintf(err, errlen, "%s: %d node%s belong%s to no element (id%s %s%s): remove %s", path, unused,
               unused > 1 ? "s" : "", unused > 1 ? "" : "s", unused > 1 ? "s" : "", ids, unused > 8 ? ", ..." : "",
               unused > 1 ? "them" : "it");
      rc = PALP_EINVAL;
    }
    free(used);
  }
  for (int s = 0; !rc && s < r.nsets; ++s) {
    raw_set *rs = &r.sets[s];
    int *items = malloc(sizeof(int) * (size_t)(rs->count ? rs->count : 1));
    if (!items) {
      rc = PALP_ENOMEM;
      break;
    }
    for (int i = 0; i < rs->count; ++i) {
      items[i] = rs->is_element ? lookup(et, r.ne, rs->ids[i]) : lookup(nt, r.nn, rs->ids[i]);
      if (items[i] < 0) {
        snprintf(err, errlen, "%s: set %s names undefined %s %ld", path, rs->name, rs->is_element ? "element" : "node",
                 rs->ids[i]);
        rc = PALP_EPARSE;
        break;
      }
    }
    if (!rc) rc = palp_fem_mesh_add_set(out, rs->name, rs->is_element, items, rs->count);
    else free(items);
  }
  free(nt);
  free(et);
  /* the file's element ids, kept for the checks below: their messages name the element as the file
   * does (until session 81 by its place in the file, "element 2" of a file numbering from 1001) */
  long *eids = r.elem_id;
  r.elem_id = NULL;
  reader_free(&r);
  if (rc) {
    free(eids);
    palp_fem_mesh_destroy(out);
    return rc;
  }
  const palp_fem_set *mem = palp_fem_mesh_find_set(out, "MEMBRANE", 1);
  if (mem)
    for (int i = 0; i < mem->count; ++i) out->region[mem->items[i]] = PALP_FEM_MEMBRANE;
  const palp_fem_set *base = palp_fem_mesh_find_set(out, "BASE", 0);
  if (base)
    for (int i = 0; i < base->count; ++i) out->fixed[base->items[i]] = 1;
  else
    for (int n = 0; n < out->node_count; ++n) out->fixed[n] = out->x[n][2] <= 1e-9;
  const palp_fem_set *top = palp_fem_mesh_find_set(out, "TOP", 0);
  if (top && top->count > 0) out->top_node = top->items[0];
  else
    for (int n = 0; n < out->node_count; ++n)
      if (out->x[n][2] > out->x[out->top_node][2]) out->top_node = n;
  int nfixed = 0;
  for (int n = 0; n < out->node_count; ++n) nfixed += out->fixed[n];
  if (nfixed == 0) {
    snprintf(err, errlen, "%s: nothing is clamped (no NSET BASE and no node at z <= 1e-9 m)", path);
    free(eids);
    palp_fem_mesh_destroy(out);
    return PALP_EINVAL;
  }
  palp_fem_mesh_orient(out);
  for (int e = 0; e < out->element_count; ++e)
    if (!(palp_fem_element_volume(out, e) > 0.0)) {
      snprintf(err, errlen, "%s: element %ld is degenerate (volume %g m^3: its corners flat, folded or repeated)",
               path, eids ? eids[e] : (long)e + 1, palp_fem_element_volume(out, e));
      free(eids);
      palp_fem_mesh_destroy(out);
      return PALP_EINVAL;
    }
  /* A positive total volume is not enough: corners out of order can fold an element so
   * that some Gauss-point determinants are negative while their sum is not. The model
   * checks the same 8 points (fem_model.c); here the message names the file's element id. */
  for (int e = 0; e < out->element_count; ++e) {
    const int g = inverted_gauss_point(out, e);
    if (g) {
      snprintf(err, errlen, "%s: element %ld is inverted at Gauss point %d (non-positive Jacobian: its corners are "
               "out of the C3D8 order)", path, eids ? eids[e] : (long)e + 1, g);
      free(eids);
      palp_fem_mesh_destroy(out);
      return PALP_EINVAL;
    }
  }
  free(eids);
  rc = palp_fem_mesh_standard_sets(out);
  if (rc) palp_fem_mesh_destroy(out);
  return rc;
}
