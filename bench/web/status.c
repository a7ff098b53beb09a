/* bench_web_status: prints every palp_server_status sample of a domain for a while, one line each,
 * so bench_web.py can compare the server's tick figures with and without palp-web (it must not be
 * the bridge itself that reads them).
 *   bench_web_status DOMAIN SECONDS
 * Output: "status <uptime s> <load> <tick p50 us> <tick p99 us> <tick max us> <ticks> <overruns> <open>" */
#include <stdio.h>
#include <stdlib.h>

#include <dds/dds.h>

#include "palp_dds.h"

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: bench_web_status DOMAIN SECONDS\n");
    return 2;
  }
  const int domain = atoi(argv[1]);
  const double seconds = atof(argv[2]);
  if (domain < 0 || domain > 232 || !(seconds > 0)) {
    fprintf(stderr, "bench_web_status: bad domain or duration\n");
    return 2;
  }
  if (palp_dds_use_config(PALP_DDS_DEFAULT_CONFIG) != 0) return 2;
  dds_entity_t pp = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (pp < 0) return 1;
  dds_entity_t t = palp_dds_create_topic(pp, PALP_TOPIC_SERVER_STATUS);
  dds_entity_t r = palp_dds_create_reader(pp, t, PALP_TOPIC_SERVER_STATUS);
  const dds_time_t end = dds_time() + (dds_duration_t)(seconds * 1e9);
  while (dds_time() < end) {
    void *ptr[4] = {NULL};
    dds_sample_info_t info[4];
    int n = dds_take(r, ptr, info, 4, 4);
    for (int i = 0; i < n; i++) {
      const palp_ServerStatus *s = ptr[i];
      if (!info[i].valid_data) continue;
      printf("status %.3f %.4f %.1f %.1f %.1f %llu %llu %u\n", s->uptime, s->load, s->tick_us_p50, s->tick_us_p99,
             s->tick_us_max, (unsigned long long)s->ticks, (unsigned long long)s->overruns, s->sessions_open);
      fflush(stdout);
    }
    if (n > 0) dds_return_loan(r, ptr, n);
    dds_sleepfor(DDS_MSECS(50));
  }
  dds_delete(pp);
  return 0;
}
