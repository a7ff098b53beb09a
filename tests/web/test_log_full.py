#!/usr/bin/env python3
"""web_log_full: the instructor's dashboard says the session log's trouble in words (session 67), as the
server's own log does (db/loss_watch.c), not only as red counters. A real palp-server whose log is capped
at 1 MB (session_log_max_mb) and padded by the test to ~0.96 MB; a trainee practises "easy" for 10 s and
the log fills: the dashboard says LOSING records, with the counts of the status it came in and what to do,
and her own page and station that the log is losing records while her session runs (session 68), and her page
that her score comes from an incomplete log (or why none comes); her station gone, nothing more is lost or written: it says so, with how long ago the last loss was; the test
frees the padding (as a prune would) and a second trainee presses: "writing again", with the count the
server's own log gives in its "writing again" line; cid, practising freely across the fill's end, is told
by his station that the log is losing his session's records, then that it writes again, then the loss in all, which
is his session's own (session 69: palp_session_log), the count the log's row for his session holds. DDS domain 137.
usage: test_log_full.py BUILD SOURCE OUT"""
import os
import re
import sqlite3
import time

import harness
from harness import check

DOMAIN = 137


def run(build, source, out):
    procs = harness.Procs(build, source, out, DOMAIN)
    browser = None
    db = os.path.join(out, "sessions.db")
    for suffix in ("", "-wal", "-shm"):
        if os.path.exists(db + suffix):
            os.unlink(db + suffix)
    try:
        # the server makes its log (schema and all), stops; the test pads it to ~0.96 MB of the 1 MB cap
        first = procs.server(db=db)
        check(procs.wait_log(first, r"tick thread", 20) is not None, "a first server makes the log")
        procs.stop(first)
        h = sqlite3.connect(db)
        h.execute("CREATE TABLE pad(x BLOB)")
        h.execute("INSERT INTO pad VALUES(zeroblob(850000))")
        h.commit()
        size = h.execute("SELECT page_count * page_size FROM pragma_page_count, pragma_page_size").fetchone()[0]
        h.close()
        check(900000 <= size < 1000000, "the log padded to %d bytes (0.90-1.00 MB of its 1 MB cap)" % size)

        # the shipped exercises, the log capped at 1 MB
        server = procs.server(config=harness.server_config(source, out, "server-exercises.json", "server-capped.json",
                                                           lambda cfg: cfg.update(session_log_max_mb=1)), db=db)
        check(procs.wait_log(server, r"session log: 0\.9\d MB of its cap of 1\.00 MB \(session_log_max_mb\): nearly "
                                     r"full", 20) is not None, "the server says at start that its log is nearly full")
        web = procs.web()
        browser = harness.cdp.Chromium(width=1200, height=800, out_dir=out)
        page = browser.new_page(web.base + "/dashboard.html")
        check(page.wait_for("window.palpState && palpState.status && palpState.status.servers.length === 1", 20) is True,
              "the dashboard has the server's status")
        check(page.eval("document.getElementById('server').textContent.indexOf('session log') < 0") is True,
              "no session-log line while nothing is lost")

        # ann practises "easy" (phantom 11) with a fingertip, her page open: the server scores her session from
        # what the log holds, and her page says what that score is worth
        ann_page = browser.new_page(web.base + "/trainee.html?trainee=ann")
        check(ann_page.wait_for("window.palpState && palpState.connected", 20) is True, "ann's page connected")
        obs_page = browser.new_page(web.base + "/trainee.html?role=observer")  # the instructor follows any session
        check(obs_page.wait_for("window.palpState && palpState.connected", 20) is True, "an observer's page connected")
        # 10 s (7 until session 84: among a full run's first tests the dashboard's check took most of the
        # session, and ann's page was asked after it had closed: 4.7 s between the log's first loss and the close)
        ann = procs.trainee("ann", 11, ["--input", "sim:press,hold_s=4", "--duration", "10"])
        # the line and the counts of the status it was built from, read in one go
        line = ("(function(){const ks=Array.from(document.querySelectorAll('#server .k'));"
                "const k=ks.find(function(e){return e.textContent==='session log';});"
                "const l=palpState.status.servers[0].log;"
                "return k ? {text: k.nextSibling.textContent, bad: k.nextSibling.className, log: l} : null;})()")
        losing = page.wait_for("(function(){const r=%s; return r && r.text.indexOf('LOSING') === 0 ? r : null;})()"
                               % line, 25)
        want = None
        if losing:
            n_shed, n_failed = int(losing["log"][1]), int(losing["log"][2])
            want = ("LOSING records: %d lost so far (%d shed: its queue was full; %d failed: its file reached its cap "
                    "(session_log_max_mb) or its disk is full, or it cannot write); prune old sessions (palp-review "
                    "prune), free space or raise the cap; the server's log says which"
                    % (n_shed + n_failed, n_shed, n_failed))
        check(losing is not None and losing["text"] == want and n_failed > 0 and "bad" in losing["bad"],
              "as ann fills the log, the dashboard says it is losing records, the status's counts and what to do, "
              "in red: %r" % (losing and losing["text"]))
        # her own page says it too while her session runs (session 68), in her station's words: the bridge reads
        # her server's status as her station does (idl/palp_dds_log_view.c)
        ann_log = ann_page.wait_for("(function(){const e=document.getElementById('log');"
                                    "return e && !e.hidden && e.textContent.indexOf('losing') >= 0 ? "
                                    "{text: e.textContent, cls: e.className} : null;})()", 15)
        why = r"(the log's disk or its cap is full|the server was too busy to write some, and the log's disk or its cap is full)"
        m = ann_log and re.fullmatch(r"The server's session log is losing this session's records: (\d+) so far "
                                     r"\(" + why + r"\); this session will be incomplete in the review: tell your "
                                     r"instructor\.", ann_log["text"])
        check(m is not None and int(m.group(1)) > 0 and ann_log["cls"] == "",
              "ann's page tells her the log is losing records while her session runs: %r" % (ann_log and ann_log["text"]))

        obs_log = obs_page.wait_for("(function(){const e=document.getElementById('log');"
                                    "return e && !e.hidden && e.textContent.indexOf('losing') >= 0 ? e.textContent : null;})()",
                                    15)
        m = obs_log and re.fullmatch(r"The server's session log is losing this session's records: (\d+) so far "
                                     r"\(" + why + r"\); this session will be incomplete in the review; the server's log "
                                     r"says what to do\.", obs_log)
        check(m is not None and int(m.group(1)) > 0,
              "  and the instructor following her session is told what to do, not to tell an instructor: %r" % obs_log)

        # (session 90) the screenshot last: taken between the checks, under a fresh clone's load it took ann's
        # page's check past her 10 s session, and her page's line had gone with it
        print("screenshot:", page.screenshot(os.path.join(out, "dashboard-log-losing.png")))
        obs_page.close()  # while it is open, ann's page is a background tab, whose screenshot hangs

        # what ann's page says of her score: scored from a log that lost records, and so said; or, where the log
        # kept too little of her session to score (its row, or its exercise, lost), why no score comes
        told = ann_page.wait_for("(function(){const e=document.getElementById('debrief-score');"
                                 "return e && !e.hidden && e.textContent ? e.textContent : null;})()", 40)
        graded = told is not None and re.fullmatch(r"Your score: \d+\.\d of 100, (passed|not passed) \(the automatic "
                                                  r"score, as the review gives it; your instructor grades you\)\..* The "
                                                  r"session's log is incomplete: the score may be low\.", told)
        unscored = told is not None and re.fullmatch(r"No score: (the session log lost \d+ of its records|not in the "
                                                    r"session log, which (is losing|lost) records) \(database or disk "
                                                    r"is full\); tell your instructor\.", told)
        check(bool(graded or unscored), "ann's page says her score comes from an incomplete log, or why none comes: %r"
              % told)
        print("screenshot:", ann_page.screenshot(os.path.join(out, "trainee-log-incomplete.png")))

        # ann's station ends: nothing more is lost; 3 s of "losing" held, then quiet, or "writing again" when
        # her session's last small batch found room on a partly filled page (both seen in server_log_full)
        ann.wait(timeout=30)
        said = re.search(r"\[trainee ann\] the server's session log is losing this session's records: (\d+) so far "
                         r"\(" + why + r"\); this session will be incomplete in the review: tell your instructor\n",
                         procs.log(ann))
        check(said is not None and int(said.group(1)) > 0,
              "  and her station said so, --quiet as it is: %r" % (said and said.group(0)))
        in_all = re.search(r"\[trainee ann\] the server's session log lost (\d+) of this session's records \(" + why +
                           r"\): it will be incomplete in the review\n", procs.log(ann))
        check(in_all is not None and said is not None and int(in_all.group(1)) >= int(said.group(1)),
              "  and as it ended, the loss in all (>= the first said): %r" % (in_all and in_all.group(0)))
        page_all = ann_page.wait_for("(function(){const e=document.getElementById('log');"
                                     "return e && !e.hidden && e.textContent.indexOf(' lost ') >= 0 ? e.textContent : null;})()",
                                     10)
        m = page_all and re.fullmatch(r"The server's session log lost (\d+) of this session's records \(" + why +
                                      r"\): it will be incomplete in the review\.", page_all)
        check(m is not None and said is not None and int(m.group(1)) >= int(said.group(1)),
              "  and her page, the session over, says the loss in all as her station does: %r" % page_all)
        ann_page.close()  # done with: an open page keeps its animation frames running (Chromium's CPU)
        quiet = page.wait_for("(function(){const r=%s; return r && r.text.indexOf('LOSING') < 0 ? r : null;})()"
                              % line, 20)
        m = quiet and re.fullmatch(r"(\d+) records lost \(0 shed: its queue was full; (\d+) failed: its file reached "
                                   r"its cap \(session_log_max_mb\) or its disk is full, or it cannot write\), the "
                                   r"last 0:(\d\d) ago; nothing written since; prune old sessions \(palp-review "
                                   r"prune\), free space or raise the cap; the server's log says which", quiet["text"])
        m2 = quiet and re.fullmatch(r"writing again; (\d+) records lost earlier \(0 shed: its queue was full; (\d+) "
                                    r"failed: its file reached its cap \(session_log_max_mb\) or its disk is full, or "
                                    r"it cannot write\)", quiet["text"])
        n_lost = int(quiet["log"][2]) if quiet else -1
        check((m is not None and int(m.group(1)) == n_lost and int(m.group(2)) == n_lost and 3 <= int(m.group(3)) <= 30)
              or (m2 is not None and int(m2.group(1)) == n_lost and int(m2.group(2)) == n_lost),
              "her station gone, the dashboard says the loss has stopped (3-30 s since the last, nothing written "
              "since; or, her last batch in, writing again), with the status's count: %r" % (quiet and quiet["text"]))

        # cid practises freely (force-driven, dome A) on the full log: his station says it is losing records (session
        # 68), and once the padding is freed, that it writes again, and as it ends the loss in all
        cid = procs.trainee("cid", 1, ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1",
                                       "--t-on", "0", "--t-off", "60", "--duration", "60"])
        cid_losing = procs.wait_log(cid, r"\[trainee cid\] the server's session log is losing this session's records: "
                                         r"(\d+) so far \(" + why + r"\); this session will be incomplete in the "
                                         r"review: tell your instructor\n", 15)

        # the padding freed (a prune's part), another trainee: the log writes again, and says so
        h = sqlite3.connect(db, timeout=10)
        h.execute("DROP TABLE pad")
        h.commit()
        h.close()
        procs.trainee("bea", 2, ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1",
                                 "--t-on", "0", "--t-off", "60", "--duration", "6"])
        again = page.wait_for("(function(){const r=%s; return r && r.text.indexOf('writing again') === 0 ? r : null;})()"
                              % line, 25)
        procs.wait_log(server, r"session log: writing again \((\d+) records lost in all\)", 10)
        said = list(re.finditer(r"session log: writing again \((\d+) records lost in all\)", procs.log(server)))
        said = said[-1] if said else None  # the last recovery the server's watch said
        m = again and re.fullmatch(r"writing again; (\d+) records lost earlier \(0 shed: its queue was full; (\d+) "
                                   r"failed: its file reached its cap \(session_log_max_mb\) or its disk is full, or it "
                                   r"cannot write\)", again["text"])
        check(m is not None and said is not None and int(m.group(1)) == int(said.group(1)) and
              int(m.group(2)) == int(said.group(1)),
              "the padding freed, bea's session is written: the dashboard says 'writing again' with the count the "
              "server's own log gives (%s): %r" % (said and said.group(0), again and again["text"]))
        print("screenshot:", page.screenshot(os.path.join(out, "dashboard-log-again.png")))
        cid_again = procs.wait_log(cid, r"\[trainee cid\] the server's session log is writing again; (\d+) of this "
                                        r"session's records were lost: it will be incomplete in the review\n", 20)
        # the dashboard's card for his session says the same count, his own (session 69): which reviews will be
        # incomplete, not only that the server's log loses records
        card = page.wait_for(
            "(function(){const c=Array.from(document.querySelectorAll('.card')).find(function(e){"
            "return e.querySelector('h3 span').textContent.indexOf('cid, session ') === 0;});"
            "if(!c) return null; const r=Array.from(c.querySelectorAll('tr')).find(function(t){"
            "return t.cells[0].textContent==='session log';});"
            "return r && r.cells[1].textContent !== 'nothing lost' ? {text: r.cells[1].textContent, "
            "cls: r.cells[1].className} : null;})()", 5)
        check(card is not None and card["text"] == "%s of its records lost" % cid_again.group(1) and card["cls"] == "warn",
              "the dashboard's card for cid's session says his own count, in red: %r (his station: %s)"
              % (card, cid_again.group(1)))
        procs.stop(cid)
        cid_all = re.search(r"\[trainee cid\] the server's session log lost (\d+) of this session's records \(" + why +
                            r"\): it will be incomplete in the review\n", procs.log(cid))
        check(int(cid_again.group(1)) >= int(cid_losing.group(1)) > 0 and cid_all is not None and
              int(cid_all.group(1)) == int(cid_again.group(1)),
              "cid's station, practising freely on the full log, said it was losing records (%s), then, the padding "
              "freed, that it writes again (%s), and as it ended the same loss in all (%s)"
              % (cid_losing.group(1), cid_again.group(1), cid_all and cid_all.group(1)))
        # what cid was told is his own session's loss (palp_session_log, session 69), the count the review shows for
        # his session (its row, made once the log took his records again), not the server's: ann's before him too
        row = None
        for _ in range(50):
            h = sqlite3.connect(db, timeout=10)
            got = h.execute("SELECT records_shed + records_failed FROM session WHERE trainee = 'cid'").fetchall()
            h.close()
            row = got[0][0] if len(got) == 1 else None
            if cid_all is not None and row == int(cid_all.group(1)):
                break
            time.sleep(0.1)
        server_lost = int(again["log"][1]) + int(again["log"][2]) if again else -1
        check(cid_all is not None and row == int(cid_all.group(1)) and row < server_lost,
              "  his loss in all is his session's own, as the log's row for it counts: station %s, row %s, of the "
              "server's %d" % (cid_all and cid_all.group(1), row, server_lost))
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
