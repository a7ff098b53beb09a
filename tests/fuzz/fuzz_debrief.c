/* fuzz_debrief.c - the session log's debrief event detail (palp_db_debrief_parse), which
 * palp-review reads from a file anyone may have edited and on which its "not blind" rests. An
 * accepted detail obeys the invariants the review relies on and comes back the same when
 * rewritten. */
#include <string.h>

#include "fuzz_util.h"
#include "palp_db.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_cstr(data, size);
  palp_db_debrief d;
  if (palp_db_debrief_parse(text, &d) == 0) {
    if (d.level < PALP_DB_DEBRIEF_NONE || d.level > PALP_DB_DEBRIEF_LESIONS || d.found > d.lesions ||
        d.lesions > PALP_DB_DEBRIEF_MAX_LESIONS || d.listed < 0 || d.listed > PALP_DB_DEBRIEF_MAX_LESIONS ||
        (d.level != PALP_DB_DEBRIEF_LESIONS && d.listed) || (d.sent && d.level == PALP_DB_DEBRIEF_LESIONS && d.listed != d.lesions) ||
        (!d.sent && !d.why[0]) || d.marks < 0 || d.false_marks > d.marks || d.duplicates > d.marks)
      abort();
    int found = 0;
    for (int i = 0; i < d.listed; i++) found += d.found_by[i] != 0;
    if (d.sent && d.level == PALP_DB_DEBRIEF_LESIONS && found != d.found) abort();
    char again[512];
    palp_db_debrief b;
    if (palp_db_debrief_format(&d, again, sizeof again) < 0 || palp_db_debrief_parse(again, &b) != 0 ||
        b.sent != d.sent || b.level != d.level || b.lesions != d.lesions || b.found != d.found || b.marks != d.marks ||
        b.false_marks != d.false_marks || b.duplicates != d.duplicates || b.listed != d.listed ||
        memcmp(b.found_by, d.found_by, sizeof b.found_by) != 0 || strcmp(b.why, d.why) != 0 || strcmp(again, text) != 0)
      abort(); /* one format: a detail accepted is exactly what format writes */
  }
  free(text);
  return 0;
}
