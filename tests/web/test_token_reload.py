#!/usr/bin/env python3
"""web_token_reload: SIGHUP re-reads the token files without dropping the pages (docs/web.md, "Tokens
rotated without a restart").

palp-server and a trainee alice pressing a sine (domain 167); palp-web with --token-file (the instructors')
and --trainee-tokens (alice, bob, carol), both files written 2 h ago. Open: alice's page following her
session (streaming), and pages of carol's, bob's and the instructors' tokens. The files rewritten: the
instructors' token replaced, alice's kept, bob's changed, carol removed, dan added; SIGHUP:
- the log says "instructors' token replaced, trainees' tokens 3 (added 1, removed 1, changed 1); closed 3
  pages whose token was withdrawn", and that the new tokens expire 12.0 h from now (within 0.1 h: issued
  at the files' new write, where start said 10.0 h);
- carol's, bob's and the instructors' pages are told {"type": "expired"} with "This access token was
  withdrawn: ..." and closed (1008, "token withdrawn");
- alice's page stays open and keeps streaming (>= 8 frames in the 2 s after);
- the old instructors' token, bob's old one and carol's get 401; the new instructors' token, bob's new one,
  dan's and alice's 200; a WebSocket of the new instructors' token says hello.
Then bad files and SIGHUP, each with the instructors' token replaced too (all or nothing): a world-readable
trainees' file, a malformed line, a trainee given the new instructors' token: each logged as an error in
start's words naming the file, the old tokens still served (the previous instructors' token 200, the one
the failed read would have brought 401, alice 200) and alice's page still streaming.
alice's page, renumbered, still counts among her token's 3 pages (a 4th refused), and closed frees its place
(3 of hers open again).
Last, palp-web with --token on the command line (domain 168): SIGHUP twice says once that --token cannot
change, and re-reads --trainee-tokens; the same file with its last write set 13 h back and SIGHUP: its
tokens are issued then, so expired (the warning says 1.0 h ago and to send SIGHUP), bob's 401 says so.
No browser: raw HTTP and WebSocket clients. usage: test_token_reload.py BUILD SOURCE OUT"""
import json
import os
import re
import signal
import struct
import time

import harness
from harness import check

INSTR1 = "instructor-token-one-0123456789"
INSTR2 = "instructor-token-two-0123456789"
INSTR3 = "instructor-token-three-012345678"
ALICE = "alice-kept-token-0123456789"
BOB1 = "bob-first-token-0123456789"
BOB2 = "bob-second-token-0123456789"
CAROL = "carol-removed-token-0123456789"
DAN = "dan-added-token-0123456789"
WITHDRAWN = "This access token was withdrawn: ask your instructor for a new one."
HOUR = 3600.0


def secret(path, text, mode=0o600, age_s=0.0):
    with open(path, "w") as f:
        f.write(text)
    os.chmod(path, mode)
    if age_s:
        t = time.time() - age_s
        os.utime(path, (t, t))


def ws_open(web, token):
    ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, token), timeout=10)
    op, data = ws.recv()
    check(op == 1 and data.startswith(b'{"type":"hello"'), "a WebSocket of %s... says hello" % token[:12])
    return ws


def until_closed(ws, seconds):
    """The text messages (parsed) a WebSocket receives until its close frame: (messages, (code, reason)), or
    (messages, None) if it is not closed within `seconds`."""
    msgs = []
    ws.sock.settimeout(0.5)
    end = time.time() + seconds
    while time.time() < end:
        try:
            b0, b1 = ws._read(2)
        except OSError:  # a timeout: read on
            continue
        n = b1 & 0x7F
        if n == 126:
            n = struct.unpack("!H", ws._read(2))[0]
        elif n == 127:
            n = struct.unpack("!Q", ws._read(8))[0]
        data = ws._read(n)
        if b0 & 0x0F == 8:
            return msgs, (struct.unpack("!H", data[:2])[0] if len(data) >= 2 else None, data[2:].decode())
        if b0 & 0x0F == 1:
            msgs.append(json.loads(data))
    return msgs, None


def frames_in(ws, seconds):
    return harness.ws_messages(ws, seconds)[1]


def status_of(web, token):
    return harness.http_get(web.base + "/trainee.html?token=" + token)[0]


def sighup(procs, web, pattern, timeout=5):
    """SIGHUP, and the log's line matching pattern after it (its text)."""
    before = len(procs.log(web))
    web.send_signal(signal.SIGHUP)
    end = time.time() + timeout
    while time.time() < end:
        m = re.search(pattern, procs.log(web)[before:])
        if m:
            return m.group(0)
        time.sleep(0.05)
    return None


def run(build, source, out):
    procs = harness.Procs(build, source, out, 167)
    procs2 = None
    tokfile, trainfile = os.path.join(out, "web-token"), os.path.join(out, "trainee-tokens.txt")
    try:
        secret(tokfile, INSTR1 + "\n", age_s=2 * HOUR)
        secret(trainfile, "alice %s\nbob %s\ncarol %s\n" % (ALICE, BOB1, CAROL), age_s=2 * HOUR)
        procs.server()
        web = procs.web(["--token-file", tokfile, "--trainee-tokens", trainfile])
        m = re.search(r"the instructors' token expires at \S+ \(([\d.]+) h from now", procs.log(web))
        check(m is not None and abs(float(m.group(1)) - 10.0) <= 0.1,
              "at start: the instructors' token (written 2 h ago) expires in 10.0 h within 0.1: %s"
              % (m and m.group(0)))
        procs.trainee("alice", 1, ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1",
                                   "--t-on", "0.3", "--t-off", "60", "--duration", "60"])
        alice = ws_open(web, ALICE)
        mine = harness.ws_until(alice, 15, lambda m: m["type"] == "sessions" and
                                [s["trainee"] for s in m["sessions"]] == ["alice"])
        check(mine is not None, "alice's page lists her session")
        alice.send(json.dumps({"follow": mine["sessions"][0]["id"]}))
        n = frames_in(alice, 1.0)
        check(n >= 4, "alice's page streams her session: %d frames in 1 s (>= 4)" % n)
        carol, bob, inst = ws_open(web, CAROL), ws_open(web, BOB1), ws_open(web, INSTR1)

        # New tokens: the instructors' replaced, alice's kept, bob's changed, carol's removed, dan's added.
        secret(tokfile, INSTR2 + "\n")
        secret(trainfile, "# the 11:00 class\ndan %s\nalice %s\nbob %s\n" % (DAN, ALICE, BOB2))
        want = ("SIGHUP: tokens re-read: instructors' token replaced, trainees' tokens 3 (added 1, removed 1, "
                "changed 1); closed 3 pages whose token was withdrawn")
        line = sighup(procs, web, re.escape(want))
        check(line is not None, "SIGHUP: the log says \"%s\"" % want)
        m = re.search(r"SIGHUP: the instructors' token expires at \S+ \(([\d.]+) h from now", procs.log(web))
        check(m is not None and abs(float(m.group(1)) - 12.0) <= 0.1,
              "the new tokens are issued at the files' new write: expire in 12.0 h within 0.1: %s" % (m and m.group(0)))
        for name, ws in (("carol's (removed)", carol), ("bob's (changed)", bob), ("the instructors' (replaced)", inst)):
            msgs, closed = until_closed(ws, 3)
            told = [m for m in msgs if m["type"] == "expired"]
            check(told and told[-1]["message"] == WITHDRAWN and closed == (1008, "token withdrawn"),
                  "%s page is told %s and closed: %s" % (name, told[-1:] or msgs[-1:], closed))
            ws.close()
        n = frames_in(alice, 2.0)
        check(n >= 8, "alice's page (her token kept) stays open and streams: %d frames in the 2 s after (>= 8)" % n)
        got = {t: status_of(web, t) for t in (INSTR1, BOB1, CAROL, INSTR2, BOB2, DAN, ALICE)}
        check([got[t] for t in (INSTR1, BOB1, CAROL)] == [401] * 3 and
              [got[t] for t in (INSTR2, BOB2, DAN, ALICE)] == [200] * 4,
              "the old instructors' token, bob's old and carol's 401 %s; the new instructors', bob's new, dan's and "
              "alice's 200 %s" % ([got[t] for t in (INSTR1, BOB1, CAROL)], [got[t] for t in (INSTR2, BOB2, DAN, ALICE)]))
        ws_open(web, INSTR2).close()
        # alice's page, renumbered (dan now comes first), still counts as hers: 2 more open, a 4th refused
        more = [ws_open(web, ALICE) for _ in range(2)]
        fourth = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10)
        _, closed = until_closed(fourth, 3)
        for w in more + [fourth]:
            w.close()
        check(closed == (1008, "this trainee's token has 3 pages open already: close one of them"),
              "alice's open page still counts as one of her token's 3: a 4th is refused (%s)" % (closed,))

        # Bad files: all or nothing, the old tokens served, the pages left open.
        bad = [
            ("a world-readable trainees' file", 0o644, "alice %s\n" % ALICE,
             r"--trainee-tokens \S+trainee-tokens\.txt is readable by every user of this machine \(mode 0644\)"),
            ("a malformed line", 0o600, "alice %s\neve\n" % ALICE,
             r"--trainee-tokens \S+trainee-tokens\.txt: line 2: expected NAME TOKEN"),
            ("a trainee given the instructors' token", 0o600, "alice %s\neve %s\n" % (ALICE, INSTR3),
             r"--trainee-tokens \S+trainee-tokens\.txt: line 2 \(eve\): the same token as the instructors' \(--token or --token-file\)"),
        ]
        for what, mode, text, reason in bad:
            secret(tokfile, INSTR3 + "\n")
            secret(trainfile, text, mode)
            line = sighup(procs, web, r".*SIGHUP: (tokens not re-read.*|tokens re-read.*)")
            check(line is not None and " ERROR " in line and
                  re.search("tokens not re-read, the old ones still served: " + reason, line),
                  "%s: an error naming the file and why: %s" % (what, line))
            got = [status_of(web, t) for t in (INSTR2, INSTR3, ALICE, BOB2)]
            n = frames_in(alice, 0.5)
            check(got == [200, 401, 200, 200] and n >= 1, "the old tokens still served (instructors' old, new, alice, "
                  "bob: %s) and alice's page streams (%d frames in 0.5 s)" % (got, n))
        # closed, her page frees its place under its new number: 3 of her pages open again
        alice.close()
        time.sleep(0.3)
        three, said = [], []
        for _ in range(3):
            w = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10)
            three.append(w)
            try:
                said.append(w.recv()[1].startswith(b'{"type":"hello"'))
            except (ConnectionError, OSError):
                said.append(False)
        for w in three:
            w.close()
        check(said == [True] * 3, "alice's page closed frees its place, under its new number: 3 of hers open again "
              "(%s)" % said)
        rc = procs.stop(web)
        check(rc == 0 and "pages closed because a SIGHUP withdrew their token: 3" in procs.log(web),
              "palp-web stops cleanly on SIGINT (exit %s), its last stats count the 3 pages closed" % rc)

        # --token on the command line cannot change: said once; the trainees' file is re-read.
        procs2 = harness.Procs(build, source, out, 168)
        secret(trainfile, "alice %s\n" % ALICE)
        fixed = procs2.web(["--token", INSTR1, "--trainee-tokens", trainfile], name="web-fixed")
        secret(trainfile, "alice %s\nbob %s\n" % (ALICE, BOB1))
        l1 = sighup(procs2, fixed, r"SIGHUP: tokens re-read: .*")
        secret(trainfile, "bob %s\n" % BOB1)
        l2 = sighup(procs2, fixed, r"SIGHUP: tokens re-read: .*")
        said = procs2.log(fixed).count("--token was given on the command line: the instructors' token cannot change")
        check(said == 1, "--token on the command line: SIGHUP twice says once it cannot change (%d times)" % said)
        check(l1 is not None and "instructors' token unchanged, trainees' tokens 2 (added 1, removed 0, changed 0)" in l1
              and l2 is not None and "trainees' tokens 1 (added 0, removed 1, changed 0)" in l2,
              "and re-reads --trainee-tokens: %s; %s" % (l1, l2))
        got = [status_of(fixed, t) for t in (INSTR1, ALICE, BOB1)]
        check(got == [200, 401, 200], "the instructors' token, alice's (removed), bob's: %s (200, 401, 200)" % got)
        # the same file, its last write 13 h ago: bob's token, the same, is issued then and so expired
        secret(trainfile, "bob %s\n" % BOB1, age_s=13 * HOUR)
        sighup(procs2, fixed, r"SIGHUP: tokens re-read: .*")  # (the log after this SIGHUP)
        l3 = re.findall(r"SIGHUP: the trainees' tokens expired at .*", procs2.log(fixed))
        l3 = l3[0] if len(l3) == 1 else None
        status, body, _ = harness.http_get(fixed.base + "/trainee.html?token=" + BOB1)
        check(l3 is not None and "write new tokens and send SIGHUP (or restart palp-web)" in l3 and
              abs(float(re.search(r"([\d.]+) h ago", l3).group(1)) - 1.0) <= 0.1 and status == 401 and
              b"has expired" in body, "a file last written 13 h ago: its tokens expired 1.0 h ago, said with the "
              "advice to send SIGHUP (%s); bob's token gets the expired 401 (%d)" % (l3, status))
    finally:
        if procs2:
            procs2.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
