/* test_inputs.c - station input sources and the SVG snapshot, with hand-worked values. */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input.h"
#include "palp.h"
#include "view.h"
#include "check.h"


int main(void) {
  /* Paper step (3 N for 2 s from t = 0), distribution II at polar 30 deg, azimuth 40 deg
   * on R = 0.04 m: centre R (sin30 cos40, sin30 sin40, cos30) = (0.0153209, 0.0128558, 0.0346410) m,
   * force 3 N along the inward normal = -3 (0.383022, 0.321394, 0.866025) N. */
  palp_cli_script_def d = {.distribution = 2, .polar_deg = 30, .azimuth_deg = 40,
                           .profile = palp_profile_paper_step(), .end_time = 3.0};
  palp_cli_input in;
  CHECK(palp_cli_script_input(&d, &in) == 0 && in.open(in.ctx, 0.04) == 0, "script input opens");
  palp_cli_cmd c[4];
  int n = in.poll(in.ctx, 1.0, c, 4);
  CHECK(n == 1 && c[0].mode == 1 && c[0].distribution == 2, "t = 1 s: one force-driven finger (n %d, mode %d)", n,
        c[0].mode);
  CHECK(fabs(c[0].center.x - 0.0153209) < 1e-7 && fabs(c[0].center.y - 0.0128558) < 1e-7 &&
            fabs(c[0].center.z - 0.0346410) < 1e-7,
        "centre (%.7f, %.7f, %.7f) m (hand: 0.0153209, 0.0128558, 0.0346410; 1e-7 m)", c[0].center.x, c[0].center.y,
        c[0].center.z);
  CHECK(fabs(c[0].force.x + 1.149067) < 1e-6 && fabs(c[0].force.y + 0.964181) < 1e-6 &&
            fabs(c[0].force.z + 2.598076) < 1e-6,
        "force (%.6f, %.6f, %.6f) N (hand: -1.149067, -0.964181, -2.598076; 1e-6 N)", c[0].force.x, c[0].force.y,
        c[0].force.z);
  n = in.poll(in.ctx, 2.5, c, 4);
  CHECK(n == 1 && c[0].mode == 0, "t = 2.5 s: after the 2 s step the finger is lifted (mode %d)", c[0].mode);
  CHECK(in.poll(in.ctx, 3.0, c, 4) == PALP_CLI_INPUT_END, "t = 3 s: the script has ended");
  in.close(in.ctx);

  /* Position-driven finger of radius 8 mm pressed 5 mm deep at the pole: tip centre at
   * z = R + r - depth = 0.04 + 0.008 - 0.005 = 0.043 m. */
  palp_cli_script_def f = {.finger_mode = 1, .polar_deg = 0, .radius = 0.008, .end_time = 1,
                           .profile = {.kind = PALP_PROFILE_STEP, .magnitude = 0.005, .t_on = 0, .t_off = 1}};
  palp_cli_script_input(&f, &in);
  in.open(in.ctx, 0.04);
  n = in.poll(in.ctx, 0.5, c, 4);
  CHECK(n == 1 && c[0].mode == 2 && fabs(c[0].center.z - 0.043) < 1e-12 && fabs(c[0].center.x) < 1e-12 &&
            c[0].radius == 0.008,
        "finger tip at z = %.6f m, radius %.3f m (hand: 0.043 m, 0.008 m)", c[0].center.z, c[0].radius);
  in.close(in.ctx);

  /* Replay: rows come back at their times, the latest per finger wins. */
  const char *path = "test_inputs_replay.csv";
  FILE *w = fopen(path, "w");
  palp_cli_contact_csv_header(w);
  palp_cli_cmd a = {.finger = 0, .mode = 1, .distribution = 3, .center = {0, 0, 0.04}, .force = {0, 0, -1}};
  palp_cli_cmd b = a;
  b.force.z = -2;
  palp_cli_cmd r = {.finger = 0, .mode = 0};
  palp_cli_contact_csv_row(w, 0.10, &a);
  palp_cli_contact_csv_row(w, 0.20, &b);
  palp_cli_contact_csv_row(w, 0.30, &r);
  fclose(w);
  char err[256] = "";
  CHECK(palp_cli_replay_input(path, &in, err, sizeof err) == 0, "replay opens %s %s", path, err);
  n = in.poll(in.ctx, 0.05, c, 4);
  CHECK(n == 0, "before the first row nothing is pressed (n %d)", n);
  n = in.poll(in.ctx, 0.15, c, 4);
  CHECK(n == 1 && c[0].mode == 1 && c[0].force.z == -1 && c[0].distribution == 3, "t = 0.15 s: row 1 (-1 N)");
  n = in.poll(in.ctx, 0.25, c, 4);
  CHECK(n == 1 && c[0].force.z == -2, "t = 0.25 s: row 2 (-2 N)");
  n = in.poll(in.ctx, 0.35, c, 4);
  CHECK(n == 1 && c[0].mode == 0, "t = 0.35 s: released");
  CHECK(in.poll(in.ctx, 0.81, c, 4) == PALP_CLI_INPUT_END, "0.5 s after the last row the replay ends");
  in.close(in.ctx);
  w = fopen(path, "w");
  fprintf(w, "t_s,finger\n0.1,9,1,1,0,0,0,0,0,0,0\n");
  fclose(w);
  CHECK(palp_cli_replay_input(path, &in, err, sizeof err) == PALP_EPARSE && strstr(err, ":2:"),
        "finger 9 is refused with its line number: %s", err);
  /* What the server refuses on every sample is refused with its line and field, as --distribution
   * is range-checked (the station replayed it at 0 N and said nothing; 257 went out as the byte 1);
   * so is text after the 11th field. Line 3: a good row comes first. */
  const struct {
    const char *row, *field;
  } bad[] = {{"0.2,0,1,257,0,0,0.04,0,0,-1,0", "distribution 257"},
             {"0.2,0,1,0,0,0,0.04,0,0,-1,0", "distribution 0"},
             {"0.2,0,1,-1,0,0,0.04,0,0,-1,0", "distribution -1"},
             {"0.2,0,1,5,0,0,0.04,0,0,-1,0", "distribution 5"},
             {"0.2,0,0,300,0,0,0.04,0,0,0,0", "distribution 300"},
             {"0.2,0,2,3,0,0,0.05,0,0,0,0", "radius_m 0"},
             {"0.2,0,2,3,0,0,0.05,0,0,0,-0.008", "radius_m -0.008"},
             {"0.2,0,1,3,0,0,0.04,0,0,-1,0,junk", "after radius_m"},
             {"0.2,0,2,3,0,0,0.05,0,0,0,8mm", "after radius_m"}};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    w = fopen(path, "w");
    fprintf(w, "t_s,finger\n0.1,0,1,3,0,0,0.04,0,0,-1,0\n%s\n", bad[k].row);
    fclose(w);
    err[0] = '\0';
    CHECK(palp_cli_replay_input(path, &in, err, sizeof err) == PALP_EPARSE && strstr(err, ":3:") &&
              strstr(err, bad[k].field),
          "\"%s\" is refused naming line 3 and \"%s\": %s", bad[k].row, bad[k].field, err);
  }
  /* (session 82) a line longer than the reader's 511 bytes is refused naming the file and line: a
   * valid row, 500 blanks and another valid row was read as two rows (two contact commands) */
  w = fopen(path, "w");
  fprintf(w, "t_s,finger\n0.1,0,1,3,0,0,0.04,0,0,-1,0%500s0.2,0,1,3,0,0,0.04,0,0,-2,0\n", "");
  fclose(w);
  err[0] = '\0';
  CHECK(palp_cli_replay_input(path, &in, err, sizeof err) == PALP_EPARSE && strstr(err, path) &&
            strstr(err, ":2: line longer than 511 bytes"),
        "a 554-byte line (two 27-byte rows joined by 500 blanks) is refused naming the file and line 2: %s", err);
  /* and a last row of 511 bytes that ends at the file's end without a newline still passes */
  w = fopen(path, "w");
  fprintf(w, "t_s,finger\n0.1,0,1,3,0,0,0.04,0,0,-1,0%484s", ""); /* 27 + 484 = 511 bytes */
  fclose(w);
  err[0] = '\0';
  const int last = palp_cli_replay_input(path, &in, err, sizeof err);
  CHECK(last == 0, "a last row padded to 511 bytes, no newline at the end, passes: %s", err);
  if (last == 0) in.close(in.ctx);
  /* what --contact-csv writes stays good: a release of distribution 0 and radius 0, a finger row
   * of radius 8 mm, CRLF line ends */
  w = fopen(path, "w");
  fprintf(w, "t_s,finger\n0.1,0,2,0,0,0,0.05,0,0,0,0.008\r\n0.2,0,0,0,0,0,0,0,0,0,0\r\n");
  fclose(w);
  err[0] = '\0';
  const int good = palp_cli_replay_input(path, &in, err, sizeof err);
  CHECK(good == 0, "a finger row and a release (distribution 0, radius 0), CRLF, pass: %s", err);
  if (good == 0) in.close(in.ctx);
  remove(path);

  /* SVG: one polygon per dome triangle of a 19-vertex mesh. */
  palp_mesh_def md = {.radius = 0.04, .vertex_count = 19};
  palp_mesh mesh;
  CHECK(palp_mesh_create(&md, &mesh) == 0, "19-vertex mesh");
  palp_Phantom ph;
  memset(&ph, 0, sizeof ph);
  palp_Vec3 rest[64], pos[64];
  int32_t tri[3 * 128];
  for (int i = 0; i < mesh.vertex_count; i++) {
    rest[i] = (palp_Vec3){mesh.rest[i].x, mesh.rest[i].y, mesh.rest[i].z};
    pos[i] = rest[i];
  }
  for (int t = 0; t < mesh.triangle_count; t++)
    for (int k = 0; k < 3; k++) tri[3 * t + k] = mesh.tri[t][k];
  pos[mesh.top_vertex].z -= 0.002; /* 2 mm dent at the pole */
  ph.radius = 0.04;
  ph.rest = (dds_sequence_palp_Vec3){(uint32_t)mesh.vertex_count, (uint32_t)mesh.vertex_count, rest, false};
  ph.triangles = (dds_sequence_long){(uint32_t)(3 * mesh.triangle_count), (uint32_t)(3 * mesh.triangle_count), tri, false};
  ph.dome_triangle_count = mesh.dome_triangle_count;
  palp_Deformation def;
  memset(&def, 0, sizeof def);
  def.positions = (dds_sequence_palp_Vec3){(uint32_t)mesh.vertex_count, (uint32_t)mesh.vertex_count, pos, false};
  int v = -1;
  double m = palp_cli_max_displacement(&ph, &def, &v);
  CHECK(fabs(m - 0.002) < 1e-15 && v == mesh.top_vertex, "max displacement %.6f m at vertex %d (hand: 0.002 m at the pole %d)",
        m, v, mesh.top_vertex);
  const char *svg = "test_inputs.svg";
  CHECK(palp_cli_view_svg(&ph, &def, "a <b> & c", svg) == 0, "SVG written");
  FILE *s = fopen(svg, "r");
  int polys = 0, esc = 0;
  char line[512];
  while (s && fgets(line, sizeof line, s)) {
    polys += strncmp(line, "<polygon", 8) == 0;
    esc += strstr(line, "a &lt;b&gt; &amp; c") != NULL;
  }
  if (s) fclose(s);
  CHECK(polys == mesh.dome_triangle_count && esc == 1, "%d polygons (want %d dome triangles), title escaped %d", polys,
        mesh.dome_triangle_count, esc);
  /* A name from a Latin-1 scene file or a peer (a stray 0xfc, a control byte, a truncated sequence, DEL,
   * and U+FFFF, well-formed UTF-8 that is no XML character) keeps the snapshot XML: each such byte
   * written as '?', the well-formed UTF-8 kept (session 82 review: the file was not XML, and the station
   * said it was written). */
  CHECK(palp_cli_view_svg(&ph, &def, "Brust\xfc\x01 T\xc3\xbc" "bingen\x7f \xef\xbf\xbf \xe2\x82", svg) == 0,
        "SVG written");
  s = fopen(svg, "r");
  int clean = 0, ctl = 0;
  while (s && fgets(line, sizeof line, s)) {
    clean += strstr(line, ">Brust?\? T\xc3\xbc" "bingen? ?\?\? ?\?</text>") != NULL;
    for (const unsigned char *p = (const unsigned char *)line; *p; p++) ctl += (*p < 0x20 && *p != '\n') || *p == 0x7f;
  }
  if (s) fclose(s);
  CHECK(clean == 1 && ctl == 0, "a name with bytes that are no UTF-8 and control bytes: the title written as "
        "\"Brust?\? T\\u00fc" "bingen? ?\?\? ?\?\" (%d) and no control byte in the file (%d)", clean, ctl);
  remove(svg);

  /* A forged catalogue entry is refused before any index in it is used (the
   * visual station crashed on bad triangle indices). */
  char why[256] = "";
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == 0, "the real mesh passes the catalogue check (%s)", why);
  tri[7] = 1000000;
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == PALP_EINVAL && strstr(why, "triangle 2 has vertex index 1000000"),
        "triangle index 1000000 refused: \"%s\"", why);
  CHECK(palp_cli_view_svg(&ph, &def, "forged", svg) == PALP_EINVAL && fopen(svg, "r") == NULL,
        "no SVG drawn from a forged mesh, and no file created");
  tri[7] = -1;
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == PALP_EINVAL, "triangle index -1 refused: \"%s\"", why);
  tri[7] = mesh.tri[2][1];
  ph.triangles._length = 3 * (uint32_t)mesh.triangle_count - 1;
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == PALP_EINVAL, "index count not a multiple of 3 refused: \"%s\"", why);
  ph.triangles._length = 3 * (uint32_t)mesh.triangle_count;
  ph.dome_triangle_count = mesh.triangle_count + 1;
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == PALP_EINVAL, "dome triangle count past the end refused: \"%s\"", why);
  ph.dome_triangle_count = mesh.dome_triangle_count;
  rest[3].y = NAN;
  CHECK(palp_cli_phantom_check(&ph, why, sizeof why) == PALP_EINVAL, "NaN rest vertex refused: \"%s\"", why);
  rest[3].y = mesh.rest[3].y;
  def.positions._length = (uint32_t)mesh.vertex_count - 1;
  CHECK(palp_cli_deformation_check(&ph, &def) == PALP_EINVAL, "a deformation frame one vertex short is refused");
  def.positions._length = (uint32_t)mesh.vertex_count;
  CHECK(palp_cli_deformation_check(&ph, &def) == 0, "the matching deformation frame passes");
  /* A finite vertex far out (session 75: 1e200 m made the map's scale inf and a cell's colour index a NaN,
   * a crash) is refused, as is one 11 m out and a non-finite time; one 9 m out passes and is drawn. */
  const palp_Vec3 keep = pos[mesh.top_vertex];
  pos[mesh.top_vertex].x = 1e200;
  CHECK(palp_cli_deformation_check(&ph, &def) == PALP_EINVAL, "a vertex at 1e200 m refused");
  pos[mesh.top_vertex].x = 11.0;
  CHECK(palp_cli_deformation_check(&ph, &def) == PALP_EINVAL, "a vertex 11 m out refused");
  pos[mesh.top_vertex].x = 9.0;
  CHECK(palp_cli_deformation_check(&ph, &def) == 0, "a vertex 9 m out passes");
  palp_cli_view view;
  if (palp_cli_view_init(&view, &ph, 41, 21, 0) == 0) {
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    palp_cli_view_render(&view, &def, mem, 1);
    palp_cli_view_render(&view, &def, mem, 0);
    fclose(mem);
    CHECK(text && strstr(text, "max displacement 9") != NULL, "and drawn, in colour and in characters (%zu bytes)", len);
    free(text);
    palp_cli_view_free(&view);
  } else {
    CHECK(0, "a view of the phantom");
  }
  pos[mesh.top_vertex] = keep;
  /* What a device driver's feedback() is given (palp_cli_device_force): 3-4-0 N at a 2.5 N limit is
   * 1.5-2-0 N (hand: x 2.5 / 5), flagged; 1-2-2 N (3 N) passes as it is; NaN and 1e308 N-squared
   * overflow give 0 N. */
  /* terminal-safe text: an OSC retitle, a carriage return and a bell become '?', newline, tab and UTF-8 stay */
  char txt[] = "\033]0;x\007ok\rfake\tline\n30\xc2\xb0 \x7f";
  palp_cli_terminal_safe(txt);
  CHECK(strcmp(txt, "?]0;x?ok?fake\tline\n30\xc2\xb0 ?") == 0, "terminal-safe: \"%s\"", txt);
  /* C1 controls in UTF-8 (CSI 2J, OSC 0;owned ST) go too, both bytes; U+00A0 and U+00E9 stay */
  char c1[] = "T\xc2\x9b" "2J\xc2\x9d" "0;owned\xc2\x9c \xc2\xa0\xc3\xa9";
  palp_cli_terminal_safe(c1);
  CHECK(strcmp(c1, "T??2J??0;owned?? \xc2\xa0\xc3\xa9") == 0, "terminal-safe C1: \"%s\"", c1);
  palp_vec3 dv;
  CHECK(palp_cli_device_force((palp_vec3){3, 4, 0}, 2.5, &dv) == 1 && fabs(dv.x - 1.5) < 1e-12 && fabs(dv.y - 2.0) < 1e-12 &&
            dv.z == 0, "5 N limited to 2.5 N: (%g, %g, %g)", dv.x, dv.y, dv.z);
  CHECK(palp_cli_device_force((palp_vec3){1, 2, 2}, 10, &dv) == 0 && dv.x == 1 && dv.y == 2 && dv.z == 2, "3 N passes");
  CHECK(palp_cli_device_force((palp_vec3){NAN, 0, 0}, 10, &dv) == PALP_EINVAL && dv.x == 0 && dv.y == 0 && dv.z == 0,
        "NaN gives 0 N");
  CHECK(palp_cli_device_force((palp_vec3){1e308, 1e308, 0}, 10, &dv) == PALP_EINVAL && dv.x == 0, "a magnitude past "
        "double gives 0 N");
  /* The driver loader (palp_cli_device_input): a haptic device, read_position and write_force, runs
   * on the haptic thread and needs no poll (client/input.h). Such a driver was refused with
   * "initialisation failed (0)" and its context left allocated; one with neither that pair nor poll
   * is refused, saying what is missing, and closed. The variants' own handle (dlopen counts) keeps
   * their close() counter readable after the loader lets go of it. */
  {
    void *vh = dlopen(PALP_TEST_DEVICE_VARIANTS, RTLD_NOW | RTLD_LOCAL);
    int *closed = vh ? (int *)dlsym(vh, "palp_test_driver_closed") : NULL;
    CHECK(closed != NULL, "the test's driver variants load: %s", vh ? "" : dlerror());
    palp_cli_input dv_in;
    char derr[512] = "";
    int rc = palp_cli_device_input(PALP_TEST_DEVICE_EXAMPLE, "1", &dv_in, derr, sizeof derr);
    CHECK(rc == 0 && dv_in.poll && dv_in.read_position && dv_in.write_force, "the example driver loads: %s", derr);
    if (rc == 0) dv_in.close(dv_in.ctx);
    if (closed) {
      derr[0] = '\0';
      rc = palp_cli_device_input(PALP_TEST_DEVICE_VARIANTS, "haptic", &dv_in, derr, sizeof derr);
      palp_vec3 x = {0, 0, 0};
      const int on = rc == 0 ? dv_in.read_position(dv_in.ctx, 0.0, &x) : -1;
      CHECK(rc == 0 && !dv_in.poll && on == 1 && x.z == 0.05,
            "a driver with read_position and write_force and no poll loads and reads (rc %d, z %g m): %s", rc, x.z, derr);
      if (rc == 0) dv_in.close(dv_in.ctx);
      const int before = *closed;
      derr[0] = '\0';
      rc = palp_cli_device_input(PALP_TEST_DEVICE_VARIANTS, "read-only", &dv_in, derr, sizeof derr);
      CHECK(rc == PALP_EINVAL && strstr(derr, "neither read_position and write_force") && strstr(derr, "nor poll") &&
                *closed == before + 1,
            "read_position alone is refused, saying what is missing, and closed (%d close call(s)): %s",
            *closed - before, derr);
      derr[0] = '\0';
      rc = palp_cli_device_input(PALP_TEST_DEVICE_VARIANTS, "bogus", &dv_in, derr, sizeof derr);
      CHECK(rc == PALP_EINVAL && strstr(derr, "initialisation failed"), "a driver's own refusal is passed on: %s", derr);
    }
    if (vh) dlclose(vh);
  }
  def.sim_time = INFINITY;
  CHECK(palp_cli_deformation_check(&ph, &def) == PALP_EINVAL, "a frame at t = inf refused");
  def.sim_time = 0;
  palp_mesh_destroy(&mesh);
  fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
