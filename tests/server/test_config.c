/* test_config.c - server configuration: defaults, path resolution, and errors that name the field. */
#include <stdio.h>
#include <string.h>

#include "config.h"
#include "palp.h"

static int failures;

static void expect_error(const char *json, const char *field, int code) {
  palp_srv_config cfg;
  char err[512] = "";
  int rc = palp_srv_config_parse(json, "/base", &cfg, err, sizeof err);
  int ok = rc == code && strncmp(err, field, strlen(field)) == 0;
  fprintf(stderr, "%s error %d \"%s\" (want code %d, message starting with \"%s\")\n", ok ? "ok  " : "FAIL", rc, err,
          code, field);
  failures += !ok;
}

#define PH "\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s.json\"}]"

int main(void) {
  /* Every message starts with the offending field, so an instructor can find it. */
  expect_error("{", "not valid JSON", PALP_EPARSE);
  expect_error("[]", "top level", PALP_EPARSE);
  expect_error("{}", "phantoms: missing", PALP_EPARSE);
  expect_error("{\"phantoms\": []}", "phantoms: at least one", PALP_EINVAL);
  expect_error("{\"tick_rate_hz\": \"fast\", " PH "}", "tick_rate_hz: expected a number", PALP_EPARSE);
  expect_error("{\"tick_rate_hz\": 0, " PH "}", "tick_rate_hz: 0 is outside", PALP_EINVAL);
  expect_error("{\"domain_id\": 1.5, " PH "}", "domain_id: expected an integer", PALP_EPARSE);
  expect_error("{\"domain_id\": 233, " PH "}", "domain_id: 233 is outside", PALP_EINVAL);
  expect_error("{\"max_force\": -1, " PH "}", "max_force:", PALP_EINVAL);
  expect_error("{\"force_policy\": \"maybe\", " PH "}", "force_policy:", PALP_EINVAL);
  expect_error("{\"session_exercise\": \"yes\", " PH "}",
               "session_exercise: \"yes\" is not \"secured\", \"always\" or \"off\"", PALP_EINVAL);
  expect_error("{\"tick_rate\": 100, " PH "}", "tick_rate: unknown field", PALP_EPARSE);
  /* session 66: the session log's cap, in MB: 0 (none) or 1 .. 10^7 */
  expect_error("{\"session_log_max_mb\": 0.5, " PH "}", "session_log_max_mb: 0.5 is below 1 MB (0 sets no cap)",
               PALP_EINVAL);
  expect_error("{\"session_log_max_mb\": -1, " PH "}", "session_log_max_mb: -1 is outside", PALP_EINVAL);
  expect_error("{\"session_log_max_mb\": 2e7, " PH "}", "session_log_max_mb: 2e+07 is outside", PALP_EINVAL);
  expect_error("{\"session_log_max_mb\": \"16 GB\", " PH "}", "session_log_max_mb: expected a number", PALP_EPARSE);
  expect_error("{\"finger_radius_min\": 0.02, \"finger_radius_max\": 0.01, " PH "}", "finger_radius_max:", PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\"}]}", "phantoms[0].scene: missing", PALP_EPARSE);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": 3}]}", "phantoms[0].scene: expected a string",
               PALP_EPARSE);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s\"}, {\"id\": 1, \"name\": \"b\", "
               "\"scene\": \"s\"}]}",
               "phantoms[1].id: 1 is already used", PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 0, \"name\": \"a\", \"scene\": \"s\"}]}", "phantoms[0].id:", PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s\", \"colour\": 1}]}",
               "phantoms[0].colour: unknown field", PALP_EPARSE);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s\", \"physics_rate_hz\": 0}]}",
               "phantoms[0].physics_rate_hz: 0 is outside", PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s\", \"physics_rate_hz\": \"fast\"}]}",
               "phantoms[0].physics_rate_hz: expected a number", PALP_EPARSE);

  /* session 82: log_interval bounds a flood's log lines, so above 0; one name for one phantom. */
  expect_error("{\"log_interval\": 0, " PH "}", "log_interval: 0 is outside [0.1, 3600]", PALP_EINVAL);
  expect_error("{\"log_interval\": 0.05, " PH "}", "log_interval: 0.05 is outside [0.1, 3600]", PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"\", \"scene\": \"s\"}]}", "phantoms[0].name: empty",
               PALP_EINVAL);
  expect_error("{\"phantoms\": [{\"id\": 1, \"name\": \"dome A\", \"scene\": \"s\"}, {\"id\": 2, \"name\": "
               "\"b\", \"scene\": \"s\"}, {\"id\": 3, \"name\": \"dome A\", \"scene\": \"t\"}]}",
               "phantoms[2].name: \"dome A\" is already used by phantoms[0]", PALP_EINVAL);
  {
    /* an exercise's title, known once it is loaded, against the phantoms' names and the other titles */
    const char *const names[] = {"a", "b", "easy", "a"}, *const titles[] = {"a", "b", "easy", "easy"};
    const char *const empty[] = {"a", ""};
    char e1[512] = "", e2[512] = "", e3[512] = "", e4[512] = "";
    const int r1 = palp_srv_config_check_names(names, 4, 2, e1, sizeof e1);
    const int r2 = palp_srv_config_check_names(titles, 4, 2, e2, sizeof e2);
    const int r3 = palp_srv_config_check_names(empty, 2, 1, e3, sizeof e3);
    const int r4 = palp_srv_config_check_names(names, 3, 2, e4, sizeof e4);
    const int good = r1 == PALP_EINVAL && strstr(e1, "exercises[1] (its title): \"a\" is already used by phantoms[0]") == e1 &&
                     r2 == PALP_EINVAL && strstr(e2, "exercises[1] (its title): \"easy\" is already used by exercises[0]") == e2 &&
                     r3 == PALP_EINVAL && strstr(e3, "exercises[0] (its title): empty") == e3 && r4 == 0;
    fprintf(stderr, "%s hosted names: \"%s\"; \"%s\"; \"%s\"; distinct names %d\n", good ? "ok  " : "FAIL", e1, e2, e3,
            r4);
    failures += !good;
  }
  {
    palp_srv_config c;
    char e[512] = "";
    const int r = palp_srv_config_parse("{\"log_interval\": 0.1, " PH "}", "/base", &c, e, sizeof e);
    const int good = r == 0 && c.log_interval == 0.1;
    fprintf(stderr, "%s log_interval 0.1 accepted (%d %s)\n", good ? "ok  " : "FAIL", r, e);
    failures += !good;
  }

  /* issue 13: exercises, each one more phantom after the phantoms. */
  expect_error("{" PH ", \"exercises\": {}}", "exercises: expected an array", PALP_EPARSE);
  expect_error("{" PH ", \"exercises\": [{\"id\": 2}]}", "exercises[0].file: missing", PALP_EPARSE);
  expect_error("{" PH ", \"exercises\": [{\"id\": 2, \"file\": \"\"}]}", "exercises[0].file: empty", PALP_EINVAL);
  expect_error("{" PH ", \"exercises\": [{\"id\": 1, \"file\": \"e.json\"}]}",
               "exercises[0].id: 1 is already used by phantoms[0]", PALP_EINVAL);
  expect_error("{" PH ", \"exercises\": [{\"id\": 2, \"file\": \"e.json\"}, {\"id\": 2, \"file\": \"f.json\"}]}",
               "exercises[1].id: 2 is already used by exercises[0]", PALP_EINVAL);
  expect_error("{" PH ", \"exercises\": [{\"id\": 2, \"file\": \"e.json\", \"lesions\": []}]}",
               "exercises[0].lesions: unknown field", PALP_EPARSE);
  expect_error("{" PH ", \"exercises\": [{\"id\": 2, \"file\": \"e.json\", \"physics_rate_hz\": 0}]}",
               "exercises[0].physics_rate_hz: 0 is outside", PALP_EINVAL);
  expect_error("{" PH ", \"assess_sample_hz\": 0}", "assess_sample_hz: 0 is outside", PALP_EINVAL);
  {
    palp_srv_config c;
    char e[512] = "";
    int r = palp_srv_config_parse("{" PH ", \"exercises\": [{\"id\": 5, \"file\": \"ex/a.json\", "
                                  "\"physics_rate_hz\": 250}]}", "/base", &c, e, sizeof e);
    int good = r == 0 && c.phantom_count == 2 && c.exercise_count == 1 && c.phantom[1].id == 5 &&
               strcmp(c.phantom[1].exercise_path, "/base/ex/a.json") == 0 && c.phantom[1].physics_rate_hz == 250 &&
               c.phantom[0].exercise_path[0] == 0 && c.assess_sample_hz == 100;
    fprintf(stderr, "%s exercise hosted as phantom 5 after the phantoms, file %s, assess_sample_hz %g\n",
            good ? "ok  " : "FAIL", c.phantom[1].exercise_path, c.assess_sample_hz);
    failures += !good;
  }

  /* Defaults (docs/server.md) and relative paths resolved against the config's directory. */
  palp_srv_config cfg;
  char err[512] = "";
  int rc = palp_srv_config_parse("{" PH "}", "/base", &cfg, err, sizeof err);
  int ok = rc == 0 && cfg.tick_rate_hz == 100 && cfg.domain_id == 0 && cfg.max_sessions == 32 &&
           cfg.deformation_rate_hz == 30 && cfg.max_force == 20 && cfg.force_policy == PALP_SRV_FORCE_CLAMP &&
           cfg.phantom_count == 1 && strcmp(cfg.phantom[0].scene_path, "/base/s.json") == 0 &&
           strcmp(cfg.dds_config, "/base/cyclonedds-loopback.xml") == 0 && cfg.database[0] == 0 &&
           cfg.session_log_max_mb == 0; /* no cap unless the lab sets one */
  fprintf(stderr, "%s defaults: rc %d, %g Hz, %d sessions, scene %s, dds %s\n", ok ? "ok  " : "FAIL", rc,
          cfg.tick_rate_hz, cfg.max_sessions, cfg.phantom[0].scene_path, cfg.dds_config);
  failures += !ok;

  rc = palp_srv_config_parse("{\"phantoms\": [{\"id\": 7, \"name\": \"a\", \"scene\": \"/abs/s.json\"}], "
                             "\"database\": \"../out/x.db\", \"force_policy\": \"reject\", \"tick_rate_hz\": 1000}",
                             "/base", &cfg, err, sizeof err);
  ok = rc == 0 && strcmp(cfg.phantom[0].scene_path, "/abs/s.json") == 0 && strcmp(cfg.database, "/base/../out/x.db") == 0 &&
       cfg.force_policy == PALP_SRV_FORCE_REJECT && cfg.tick_rate_hz == 1000 && cfg.phantom[0].id == 7;
  fprintf(stderr, "%s absolute scene path kept, database resolved (%s)\n", ok ? "ok  " : "FAIL", cfg.database);
  failures += !ok;

  /* session 60: the lesions go to instructors only with DDS Security unless the config says so */
  {
    const char *v[] = {"", "\"session_exercise\": \"always\", ", "\"session_exercise\": \"off\", ",
                       "\"session_exercise\": \"secured\", "};
    const palp_srv_session_exercise_policy want[] = {PALP_SRV_SESSION_EXERCISE_SECURED, PALP_SRV_SESSION_EXERCISE_ALWAYS,
                                                     PALP_SRV_SESSION_EXERCISE_OFF, PALP_SRV_SESSION_EXERCISE_SECURED};
    for (int i = 0; i < 4; i++) {
      char json[256];
      snprintf(json, sizeof json, "{%s" PH "}", v[i]);
      rc = palp_srv_config_parse(json, "/base", &cfg, err, sizeof err);
      ok = rc == 0 && cfg.session_exercise == want[i];
      fprintf(stderr, "%s session_exercise {%s}: %d (want %d)\n", ok ? "ok  " : "FAIL", v[i], (int)cfg.session_exercise,
              (int)want[i]);
      failures += !ok;
    }
  }

  /* A phantom's own physics rate (issue 11); absent = 0, i.e. the server's tick_rate_hz. */
  rc = palp_srv_config_parse("{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s\", \"physics_rate_hz\": 250},"
                             " {\"id\": 2, \"name\": \"b\", \"scene\": \"s\"}]}",
                             "/base", &cfg, err, sizeof err);
  ok = rc == 0 && cfg.phantom[0].physics_rate_hz == 250 && cfg.phantom[1].physics_rate_hz == 0;
  fprintf(stderr, "%s physics_rate_hz: phantom 1 %g Hz, phantom 2 %g (server rate)\n", ok ? "ok  " : "FAIL",
          cfg.phantom[0].physics_rate_hz, cfg.phantom[1].physics_rate_hz);
  failures += !ok;

  /* The shipped configurations load (server-exercises.json: issue 13's exercises). */
  rc = palp_srv_config_load(PALP_CONFIG_DIR "/server-exercises.json", &cfg, err, sizeof err);
  ok = rc == 0 && cfg.exercise_count == 4 && cfg.phantom_count == 9; /* 5 phantoms + 4 exercises */
  fprintf(stderr, "%s shipped config/server-exercises.json: rc %d %s\n", ok ? "ok  " : "FAIL", rc, err);
  failures += !ok;
  /* The shipped configuration loads. */
  rc = palp_srv_config_load(PALP_CONFIG_DIR "/server.json", &cfg, err, sizeof err);
  ok = rc == 0 && cfg.phantom_count >= 1 && cfg.tick_rate_hz == 100;
  fprintf(stderr, "%s shipped config/server.json: rc %d %s\n", ok ? "ok  " : "FAIL", rc, err);
  failures += !ok;
  rc = palp_srv_config_load("/nonexistent/server.json", &cfg, err, sizeof err);
  ok = rc == PALP_EIO && strstr(err, "/nonexistent/server.json: cannot open") != NULL;
  fprintf(stderr, "%s missing file: %s\n", ok ? "ok  " : "FAIL", err);
  failures += !ok;

  fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
