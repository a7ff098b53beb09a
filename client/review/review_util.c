/* palp-review's shared helpers: escaping for HTML, JSON and CSV, time formatting and parsing,
 * loading a session's contacts and deriving its presses. The command modules (review.c, export.c,
 * replay.c, report.c, assess_log.c, class.c) depend on this one and never on each other. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "palp_place.h"
#include "palp_utf8.h"
#include "review_util.h"


void review_fmt_time(double unix_s, char *buf, size_t len) {
  if (!(unix_s > 0)) {
    snprintf(buf, len, "-");
    return;
  }
  /* a time from the file: past the year 9999 (2.5e11 s) it is no time a log was written, and the cast
   * to time_t would overflow */
  struct tm tm;
  const time_t t = (time_t)fmin(unix_s, 253402300799.0);
  if (unix_s > 253402300799.0 || !localtime_r(&t, &tm) || !strftime(buf, len, "%Y-%m-%d %H:%M:%S %z", &tm))
    snprintf(buf, len, "-");
}

int review_finish_output(FILE *f) {
  int err = 0;
  if (fflush(f)) err = errno;
  if (!err && ferror(f)) err = EIO;
  if (f != stdout && fclose(f) && !err) err = errno;
  if (!err) return 0;
  errno = err;
  return -1;
}

int review_utf8_len(const unsigned char *p) {
  /* a C string: its NUL ends any sequence it cuts short (the bytes before it are not continuations) */
  return (int)palp_utf8_len(p, p[0] ? 4 : 1);
}

int review_utf8_valid(const char *s) {
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p;) {
    const int n = review_utf8_len(p);
    if (!n) return 0;
    p += n;
  }
  return 1;
}

void review_tty(char *s) {
  for (unsigned char *p = (unsigned char *)s; p && *p;) {
    const int n = review_utf8_len(p);
    if (n == 0 || *p < 0x20 || *p == 0x7f) *p++ = '?';
    else if (n == 2 && p[0] == 0xc2 && p[1] < 0xa0) p[0] = p[1] = '?', p += 2; /* C1: U+0080..U+009F, CSI among them */
    else p += n;
  }
}

/* A JSON string of any stored text: every control character escaped, and a byte that does not begin a
 * well-formed UTF-8 character written as U+FFFD (since session 81: such bytes went out raw, and the
 * export was not JSON a strict parser reads). */
void json_str(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p;) {
    const int n = review_utf8_len(p);
    if (!n) {
      fputs("\\ufffd", f);
      p++;
      continue;
    }
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p == '\n') fputs("\\n", f);
    else if (*p == '\t') fputs("\\t", f);
    else if (*p < 0x20 || *p == 0x7f) fprintf(f, "\\u%04x", *p);
    else fwrite(p, 1, (size_t)n, f);
    p += n;
  }
  fputc('"', f);
}

void html_str(FILE *f, const char *s) {
  for (const char *p = s ? s : ""; *p; p++) {
    switch (*p) {
    case '<': fputs("&lt;", f); break;
    case '>': fputs("&gt;", f); break;
    case '&': fputs("&amp;", f); break;
    case '"': fputs("&quot;", f); break;
    case '\'': fputs("&#39;", f); break;
    default: fputc(*p, f);
    }
  }
}

void csv_str(FILE *f, const char *s) {
  /* Always quoted (RFC 4180), quotes doubled: a field may hold commas and line breaks. A text that a
   * spreadsheet would run as a formula (=, +, -, @, or a tab or carriage return first: a trainee
   * named '=HYPERLINK(...)') gets a leading apostrophe, the usual guard (OWASP, "CSV injection"). */
  fputc('"', f);
  if (s && *s && strchr("=+-@\t\r", *s)) fputc('\'', f);
  for (const char *p = s ? s : ""; *p; p++) {
    if (*p == '"') fputc('"', f);
    fputc(*p, f);
  }
  fputc('"', f);
}

int review_option_known(const char *a, const char *const *names) {
  for (; *names; names++)
    if (!strcmp(a, *names)) return 1;
  return 0;
}

/* Parses YYYY-MM-DD[THH:MM[:SS]] (or a space instead of T) as local time. */
int review_parse_date(const char *s, double *out) {
  struct tm tm;
  memset(&tm, 0, sizeof tm);
  int y, mo, d, h = 0, mi = 0, se = 0, end = -1;
  char sep = 0;
  /* The whole string, one of the three forms (since session 81: text after a date or time was ignored,
   * "2026-03-01Tfoo" and "2026-03-01 12:00:00junk" accepted). */
  const size_t len = strlen(s);
  int n = sscanf(s, "%4d-%2d-%2d%n", &y, &mo, &d, &end);
  if (n != 3 || end < 0) return -1;
  if ((size_t)end != len) {
    const int date_end = end;
    end = -1;
    n = sscanf(s + date_end, "%c%2d:%2d%n", &sep, &h, &mi, &end);
    if (n != 3 || end < 0) return -1;
    int at = date_end + end;
    if ((size_t)at != len) {
      end = -1;
      if (sscanf(s + at, ":%2d%n", &se, &end) != 1 || end < 0 || (size_t)(at + end) != len) return -1;
    }
  }
  if (sep && sep != 'T' && sep != ' ') return -1;
  if (strspn(s, "0123456789-T: ") != len) return -1; /* no sign or space inside a field */
  if (mo < 1 || mo > 12 || d < 1 || d > 31 || h < 0 || h > 23 || mi < 0 || mi > 59 || se < 0 || se > 59) return -1;
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  tm.tm_sec = se;
  tm.tm_isdst = -1;
  time_t t = mktime(&tm);
  if (t == (time_t)-1) return -1;
  /* mktime carries a day past the month's end into the next (2026-02-31 became 3 March): a date that
   * is not on the calendar is refused. (A local time skipped by a clock change moves by the hour.) */
  if (tm.tm_year != y - 1900 || tm.tm_mon != mo - 1 || tm.tm_mday != d) return -1;
  *out = (double)t;
  return 0;
}

int review_parse_until(const char *s, double *out) {
  if (review_parse_date(s, out)) return -1;
  if (strlen(s) != 10) return 0; /* a time given: that instant */
  /* A date alone: its whole day, to the next day's 00:00 local (mktime carries the 32nd into the next
   * month and keeps a clock change's hour right). Until session 90 it was its 00:00, so "--since D
   * --until D" found nothing and "--until D" left D out (found by review). */
  const time_t t0 = (time_t)*out;
  struct tm tm;
  if (!localtime_r(&t0, &tm)) return -1;
  tm.tm_mday++;
  tm.tm_hour = tm.tm_min = tm.tm_sec = 0;
  tm.tm_isdst = -1;
  const time_t t1 = mktime(&tm);
  if (t1 == (time_t)-1) return -1;
  *out = (double)t1;
  return 0;
}

static int contact_cb(void *u, const palp_db_contact *c) {
  review_contacts *v = u;
  if (v->n == v->cap) {
    int ncap = v->cap ? 2 * v->cap : 64;
    palp_db_contact *nv = realloc(v->v, (size_t)ncap * sizeof *nv);
    if (!nv) return PALP_ENOMEM;
    v->v = nv;
    v->cap = ncap;
  }
  v->v[v->n++] = *c;
  return 0;
}

int review_load_contacts(palp_db *db, int64_t sid, review_contacts *out) {
  memset(out, 0, sizeof *out);
  return palp_db_each_contact(db, sid, contact_cb, out);
}

double review_clock_hours(palp_vec3 p) { return palp_place_clock_shown(p); }

const char *review_clock_cell(palp_vec3 p, int width, char *buf, size_t len) {
  char cell[24];
  if (palp_place_at_pole(p)) snprintf(cell, sizeof cell, "pole");
  else snprintf(cell, sizeof cell, "%.1f h", palp_place_clock_shown(p));
  snprintf(buf, len, "%*s", width, cell);
  return buf;
}

double review_arc_m(palp_vec3 p) { return palp_place_arc(p); }

typedef struct press_acc {
  review_press *v;
  int n;
} press_acc;

static int fb_peak_cb(void *u, int64_t frame, int slot, palp_vec3 f) {
  press_acc *a = u;
  const double m = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
  /* Slots are reused after removal: the press on this slot live at that frame owns the sample
   * (feedback carries the frame after the step, so the live range is (on, off]). */
  for (int i = a->n - 1; i >= 0; i--)
    if (a->v[i].slot == slot && frame > a->v[i].frame_on && (a->v[i].frame_off < 0 || frame <= a->v[i].frame_off)) {
      if (a->v[i].kind == PALP_DB_KIND_FINGER && m > a->v[i].peak_force_n) a->v[i].peak_force_n = m;
      break;
    }
  return 0;
}

int review_presses(palp_db *db, int64_t sid, const review_contacts *c, review_press **out, int *n) {
  review_press *v = calloc((size_t)(c->n > 0 ? c->n : 1), sizeof *v);
  if (!v) return PALP_ENOMEM;
  int k = 0;
  for (int i = 0; i < c->n; i++) {
    const palp_db_contact *x = &c->v[i];
    if (x->op == PALP_DB_OP_ADD) {
      review_press *p = &v[k++];
      p->slot = x->slot;
      p->kind = x->kind;
      p->distribution = x->def.distribution;
      p->first_center_m = p->last_center_m = x->center_m;
      p->t_on_s = x->sim_time_s;
      p->t_off_s = -1;
      p->frame_on = x->frame;
      p->frame_off = -1;
      if (x->kind == PALP_DB_KIND_FORCE)
        p->peak_force_n = sqrt(x->force_n.x * x->force_n.x + x->force_n.y * x->force_n.y + x->force_n.z * x->force_n.z);
      continue;
    }
    for (int j = k - 1; j >= 0; j--) {
      review_press *p = &v[j];
      if (p->slot != x->slot || p->t_off_s >= 0) continue;
      if (x->op == PALP_DB_OP_REMOVE) {
        p->t_off_s = x->sim_time_s;
        p->frame_off = x->frame;
      } else {
        p->updates++;
        if (x->kind == PALP_DB_KIND_FINGER) p->last_center_m = x->center_m;
        else {
          double m = sqrt(x->force_n.x * x->force_n.x + x->force_n.y * x->force_n.y + x->force_n.z * x->force_n.z);
          if (m > p->peak_force_n) p->peak_force_n = m;
        }
      }
      break;
    }
  }
  press_acc a = {v, k};
  int rc = palp_db_each_feedback(db, sid, fb_peak_cb, &a);
  if (rc) {
    free(v);
    return rc;
  }
  *out = v;
  *n = k;
  return 0;
}

/* The paper's numeral and the scene file's keyword, as every tool prints it (docs/naming.md). */
const char *review_dist_name(palp_distribution d) {
  switch (d) {
  case PALP_DIST_SINGLE: return "I single";
  case PALP_DIST_UNIFORM: return "II uniform";
  case PALP_DIST_GAUSSIAN: return "III gaussian";
  case PALP_DIST_GAUSSIAN_OFFSET: return "IV gaussian_offset";
  }
  return "-";
}

/* The model's valid range over a session, from the server's valid_range events (db/valid_range.c),
 * in the station's words for the same four limits (client/main.c, valid_range_text), so the
 * trainee's screen, the log and the instructor's review name them alike (docs/naming.md); the
 * fourth, the literal gel law's stable range (LM_GEL_LAW_RANGE), reaches the station since session 77. */
int review_valid_range(palp_db *db, const palp_db_session_info *s, palp_db_valid_range *r, int64_t *events,
                       int64_t *unreadable) {
  const int rc = palp_db_session_valid_range(db, s->id, r, events, unreadable);
  if (rc < 0) return rc;
  if (*events) return REVIEW_RANGE_OUTSIDE;
  /* none logged: inside at every step only if this server logged such events at all */
  return review_params_flag(db, s->id, "valid_range_events") ? REVIEW_RANGE_INSIDE : REVIEW_RANGE_UNKNOWN;
}

/* The session's params_json parsed (the caller deletes it), NULL when absent or unreadable. */
static cJSON *session_params(palp_db *db, int64_t session_id) {
  char *params = NULL;
  cJSON *j = NULL;
  if (palp_db_session_json(db, session_id, NULL, &params) == 0 && params) j = cJSON_Parse(params);
  free(params);
  return j;
}

int review_params_string(palp_db *db, int64_t session_id, const char *key, char *buf, size_t len) {
  if (len) buf[0] = 0;
  cJSON *j = session_params(db, session_id);
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(j, key);
  const int found = cJSON_IsString(v) && v->valuestring && len;
  if (found) snprintf(buf, len, "%s", v->valuestring);
  cJSON_Delete(j);
  return found;
}

int review_params_number(palp_db *db, int64_t session_id, const char *key, double *out) {
  cJSON *j = session_params(db, session_id);
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(j, key);
  const int found = cJSON_IsNumber(v) && isfinite(v->valuedouble);
  if (found) *out = v->valuedouble;
  cJSON_Delete(j);
  return found;
}

int review_params_flag(palp_db *db, int64_t session_id, const char *key) {
  cJSON *j = session_params(db, session_id);
  const int said = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, key));
  cJSON_Delete(j);
  return said;
}

int review_valid_range_text(palp_db *db, const palp_db_session_info *s, char *buf, size_t len) {
  palp_db_valid_range r;
  int64_t events = 0, unreadable = 0;
  const int rc = review_valid_range(db, s, &r, &events, &unreadable);
  if (rc < 0) {
    snprintf(buf, len, "UNKNOWN: %s", palp_db_errmsg(db));
    return rc;
  }
  if (rc == REVIEW_RANGE_INSIDE) {
    snprintf(buf, len, "inside at every step (the server logged no step outside it)");
    return rc;
  }
  if (rc == REVIEW_RANGE_UNKNOWN && s->pruned_unix_s > 0) {
    snprintf(buf, len, "not in this log, and no longer recomputable: the session was pruned (its frames and inputs "
                       "deleted)");
    return rc;
  }
  if (rc == REVIEW_RANGE_UNKNOWN) {
    snprintf(buf, len, "not in this log (an earlier server, or recorded over DDS); `palp-review replay %s` "
                       "recomputes it", s->uid);
    return rc;
  }
  const double dt = s->dt_s > 0 ? s->dt_s : 0;
  char of[48] = ""; /* the simulated time, where frames were logged */
  if (s->sim_duration_s > 0) snprintf(of, sizeof of, " of %.2f s simulated", s->sim_duration_s);
  size_t n = (size_t)snprintf(buf, len, "OUTSIDE for %.2f s%s (%lld steps of %.3g ms): ", (double)r.steps * dt, of,
                              (long long)r.steps, dt * 1e3);
  const char *sep = "";
  if (r.depth_steps) {
    n += (size_t)snprintf(buf + n, n < len ? len - n : 0, "%.2f s pressed deeper than this place of the phantom "
                          "was checked against the reference model (by up to %.1f mm)",
                          (double)r.depth_steps * dt, r.deepest_m * 1e3);
    sep = "; ";
  }
  if (r.skin_steps) {
    n += (size_t)snprintf(buf + n, n < len ? len - n : 0, "%s%.2f s the skin is stretched or bent beyond what "
                          "the model describes well", sep, (double)r.skin_steps * dt);
    sep = "; ";
  }
  if (r.limit_steps) {
    n += (size_t)snprintf(buf + n, n < len ? len - n : 0, "%s%.2f s the phantom is pressed onto its base or harder "
                          "than the model can follow", sep, (double)r.limit_steps * dt);
    sep = "; ";
  }
  /* the scene's literal gel law left its stable range, and the gel there was that law without its
   * momentum term (docs/model.md) */
  if (r.gel_steps) {
    n += (size_t)snprintf(buf + n, n < len ? len - n : 0, "%s%.2f s the gel's literal pressure law stepped outside "
                          "its stable range (its momentum term left out at %lld frames)", sep,
                          (double)r.gel_steps * dt, (long long)r.gel_frames);
  }
  if (unreadable)
    snprintf(buf + n, n < len ? len - n : 0, " (%lld of %lld events unreadable: counted in the total only)",
             (long long)unreadable, (long long)events);
  return REVIEW_RANGE_OUTSIDE;
}

double review_valid_range_seconds(palp_db *db, const palp_db_session_info *s) {
  palp_db_valid_range r;
  int64_t events = 0, unreadable = 0;
  const int rc = review_valid_range(db, s, &r, &events, &unreadable);
  if (rc == REVIEW_RANGE_OUTSIDE) return (double)r.steps * (s->dt_s > 0 ? s->dt_s : 0);
  return rc == REVIEW_RANGE_INSIDE ? 0.0 : -1.0;
}

void review_fmt_logging(const palp_db_session_info *s, const palp_db_log_health *h, char *buf, size_t len) {
  /* The writer logs a frame every k-th physics step (k = rate / 100, server/db_log.c), so
   * "frames at 250 Hz" would misstate a 250 Hz session's log by 3x: say both rates. */
  const int64_t k = h && h->frame_step > 1 ? h->frame_step : 1;
  if (k == 1)
    snprintf(buf, len, "%lld frames logged, every physics step: %.0f Hz, dt %.6g s", (long long)s->frames, s->tick_hz,
             s->dt_s);
  else
    snprintf(buf, len, "%lld frames logged, one every %lld physics steps (%.1f Hz) of %.0f Hz, dt %.6g s",
             (long long)s->frames, (long long)k, s->tick_hz / (double)k, s->tick_hz, s->dt_s);
}
