/* debrief.c - the detail of a debrief event (PALP_DB_EVENT_DEBRIEF): what an exercise session's
 * trainee was told as it closed, written by palp-server (server/db_log.c) and palp-recorder, read
 * back by palp-review (its "not blind" rule and the debrief it shows the instructor). One format,
 * written and parsed here, so the writers and the reader cannot drift. The row is from a file an
 * instructor may be handed: every number is checked against the others before it is used. */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "palp_db.h"

static const char *const LEVEL[] = {"none", "count", "lesions"};

const char *palp_db_debrief_level_name(palp_db_debrief_level l) {
  return (l >= PALP_DB_DEBRIEF_NONE && l <= PALP_DB_DEBRIEF_LESIONS) ? LEVEL[l] : NULL;
}

static int level_of(const char *s, size_t n) {
  for (int i = 0; i < 3; i++)
    if (strlen(LEVEL[i]) == n && !strncmp(s, LEVEL[i], n)) return i;
  return -1;
}

/* The rules the wire's checker applies (palp_dds_debrief_ok), plus the log's own: nothing but
 * the count of marks at level none, a lesion listed only at level lesions and then all of them. */
static int consistent(const palp_db_debrief *d) {
  if (!palp_db_debrief_level_name(d->level)) return 0;
  if (d->marks < 0 || d->marks > 1000000 || d->lesions < 0 || d->found < 0 || d->false_marks < 0 ||
      d->duplicates < 0 || d->listed < 0)
    return 0;
  if (!d->sent) return d->why[0] != '\0' && !strchr(d->why, '\n');
  if (d->level == PALP_DB_DEBRIEF_NONE)
    return d->lesions == 0 && d->found == 0 && d->false_marks == 0 && d->duplicates == 0 && d->listed == 0;
  if (d->lesions > PALP_DB_DEBRIEF_MAX_LESIONS || d->found > d->lesions || d->false_marks > d->marks ||
      d->duplicates > d->marks)
    return 0;
  if (d->level == PALP_DB_DEBRIEF_COUNT) return d->listed == 0;
  if (d->listed != d->lesions) return 0;
  int found = 0;
  for (int i = 0; i < d->listed; i++) found += d->found_by[i] != 0;
  return found == d->found;
}

int palp_db_debrief_format(const palp_db_debrief *d, char *buf, size_t len) {
  if (!d || !buf || !consistent(d)) return PALP_EINVAL;
  const char *lv = LEVEL[d->level];
  if (!d->sent) return snprintf(buf, len, "not sent (level %s): %s", lv, d->why);
  if (d->level == PALP_DB_DEBRIEF_NONE) return snprintf(buf, len, "told at level none: marks standing %d", d->marks);
  int n = snprintf(buf, len, "told at level %s: found %d of %d lesions; marks standing %d, near no lesion %d, duplicates %d",
                   lv, d->found, d->lesions, d->marks, d->false_marks, d->duplicates);
  if (d->level == PALP_DB_DEBRIEF_LESIONS && n >= 0) {
    const char *head = "; found by marks";
    n += snprintf(len > (size_t)n ? buf + n : NULL, len > (size_t)n ? len - (size_t)n : 0, "%s", head);
    for (int i = 0; i < d->listed && n >= 0; i++)
      n += snprintf(len > (size_t)n ? buf + n : NULL, len > (size_t)n ? len - (size_t)n : 0, " %" PRIu32, d->found_by[i]);
  }
  return n;
}

/* A strict reader of what format writes: literal text, and unsigned decimal numbers of at most
 * 10 digits (no sign, no space, no leading zero but 0 itself) up to max. */
static int lit(const char **p, const char *s) {
  const size_t n = strlen(s);
  if (strncmp(*p, s, n)) return 0;
  *p += n;
  return 1;
}

static int num(const char **p, uint64_t max, uint64_t *out) {
  const char *q = *p;
  uint64_t v = 0;
  int k = 0;
  while (q[k] >= '0' && q[k] <= '9' && k < 11) v = v * 10 + (uint64_t)(q[k] - '0'), k++;
  if (k == 0 || k > 10 || (k > 1 && q[0] == '0') || v > max) return 0;
  *out = v;
  *p = q + k;
  return 1;
}

static int inum(const char **p, int *out) {
  uint64_t v;
  if (!num(p, 1000000000u, &v)) return 0;
  *out = (int)v;
  return 1;
}

int palp_db_debrief_parse(const char *detail, palp_db_debrief *out) {
  if (!detail || !out) return PALP_EINVAL;
  palp_db_debrief d;
  memset(&d, 0, sizeof d);
  const char *p = detail;
  if (lit(&p, "not sent (level ")) {
    const char *close = strstr(p, "): ");
    if (!close) return PALP_EINVAL;
    const int l = level_of(p, (size_t)(close - p));
    const char *why = close + 3;
    if (l < 0 || strlen(why) >= sizeof d.why) return PALP_EINVAL;
    d.level = (palp_db_debrief_level)l;
    snprintf(d.why, sizeof d.why, "%s", why);
  } else if (lit(&p, "told at level none: marks standing ")) {
    d.sent = 1;
    if (!inum(&p, &d.marks) || *p) return PALP_EINVAL;
  } else if (lit(&p, "told at level ")) {
    d.sent = 1;
    if (lit(&p, "count")) d.level = PALP_DB_DEBRIEF_COUNT;
    else if (lit(&p, "lesions")) d.level = PALP_DB_DEBRIEF_LESIONS;
    else return PALP_EINVAL;
    if (!lit(&p, ": found ") || !inum(&p, &d.found) || !lit(&p, " of ") || !inum(&p, &d.lesions) ||
        !lit(&p, " lesions; marks standing ") || !inum(&p, &d.marks) || !lit(&p, ", near no lesion ") ||
        !inum(&p, &d.false_marks) || !lit(&p, ", duplicates ") || !inum(&p, &d.duplicates))
      return PALP_EINVAL;
    if (d.level == PALP_DB_DEBRIEF_LESIONS) {
      if (!lit(&p, "; found by marks")) return PALP_EINVAL;
      while (*p) {
        uint64_t v;
        if (d.listed >= PALP_DB_DEBRIEF_MAX_LESIONS || !lit(&p, " ") || !num(&p, UINT32_MAX, &v)) return PALP_EINVAL;
        d.found_by[d.listed++] = (uint32_t)v;
      }
    } else if (*p) {
      return PALP_EINVAL;
    }
  } else {
    return PALP_EINVAL;
  }
  if (!consistent(&d)) return PALP_EINVAL;
  *out = d;
  return 0;
}

typedef struct find_ctx {
  int found, bad;
  palp_db_debrief d;
} find_ctx;

static int take_event(void *user, double wall, int64_t frame, const char *kind, const char *detail, int64_t count) {
  (void)wall, (void)frame, (void)count;
  find_ctx *c = user;
  if (!kind || strcmp(kind, palp_db_event_kind_name(PALP_DB_EVENT_DEBRIEF))) return 0;
  c->found = 1;
  c->bad = palp_db_debrief_parse(detail, &c->d) < 0;
  return 0;
}

int palp_db_session_debrief(palp_db *db, int64_t session_id, palp_db_debrief *out) {
  if (!db || !out) return PALP_EINVAL;
  find_ctx c;
  memset(&c, 0, sizeof c);
  const int rc = palp_db_each_event(db, session_id, take_event, &c);
  if (rc < 0) return rc;
  if (c.found && c.bad) memset(&c.d, 0, sizeof c.d);
  *out = c.d;
  if (!c.found) return 0;
  return c.bad ? PALP_EINVAL : 1;
}
