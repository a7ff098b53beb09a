/* input_replay.c - replays a contact CSV written by palp-client --contact-csv. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input.h"

typedef struct row {
  double t;
  palp_cli_cmd c;
} row;

typedef struct replay {
  row *rows;
  int n, next;
  palp_cli_cmd cur[PALP_CLI_MAX_FINGERS];
  int used[PALP_CLI_MAX_FINGERS];
} replay;

void palp_cli_contact_csv_header(FILE *f) {
  fprintf(f, "t_s,finger,mode,distribution,cx_m,cy_m,cz_m,fx_N,fy_N,fz_N,radius_m\n");
}

void palp_cli_contact_csv_row(FILE *f, double t, const palp_cli_cmd *c) {
  fprintf(f, "%.6f,%d,%d,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", t, c->finger, c->mode, c->distribution,
          c->center.x, c->center.y, c->center.z, c->force.x, c->force.y, c->force.z, c->radius);
}

static int r_open(void *ctx, double R) {
  (void)ctx;
  (void)R;
  return 0;
}

static int r_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  replay *r = ctx;
  while (r->next < r->n && r->rows[r->next].t <= t) {
    const palp_cli_cmd *c = &r->rows[r->next++].c;
    r->cur[c->finger] = *c;
    r->used[c->finger] = 1;
  }
  /* Ends half a second after the last row so the last release is delivered. */
  if (r->next >= r->n && (r->n == 0 || t > r->rows[r->n - 1].t + 0.5)) return PALP_CLI_INPUT_END;
  int k = 0;
  for (int f = 0; f < PALP_CLI_MAX_FINGERS && k < cap; f++)
    if (r->used[f]) cmd[k++] = r->cur[f];
  return k;
}

static void r_close(void *ctx) {
  replay *r = ctx;
  free(r->rows);
  free(r);
}

int palp_cli_replay_input(const char *path, palp_cli_input *out, char *err, size_t errlen) {
  FILE *f = fopen(path, "r");
  if (!f) {
    snprintf(err, errlen, "%s: cannot open", path);
    return PALP_EIO;
  }
  replay *r = calloc(1, sizeof *r);
  int cap = 0, line = 0, rc = 0;
  char buf[512];
  while (r && fgets(buf, sizeof buf, f)) {
    line++;
    /* A line longer than buf came in two reads, and its tail was parsed as a row of its own (a
     * valid row, 500 blanks and another valid row made two contact commands; line numbers drifted):
     * refused (session 82). The last line may end at the file's end without a newline. */
    if (!strchr(buf, '\n')) {
      const int next = getc(f);
      if (next != EOF) {
        snprintf(err, errlen, "%s:%d: line longer than %zu bytes", path, line, sizeof buf - 1);
        rc = PALP_EPARSE;
        break;
      }
    }
    if (line == 1 && strncmp(buf, "t_s,", 4) == 0) continue;
    if (buf[0] == '\n' || buf[0] == '#') continue;
    row w;
    memset(&w, 0, sizeof w);
    int end = 0;
    int n = sscanf(buf, "%lf,%d,%d,%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf%n", &w.t, &w.c.finger, &w.c.mode,
                   &w.c.distribution, &w.c.center.x, &w.c.center.y, &w.c.center.z, &w.c.force.x, &w.c.force.y,
                   &w.c.force.z, &w.c.radius, &end);
    /* Nothing but the line's end after the 11th field: sscanf stops there and took
     * "...,0.008,junk" (or a twelfth column) as a good row. */
    if (n == 11) {
      size_t k = (size_t)end;
      while (buf[k] == ' ' || buf[k] == '\t' || buf[k] == '\r' || buf[k] == '\n') k++;
      if (buf[k] != '\0') {
        snprintf(err, errlen, "%s:%d: text after radius_m, the 11th and last field of a row", path, line);
        rc = PALP_EPARSE;
        break;
      }
    }
    /* Every number finite (sscanf takes "nan" and "inf"; a NaN time compares false with
     * everything, so the order check alone let it through), t within a day. */
    const double num[] = {w.t, w.c.center.x, w.c.center.y, w.c.center.z, w.c.force.x, w.c.force.y, w.c.force.z,
                          w.c.radius};
    int finite = 1;
    for (size_t k = 0; k < sizeof num / sizeof num[0]; k++) finite &= isfinite(num[k]) != 0;
    if (n != 11 || !finite || !(w.t >= 0 && w.t <= 86400) || w.c.finger < 0 || w.c.finger >= PALP_CLI_MAX_FINGERS ||
        w.c.mode < 0 || w.c.mode > 2 || (r->n > 0 && w.t < r->rows[r->n - 1].t)) {
      snprintf(err, errlen, "%s:%d: expected t_s,finger(0-3),mode(0-2),distribution,cx,cy,cz,fx,fy,fz,radius "
               "with finite numbers and non-decreasing t_s in [0, 86400]", path, line);
      rc = PALP_EPARSE;
      break;
    }
    /* What the server would refuse on every sample, refused here with the field: the station
     * replayed such a file at 0 N and said nothing (and a distribution of 257 went on the wire as
     * the byte 1). The server reads no distribution on a release or a finger row, nor a radius on a
     * release or a force row: there --contact-csv writes 0 (or the session's 1-4). */
    if (w.c.distribution < 0 || w.c.distribution > 4 || (w.c.mode == 1 && w.c.distribution < 1)) {
      snprintf(err, errlen, "%s:%d: distribution %d: a force row (mode 1) takes 1-4 (I single, II uniform, "
               "III gaussian, IV gaussian_offset), a release or finger row 0-4", path, line, w.c.distribution);
      rc = PALP_EPARSE;
      break;
    }
    if (w.c.mode == 2 && !(w.c.radius > 0)) {
      snprintf(err, errlen, "%s:%d: radius_m %g: a finger row (mode 2) needs the fingertip's radius, > 0 m", path,
               line, w.c.radius);
      rc = PALP_EPARSE;
      break;
    }
    if (r->n >= 100000000) {
      snprintf(err, errlen, "%s:%d: more than 100,000,000 rows", path, line);
      rc = PALP_EINVAL;
      break;
    }
    if (r->n == cap) {
      cap = cap ? 2 * cap : 1024;
      row *nr = realloc(r->rows, (size_t)cap * sizeof *nr);
      if (!nr) {
        rc = PALP_ENOMEM;
        break;
      }
      r->rows = nr;
    }
    r->rows[r->n++] = w;
  }
  fclose(f);
  if (!r) rc = PALP_ENOMEM;
  if (rc == 0 && r->n == 0) {
    snprintf(err, errlen, "%s: no contact rows", path);
    rc = PALP_EPARSE;
  }
  if (rc) {
    if (rc == PALP_ENOMEM) snprintf(err, errlen, "%s: out of memory", path);
    if (r) r_close(r);
    return rc;
  }
  *out = (palp_cli_input){.name = "replay", .ctx = r, .open = r_open, .poll = r_poll, .close = r_close};
  return 0;
}
