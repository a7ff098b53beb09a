/* view.c - terminal displacement map and SVG snapshots of the deformed dome. */
#include "view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"
#include "palp_dds.h"
#include "palp_log.h"
#include "palp_utf8.h"

/* The check is palp_dds_phantom_check (idl/), shared with palp-recorder. */
int palp_cli_phantom_check(const palp_Phantom *ph, char *err, size_t errlen) {
  return palp_dds_phantom_check(ph, 0, err, errlen);
}

int palp_cli_deformation_check(const palp_Phantom *ph, const palp_Deformation *d) {
  if (d->positions._length != ph->rest._length || !d->positions._buffer) return PALP_EINVAL;
  /* Finite is not enough: a vertex at 1e200 m squared to inf, the map's scale became inf and a
   * cell's inf / inf a NaN index into the colour ramp (a crash; session 75, found by review). No
   * phantom's vertex is 10 m from its origin (the server's scenes: a radius of 1 m at most). */
  for (uint32_t i = 0; i < d->positions._length; i++) {
    palp_Vec3 p = d->positions._buffer[i];
    if (!(fabs(p.x) <= 10.0 && fabs(p.y) <= 10.0 && fabs(p.z) <= 10.0)) return PALP_EINVAL;
  }
  if (!isfinite(d->sim_time) || !isfinite(d->volume) || !isfinite(d->rest_volume) || !isfinite(d->pressure))
    return PALP_EINVAL;
  return 0;
}

static double disp(const palp_Phantom *ph, const palp_Deformation *d, uint32_t i) {
  const palp_Vec3 a = ph->rest._buffer[i], b = d->positions._buffer[i];
  double dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  return sqrt(dx * dx + dy * dy + dz * dz);
}

double palp_cli_max_displacement(const palp_Phantom *ph, const palp_Deformation *d, int *vertex) {
  double m = 0;
  int at = -1;
  uint32_t n = ph->rest._length < d->positions._length ? ph->rest._length : d->positions._length;
  for (uint32_t i = 0; i < n; i++) {
    double x = disp(ph, d, i);
    if (x > m) m = x, at = (int)i;
  }
  if (vertex) *vertex = at;
  return m;
}

int palp_cli_view_init(palp_cli_view *v, const palp_Phantom *ph, int w, int h, double scale) {
  memset(v, 0, sizeof *v);
  v->phantom = ph;
  v->w = w;
  v->h = h;
  v->scale = scale;
  v->cell_vertex = malloc((size_t)w * (size_t)h * sizeof *v->cell_vertex);
  if (!v->cell_vertex) return PALP_ENOMEM;
  const double R = ph->radius;
  /* Terminal cells are about twice as tall as wide: h rows span the same
   * distance as w columns when w = 2h. */
  for (int r = 0; r < h; r++)
    for (int c = 0; c < w; c++) {
      double x = ((c + 0.5) / w * 2 - 1) * R, y = (1 - (r + 0.5) / h * 2) * R;
      int best = -1;
      if (x * x + y * y <= R * R) {
        double bd = INFINITY;
        for (uint32_t i = 0; i < ph->rest._length; i++) {
          const palp_Vec3 p = ph->rest._buffer[i];
          if (p.z < -1e-12) continue; /* base side: never seen from above */
          double dd = (p.x - x) * (p.x - x) + (p.y - y) * (p.y - y);
          if (dd < bd) bd = dd, best = (int)i;
        }
      }
      v->cell_vertex[r * w + c] = best;
    }
  return 0;
}

void palp_cli_view_free(palp_cli_view *v) {
  free(v->cell_vertex);
  v->cell_vertex = NULL;
}

/* Blue -> cyan -> green -> yellow -> red on the 6x6x6 ANSI cube. */
static const int ramp256[] = {17, 18, 19, 20, 21, 27, 33, 39, 45, 51, 50, 49, 48, 47, 46,
                              82, 118, 154, 190, 226, 220, 214, 208, 202, 196};
/* Zero is a dot so the dome outline shows; outside the dome is blank. */
static const char ramp_chars[] = ".:-=+*#%@";

void palp_cli_view_render(const palp_cli_view *v, const palp_Deformation *d, FILE *out, int color) {
  const palp_Phantom *ph = v->phantom;
  double maxd = palp_cli_max_displacement(ph, d, NULL);
  /* at least 0.25 mm full scale, so that a dome at rest does not show its round-off as dents;
   * 5 mm hid the long-term domes' whole signal (0.4-0.8 mm under the paper's 3 N) */
  double scale = v->scale > 0 ? v->scale : (maxd > 0.00025 ? maxd : 0.00025);
  const int nr = (int)(sizeof ramp256 / sizeof ramp256[0]), nc = (int)(sizeof ramp_chars - 1);
  for (int r = 0; r < v->h; r++) {
    for (int c = 0; c < v->w; c++) {
      int i = v->cell_vertex[r * v->w + c];
      if (i < 0) {
        fputs(color ? "\033[0m " : " ", out);
        continue;
      }
      double f = disp(ph, d, (uint32_t)i) / scale;
      if (!(f >= 0)) f = 0; /* NaN too: it must never index the ramps */
      if (!(f <= 1)) f = 1;
      if (color)
        fprintf(out, "\033[48;5;%dm ", ramp256[(int)(f * (nr - 1) + 0.5)]);
      else
        fputc(ramp_chars[(int)(f * (nc - 1) + 0.5)], out);
    }
    fputs(color ? "\033[0m\n" : "\n", out);
  }
  fprintf(out, "frame %llu  t = %.2f s  max displacement %.2f mm (full scale %.2f mm)  volume %.1f%% of rest  "
               "pressure %+.0f Pa  (top view, 12 o'clock at the top)\n",
          (unsigned long long)d->frame, d->sim_time, maxd * 1e3, scale * 1e3,
          d->rest_volume > 0 ? 100.0 * d->volume / d->rest_volume : 0.0, d->pressure);
}

static void colour(double f, int *r, int *g, int *b) {
  /* Blue (0) -> green (0.5) -> red (1), linear in each half. */
  if (!(f >= 0)) f = 0; /* NaN too */
  if (!(f <= 1)) f = 1;
  if (f < 0.5) {
    *r = 0;
    *g = (int)(510 * f);
    *b = (int)(255 * (1 - 2 * f));
  } else {
    *r = (int)(510 * (f - 0.5));
    *g = (int)(255 * (2 - 2 * f));
    *b = 0;
  }
}

/* Text for the SVG (XML 1.0): the markup characters escaped, and '?' for a C0 control other than tab
 * and newline, DEL, and every byte that does not begin a well-formed UTF-8 character. The title holds
 * the phantom's name from the network or a Latin-1 scene file: before session 82 such a byte made the
 * snapshot ill-formed, which no viewer opens, while the station said it was written. */
static void put_escaped(FILE *f, const char *s) {
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p;) {
    const int n = (int)palp_utf8_xml_len(p, p[0] ? 4 : 1); /* a C string: its NUL ends a cut sequence */
    if (*p == '<') fputs("&lt;", f);
    else if (*p == '>') fputs("&gt;", f);
    else if (*p == '&') fputs("&amp;", f);
    else if (*p == '"') fputs("&quot;", f);
    else if (n == 0 || (*p < 0x20 && *p != '\t' && *p != '\n') || *p == 0x7f) fputc('?', f);
    else {
      fwrite(p, 1, (size_t)n, f);
      p += n;
      continue;
    }
    p++;
  }
}

typedef struct tri_z {
  int t;
  double z;
} tri_z;

static int cmp_z(const void *a, const void *b) {
  double x = ((const tri_z *)a)->z, y = ((const tri_z *)b)->z;
  return (x > y) - (x < y);
}

int palp_cli_view_svg(const palp_Phantom *ph, const palp_Deformation *d, const char *title, const char *path) {
  char why[160];
  if (palp_cli_phantom_check(ph, why, sizeof why) < 0 || palp_cli_deformation_check(ph, d) < 0) return PALP_EINVAL;
  FILE *f = fopen(path, "w");
  if (!f) return PALP_EIO;
  const double R = ph->radius, S = 400.0 / (2.2 * R); /* pixels per metre */
  const int nt = (int)ph->dome_triangle_count;
  const int32_t *tri = ph->triangles._buffer;
  double maxd = palp_cli_max_displacement(ph, d, NULL);
  double scale = maxd > 0.001 ? maxd : 0.001;
  tri_z *order = malloc((size_t)(nt > 0 ? nt : 1) * sizeof *order);
  if (!order) {
    fclose(f);
    return PALP_ENOMEM;
  }
  for (int t = 0; t < nt; t++) {
    const palp_Vec3 *p = d->positions._buffer;
    order[t] = (tri_z){t, (p[tri[3 * t]].z + p[tri[3 * t + 1]].z + p[tri[3 * t + 2]].z) / 3};
  }
  qsort(order, (size_t)nt, sizeof *order, cmp_z);
  fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"480\" height=\"470\" viewBox=\"0 0 480 470\">\n");
  fprintf(f, "<rect width=\"480\" height=\"470\" fill=\"white\"/>\n");
  fprintf(f, "<text x=\"10\" y=\"18\" font-family=\"sans-serif\" font-size=\"12\">");
  put_escaped(f, title);
  fprintf(f, "</text>\n");
  fprintf(f, "<text x=\"10\" y=\"36\" font-family=\"sans-serif\" font-size=\"12\">frame %llu, t = %.2f s, "
             "max displacement %.2f mm, top view, 12 o'clock (+y) at the top</text>\n",
          (unsigned long long)d->frame, d->sim_time, maxd * 1e3);
  fprintf(f, "<g transform=\"translate(220,250)\" stroke=\"#333\" stroke-width=\"0.3\">\n");
  for (int k = 0; k < nt; k++) {
    int t = order[k].t;
    double m = 0;
    fprintf(f, "<polygon points=\"");
    for (int j = 0; j < 3; j++) {
      int vi = tri[3 * t + j];
      const palp_Vec3 p = d->positions._buffer[vi];
      fprintf(f, "%.2f,%.2f ", p.x * S, -p.y * S);
      m += disp(ph, d, (uint32_t)vi) / 3;
    }
    int r, g, b;
    colour(m / scale, &r, &g, &b);
    fprintf(f, "\" fill=\"rgb(%d,%d,%d)\"/>\n", r, g, b);
  }
  fprintf(f, "</g>\n");
  /* Legend: 0 .. full scale. */
  for (int i = 0; i < 20; i++) {
    int r, g, b;
    colour(1.0 - i / 19.0, &r, &g, &b);
    fprintf(f, "<rect x=\"440\" y=\"%d\" width=\"20\" height=\"15\" fill=\"rgb(%d,%d,%d)\"/>\n", 100 + 15 * i, r, g, b);
  }
  fprintf(f, "<text x=\"400\" y=\"95\" font-family=\"sans-serif\" font-size=\"11\">%.2f mm</text>\n", scale * 1e3);
  fprintf(f, "<text x=\"425\" y=\"415\" font-family=\"sans-serif\" font-size=\"11\">0 mm</text>\n");
  fprintf(f, "</svg>\n");
  free(order);
  int bad = ferror(f);
  if (fclose(f) != 0 || bad) return PALP_EIO;
  return 0;
}

void palp_cli_terminal_safe(char *s) {
  for (; s && *s; s++) {
    const unsigned char c = (unsigned char)*s;
    if ((c < 0x20 && c != '\n' && c != '\t') || c == 0x7f) *s = '?';
    /* a C1 control in UTF-8 (0xC2 0x80..0x9F): CSI and OSC cleared a trainee's screen and retitled her
     * terminal from an exercise's title (session 80's review, 2026-12-07); both bytes go */
    if (palp_utf8_c1_at(s)) s[0] = s[1] = '?';
  }
}
