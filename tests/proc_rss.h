/*
 * proc_rss.h - a process's resident memory [kB] from /proc (tests bounding a program's memory under
 * a flood): one reading for the server, recorder and web tests.
 */
#ifndef PALP_TEST_PROC_RSS_H
#define PALP_TEST_PROC_RSS_H

#include <stdio.h>
#include <sys/types.h>

/* VmRSS of process pid (0: this one) [kB]; -1 when it cannot be read. */
static inline long palp_test_rss_kb(pid_t pid) {
  char path[64], line[256];
  if (pid) snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
  else snprintf(path, sizeof path, "/proc/self/status");
  FILE *f = fopen(path, "r");
  long kb = -1;
  while (f && fgets(line, sizeof line, f))
    if (sscanf(line, "VmRSS: %ld kB", &kb) == 1) break;
  if (f) fclose(f);
  return kb;
}

#endif
