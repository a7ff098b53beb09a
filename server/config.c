/* config.c - palp-server configuration from JSON (cJSON). */
#include "config.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "palp.h"
#include "palp_assess.h" /* PALP_ASSESS_SAMPLE_HZ */
#include "palp_input_file.h"

static int fail(char *err, size_t errlen, int code, const char *fmt, ...) {
  if (err && errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
  }
  return code;
}

void palp_srv_config_defaults(palp_srv_config *cfg) {
  memset(cfg, 0, sizeof *cfg);
  cfg->domain_id = 0;
  cfg->tick_rate_hz = 100.0;
  cfg->tick_threads = 0;
  cfg->deformation_rate_hz = 30.0;
  cfg->status_rate_hz = 1.0;
  cfg->max_sessions = 32;
  cfg->max_force = 20.0; /* well above the paper's 3 N; a real finger stays < 10 N */
  cfg->force_policy = PALP_SRV_FORCE_CLAMP;
  cfg->session_exercise = PALP_SRV_SESSION_EXERCISE_SECURED; /* lesions on the wire only where permissions guard them */
  cfg->finger_radius_min = 0.002;
  cfg->finger_radius_max = 0.03;
  cfg->log_interval = 1.0;
  cfg->absurd_force = 1000.0; /* no hand presses 1 kN: beyond it is a unit error or an attack */
  cfg->max_viewers = 8;
  cfg->stations_per_writer = 2;
  cfg->join_rate = 20.0;
  cfg->join_burst = 40;
  cfg->closed_retention = 10.0;
  cfg->station_grace = 5.0; /* a station stalled by its machine (swap, a busy core) keeps its session */
  cfg->dds_log_lines = 10;
  cfg->dds_log_window = 10.0;
  cfg->assess_sample_hz = PALP_ASSESS_SAMPLE_HZ;
  snprintf(cfg->dds_config, sizeof cfg->dds_config, "cyclonedds-loopback.xml");
  snprintf(cfg->security_identity, sizeof cfg->security_identity, "server");
}

/* The slowest physics rate a world can step [Hz]: a step is 1 / rate, and palp_world_create
 * refuses steps longer than PALP_WORLD_MAX_DT (0.1 s), so 10 Hz. Below it the start failed
 * with "cannot build the world" naming neither key, and --check passed. */
#define MIN_PHYSICS_RATE_HZ (1.0 / PALP_WORLD_MAX_DT)

static int resolve(const char *base_dir, const char *rel, char *out, size_t outlen) {
  int n;
  if (rel[0] == '/' || !base_dir || !base_dir[0])
    n = snprintf(out, outlen, "%s", rel);
  else
    n = snprintf(out, outlen, "%s/%s", base_dir, rel);
  return (n < 0 || (size_t)n >= outlen) ? -1 : 0;
}

/* Number in [lo, hi]; a missing optional field keeps *v. */
static int get_number(const cJSON *obj, const char *key, const char *where, double lo, double hi,
                      int required, double *v, char *err, size_t errlen) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? fail(err, errlen, PALP_EPARSE, "%s%s: missing", where, key) : 0;
  if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
    return fail(err, errlen, PALP_EPARSE, "%s%s: expected a number", where, key);
  if (it->valuedouble < lo || it->valuedouble > hi)
    return fail(err, errlen, PALP_EINVAL, "%s%s: %g is outside [%g, %g]", where, key, it->valuedouble,
                lo, hi);
  *v = it->valuedouble;
  return 0;
}

/* A physics rate [Hz], optional: MIN_PHYSICS_RATE_HZ to 10 kHz, the reason said when too slow. */
static int get_rate(const cJSON *obj, const char *key, const char *where, double *v, char *err, size_t errlen) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (cJSON_IsNumber(it) && isfinite(it->valuedouble) && it->valuedouble < MIN_PHYSICS_RATE_HZ)
    return fail(err, errlen, PALP_EINVAL,
                "%s%s: %g is outside [%g, 10000] (a slower step is longer than the %g s a world steps)", where, key,
                it->valuedouble, MIN_PHYSICS_RATE_HZ, PALP_WORLD_MAX_DT);
  return get_number(obj, key, where, MIN_PHYSICS_RATE_HZ, 10000, 0, v, err, errlen);
}

static int get_int(const cJSON *obj, const char *key, const char *where, double lo, double hi,
                   int required, int64_t *v, char *err, size_t errlen) {
  double d = (double)*v;
  int rc = get_number(obj, key, where, lo, hi, required, &d, err, errlen);
  if (rc) return rc;
  if (d != floor(d)) return fail(err, errlen, PALP_EPARSE, "%s%s: expected an integer", where, key);
  *v = (int64_t)d;
  return 0;
}

static int get_string(const cJSON *obj, const char *key, const char *where, int required, char *out,
                      size_t outlen, char *err, size_t errlen) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return required ? fail(err, errlen, PALP_EPARSE, "%s%s: missing", where, key) : 0;
  if (!cJSON_IsString(it)) return fail(err, errlen, PALP_EPARSE, "%s%s: expected a string", where, key);
  if (strlen(it->valuestring) >= outlen)
    return fail(err, errlen, PALP_EINVAL, "%s%s: longer than %zu characters", where, key, outlen - 1);
  snprintf(out, outlen, "%s", it->valuestring);
  return 0;
}

/* A string that must be one of names (NULL-terminated, at most 8); *out keeps its value when the
 * key is absent, else becomes the name's index. */
static int get_choice(const cJSON *obj, const char *key, const char *where, const char *const *names, int *out,
                      char *err, size_t errlen) {
  char v[32] = "";
  int rc = get_string(obj, key, where, 0, v, sizeof v, err, errlen);
  if (rc || !cJSON_GetObjectItemCaseSensitive(obj, key)) return rc;
  int n = 0;
  for (; names[n]; n++)
    if (strcmp(v, names[n]) == 0) {
      *out = n;
      return 0;
    }
  char list[160] = "";
  size_t at = 0;
  for (int i = 0; i < n && at < sizeof list; i++)
    at += (size_t)snprintf(list + at, sizeof list - at, "%s\"%s\"", i == 0 ? "" : i == n - 1 ? (n == 2 ? " nor " : " or ") : ", ",
                           names[i]);
  return fail(err, errlen, PALP_EINVAL, "%s%s: \"%s\" is %s %s", where, key, v, n == 2 ? "neither" : "not", list);
}

/* A misspelt key would otherwise silently fall back to a default. */
static int check_keys(const cJSON *obj, const char *where, const char *const *known, char *err,
                      size_t errlen) {
  for (const cJSON *it = obj->child; it; it = it->next) {
    int ok = 0;
    for (const char *const *k = known; *k; k++)
      if (strcmp(*k, it->string) == 0) ok = 1;
    if (!ok) return fail(err, errlen, PALP_EPARSE, "%s%s: unknown field", where, it->string);
  }
  return 0;
}

static const char *const top_keys[] = {"domain_id",      "tick_rate_hz",   "tick_threads", "tick_priority",
                                       "deformation_rate_hz", "status_rate_hz", "max_sessions",
                                       "max_force",      "force_policy",   "finger_radius_min",
                                       "finger_radius_max", "log_interval", "dds_config",
                                       "database",       "phantoms",       "comment",
                                       "absurd_force",   "max_viewers",    "stations_per_writer",
                                       "join_rate",      "join_burst",     "closed_retention",
                                       "dds_log_lines",  "dds_log_window", "security",
                                       "server_name",    "server_number",  "log_level",      "exercises",
                                       "assess_sample_hz", "station_grace", "session_exercise",
                                       "session_log_max_mb", NULL};
static const char *const security_keys[] = {"pki", "identity", "comment", NULL};
static const char *const phantom_keys[] = {"id", "name", "scene", "physics_rate_hz", "comment", NULL};
static const char *const exercise_keys[] = {"id", "file", "physics_rate_hz", "comment", NULL};

/* "phantoms[i].name" or "exercises[j] (its title)": the entry a hosted phantom's name comes from. */
static void name_entry(int i, int plain, char *out, size_t len) {
  if (i < plain) snprintf(out, len, "phantoms[%d].name", i);
  else snprintf(out, len, "exercises[%d] (its title)", i - plain);
}

int palp_srv_config_check_names(const char *const *names, int count, int plain, char *err, size_t errlen) {
  char a[48], b[48];
  for (int i = 0; i < count; i++) {
    name_entry(i, plain, a, sizeof a);
    if (!names[i][0]) return fail(err, errlen, PALP_EINVAL, "%s: empty (a station chooses a phantom by its name)", a);
    for (int j = 0; j < i; j++)
      if (strcmp(names[i], names[j]) == 0) {
        name_entry(j, plain, b, sizeof b);
        return fail(err, errlen, PALP_EINVAL,
                    "%s: \"%s\" is already used by %s (a station chooses a phantom by its name: one name, one "
                    "phantom)", a, names[i], b);
      }
  }
  return 0;
}

int palp_srv_config_check_ids(const palp_srv_config *cfg, char *err, size_t errlen) {
  /* A numbered server puts its number in the high bits of every id it hands out
   * (PALP_DDS_ID): its own ids must leave them free. */
  if (cfg->server_number == 0) return 0;
  const int plain = cfg->phantom_count - cfg->exercise_count;
  for (int i = 0; i < cfg->phantom_count; i++)
    if (cfg->phantom[i].id > PALP_SRV_MAX_LOCAL_ID)
      return fail(err, errlen, PALP_EINVAL, "%s[%d].id: %u is above %u, the largest id a server with a "
                  "server_number can qualify", i < plain ? "phantoms" : "exercises", i < plain ? i : i - plain,
                  cfg->phantom[i].id, PALP_SRV_MAX_LOCAL_ID);
  return 0;
}

static int parse_phantoms(const cJSON *arr, const char *base_dir, palp_srv_config *cfg, char *err,
                          size_t errlen) {
  if (!arr) return fail(err, errlen, PALP_EPARSE, "phantoms: missing");
  if (!cJSON_IsArray(arr)) return fail(err, errlen, PALP_EPARSE, "phantoms: expected an array");
  int n = cJSON_GetArraySize(arr);
  if (n < 1) return fail(err, errlen, PALP_EINVAL, "phantoms: at least one phantom is needed");
  if (n > PALP_SRV_MAX_PHANTOMS)
    return fail(err, errlen, PALP_EINVAL, "phantoms: %d phantoms, at most %d", n, PALP_SRV_MAX_PHANTOMS);
  for (int i = 0; i < n; i++) {
    const cJSON *p = cJSON_GetArrayItem(arr, i);
    char where[32];
    snprintf(where, sizeof where, "phantoms[%d].", i);
    if (!cJSON_IsObject(p)) return fail(err, errlen, PALP_EPARSE, "phantoms[%d]: expected an object", i);
    int rc = check_keys(p, where, phantom_keys, err, errlen);
    if (rc) return rc;
    palp_srv_phantom_cfg *ph = &cfg->phantom[i];
    int64_t id = 0;
    if ((rc = get_int(p, "id", where, 1, 4294967295.0, 1, &id, err, errlen))) return rc;
    ph->id = (uint32_t)id;
    for (int j = 0; j < i; j++)
      if (cfg->phantom[j].id == ph->id)
        return fail(err, errlen, PALP_EINVAL, "%sid: %u is already used by phantoms[%d]", where, ph->id,
                    j);
    if ((rc = get_string(p, "name", where, 1, ph->name, sizeof ph->name, err, errlen))) return rc;
    {
      const char *names[PALP_SRV_MAX_PHANTOMS];
      for (int j = 0; j <= i; j++) names[j] = cfg->phantom[j].name;
      if ((rc = palp_srv_config_check_names(names, i + 1, i + 1, err, errlen))) return rc;
    }
    char scene[PALP_SRV_PATH_MAX];
    if ((rc = get_string(p, "scene", where, 1, scene, sizeof scene, err, errlen))) return rc;
    if (resolve(base_dir, scene, ph->scene_path, sizeof ph->scene_path))
      return fail(err, errlen, PALP_EINVAL, "%sscene: path too long", where);
    ph->physics_rate_hz = 0;
    if ((rc = get_rate(p, "physics_rate_hz", where, &ph->physics_rate_hz, err, errlen))) return rc;
  }
  cfg->phantom_count = n;
  return 0;
}

/* "exercises": [{"id": N, "file": "exercises/easy.json", "physics_rate_hz": 250}]: each becomes
 * one more hosted phantom (after the phantoms, sharing their id space and their limit); the
 * server loads the exercise file itself (its name, phantom and lesions: palp_exercise_load). */
static int parse_exercises(const cJSON *arr, const char *base_dir, palp_srv_config *cfg, char *err,
                           size_t errlen) {
  cfg->exercise_count = 0;
  if (!arr) return 0;
  if (!cJSON_IsArray(arr)) return fail(err, errlen, PALP_EPARSE, "exercises: expected an array");
  const int n = cJSON_GetArraySize(arr);
  if (cfg->phantom_count + n > PALP_SRV_MAX_PHANTOMS)
    return fail(err, errlen, PALP_EINVAL, "exercises: %d phantoms and %d exercises, at most %d in all",
                cfg->phantom_count, n, PALP_SRV_MAX_PHANTOMS);
  for (int i = 0; i < n; i++) {
    const cJSON *p = cJSON_GetArrayItem(arr, i);
    char where[32];
    snprintf(where, sizeof where, "exercises[%d].", i);
    if (!cJSON_IsObject(p)) return fail(err, errlen, PALP_EPARSE, "exercises[%d]: expected an object", i);
    int rc = check_keys(p, where, exercise_keys, err, errlen);
    if (rc) return rc;
    palp_srv_phantom_cfg *ph = &cfg->phantom[cfg->phantom_count + i];
    memset(ph, 0, sizeof *ph);
    int64_t id = 0;
    if ((rc = get_int(p, "id", where, 1, 4294967295.0, 1, &id, err, errlen))) return rc;
    ph->id = (uint32_t)id;
    for (int j = 0; j < cfg->phantom_count + i; j++)
      if (cfg->phantom[j].id == ph->id)
        return fail(err, errlen, PALP_EINVAL, "%sid: %u is already used by %s[%d]", where, ph->id,
                    j < cfg->phantom_count ? "phantoms" : "exercises",
                    j < cfg->phantom_count ? j : j - cfg->phantom_count);
    char file[PALP_SRV_PATH_MAX];
    if ((rc = get_string(p, "file", where, 1, file, sizeof file, err, errlen))) return rc;
    if (!file[0]) return fail(err, errlen, PALP_EINVAL, "%sfile: empty", where);
    if (resolve(base_dir, file, ph->exercise_path, sizeof ph->exercise_path))
      return fail(err, errlen, PALP_EINVAL, "%sfile: path too long", where);
    ph->physics_rate_hz = 0;
    if ((rc = get_rate(p, "physics_rate_hz", where, &ph->physics_rate_hz, err, errlen))) return rc;
    snprintf(ph->name, sizeof ph->name, "exercise %u", ph->id); /* the title replaces it once loaded */
  }
  cfg->phantom_count += n;
  cfg->exercise_count = n;
  return 0;
}

/* "security": {"pki": DIR, "identity": "server"}: the classroom PKI made by
 * scripts/make-classroom-pki.sh; the files themselves are checked when the
 * participant is created (palp_dds_security_init). */
static int parse_security(const cJSON *sec, const char *base_dir, palp_srv_config *cfg, char *err, size_t errlen) {
  if (!sec) return 0;
  if (!cJSON_IsObject(sec)) return fail(err, errlen, PALP_EPARSE, "security: expected an object");
  int rc = check_keys(sec, "security.", security_keys, err, errlen);
  if (rc) return rc;
  char tmp[PALP_SRV_PATH_MAX] = "";
  if ((rc = get_string(sec, "pki", "security.", 1, tmp, sizeof tmp, err, errlen))) return rc;
  if (!tmp[0]) return fail(err, errlen, PALP_EINVAL, "security.pki: empty (leave \"security\" out for plain DDS)");
  if (resolve(base_dir, tmp, cfg->security_pki, sizeof cfg->security_pki))
    return fail(err, errlen, PALP_EINVAL, "security.pki: path too long");
  if ((rc = get_string(sec, "identity", "security.", 0, cfg->security_identity, sizeof cfg->security_identity, err,
                       errlen)))
    return rc;
  return 0;
}

int palp_srv_config_parse(const char *json, const char *base_dir, palp_srv_config *cfg, char *err,
                          size_t errlen) {
  palp_srv_config_defaults(cfg);
  char why[200];
  cJSON *root = palp_json_parse_strict(json, why, sizeof why);
  if (!root) return fail(err, errlen, PALP_EPARSE, "%s", why);
  int rc = 0;
  const char *w = "";
  int64_t i64;
  if (!cJSON_IsObject(root)) {
    rc = fail(err, errlen, PALP_EPARSE, "top level: expected an object");
    goto out;
  }
  if ((rc = check_keys(root, w, top_keys, err, errlen))) goto out;
  i64 = cfg->domain_id;
  /* 232 is the largest domain whose RTPS ports fit in 16 bits. */
  if ((rc = get_int(root, "domain_id", w, 0, 232, 0, &i64, err, errlen))) goto out;
  cfg->domain_id = (uint32_t)i64;
  if ((rc = get_rate(root, "tick_rate_hz", w, &cfg->tick_rate_hz, err, errlen))) goto out;
  i64 = cfg->tick_threads;
  if ((rc = get_int(root, "tick_threads", w, 0, 64, 0, &i64, err, errlen))) goto out;
  cfg->tick_threads = (int)i64;
  i64 = cfg->tick_priority;
  if ((rc = get_int(root, "tick_priority", w, 0, 99, 0, &i64, err, errlen))) goto out;
  cfg->tick_priority = (int)i64;
  if ((rc = get_number(root, "deformation_rate_hz", w, 0.1, 1000, 0, &cfg->deformation_rate_hz, err,
                       errlen)))
    goto out;
  if ((rc = get_number(root, "status_rate_hz", w, 0.1, 100, 0, &cfg->status_rate_hz, err, errlen)))
    goto out;
  i64 = cfg->max_sessions;
  if ((rc = get_int(root, "max_sessions", w, 1, 1024, 0, &i64, err, errlen))) goto out;
  cfg->max_sessions = (int)i64;
  if ((rc = get_number(root, "max_force", w, 0.01, PALP_SRV_CFG_MAX_FORCE_MAX, 0, &cfg->max_force, err, errlen))) goto out;
  if ((rc = get_number(root, "finger_radius_min", w, PALP_SRV_CFG_FINGER_RADIUS_MIN, PALP_SRV_CFG_FINGER_RADIUS_MAX, 0, &cfg->finger_radius_min, err, errlen)))
    goto out;
  if ((rc = get_number(root, "finger_radius_max", w, PALP_SRV_CFG_FINGER_RADIUS_MIN, PALP_SRV_CFG_FINGER_RADIUS_MAX, 0, &cfg->finger_radius_max, err, errlen)))
    goto out;
  if (cfg->finger_radius_max < cfg->finger_radius_min) {
    rc = fail(err, errlen, PALP_EINVAL, "finger_radius_max: %g is below finger_radius_min %g",
              cfg->finger_radius_max, cfg->finger_radius_min);
    goto out;
  }
  /* Above 0 (since session 82): it bounds the server's log lines of a flood of bad samples, each
   * reason's at one a log_interval; 0 wrote a line (and a flush) per sample on the tick thread. */
  {
    const cJSON *li = cJSON_GetObjectItemCaseSensitive(root, "log_interval");
    if (cJSON_IsNumber(li) && isfinite(li->valuedouble) && li->valuedouble < 0.1) {
      rc = fail(err, errlen, PALP_EINVAL,
                "log_interval: %g is outside [0.1, 3600] (it bounds a flood's log lines to one per interval "
                "and reason)", li->valuedouble);
      goto out;
    }
  }
  if ((rc = get_number(root, "log_interval", w, 0.1, 3600, 0, &cfg->log_interval, err, errlen))) goto out;
  /* 0 (no cap) or at least 1 MB: a smaller cap would hold less than a minute's session; at most 10 TB */
  if ((rc = get_number(root, "session_log_max_mb", w, 0, 1e7, 0, &cfg->session_log_max_mb, err, errlen))) goto out;
  if (cfg->session_log_max_mb > 0 && cfg->session_log_max_mb < 1) {
    rc = fail(err, errlen, PALP_EINVAL, "session_log_max_mb: %g is below 1 MB (0 sets no cap)", cfg->session_log_max_mb);
    goto out;
  }
  if ((rc = get_number(root, "absurd_force", w, 0.01, PALP_SRV_CFG_ABSURD_FORCE_MAX, 0, &cfg->absurd_force, err, errlen))) goto out;
  if (cfg->absurd_force < cfg->max_force) {
    rc = fail(err, errlen, PALP_EINVAL, "absurd_force: %g is below max_force %g", cfg->absurd_force,
              cfg->max_force);
    goto out;
  }
  i64 = cfg->max_viewers;
  if ((rc = get_int(root, "max_viewers", w, 0, 64, 0, &i64, err, errlen))) goto out;
  cfg->max_viewers = (int)i64;
  i64 = cfg->stations_per_writer;
  if ((rc = get_int(root, "stations_per_writer", w, 1, 64, 0, &i64, err, errlen))) goto out;
  cfg->stations_per_writer = (int)i64;
  if ((rc = get_number(root, "join_rate", w, 0.01, 10000, 0, &cfg->join_rate, err, errlen))) goto out;
  i64 = cfg->join_burst;
  if ((rc = get_int(root, "join_burst", w, 1, 100000, 0, &i64, err, errlen))) goto out;
  cfg->join_burst = (int)i64;
  if ((rc = get_number(root, "closed_retention", w, 0, 86400, 0, &cfg->closed_retention, err, errlen)))
    goto out;
  if ((rc = get_number(root, "station_grace", w, 0, 600, 0, &cfg->station_grace, err, errlen))) goto out;
  i64 = cfg->dds_log_lines;
  if ((rc = get_int(root, "dds_log_lines", w, 0, 100000, 0, &i64, err, errlen))) goto out;
  cfg->dds_log_lines = (int)i64;
  if ((rc = get_number(root, "dds_log_window", w, 0.1, 86400, 0, &cfg->dds_log_window, err, errlen)))
    goto out;
  {
    /* in the order of palp_srv_force_policy */
    static const char *const policies[] = {"clamp", "reject", NULL};
    int policy = (int)cfg->force_policy;
    if ((rc = get_choice(root, "force_policy", w, policies, &policy, err, errlen))) goto out;
    cfg->force_policy = (palp_srv_force_policy)policy;
  }
  {
    char tmp[PALP_SRV_PATH_MAX];
    snprintf(tmp, sizeof tmp, "%s", cfg->dds_config);
    if ((rc = get_string(root, "dds_config", w, 0, tmp, sizeof tmp, err, errlen))) goto out;
    if (resolve(base_dir, tmp, cfg->dds_config, sizeof cfg->dds_config)) {
      rc = fail(err, errlen, PALP_EINVAL, "dds_config: path too long");
      goto out;
    }
    tmp[0] = 0;
    if ((rc = get_string(root, "database", w, 0, tmp, sizeof tmp, err, errlen))) goto out;
    if (tmp[0] && resolve(base_dir, tmp, cfg->database, sizeof cfg->database)) {
      rc = fail(err, errlen, PALP_EINVAL, "database: path too long");
      goto out;
    }
  }
  if ((rc = get_number(root, "assess_sample_hz", w, 1, 10000, 0, &cfg->assess_sample_hz, err, errlen))) goto out;
  {
    /* in the order of palp_srv_session_exercise_policy */
    static const char *const policies[] = {"secured", "always", "off", NULL};
    int policy = (int)cfg->session_exercise;
    if ((rc = get_choice(root, "session_exercise", w, policies, &policy, err, errlen))) goto out;
    cfg->session_exercise = (palp_srv_session_exercise_policy)policy;
  }
  if ((rc = parse_security(cJSON_GetObjectItemCaseSensitive(root, "security"), base_dir, cfg, err, errlen))) goto out;
  if ((rc = get_string(root, "log_level", w, 0, cfg->log_level, sizeof cfg->log_level, err, errlen))) goto out;
  if (cfg->log_level[0] && strcmp(cfg->log_level, "error") && strcmp(cfg->log_level, "warn") &&
      strcmp(cfg->log_level, "warning") && strcmp(cfg->log_level, "info") && strcmp(cfg->log_level, "debug")) {
    rc = fail(err, errlen, PALP_EINVAL, "log_level: \"%s\" is not error, warn, info or debug", cfg->log_level);
    goto out;
  }
  if ((rc = get_string(root, "server_name", w, 0, cfg->server_name, sizeof cfg->server_name, err, errlen))) goto out;
  i64 = cfg->server_number;
  if ((rc = get_int(root, "server_number", w, 0, PALP_SRV_MAX_SERVER_NUMBER, 0, &i64, err, errlen))) goto out;
  cfg->server_number = (uint32_t)i64;
  rc = parse_phantoms(cJSON_GetObjectItemCaseSensitive(root, "phantoms"), base_dir, cfg, err, errlen);
  if (rc == 0) rc = parse_exercises(cJSON_GetObjectItemCaseSensitive(root, "exercises"), base_dir, cfg, err, errlen);
  if (!rc) rc = palp_srv_config_check_ids(cfg, err, errlen);
out:
  cJSON_Delete(root);
  return rc;
}

int palp_srv_config_load(const char *path, palp_srv_config *cfg, char *err, size_t errlen) {
  /* A configuration is a few kB: 1 MiB (as for exercise files) bounds what a wrong path makes
   * us hold; --config /dev/zero read until memory ran out, and a FIFO hung the start. */
  char *buf, why[200];
  const int rd = palp_input_file_read(path, (size_t)1 << 20, &buf, NULL, why, sizeof why);
  if (rd) return fail(err, errlen, rd, "%s: %s", path, why);
  char dir[PALP_SRV_PATH_MAX];
  snprintf(dir, sizeof dir, "%s", path);
  char *slash = strrchr(dir, '/');
  if (slash)
    *slash = 0;
  else
    snprintf(dir, sizeof dir, ".");
  char inner[512];
  int rc = palp_srv_config_parse(buf, dir, cfg, inner, sizeof inner);
  free(buf);
  if (rc) return fail(err, errlen, rc, "%s: %s", path, inner);
  return 0;
}
