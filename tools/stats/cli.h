/*
 * cli.h - what the palp-stats commands share (main.c): options, column lookup,
 * numeric cells read as exact decimals, error messages, JSON output.
 */
#ifndef PALP_TOOLS_STATS_CLI_H
#define PALP_TOOLS_STATS_CLI_H

#include <cjson/cJSON.h>

#include "csv.h"
#include "decimal.h"
#include "palp_app.h"

enum { EXIT_DATA = 1, EXIT_USAGE = 2 };

typedef struct options {
  const char *command;
  const char *file;
  const char *group, *value, *a, *b;
  const char *svg;
  const char *unit;    /* tost: column naming each row's unit (e.g. run); the unit means are the observations */
  const char *subject; /* ba-rm: column naming each row's subject */
  int json;
  int skip_empty;
  char sep;
  /* serial-data commands (serial_cmd.c) */
  int serial;          /* tost: SE from the AR(1) effective sample size */
  int have_margin, have_lower, have_upper;
  double margin, lower, upper;
  double alpha;        /* tost, default 0.05 */
  double level;        /* bootstrap interval, default 0.90 */
  long block;          /* bootstrap block length, 0 = the AR(1) rule */
  long resamples;      /* bootstrap resamples, default 10000 */
  unsigned long long seed;
  int have_seed;       /* --seed given (bootstrap's only) */
  palp_log *log; /* main's: data errors and notes go through it */
} options;

int find_column(const palp_csv *csv, const options *o, const char *want, const char *flag, int *col);
/* 1, with a usage error ending in want, when columns c1 (given to option f1 as w1) and c2 are one. */
int same_column(const options *o, const palp_csv *csv, int c1, const char *f1, const char *w1, int c2,
                const char *f2, const char *w2, const char *want);
/* The exit status for a column reader's failure: -2 a wrong command line, else the data. */
static inline int read_exit(int rd) { return rd == -2 ? EXIT_USAGE : EXIT_DATA; }
int cell_is_empty(const palp_csv *csv, size_t row, int col);
/* Parses one numeric cell; on failure prints where and why, with a hint. */
int cell_number(const palp_csv *csv, const options *o, size_t row, int col, palp_dec *out);
__attribute__((format(printf, 2, 3))) void data_error(palp_log *log, const char *fmt, ...);
void print_json(cJSON *root);

/* serial_cmd.c: neff, bootstrap, tost, ba-rm */
int run_neff(const options *o, const palp_csv *csv);
int run_bootstrap(const options *o, const palp_csv *csv);
int run_tost(const options *o, const palp_csv *csv);
int run_ba_rm(const options *o, const palp_csv *csv);

#endif
