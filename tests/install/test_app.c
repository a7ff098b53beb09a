#define _DEFAULT_SOURCE /* realpath */
/* test_app.c - the shared program support (app/): one DDS-config rule, the data
 * directory, and the levelled log's line format, levels and rotation. */
#include <regex.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "palp.h"
#include "palp_app.h"

static int failures;
#define CHECK(cond, ...)                                                                                           \
  do {                                                                                                             \
    if (cond) {                                                                                                    \
      printf("ok   ");                                                                                             \
    } else {                                                                                                       \
      printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                                                       \
      failures++;                                                                                                  \
    }                                                                                                              \
    printf(__VA_ARGS__);                                                                                           \
    printf("\n");                                                                                                  \
  } while (0)

static int count_lines(const char *path, const char *needle) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  char line[4096];
  int n = 0;
  while (fgets(line, sizeof line, f)) n += needle ? strstr(line, needle) != NULL : 1;
  fclose(f);
  return n;
}

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: test_app LOOPBACK_XML TMPDIR\n");
    return 2;
  }
  const char *loopback = argv[1];
  char dir[512], other[600], logp[600], rotated[600];
  snprintf(dir, sizeof dir, "%s/test_app.%ld", argv[2], (long)getpid());
  mkdir(argv[2], 0777);
  mkdir(dir, 0777);
  snprintf(other, sizeof other, "%s/other.xml", dir);
  FILE *f = fopen(other, "w");
  fputs("<CycloneDDS/>\n", f);
  fclose(f);
  char chosen[1200], err[512];
  char real_loopback[1024], real_other[1024];
  realpath(loopback, real_loopback);
  realpath(other, real_other);

  /* 1. The DDS config rule: flag > CYCLONEDDS_URI > fallback > installed default. */
  unsetenv("CYCLONEDDS_URI");
  int rc = palp_app_use_dds_config(NULL, loopback, chosen, sizeof chosen, err, sizeof err);
  CHECK(rc == 0 && !strcmp(chosen, real_loopback), "no flag, no env: the fallback (%s)", chosen);
  CHECK(!strncmp(getenv("CYCLONEDDS_URI"), "file://", 7) && !strcmp(getenv("CYCLONEDDS_URI") + 7, real_loopback),
        "CYCLONEDDS_URI set to file://<absolute fallback>");
  rc = palp_app_use_dds_config(NULL, other, chosen, sizeof chosen, err, sizeof err);
  CHECK(rc == 0 && !strncmp(chosen, "CYCLONEDDS_URI=", 15) && strstr(getenv("CYCLONEDDS_URI"), "cyclonedds-loopback"),
        "CYCLONEDDS_URI set: it wins over the fallback (%s)", chosen);
  rc = palp_app_use_dds_config(other, loopback, chosen, sizeof chosen, err, sizeof err);
  CHECK(rc == 0 && !strcmp(chosen, real_other) && strstr(getenv("CYCLONEDDS_URI"), "other.xml"),
        "--dds-config wins over CYCLONEDDS_URI (%s)", chosen);
  rc = palp_app_use_dds_config("/nonexistent/x.xml", NULL, chosen, sizeof chosen, err, sizeof err);
  CHECK(rc < 0 && strstr(err, "/nonexistent/x.xml"), "a missing --dds-config is an error naming it: %s", err);
  unsetenv("CYCLONEDDS_URI");
  rc = palp_app_use_dds_config(NULL, NULL, chosen, sizeof chosen, err, sizeof err);
  CHECK(rc == 0 && strstr(chosen, "/config/cyclonedds-loopback.xml"),
        "nothing given: the data directory's loopback config (%s)", chosen);

  /* 2. The data directory: PALP_DATA_DIR wins; a bad one is an error, not a fallback. */
  char data[1024];
  setenv("PALP_DATA_DIR", dir, 1);
  rc = palp_app_data_dir(data, sizeof data, err, sizeof err);
  CHECK(rc == 0 && !strcmp(data, dir), "PALP_DATA_DIR=%s", data);
  setenv("PALP_DATA_DIR", "/nonexistent/palp-data", 1);
  rc = palp_app_data_dir(data, sizeof data, err, sizeof err);
  CHECK(rc < 0 && strstr(err, "/nonexistent/palp-data"), "a PALP_DATA_DIR that is not a directory: %s", err);
  unsetenv("PALP_DATA_DIR");
  rc = palp_app_data_path("config/server.json", data, sizeof data, err, sizeof err);
  CHECK(rc == 0 && access(data, R_OK) == 0, "build tree: <data>/config/server.json is readable (%s)", data);

  /* 3. The log: ISO 8601 UTC line format, levels, rotation by re-open. */
  snprintf(logp, sizeof logp, "%s/x.log", dir);
  snprintf(rotated, sizeof rotated, "%s/x.log.1", dir);
  palp_log lg;
  CHECK(palp_log_init(&lg, "palp-test", PALP_LOG_INFO, logp) == 0, "log file opened");
  palp_log_info(&lg, "first %d", 1);
  palp_log_debug(&lg, "hidden at info");
  palp_log_warn(&lg, "a warning");
  palp_log_error(&lg, "an error\n"); /* a trailing newline is not doubled */
  FILE *lf = fopen(logp, "r");
  char line[512] = "";
  if (lf) {
    if (!fgets(line, sizeof line, lf)) line[0] = 0;
    fclose(lf);
  }
  regex_t re;
  regcomp(&re, "^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}\\.[0-9]{3}Z INFO  palp-test: first 1\n$",
          REG_EXTENDED);
  CHECK(regexec(&re, line, 0, NULL, 0) == 0, "line format: %.*s", (int)strcspn(line, "\n"), line);
  regfree(&re);
  CHECK(count_lines(logp, NULL) == 3 && count_lines(logp, "hidden") == 0, "info level: 3 lines, no debug (%d)",
        count_lines(logp, NULL));
  palp_log_set_level(&lg, PALP_LOG_DEBUG);
  palp_log_debug(&lg, "shown at debug");
  CHECK(count_lines(logp, "DEBUG palp-test: shown at debug") == 1, "debug level shows debug lines");
  rename(logp, rotated);
  palp_log_info(&lg, "still to the moved file");
  CHECK(palp_log_reopen(&lg) == 0, "re-open after rotation");
  palp_log_info(&lg, "to the new file");
  CHECK(count_lines(rotated, "still to the moved file") == 1 && count_lines(logp, NULL) == 1 &&
            count_lines(logp, "to the new file") == 1,
        "before re-open: the moved file; after: a new file with 1 line");
  palp_log_close(&lg);
  palp_log_level lv;
  CHECK(palp_log_parse_level("warn", &lv) == 0 && lv == PALP_LOG_WARN && palp_log_parse_level("loud", &lv) < 0,
        "level names parsed, a bad one refused");
  CHECK(palp_log_init(&lg, "palp-test", PALP_LOG_INFO, "/nonexistent/dir/x.log") < 0,
        "an unwritable log file is an error");

  /* 3. Loopback-only DDS configs, or not (palp-server refuses the second kind unsecured). */
  struct {
    const char *xml;
    int want;
    const char *what;
  } scope[] = {
      {"<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\" multicast=\"false\"/>"
       "</Interfaces></General></Domain></CycloneDDS>", 1, "127.0.0.1"},
      {"<Interfaces><NetworkInterface name='lo'/></Interfaces>", 1, "name lo"},
      /* session 77's review: a 127. prefix that is no address (a host name to look up), and
       * multicast received on every interface */
      {"<Domain><General><Interfaces><NetworkInterface name='lo'/></Interfaces></General><Discovery><Peers>"
       "<Peer address=\"127.0.0.256\"/></Peers></Discovery></Domain>", 0, "a peer 127.0.0.256 (no address)"},
      {"<Domain><General><Interfaces><NetworkInterface name='lo'/></Interfaces></General><Discovery><Peers>"
       "<Peer address=\"127..1\"/></Peers></Discovery></Domain>", 0, "a peer 127..1"},
      {"<Domain><General><Interfaces><NetworkInterface name='lo'/></Interfaces></General><Discovery><Peers>"
       "<Peer address=\"127.0.0.1.10\"/></Peers></Discovery></Domain>", 0, "a peer 127.0.0.1.10"},
      {"<Domain><General><Interfaces><NetworkInterface name='lo'/></Interfaces></General><Discovery><Peers>"
       "<Peer address=\"127.3.0.1:7400\"/></Peers></Discovery></Domain>", 1, "a peer 127.3.0.1:7400"},
      {"<General><Interfaces><NetworkInterface name='lo' multicast='true'/></Interfaces><AllowMulticast>true"
       "</AllowMulticast><MulticastRecvNetworkInterfaceAddresses>any</MulticastRecvNetworkInterfaceAddresses></General>",
       0, "multicast received on any interface"},
      {"<General><Interfaces><NetworkInterface name='lo'/></Interfaces><MulticastRecvNetworkInterfaceAddresses>all"
       "</MulticastRecvNetworkInterfaceAddresses></General>", 0, "multicast received on all interfaces"},
      {"<General><Interfaces><NetworkInterface name='lo'/></Interfaces><MulticastRecvNetworkInterfaceAddresses>"
       "127.0.0.1, 192.0.2.7</MulticastRecvNetworkInterfaceAddresses></General>", 0, "multicast received on 192.0.2.7"},
      {"<General><Interfaces><NetworkInterface name='lo'/></Interfaces><MulticastRecvNetworkInterfaceAddresses>"
       "preferred</MulticastRecvNetworkInterfaceAddresses></General>", 1, "multicast received where preferred"},
      {"<General><Interfaces><NetworkInterface name='lo'/></Interfaces><MulticastRecvNetworkInterfaceAddresses>"
       "127.0.0.1</MulticastRecvNetworkInterfaceAddresses></General>", 1, "multicast received on 127.0.0.1"},
      {"<Interfaces><NetworkInterface address=\"::1\"/></Interfaces>", 1, "::1"},
      {"<General><NetworkInterfaceAddress> 127.0.0.1 </NetworkInterfaceAddress></General>", 1, "the older element"},
      {"<Interfaces><NetworkInterface address=\"10.77.0.3\"/></Interfaces>", 0, "10.77.0.3"},
      {"<Interfaces><NetworkInterface name=\"eth0\"/></Interfaces>", 0, "eth0"},
      {"<Interfaces><NetworkInterface name=\"${PALP_DDS_INTERFACE}\"/></Interfaces>", 0, "a variable"},
      {"<Interfaces><NetworkInterface autodetermine=\"true\"/></Interfaces>", 0, "autodetermine"},
      {"<CycloneDDS><Domain><General><AllowMulticast>false</AllowMulticast></General></Domain></CycloneDDS>", 0,
       "no interface"},
      {"<Interfaces><NetworkInterface address=\"127.0.0.1\"/><NetworkInterface address=\"192.0.2.7\"/></Interfaces>",
       0, "loopback and another"},
      {"<Interfaces><!-- <NetworkInterface address=\"192.0.2.7\"/> --><NetworkInterface address=\"127.0.0.1\"/>"
       "</Interfaces>", 1, "a commented-out interface"},
      {"<Interfaces><!-- <NetworkInterface address=\"127.0.0.1\"/> --></Interfaces>", 0, "only a commented-out one"},
      {"<Interfaces><NetworkInterface address=\"127.0.0.1x\"/></Interfaces>", 0, "127.0.0.1x"},
      {"<Interfaces><NetworkInterface/></Interfaces>", 0, "neither address nor name"},
      {"", 0, "empty"},
      /* Cyclone reads names case-insensitively, takes an unambiguous prefix of a name in inline
       * XML, sends discovery to every <Peer> and tells others to send to <ExternalNetworkAddress>. */
      {"<Interfaces><NetworkInterface name=\"lo\"/><networkinterface name=\"eth0\"/></Interfaces>", 0,
       "a lower-case <networkinterface> on eth0"},
      {"<Interfaces><NetworkInterface NAME=\"eth0\"/></Interfaces>", 0, "NAME=eth0"},
      {"<Interfaces><NETWORKINTERFACE Address=\"127.0.0.1\"/></Interfaces>", 1, "upper-case names on loopback"},
      {"<Interfaces><N name=\"eth0\"/></Interfaces>", 0, "<N>, a prefix of NetworkInterface"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General><Discovery><Peers>"
       "<Peer address=\"203.0.113.5\"/></Peers></Discovery></Domain>", 0, "lo with a peer 203.0.113.5"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General><Discovery><Peers>"
       "<Peer Address=\"203.0.113.5:7410\"/></Peers></Discovery></Domain>", 0, "lo with a peer 203.0.113.5:7410"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General><Discovery><Peers>"
       "<P Address=\"203.0.113.5\"/></Peers></Discovery></Domain>", 0, "lo with <P>, a prefix of Peer"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General><Discovery><Peers>"
       "<Peer Address=\"lo\"/></Peers></Discovery></Domain>", 0, "a peer named lo, which is no host"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General><Discovery><Peers>"
       "<Peer Address=\"localhost:7410\"/><Peer Address='[::1]:7410'/><PEER ADDRESS=\"127.0.0.1\"/></Peers>"
       "</Discovery></Domain>", 1, "peers localhost:7410, [::1]:7410 and 127.0.0.1"},
      {"<General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
       "<ExternalNetworkAddress>203.0.113.5</ExternalNetworkAddress></General>", 0, "an external address"},
      {"<Domain Id=\"5\"><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General></Domain>", 0,
       "lo for domain 5 only"},
      {"<Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces><EntityAutoNaming seed=\"<!--\"/>"
       "<Interfaces><NetworkInterface name=\"eth0\"/></Interfaces><EntityAutoNaming seed=\"-->\"/></General></Domain>",
       0, "eth0 between two attribute values that look like a comment"},
      {"<Domain><Discovery><Tag><![CDATA[<NetworkInterface name=\"lo\"/>]]></Tag></Discovery></Domain>", 0,
       "an interface only in CDATA text"},
      {"<CycloneDDS/><CycloneDDS><Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General>"
       "</Domain></CycloneDDS>", 0, "lo only in a second top element"},
      {"<Interfaces><NetworkInterface name=\"lo\"/></Interfaces>, file:///tmp/other.xml", 0, "inline XML and a file"},
  };
  for (size_t k = 0; k < sizeof scope / sizeof scope[0]; k++) {
    char why[200];
    const int got = palp_app_dds_xml_loopback_only(scope[k].xml, why, sizeof why);
    CHECK(got == scope[k].want && why[0], "DDS config with %s: %s (%s)", scope[k].what,
          got ? "loopback only" : "may reach a network", why);
  }
  {
    char uri[2200], why[200];
    snprintf(uri, sizeof uri, "file://%s", real_loopback);
    setenv("CYCLONEDDS_URI", uri, 1);
    CHECK(palp_app_dds_loopback_only(why, sizeof why) == 1, "the shipped loopback config is loopback only (%s)", why);
    setenv("CYCLONEDDS_URI", "<CycloneDDS><Domain><General><Interfaces><NetworkInterface name=\"lo\"/>"
                             "</Interfaces></General></Domain></CycloneDDS>", 1);
    CHECK(palp_app_dds_loopback_only(why, sizeof why) == 1, "inline XML on lo (%s)", why);
    snprintf(uri, sizeof uri, "file://%s,file://%s", real_loopback, real_other);
    setenv("CYCLONEDDS_URI", uri, 1);
    CHECK(palp_app_dds_loopback_only(why, sizeof why) == 0, "two files: not told (%s)", why);
    snprintf(uri, sizeof uri, "file://%s", real_other);
    setenv("CYCLONEDDS_URI", uri, 1);
    CHECK(palp_app_dds_loopback_only(why, sizeof why) == 0, "<CycloneDDS/>: Cyclone's defaults (%s)", why);
    setenv("CYCLONEDDS_URI", "file:///nonexistent/dds.xml", 1);
    CHECK(palp_app_dds_loopback_only(why, sizeof why) == 0, "an unreadable file (%s)", why);
    unsetenv("CYCLONEDDS_URI");
  }

  unlink(logp);
  unlink(rotated);
  unlink(other);
  rmdir(dir);
  printf("%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
