/* test_names.c - the naming rules the access control plugin and the server rely on
 * (docs/security.md): identities, request partitions, station ownership, and the
 * server configuration's "security" block. Pure: no DDS traffic. */
#include <stdio.h>
#include <string.h>

#include "config.h"
#include "identity.h"
#include "palp.h"
#include "palp_dds_security.h"

static int failures;
#define CHECK(cond, what)                                                                                    \
  do {                                                                                                       \
    if (cond)                                                                                                \
      fprintf(stderr, "ok   %s\n", what);                                                                    \
    else {                                                                                                   \
      failures++;                                                                                            \
      fprintf(stderr, "FAIL %s:%d: %s: %s\n", __FILE__, __LINE__, #cond, what);                           \
    }                                                                                                        \
  } while (0)

int main(void) {
  palp_dds_id_kind k = PALP_DDS_ID_NONE;
  char name[PALP_DDS_NAME_MAX], err[256];
  CHECK(palp_dds_identity_parse("trainee/alice", &k, name, sizeof name, err, sizeof err) == 0 &&
            k == PALP_DDS_ID_TRAINEE && !strcmp(name, "alice"),
        "trainee/alice parses");
  CHECK(palp_dds_identity_parse("server", &k, name, sizeof name, err, sizeof err) == 0 && k == PALP_DDS_ID_SERVER &&
            !strcmp(name, "server"),
        "\"server\" is server/server");
  const char *bad[] = {"alice", "trainee/", "trainee/Alice", "trainee/a*", "trainee/a/b", "trainee/a,b",
                       "student/alice", "trainee/aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa" /* 32 */, ""};
  int refused = 0;
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    refused += palp_dds_identity_parse(bad[i], &k, name, sizeof name, err, sizeof err) == PALP_EINVAL;
  CHECK(refused == (int)(sizeof bad / sizeof bad[0]),
        "names with wildcards, separators, capitals, unknown kinds or 32+ characters are refused");

  palp_dds_security sec = {.kind = PALP_DDS_ID_TRAINEE, .name = "alice"};
  char part[64];
  palp_dds_request_partition(&sec, part, sizeof part);
  CHECK(!strcmp(part, "palp/trainee/alice"), "alice requests in palp/trainee/alice");
  palp_dds_secure_session_partition("alice", 7, part, sizeof part);
  CHECK(!strcmp(part, "palp/s/alice/7"), "alice's session 7 lives in palp/s/alice/7");

  CHECK(palp_dds_identity_from_partition("palp/instructor/ines", &k, name, sizeof name) == 0 &&
            k == PALP_DDS_ID_INSTRUCTOR && !strcmp(name, "ines"),
        "palp/instructor/ines is instructor ines");
  const char *bad_parts[] = {"palp/trainee/*", "palp/trainee/al?ce", "palp/server/server", "palp/session/3",
                             "palp/s/alice/3", "", "palp/trainee/", "x/trainee/alice"};
  refused = 0;
  for (size_t i = 0; i < sizeof bad_parts / sizeof bad_parts[0]; i++)
    refused += palp_dds_identity_from_partition(bad_parts[i], &k, name, sizeof name) == PALP_EINVAL;
  CHECK(refused == (int)(sizeof bad_parts / sizeof bad_parts[0]),
        "wildcard, server, session and malformed partitions name no requester");

  palp_srv_requester who = {.kind = PALP_DDS_ID_TRAINEE, .name = "al"};
  CHECK(palp_srv_station_owned_by("trainee/al/host/1/x", &who), "trainee/al owns trainee/al/host/1/x");
  CHECK(!palp_srv_station_owned_by("trainee/alice/host/1/x", &who), "trainee/al does not own trainee/alice/...");
  CHECK(!palp_srv_station_owned_by("trainee/al", &who), "nor the bare identity without a station part");
  CHECK(!palp_srv_station_owned_by("instructor/al/h/1/x", &who), "nor an instructor's station of the same name");

  palp_srv_config cfg;
  const char *base = "{\"phantoms\": [{\"id\": 1, \"name\": \"a\", \"scene\": \"s.json\"}]";
  char json[512];
  snprintf(json, sizeof json, "%s, \"security\": {\"pki\": \"../out/pki\"}}", base);
  CHECK(palp_srv_config_parse(json, "/etc/palp", &cfg, err, sizeof err) == 0 &&
            !strcmp(cfg.security_pki, "/etc/palp/../out/pki") && !strcmp(cfg.security_identity, "server"),
        "\"security\": {\"pki\"} resolves against the config's directory, identity server by default");
  snprintf(json, sizeof json, "%s}", base);
  CHECK(palp_srv_config_parse(json, "/etc/palp", &cfg, err, sizeof err) == 0 && cfg.security_pki[0] == 0,
        "no \"security\": plain DDS");
  snprintf(json, sizeof json, "%s, \"security\": {\"pki\": \"p\", \"identiy\": \"x\"}}", base);
  CHECK(palp_srv_config_parse(json, "", &cfg, err, sizeof err) == PALP_EPARSE && strstr(err, "security.identiy"),
        "a misspelt security field is named");
  snprintf(json, sizeof json, "%s, \"security\": {\"identity\": \"server\"}}", base);
  CHECK(palp_srv_config_parse(json, "", &cfg, err, sizeof err) == PALP_EPARSE && strstr(err, "security.pki"),
        "security without pki is refused");
  fprintf(stderr, "%s\n", failures ? "FAILED" : "passed");
  return failures ? 1 : 0;
}
