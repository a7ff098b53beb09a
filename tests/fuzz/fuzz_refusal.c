/* fuzz_refusal.c - a Cyclone warning about a peer DDS Security refused (palp_dds_refusal_parse),
 * whose subject and reason come from that peer's certificate, so from the network; then the
 * refusal table every palp DDS program keeps (palp_dds_refusals). A parsed refusal must be
 * two terminated, printable fields of bounded size, and the table must count it once and say
 * it in one line; a GUID that parses names the peer by the identity given that prefix exactly
 * when it was refused for its permissions. */
#include "fuzz_util.h"
#include "palp_dds_refusals.h"

static void count_line(void *ctx, const char *line) {
  if (strchr(line, '\n')) abort(); /* one refusal, one log line */
  ++*(int *)ctx;
}

static int printable(const char *s, size_t cap) {
  const size_t n = strnlen(s, cap);
  if (n == cap) return 0;
  for (size_t i = 0; i < n; i++)
    if ((unsigned char)s[i] < 0x20 || (unsigned char)s[i] >= 0x7f) return 0;
  return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  palp_dds_refusal r;
  memset(&r, 0x55, sizeof r); /* the parser must not rely on a cleared struct */
  if (!palp_dds_refusal_parse((const char *)data, size, &r)) return 0;
  if (!printable(r.who, sizeof r.who) || !printable(r.why, sizeof r.why) || !r.who[0]) abort();
  if (r.kind != PALP_DDS_REFUSED_HANDSHAKE && r.kind != PALP_DDS_REFUSED_PERMISSIONS) abort();
  palp_dds_refusals t;
  int lines = 0;
  palp_dds_refusals_init(&t, count_line, &lines, 60.0);
  unsigned char pre[6];
  const int has_guid = palp_dds_refusal_guid_prefix(r.who, pre);
  if (has_guid && strncmp(r.who, "participant ", 12)) abort();
  if (has_guid) {
    palp_dds_peer_name nm = {.who = "trainee/x"};
    memcpy(nm.prefix, pre, sizeof pre);
    if (palp_dds_refusals_set_names(&t, &nm, 1) != 0) abort();
  }
  palp_dds_refusals_note(&t, &r, 0);
  palp_dds_refusal_entry e;
  if (palp_dds_refusals_list(&t, &e, 1) != 1) abort();
  const int named = !strcmp(e.r.who, "trainee/x");
  if (named != (has_guid && r.kind == PALP_DDS_REFUSED_PERMISSIONS) && strcmp(r.who, "trainee/x")) abort();
  palp_dds_refusals_note(&t, &r, 1000000000LL);
  palp_dds_refusals_flush(&t);
  uint64_t total = 0;
  palp_dds_refusals_counts(&t, &total, NULL);
  if (total != 2 || lines != 2) abort(); /* the first at once, the repeat at the flush */
  palp_dds_refusals_destroy(&t);
  return 0;
}
