#!/usr/bin/env python3
"""web_token_expiry: access tokens expire (docs/web.md, "Token lifetime").

A token opens pages for --token-lifetime-h hours (default 12) after it was issued: when its file was
last written (--token-file, --trainee-tokens), or at palp-web's start for --token. The test sets the
files' modification times instead of waiting (the clock is the files'; margin 1 h either side of 12 h):
- the instructors' token file written 11 h ago: its page is served and its WebSocket says hello;
- the trainees' file written 13 h ago: alice's token gets 401 whose body says "This access token has
  expired: ask your instructor for a new one." (by URL and by cookie), a token nobody was given a bare
  401 without it; her WebSocket is told {"type": "expired", ...} and closed; palp-web said at start that
  the trainees' tokens expired 1.0 h ago (within 0.1 h) and the instructors' expires in 1.0 h, logs the
  expiry once however often alice tries (its time 12 h after the issue it names, within 1 s), and
  --stats counts the refusals.
- --token T with --token-lifetime-h 0.003 (10.8 s from start): a trainee page in Chromium, open and
  streaming before, is told at the expiry (not before the start + 10.8 s, at most 1.5 s after the page's
  WebSocket opened + 10.8 s), shows the message and stops reconnecting; a raw WebSocket too (each
  counted once); a request afterwards gets the expired 401.
- --token-lifetime-h 0: a token file written 30 days ago still serves.
No palp-server (pages are served without one). DDS domain 155. usage: test_token_expiry.py BUILD SOURCE OUT"""
import calendar
import json
import os
import re
import time

import harness
from harness import check

INSTR = "instructor-expiry-token-0123456789"
ALICE = "alice-expiry-token-0123456789"
TEXT = "This access token has expired: ask your instructor for a new one."
HOUR = 3600.0
SHORT_H = 0.003  # 10.8 s


def secret(path, text, age_s):
    with open(path, "w") as f:
        f.write(text)
    os.chmod(path, 0o600)
    t = time.time() - age_s
    os.utime(path, (t, t))


def expired_401(status, body):
    return status == 401 and TEXT.encode() in body


def ws_url(web, token):
    return "ws://127.0.0.1:%d/ws?token=%s" % (web.port, token)


def run(build, source, out):
    procs = harness.Procs(build, source, out, 155)
    browser = None
    tokfile, trainfile = os.path.join(out, "web-token"), os.path.join(out, "trainee-tokens.txt")
    try:
        # 1. Files written 11 h and 13 h ago, the default lifetime of 12 h.
        secret(tokfile, INSTR + "\n", 11 * HOUR)
        secret(trainfile, "alice %s\n" % ALICE, 13 * HOUR)
        web = procs.web(["--token-file", tokfile, "--trainee-tokens", trainfile, "--stats"])
        log = procs.log(web)
        m = re.search(r"the instructors' token expires at \S+ \(([\d.]+) h from now, --token-lifetime-h 12\)", log)
        check(m is not None and abs(float(m.group(1)) - 1.0) <= 0.1,
              "at start: the instructors' token (written 11 h ago) expires in 1.0 h within 0.1: %s" % (m and m.group(0)))
        m = re.search(r"the trainees' tokens expired at \S+, ([\d.]+) h ago", log)
        check(m is not None and abs(float(m.group(1)) - 1.0) <= 0.1,
              "at start: a warning that the trainees' tokens (written 13 h ago) expired 1.0 h ago within 0.1: %s"
              % (m and m.group(0)))

        status, body, _ = harness.http_get(web.base + "/trainee.html?token=" + INSTR)
        check(status == 200 and b"trainee" in body, "a token within its lifetime: the page is served (%d)" % status)
        ws = harness.cdp.WebSocket(ws_url(web, INSTR), timeout=10)
        op, data = ws.recv()
        ws.close()
        check(op == 1 and data.startswith(b'{"type":"hello"'), "and its WebSocket says hello")

        status, body, _ = harness.http_get(web.base + "/trainee.html?token=" + ALICE)
        check(expired_401(status, body) and b"trainee view" not in body,
              "alice's expired token in the URL: %d, the body says why: %r" % (status, body[-160:]))
        status, body, _ = harness.http_get(web.base + "/js/common.js", {"Cookie": "palp_token=" + ALICE})
        check(expired_401(status, body), "by cookie: %d, the same reason" % status)
        status, body, _ = harness.http_get(web.base + "/trainee.html?token=nobodys-token-0123456789")
        check(status == 401 and b"expired" not in body, "a token nobody was given: a bare 401 (%d)" % status)
        ws = harness.cdp.WebSocket(ws_url(web, ALICE), timeout=10)
        op, data = ws.recv()
        m = json.loads(data) if op == 1 else {}
        try:
            ws.recv()
            closed = False
        except (ConnectionError, OSError):
            closed = True
        ws.close()
        check(m.get("type") == "expired" and m.get("message") == TEXT and closed,
              "her WebSocket is told it expired and closed: %s (closed %s)" % (m, closed))
        rc = procs.stop(web)
        log = procs.log(web)
        said = [l for l in log.splitlines() if "trainee alice's token expired at" in l]
        m = re.search(r"expired at (\S+)Z \(issued (\S+)Z,", said[0]) if len(said) == 1 else None
        span = None
        if m:
            span = (calendar.timegm(time.strptime(m.group(1), "%Y-%m-%dT%H:%M:%S")) -
                    calendar.timegm(time.strptime(m.group(2), "%Y-%m-%dT%H:%M:%S"))) / HOUR
        check(len(said) == 1 and "lifetime 12 h" in said[0] and span is not None and abs(span - 12.0) < 1.5 / HOUR,
              "the log names alice's expired token once for 3 refusals, expired 12 h after issue (%s h): %s"
              % (span, said))
        check(rc == 0 and "pages told their token expired: 2 HTTP requests, 1 WebSockets" in log,
              "--stats counts them: 2 HTTP requests, 1 WebSocket (exit %s)" % rc)

        # 2. A page open when its token expires (--token: issued at start; 10.8 s).
        browser = harness.cdp.Chromium(out_dir=out)
        t_launch = time.time()
        web = procs.web(["--token", INSTR, "--token-lifetime-h", str(SHORT_H)], name="web-short")
        raw = harness.cdp.WebSocket(ws_url(web, INSTR), timeout=10)
        raw.recv()
        t_raw = time.time()
        page = browser.new_page(web.base + "/trainee.html?token=" + INSTR)
        ok = page.wait_for("window.palpState && palpState.connected === true", 8)
        t_page = time.time()
        check(ok is True, "a trainee page connected %.1f s after start, within its token's %.1f s"
              % (t_page - t_launch, SHORT_H * HOUR))
        got, t_msg = None, None
        for op, data in harness.ws_read(raw, SHORT_H * HOUR + 5):
            if op == 1 and json.loads(data).get("type") == "expired":
                got, t_msg = json.loads(data), time.time()
                break
        check(got is not None and t_msg - t_launch >= SHORT_H * HOUR - 0.05 and t_msg - t_raw <= SHORT_H * HOUR + 1.5,
              "an open WebSocket is told at the expiry: %.2f s after launch (>= %.1f), %.2f s after it opened "
              "(<= %.1f + 1.5)" % ((t_msg or 0) - t_launch, SHORT_H * HOUR, (t_msg or 0) - t_raw, SHORT_H * HOUR))
        raw.close()
        shown = page.wait_for("palpState.expired !== null && document.getElementById('conn').textContent", 5)
        state = page.eval("JSON.stringify({c: palpState.connected, r: palpState.reconnects})")
        time.sleep(2.5)
        later = page.eval("JSON.stringify({c: palpState.connected, r: palpState.reconnects})")
        page.screenshot(os.path.join(out, "trainee-expired.png"))
        check(shown == TEXT, "the page shows: %r" % shown)
        check(state == later and '"c":false' in later,
              "and stops reconnecting (%s, 2.5 s later %s)" % (state, later))
        status, body, _ = harness.http_get(web.base + "/trainee.html?token=" + INSTR)
        check(expired_401(status, body), "a request afterwards: the expired 401 (%d)" % status)
        procs.stop(web)
        check("pages told their token expired: 1 HTTP requests, 2 WebSockets" in procs.log(web),
              "--stats: 1 HTTP request and 2 WebSockets told, each once")

        # 3. --token-lifetime-h 0: never.
        secret(tokfile, INSTR + "\n", 30 * 24 * HOUR)
        web = procs.web(["--token-file", tokfile, "--token-lifetime-h", "0"], name="web-never")
        status, _, _ = harness.http_get(web.base + "/trainee.html?token=" + INSTR)
        check(status == 200 and "tokens never expire" in procs.log(web),
              "--token-lifetime-h 0: a token file written 30 days ago serves (%d)" % status)
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
