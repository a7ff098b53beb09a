#!/usr/bin/env python3
"""web_secure: palp-web in a classroom secured with DDS Security (docs/web.md, docs/security.md).

A secured palp-server, a secured trainee (trainee/alice) pressing a sine on phantom 1, and three
bridges on the same domain:
- `--pki PKI --identity instructor/ines`: a client following every session gets alice's session and
  its deformation frames, the bridge is counted as a visual member of it (its join, under the
  instructor's own name and partition, was accepted: the server refuses any other), and its hello
  says that findings are not marked through the page in a secured classroom;
- no identity: it sees no session and no frame (authenticated discovery and encrypted data keep a
  plain participant out), and after 10 s it says that the classroom may be secured;
- `--identity trainee/bob`: refused before it touches the network (exit 2), since a trainee's
  permissions read only the trainee's own sessions;
- and dave's laptop, revoked but holding his files from before, tries to join: the instructor's
  bridge lists him in the dashboard's status ("refused": trainee/dave, certificate revoked), the
  dashboard page shows it, and the bridge says it once in its log.
A raw WebSocket client (cdp.WebSocket), and headless Chromium for the dashboard's refusal line. DDS domain 125.
usage: test_secure.py BUILD SOURCE OUT (the PKI directory in PALP_TEST_PKI: fixture security_pki)"""
import json
import re
import os
import time

import harness
from harness import check


def run(build, source, out):
    pki = os.environ["PALP_TEST_PKI"]
    procs = harness.Procs(build, source, out, 125)
    try:
        procs.server(extra=["--pki", pki])
        secure = procs.web(extra=["--pki", pki, "--identity", "instructor/ines"], name="web-ines")
        plain = procs.web(name="web-plain")
        check("DDS Security on (identity instructor/ines)" in procs.log(secure),
              "the secured bridge says it runs as instructor/ines")
        procs.start("trainee-alice", [os.path.join(build, "client", "palp-client"), "--role", "trainee", "--domain",
                                      "125", "--phantom", "1", "--pki", pki, "--identity", "trainee/alice", "--quiet",
                                      "--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1",
                                      "--t-on", "0.5", "--t-off", "60", "--duration", "60"])

        # The secured bridge: alice's session, joined, and its frames.
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % secure.port, timeout=10)
        ws.send(json.dumps({"follow": "all"}))
        t0, hello = time.time(), []

        def joined(m):  # the list with alice's session joined by the bridge, keeping the hello
            if m["type"] == "hello":
                hello.append(m)
            mine = [s for s in m.get("sessions", []) if s["trainee"] == "alice"] if m["type"] == "sessions" else []
            return bool(mine) and mine[0]["visual"] >= 1 and mine[0]["joined"]

        joined_after = time.time() - t0 if harness.ws_until(ws, 25, joined) else None
        hello = hello[0] if hello else None
        check(joined_after is not None,
              "the secured bridge lists alice's session and the server counts it as a visual member (%.1f s)"
              % (joined_after if joined_after is not None else float("nan")))
        check(hello is not None and hello["findings"] is False,
              "its hello says findings are not marked through the page in a secured classroom (%s)"
              % (hello and hello.get("findings")))
        kinds, frames = harness.ws_messages(ws, 3.0)
        ws.close()
        check(frames >= 15, "it streams alice's deformation: %d frames in 3 s (dashboard rate 10/s; >= 15)" % frames)

        # The plain bridge on the same domain: nothing.
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % plain.port, timeout=10)
        ws.send(json.dumps({"follow": "all"}))
        kinds, frames = harness.ws_messages(ws, 4.0)
        ws.close()
        seen = [s for m in kinds.get("sessions", []) for s in m["sessions"]]
        check(not seen and frames == 0 and "phantom" not in kinds,
              "a bridge without an identity sees no phantom, no session and no frame (%d sessions, %d frames, "
              "%d phantoms)" % (len(seen), frames, len(kinds.get("phantom", []))))

        # ... and says once why it may hear nothing (10 s after its start).
        m = procs.wait_log(plain, r"no phantom from any palp-server in 10 s; (\d+) other DDS participants? (is|are) on "
                           r"this domain, none of which answered: if the classroom runs with DDS Security", 20)
        check(int(m.group(1)) >= 1, "the plain bridge says the classroom may be secured (%s other participants)"
              % m.group(1))

        # dave's laptop, revoked in the classroom's CRL but holding his files from before: the
        # bridge refuses him as the server does, and its dashboard status names him and why.
        procs.start("trainee-dave", [os.path.join(build, "client", "palp-client"), "--role", "trainee", "--domain",
                                     "125", "--phantom", "1", "--pki", pki + "-dave", "--identity", "trainee/dave",
                                     "--quiet", "--timeout", "8", "--duration", "1"])
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % secure.port, timeout=10)
        ws.send(json.dumps({"follow": "all"}))

        def dave_refused(m):  # and the plain bridge above, named as a stranger (below)
            return m["type"] == "status" and any(r["who"] == "trainee/dave" for r in m.get("refused", [])) and \
                any(r["who"].startswith("palp-web on host ") for r in m.get("refused", []))

        st = harness.ws_until(ws, 20, dave_refused)
        ws.close()
        dave = [r for r in st["refused"] if r["who"] == "trainee/dave"][0] if st else {}
        check(dave.get("why") == "certificate revoked" and dave.get("at") == "handshake" and dave.get("count", 0) >= 1,
              "the dashboard's status names the revoked trainee/dave and why: %s" % dave)
        # the plain bridge above, still on the domain without an identity, is named as a stranger
        # (idl/palp_dds_strangers.c) once it has shown no endpoint for 3 s; nobody else is
        others = [r for r in st["refused"] if r["who"] != "trainee/dave"] if st else None
        check(others is not None and all(re.match(r"palp-web on host \S+$", r["who"]) and r["at"] == "unauthenticated"
                                         and r["why"].startswith("a plain DDS participant") for r in others)
              and len(others) == 1,
              "and nobody else but the plain bridge, named by what it announces (%s)" % others)
        # The instructor's dashboard in headless Chromium shows it beside the server's status.
        browser = harness.cdp.Chromium(width=1200, height=800, out_dir=out)
        try:
            page = browser.new_page(secure.base + "/dashboard.html")
            ok = page.wait_for("(document.getElementById('refused') || {}).textContent && "
                               "document.getElementById('refused').textContent.startsWith('trainee/dave: certificate "
                               "revoked (')", 20)
            shown = page.eval("(document.getElementById('refused') || {}).textContent || null")
            label = page.eval("(function (e) { return e && e.previousSibling ? e.previousSibling.textContent : null; })"
                              "(document.getElementById('refused'))")
            check(ok is True and label == "refused by DDS Security",
                  "the dashboard shows it: \"%s: %s\"" % (label, shown))
            page.screenshot(os.path.join(out, "dashboard-refused.png"))
        finally:
            browser.close()
        wlog = procs.log(secure)
        check(wlog.count("DDS Security refused trainee/dave at the handshake: certificate revoked") == 1
              and "handshake failed" not in wlog,
              "the bridge's log says it once, in palp's words, and holds none of Cyclone's raw lines")

        # A trainee identity is refused up front.
        bad = procs.start("web-bob", [os.path.join(build, "web", "palp-web"), "--domain", "125", "--port", "0",
                                      "--pki", pki, "--identity", "trainee/bob"])
        try:
            rc = bad.wait(timeout=10)
        except Exception:
            rc = None
        check(rc == 2 and "only an instructor identity may read" in procs.log(bad),
              "a bridge with a trainee identity is refused before it joins (exit %s)" % rc)

        server = procs.procs[0]
        rc = procs.stop(secure)
        check(rc == 0, "the secured bridge stops cleanly on SIGINT (exit %s)" % rc)
        log = procs.log(server)
        check("refused request" not in log and "not its own" not in log,
              "the server refused none of the bridge's requests")
    finally:
        procs.close()


if __name__ == "__main__":
    harness.main(run)
