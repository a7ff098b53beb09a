/* child_lines.h - a test's helper process talks to it in lines on a pipe (its stdout): this reads them,
 * unbuffered (a FILE would hold lines that poll cannot see), until the one the test waits for. */
#ifndef PALP_TESTS_CHILD_LINES_H
#define PALP_TESTS_CHILD_LINES_H

#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Reads lines from fd until one that starts with `want`, followed by a number >= at_least when at_least
 * > 0: 1; 0 after timeout_ms without one, or when the pipe closes. */
static inline int palp_test_child_says(int fd, const char *want, long at_least, int timeout_ms) {
  char line[64];
  size_t len = 0;
  for (int waited = 0; waited < timeout_ms;) {
    struct pollfd p = {.fd = fd, .events = POLLIN};
    if (poll(&p, 1, 50) != 1) {
      waited += 50;
      continue;
    }
    char ch;
    if (read(fd, &ch, 1) != 1) return 0;
    if (ch != '\n') {
      if (len < sizeof line - 1) line[len++] = ch;
      continue;
    }
    line[len] = 0;
    len = 0;
    const size_t wl = strlen(want);
    if (strncmp(line, want, wl) != 0) continue;
    if (at_least <= 0 || atol(line + wl) >= at_least) return 1;
  }
  return 0;
}

/* [the child, before its participant] Its participant's lease `lease` (Cyclone's duration text, "30s")
 * instead of the loopback config's 1 s, the rest of the config as given: a child the test stops (SIGSTOP)
 * stands for a stalled peer, not a lost one, however long the loaded machine starves it. */
static inline void palp_test_child_lease(const char *lease) {
  const char *uri = getenv("CYCLONEDDS_URI");
  char cfg[1024];
  snprintf(cfg, sizeof cfg, "%s%s<Discovery><LeaseDuration>%s</LeaseDuration></Discovery>", uri ? uri : "",
           uri && uri[0] ? "," : "", lease);
  setenv("CYCLONEDDS_URI", cfg, 1);
}

#endif
