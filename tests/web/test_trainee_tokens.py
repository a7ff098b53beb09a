#!/usr/bin/env python3
"""web_trainee_tokens: trainees' own tokens scope a page to that trainee's sessions (docs/web.md).

palp-web with --token (the instructors') and --trainee-tokens (alice's and bob's); trainees alice and
bob each press a sine on their own phantom. With alice's token:
- the pages are served (200) and the cookie set is alice's token, not the instructors';
- the session list names alice's session only, no server status is sent;
- following bob's session, or every session (the dashboard), gets nothing: no frame in 3 s, and one
  `refused` message saying why (since session 82);
- following her own session streams it;
- while bob's exercise session ("easy") runs, the instructors' dashboard is sent where its lump is hidden
  (an `answers` message: the server runs with "session_exercise": "always", this test's copy of
  config/server-exercises.json), at the place easy.json gives (polar 30 deg, azimuth 120 deg on the 40 mm
  dome) and the place bob's debrief names; alice's page is never sent one;
- bob's exercise session ("easy") ends: its debrief, with the lesion's place, reaches an instructors'
  page and not alice's; opened afterwards, an instructors' page following every session is sent it from
  the bridge's last 16 (the dashboard's replay), one following his session alone is not, and alice's
  page is not.
With the instructors' token the list has both sessions and the dashboard streams. A token nobody was
given is refused (401). No browser: raw HTTP and WebSocket clients. DDS domain 126.
usage: test_trainee_tokens.py BUILD SOURCE OUT"""
import json
import math
import os
import struct
import subprocess
import time

import harness
from harness import check

INSTR = "instructor-token-0123456789"
ALICE = "alice-own-token-0123456789"
BOB = "bob-own-token-0123456789ab"


def sessions_seen(ws, want, seconds):
    """Session lists received until one holds `want` trainees (or time runs out): (last list, kinds seen)."""
    last, kinds = [None], set()

    def seen(m):
        kinds.add(m["type"])
        if m["type"] == "sessions":
            last[0] = m["sessions"]
            return sorted(s["trainee"] for s in last[0]) == sorted(want)
        return False

    harness.ws_until(ws, seconds, seen)
    return last[0], kinds


def run(build, source, out):
    procs = harness.Procs(build, source, out, 126)
    tokfile = os.path.join(out, "trainee-tokens.txt")
    with open(tokfile, "w") as f:
        f.write("# the class's own tokens\nalice %s\nbob %s\n" % (ALICE, BOB))
    try:
        # Secrets readable by every user of the machine are refused (docs/web.md), then accepted at 0600.
        os.chmod(tokfile, 0o644)
        r = subprocess.run([os.path.join(build, "web", "palp-web"), "--port", "0", "--domain", "126", "--token", INSTR,
                            "--trainee-tokens", tokfile], capture_output=True, text=True, timeout=20, env=procs.env)
        check(r.returncode == 2 and "readable by every user" in r.stderr,
              "a world-readable --trainee-tokens file is refused (exit %d): %s" % (r.returncode, r.stderr.strip()[:100]))
        os.chmod(tokfile, 0o600)
        # Session 81's review: a directory given as the file started palp-web with every trainee locked out,
        # and a NUL byte ended the list (bob, after it, dropped): each refused up front, named.
        tokdir = os.path.join(out, "tokdir")
        os.makedirs(tokdir, mode=0o700, exist_ok=True)
        nulfile = os.path.join(out, "tokens-nul.txt")
        with open(nulfile, "wb") as f:
            f.write(("alice %s\n" % ALICE).encode() + b"\0\n" + ("bob %s\n" % BOB).encode())
        os.chmod(nulfile, 0o600)
        for path, want in ((tokdir, "a directory, not a file"), (nulfile, "a NUL byte at byte %d" % (len(ALICE) + 7))):
            r = subprocess.run([os.path.join(build, "web", "palp-web"), "--port", "0", "--domain", "126", "--token",
                                INSTR, "--trainee-tokens", path], capture_output=True, text=True, timeout=20,
                               env=procs.env)
            check(r.returncode == 2 and want in r.stderr,
                  "--trainee-tokens %s refused up front (exit %d): %s" % (os.path.basename(path), r.returncode,
                                                                          r.stderr.strip()[:160]))
        # phantoms 1 and 2 as server-paper's, and the exercises; the lumps sent to instructors
        procs.server(config=harness.answers_config(source, out))
        web = procs.web(extra=["--token", INSTR, "--trainee-tokens", tokfile])
        check("2 trainee token(s), each page scoped" in procs.log(web), "palp-web says it has 2 scoped trainee tokens")
        sine = ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1", "--t-on", "0.5",
                "--t-off", "60", "--duration", "60"]
        procs.trainee("alice", 1, sine)
        bob = procs.trainee("bob", 11, sine)  # the "easy" exercise: his session ends with a debrief

        status, body, headers = harness.http_get(web.base + "/trainee.html?token=" + ALICE)
        cookie = headers.get("Set-Cookie", "")
        check(status == 200 and ALICE in cookie and INSTR not in cookie,
              "alice's token serves the trainee page and sets her own token as the cookie (%d)" % status)
        status, _, _ = harness.http_get(web.base + "/trainee.html?token=nobodys-token-0123456789")
        check(status == 401, "a token nobody was given is refused (%d)" % status)

        # The instructors' view: both sessions, and the dashboard streams.
        inst = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, INSTR), timeout=10)
        both, _ = sessions_seen(inst, ["alice", "bob"], 25)
        check(both is not None and sorted(s["trainee"] for s in both) == ["alice", "bob"],
              "the instructors' page lists both sessions (%s)" % [s["trainee"] for s in (both or [])])
        ids = {s["trainee"]: s["id"] for s in both}
        inst.send(json.dumps({"follow": "all"}))
        kinds, frames = harness.ws_messages(inst, 3.0)
        check(frames >= 15, "the instructors' dashboard streams: %d frames in 3 s (>= 15)" % frames)
        # where bob's lump is hidden (docs/web.md, "The hidden lumps"): easy.json's lesion at polar 30 deg,
        # azimuth 120 deg, on the skin of the 40 mm dome: 40 (sin 30 cos 120, sin 30 sin 120, cos 30) mm
        ans = [m for m in kinds.get("answers", []) if m["session"] == ids["bob"]]
        if not ans:
            a = harness.ws_until(inst, 5, lambda m: m.get("type") == "answers" and m["session"] == ids["bob"])
            ans = [a] if a else []
        inst.close()
        r, pol, az = 40.0, math.radians(30), math.radians(120)
        want = [r * math.sin(pol) * math.cos(az), r * math.sin(pol) * math.sin(az), r * math.cos(pol)]
        lump = ans[-1]["lumps"][0] if ans and len(ans[-1]["lumps"]) == 1 else None
        check(lump is not None and ans[-1]["exercise"] == "easy" and ans[-1]["found"] == 0 and
              all(abs(lump["point_mm"][k] - want[k]) <= 0.2 for k in range(3)) and lump["across_mm"] == 20,
              "the instructors' dashboard is sent where bob's lump is hidden: %s (want %s mm within 0.2 mm, 20 mm "
              "across, not found)" % (lump, [round(w, 1) for w in want]))

        # Alice's view.
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10)
        mine, kinds = sessions_seen(ws, ["alice"], 10)
        check(mine is not None and [s["trainee"] for s in mine] == ["alice"],
              "alice's page lists her session only (%s)" % [s["trainee"] for s in (mine or [])])
        ws.send(json.dumps({"follow": ids["bob"]}))
        k1, f_bob = harness.ws_messages(ws, 3.0)
        ws.send(json.dumps({"follow": "all"}))
        k2, f_all = harness.ws_messages(ws, 3.0)
        check(f_bob == 0 and f_all == 0, "following bob's session or every session gets alice's page nothing "
              "(%d and %d frames in 3 s)" % (f_bob, f_all))
        # ... but told why, each time (since session 82: the dashboard with her token said "live" and waited)
        r1, r2 = k1.get("refused", []), k2.get("refused", [])
        check(len(r1) == 1 and "not hers" in r1[0]["message"] and len(r2) == 1 and
              "dashboard is for instructors" in r2[0]["message"],
              "and is told why: %r, %r" % ([m["message"] for m in r1], [m["message"] for m in r2]))
        ws.send(json.dumps({"follow": ids["alice"]}))
        k3, f_mine = harness.ws_messages(ws, 3.0)
        check(f_mine >= 15, "following her own session streams it: %d frames in 3 s (>= 15)" % f_mine)
        seen = kinds | set(k1) | set(k2) | set(k3)
        lists = [s["trainee"] for m in k1.get("sessions", []) + k2.get("sessions", []) + k3.get("sessions", [])
                 for s in m["sessions"]]
        check("answers" not in seen, "alice's page is never sent where a lump is hidden (%s)" % sorted(seen))
        check("status" not in seen and set(lists) <= {"alice"},
              "no server status and no other trainee in any list alice's page got (%s; %s)"
              % (sorted(seen), sorted(set(lists))))
        # bob's exercise session ends: its debrief (where the exercise's lesion is, docs/assessment.md) goes to
        # an instructors' page, never to alice's, which follows her own session meanwhile
        inst = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, INSTR), timeout=10)
        inst.send(json.dumps({"follow": "all"}))
        procs.stop(bob)
        d = harness.ws_until(inst, 10, lambda m: m.get("type") == "debrief")
        inst.close()
        check(d is not None and d["trainee"] == "bob" and d["session"] == ids["bob"] and d["level"] == "lesions" and
              len(d["lumps"]) == 1, "the instructors' page is sent bob's debrief: %s" % d)
        check(d is not None and lump is not None and d["lumps"][0]["point_mm"] == lump["point_mm"],
              "the dashboard's lump is where the server's debrief puts it (%s, %s)"
              % (d and d["lumps"][0]["point_mm"], lump and lump["point_mm"]))
        k4, _ = harness.ws_messages(ws, 2.0)
        check("debrief" not in k4, "alice's page is not (%s)" % sorted(k4))
        ws.close()
        # Pages opened after bob's session ended (docs/web.md, the dashboard's replay): an instructors' page
        # following bob's session alone is not sent his debrief (one session: only what comes after the page
        # connected); the same page following every session then is, the very message sent live. A page of
        # alice's token opened now, following her own session and asking for every session, is sent none.
        inst = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, INSTR), timeout=10)
        inst.send(json.dumps({"follow": ids["bob"]}))
        k5, _ = harness.ws_messages(inst, 1.0)
        inst.send(json.dumps({"follow": "all"}))
        d2 = harness.ws_until(inst, 10, lambda m: m.get("type") == "debrief")
        inst.close()
        check("debrief" not in k5 and d2 == d, "an instructors' page opened later is sent bob's debrief once it follows "
              "every session, not while it follows his session alone (%s; %s)" % (sorted(k5), d2 and d2["trainee"]))
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10)
        ws.send(json.dumps({"follow": ids["alice"]}))
        k6, _ = harness.ws_messages(ws, 1.0)
        ws.send(json.dumps({"follow": "all"}))
        k7, _ = harness.ws_messages(ws, 1.0)
        ws.close()
        check("answers" not in k4 and "answers" not in k6 and "answers" not in k7,
              "nor, at any time, where a lump is hidden (%s; %s; %s)" % (sorted(k4), sorted(k6), sorted(k7)))
        check("debrief" not in k6 and "debrief" not in k7 and "sessions" in k6,
              "a page of alice's token opened later is not sent bob's debrief either (%s; %s)" % (sorted(k6), sorted(k7)))

        # One trainee's token holds at most 3 pages at once (session 75: one pool of max_clients for every
        # token let a trainee opening pages in a loop lock out the class and its instructor); the
        # instructors' token and another trainee's still get theirs, and a page closed frees its place.
        mine = [harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10) for _ in range(3)]
        hello = [w.recv()[1].startswith(b'{"type":"hello"') for w in mine]
        told = None  # the 4th page's close frame: its status and reason, which the page shows
        try:
            extra = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=5)
            b0, b1 = extra._read(2)
            payload = extra._read(b1 & 0x7F)
            fourth = b0 & 0x0F != 8
            if not fourth:
                told = (struct.unpack("!H", payload[:2])[0], payload[2:].decode())
            extra.close()
        except (ConnectionError, OSError):
            fourth = False
        others = []
        for tok in (INSTR, BOB):
            w = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, tok), timeout=10)
            others.append(w.recv()[1].startswith(b'{"type":"hello"'))
            w.close()
        mine.pop().close()
        time.sleep(0.3)
        w = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws?token=%s" % (web.port, ALICE), timeout=10)
        again = w.recv()[1].startswith(b'{"type":"hello"')
        w.close()
        for m in mine:
            m.close()
        check(all(hello) and not fourth and others == [True, True] and again,
              "alice's token: 3 pages open (%s), a 4th refused (%s), the instructors' and bob's pages served (%s), "
              "one closed frees its place (%s)" % (hello, "refused" if not fourth else "served", others, again))
        check(told == (1008, "this trainee's token has 3 pages open already: close one of them"),
              "the 4th is told why, in the close frame its page shows: %s" % (told,))

        rc = procs.stop(web)
        check(rc == 0, "palp-web stops cleanly on SIGINT (exit %s)" % rc)
    finally:
        procs.close()


if __name__ == "__main__":
    harness.main(run)
