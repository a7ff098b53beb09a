/* palp-review's shared helpers (review_util.c): escaping, time, contacts and presses. */
#ifndef PALP_REVIEW_UTIL_H
#define PALP_REVIEW_UTIL_H

#include <stdio.h>

#include "palp_db.h"

/* A whole session's small tables in memory (frames and feedback are streamed instead). */
typedef struct review_contacts {
  palp_db_contact *v;
  int n, cap;
} review_contacts;
int review_load_contacts(palp_db *db, int64_t sid, review_contacts *out);

/* Per contact slot use, derived from the inputs and feedback: where and how hard. */
typedef struct review_press {
  int slot;
  palp_db_contact_kind kind;
  palp_distribution distribution;
  palp_vec3 first_center_m, last_center_m;
  double t_on_s, t_off_s; /* t_off_s < 0: never removed */
  int64_t frame_on, frame_off; /* frame_off < 0: never removed */
  double peak_force_n;    /* force contacts: max |F| applied; fingers: max |feedback| */
  int updates;
} review_press;
int review_presses(palp_db *db, int64_t sid, const review_contacts *c, review_press **out, int *n);
/* "3 o'clock": the clock position of a point seen from above (12 = +y, 3 = +x), as printed: to 0.1 h,
 * 12.0 never 0.0 (palp_place_clock_shown). */
double review_clock_hours(palp_vec3 p);
/* A table's clock cell: "1.7 h", or "pole" within PALP_PLACE_POLE_ARC of the pole, where the hour is
 * noise (src/palp_place.h); right-aligned in width characters (0: as it is, for HTML). Returns buf. */
const char *review_clock_cell(palp_vec3 p, int width, char *buf, size_t len);
/* The arc from the pole [m] along the sphere through p (centred at the dome's base centre). */
double review_arc_m(palp_vec3 p);
/* The one name of a force distribution everywhere (docs/naming.md). */
const char *review_dist_name(palp_distribution d);

void review_fmt_time(double unix_s, char *buf, size_t len); /* local time, with offset */
/* YYYY-MM-DD[THH:MM[:SS]] (or a space for T) as local time; 0 or -1. */
int review_parse_date(const char *s, double *out);
/* The same for an --until bound (exclusive): a date alone means to the end of that day, the next
 * day's 00:00 local; with a time, that instant. */
int review_parse_until(const char *s, double *out);
/* 1 when a is one of names (NULL-terminated): a command's options that take a value, checked before
 * "needs a value", so that an unknown option in last place is called unknown (until session 83
 * `list --bogus` said "--bogus needs a value"). */
int review_option_known(const char *a, const char *const *names);
/* Finishes a file the review wrote: flushed, its error flag read (a write that failed on the way,
 * the disk full), closed unless it is stdout. 0, or -1 with errno saying why (EIO where an earlier
 * write failed and its own errno is gone): what was written is incomplete. */
int review_finish_output(FILE *f);
void json_str(FILE *f, const char *s);
/* Bytes of the well-formed UTF-8 character at p (1-4), 0 if none begins there; whether all of s is. */
int review_utf8_len(const unsigned char *p);
int review_utf8_valid(const char *s);
/* Text from the log made fit for a terminal, in place: control characters (C0, DEL, C1) and bytes that
 * are not UTF-8 read '?', as the reader does for names (an ESC in a grade or an exercise's title
 * retitled or cleared the instructor's terminal; session 81). */
void review_tty(char *s);
void html_str(FILE *f, const char *s);
void csv_str(FILE *f, const char *s);

/* The model's valid range over a session, as a sentence for show and report (docs/db.md):
 * REVIEW_RANGE_INSIDE, _OUTSIDE, _UNKNOWN (the log does not say), or < 0 on a database error. */
enum { REVIEW_RANGE_UNKNOWN = 0, REVIEW_RANGE_INSIDE = 1, REVIEW_RANGE_OUTSIDE = 2 };
/* 1 when the session's params_json says key: true (what its writer logs, e.g. "valid_range_events",
 * "debrief_events": none logged then means none happened), 0 otherwise or unreadable. */
int review_params_flag(palp_db *db, int64_t session_id, const char *key);
/* The session's params_json string `key` into buf (1), or "" (0: absent, not a string). */
int review_params_string(palp_db *db, int64_t session_id, const char *key, char *buf, size_t len);
/* The session's params_json number `key` into *out (1), or 0 (absent, not a finite number). */
int review_params_number(palp_db *db, int64_t session_id, const char *key, double *out);
int review_valid_range_text(palp_db *db, const palp_db_session_info *s, char *buf, size_t len);
/* The same, as numbers: the events summed (palp_db_session_valid_range) and the same code. */
int review_valid_range(palp_db *db, const palp_db_session_info *s, palp_db_valid_range *r, int64_t *events,
                       int64_t *unreadable);
/* Seconds outside it (steps x dt), 0 inside, -1 where the log does not say or cannot be read. */
double review_valid_range_seconds(palp_db *db, const palp_db_session_info *s);
/* How the log sampled the session: "10252 frames logged, one every 3 physics steps (83.3 Hz) of
 * 250 Hz, dt 0.004 s" (h: the log's health, whose frame_step is the writer's stride; NULL: every step). */
void review_fmt_logging(const palp_db_session_info *s, const palp_db_log_health *h, char *buf, size_t len);

#endif
