#!/usr/bin/env python3
"""web_stats: palp-web's --stats line counts what its web server did, as it did it (docs/web.md).

palp-web alone (no palp-server: nothing to show, the pages are served all the same) with a token and
--stats. Known traffic: 2 pages served (the token in the URL, then the cookie), 2 refused (no token, a
wrong one; their 401s carry the headers every answer carries), 2 missing (a file that is not there,
whose 404 was counted ok until 2026-12-06; a file of mode 000 in a copy of the pages, which stat() passes
and open() refuses: lws answered its own 404 and it was counted ok, until 2026-12-06), 1 WebSocket opened with the token (its hello sent) and closed, 1 refused without the token.
The line printed every 5 s, from the hub's thread while the web server's thread counts (which read the
counters themselves, unlocked, until they were copied under a lock: a data race for ThreadSanitizer,
scripts/sanitize.sh thread 'web_stats'), says exactly these counts; so does the last line, at SIGINT.
SIGHUP three times re-opens the log three times, palp-web still running (the second killed it until
2026-12-06: signal()'s handler, System V semantics under ISO C, was reset at the first).
DDS domain 155. usage: test_stats.py BUILD SOURCE OUT"""
import os
import re
import shutil
import signal
import time

import harness
from harness import check

TOKEN = "stats-test-token-0123456789"
WANT = "http 2 ok, 2 denied, 2 missing; ws 1 opened, 1 closed, 1 denied"
# the headers docs/web.md says every answer carries, a refusal's too
HEADERS = {"Content-Security-Policy": "default-src 'self'", "X-Content-Type-Options": "nosniff",
           "Cache-Control": "no-store", "Referrer-Policy": "no-referrer"}


def headers_missing(headers):
    """The names of HEADERS an answer lacks or gives another value (the CSP: one that does not begin so)."""
    got = {k.lower(): v for k, v in headers.items()}
    return [k for k, v in HEADERS.items() if not got.get(k.lower(), "").startswith(v)]


def run(build, source, out):
    procs = harness.Procs(build, source, out, 155)
    try:
        www = os.path.join(out, "www")
        shutil.rmtree(www, ignore_errors=True)
        shutil.copytree(os.path.join(source, "web", "www"), www)
        locked = os.path.join(www, "locked.html")
        with open(locked, "w") as f:
            f.write("<p>not to be served</p>\n")
        os.chmod(locked, 0)
        # root reads a file of mode 000 all the same: palp-web runs without the capabilities that let it
        prefix = ["setpriv", "--bounding-set=-dac_override,-dac_read_search", "--"] if os.geteuid() == 0 else []
        web = procs.web(["--token", TOKEN, "--stats", "--www", www], prefix=prefix)
        status, _, _ = harness.http_get(web.base + "/trainee.html?token=" + TOKEN)
        check(status == 200, "the page with the token: %d" % status)
        status, _, _ = harness.http_get(web.base + "/js/common.js", {"Cookie": "palp_token=" + TOKEN})
        check(status == 200, "its script with the cookie: %d" % status)
        for url in [web.base + "/trainee.html", web.base + "/trainee.html?token=wrong-token-0123456789"]:
            status, _, headers = harness.http_get(url)
            check(status == 401 and not headers_missing(headers), "%s: %d, with every answer's headers (lacking %s)"
                  % (url.replace(web.base, ""), status, headers_missing(headers)))
        # a file that is not there, its path allowed and the token right: a 404 counted missing, not ok
        status, _, headers = harness.http_get(web.base + "/nope.html?token=" + TOKEN)
        check(status == 404 and not headers_missing(headers), "/nope.html with the token: %d, with every answer's "
              "headers (lacking %s)" % (status, headers_missing(headers)))
        # a file there that palp-web cannot open: a 404 counted missing, not lws's own 404 counted ok
        status, _, headers = harness.http_get(web.base + "/locked.html?token=" + TOKEN)
        check(status == 404 and not headers_missing(headers), "/locked.html (mode 000) with the token: %d, with "
              "every answer's headers (lacking %s)" % (status, headers_missing(headers)))
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, TOKEN), timeout=10)
        op, data = ws.recv()
        ws.close()
        check(op == 1 and data.startswith(b'{"type":"hello"'), "a WebSocket with the token: hello")
        try:
            harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % web.port, timeout=5).close()
            refused = False
        except (ConnectionError, OSError):
            refused = True
        check(refused, "a WebSocket without it: refused")
        # the next line printed (every 5 s) after the traffic, which the server has counted by now
        t0 = time.time()
        m = procs.wait_log(web, re.escape(WANT), 15)
        check(m is not None, "a --stats line within %.1f s says \"%s\"" % (time.time() - t0, WANT))
        line = [l for l in procs.log(web).splitlines() if WANT in l][:1]
        sent = re.search(r"sent (\d+) messages", line[0]) if line else None
        check(sent is not None and int(sent.group(1)) >= 1, "and at least the hello sent: %s" % (line or ["none"])[0])
        # SIGHUP re-opens the log, again and again (a handler installed by signal() was reset at its first
        # delivery under ISO C: the second SIGHUP killed palp-web, until 2026-12-06)
        reopened = 0
        for k in range(3):
            web.send_signal(signal.SIGHUP)
            end = time.time() + 5
            while reopened <= k and web.poll() is None and time.time() < end:
                time.sleep(0.05)
                reopened = procs.log(web).count("SIGHUP: log re-opened; serving goes on")
        time.sleep(0.2)
        check(reopened == 3 and web.poll() is None, "SIGHUP three times: the log re-opened %d times, palp-web still "
              "runs (exit %s)" % (reopened, web.poll()))
        rc = procs.stop(web)
        last = [l for l in procs.log(web).splitlines() if "http " in l and " ok, " in l][-1:]
        check(rc == 0 and last and WANT in last[0], "SIGINT: exit %s; the last stats line the same: %s"
              % (rc, (last or ["none"])[0]))
    finally:
        procs.close()


if __name__ == "__main__":
    harness.main(run)
