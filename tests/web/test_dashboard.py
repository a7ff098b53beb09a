#!/usr/bin/env python3
"""web_dashboard: the instructor dashboard in headless Chromium lists every open session of a
running palp-server (the server's own log says which are open), shows the server's status and each
card's own colour scale, adds a session that opens later without a reload, drops a closed one
within a second, and shows a trainee station the server lost to a 1.5 s stall (SIGSTOP) as such
on its card until it comes back to the same session. A closed session's entries in the page's state go
with its card, and the page keeps only the newest 32 finding replies. DDS domain 192.
usage: test_dashboard.py BUILD SOURCE OUT"""
import calendar
import json
import os
import re
import signal
import time

import harness
from harness import check

CARDS = "JSON.stringify(palpState.dashboard ? palpState.dashboard.cards : null)"


def server_open_sessions(procs, server):
    """Session ids the server reports open, from its own log (independent of palp-web)."""
    log = procs.log(server)
    opened = {int(m) for m in re.findall(r"session (\d+) opened", log)}
    closed = {int(m) for m in re.findall(r"session (\d+) closed", log)}
    return sorted(opened - closed)


def run(build, source, out):
    procs = harness.Procs(build, source, out, 192)
    browser = None
    try:
        server = procs.server()
        web = procs.web()
        press = ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1", "--t-on", "0.5",
                 "--t-off", "60", "--duration", "60"]
        procs.trainee("alice", 1, press)
        procs.trainee("bob", 2, press)
        carol = procs.trainee("carol", 1, press)
        end = time.time() + 15
        while time.time() < end and len(server_open_sessions(procs, server)) < 3:
            time.sleep(0.1)
        expected = server_open_sessions(procs, server)
        check(len(expected) == 3, "the server has 3 open sessions: %s" % expected)
        browser = harness.cdp.Chromium(width=1200, height=800, out_dir=out)
        page = browser.new_page(web.base + "/dashboard.html")
        # 60 s: the page's first load, not a property; at the suite's busiest start it once had run no script
        # 20 s after Chromium started (session 82: palpState undefined; 4 of 7 full runs failed here or below,
        # none alone). The message says how far the page got.
        got = page.wait_for("window.palpState && palpState.dashboard && JSON.stringify(palpState.dashboard.cards) === %r "
                            "&& %s" % (str(expected).replace(" ", ""), CARDS), 60)
        where = page.eval("window.palpState ? JSON.stringify([palpState.connected, palpState.messages, "
                          "palpState.dashboard && palpState.dashboard.cards]) : 'no script run yet (readyState ' + "
                          "document.readyState + ')'")
        check(got is not None, "the dashboard lists every open session %s: [connected, messages, cards] %s"
              % (expected, where))
        names = page.eval("Array.from(document.querySelectorAll('.card h3 span:first-child')).map(e => e.textContent)")
        # each card named as the stations name a session: "alice, session 2" (docs/naming.md)
        parsed = [re.fullmatch(r"(\w+), session (\d+)", n) for n in names]
        check(all(parsed) and sorted(m.group(1) for m in parsed) == ["alice", "bob", "carol"] and
              sorted(int(m.group(2)) for m in parsed) == sorted(expected),
              "with the trainee names and the stations' session numbers %s: %s" % (expected, names))
        ok = page.wait_for("palpState.dashboard.frames > 6 && palpState.status && palpState.status.servers.length === 1 "
                           "&& document.getElementById('server').textContent.includes('tick p50/p99/max')", 15)
        check(ok is True, "top views receive frames and the server's status shows (load, ticks, log counters)")
        ok = page.wait_for("Array.from(document.querySelectorAll('.card .band')).some(e => !e.textContent.startsWith('0.00'))", 10)
        check(ok is True, "a live force shows on the cards")
        # Each card's own colour scale grows with its session's deepest dent: 1-2.5 N on the paper's
        # literal dome dents it 10-25 mm, so every card settles on the 20 or 30 mm step of the ladder.
        scales_js = ("Array.from(document.querySelectorAll('.card tr')).filter(r => r.cells[0].textContent === "
                     "'colour scale').map(r => r.cells[1].textContent)")
        ok = page.wait_for("(function (v) { return v.length === 3 && v.every(x => x === '0-20 mm' || x === '0-30 mm'); })"
                           "(%s)" % scales_js, 10)
        check(ok is True, "each card shows its own colour scale, grown to 20 or 30 mm: %s" % page.eval(scales_js))
        page.screenshot(os.path.join(out, "dashboard-3.png"))

        # A session opening later appears without a reload.
        procs.trainee("dave", 2, press)
        ok = page.wait_for("palpState.dashboard.cards.length === 4", 15)
        check(ok is True, "dave's new session appears without a reload: %s" % page.eval(CARDS))
        carol_id = [s for s in page.eval("palpState.sessions.map(s => [s.id, s.trainee])") if s[1] == "carol"][0][0]

        # the page's per-session state holds carol's session while it is open (her pressed skin, her card's rate)
        held = page.wait_for("palpState.dashboard.cover && %d in palpState.dashboard.cover && "
                             "%d in palpState.dashboard.fpsPerSession" % (carol_id, carol_id), 10)
        check(held is True, "the page keeps carol's session %d's pressed skin and frame rate while it is open" % carol_id)

        # carol leaves: the server closes her session; the card must go at once (well inside the 5 s grace).
        t0 = time.time()
        procs.stop(carol)
        t_drop = None
        while time.time() - t0 < 10:
            cards = page.eval("palpState.dashboard.cards")
            if carol_id not in cards:
                t_drop = time.time()
                break
            time.sleep(0.02)
        closed = re.search(r"^(\S+)Z INFO  palp-server: session %d closed" % carol_id, procs.log(server), re.M)
        check(closed is not None, "the server logged carol's session %d closed" % carol_id)
        # Timed from the server's close (its log's UTC stamp, this machine's clock), not from the stop: the
        # suite's load once held the whole machine ~4 s between the two (session 82; palp-web's own lease
        # lapsed too). < 3 s after the close: 0.0-0.4 s alone, 2.51 s once in a full run (session 84, the
        # page started among the suite's first tests; the bound was 2 s); what it rules out is a card kept
        # until the station grace (5 s) runs out.
        t_close = calendar.timegm(time.strptime(closed.group(1)[:19], "%Y-%m-%dT%H:%M:%S")) + \
            float("0" + closed.group(1)[19:]) if closed else None
        after = t_drop - t_close if t_drop is not None and t_close is not None else float("nan")
        check(t_drop is not None and after < 3.0,
              "carol's closed session left the dashboard %.2f s after the server closed it (< 3 s; %.2f s after her "
              "station was stopped)" % (after, (t_drop - t0) if t_drop is not None else float("nan")))
        check(sorted(page.eval("palpState.dashboard.cards")) == server_open_sessions(procs, server),
              "the remaining cards are the server's open sessions %s" % server_open_sessions(procs, server))
        page.screenshot(os.path.join(out, "dashboard-after-close.png"))
        # ... and her entries in the page's state with it: they are each an open session's (kept, they grew with
        # every session of a class); all 4 sessions have had them, 3 remain
        kept = page.eval("JSON.stringify([palpState.dashboard.cards, Object.keys(palpState.dashboard.cover).map(Number), "
                         "Object.keys(palpState.dashboard.fpsPerSession).map(Number)])")
        cards_now, cover_ids, fps_ids = json.loads(kept)
        check(carol_id not in cover_ids + fps_ids and set(cover_ids) <= set(cards_now) and set(fps_ids) <= set(cards_now),
              "carol's closed session %d is gone from the page's state too: cards %s, pressed skin of %s, frame rates of %s"
              % (carol_id, cards_now, cover_ids, fps_ids))

        # The bridge's finding replies a page keeps are the newest 32 (PALP.REPLIES_KEPT), not all: 40 requests from
        # this viewer page, each refused at once, one at a time (each waited for up to 10 s: one took over 3 s, the
        # bound until session 84, among a fresh clone's first tests).
        got = page.eval("""(async function () {
            const L = palpState.findingReplies; let got = 0;
            for (let i = 0; i < 40; i++) {
              const last = L[L.length - 1], t0 = performance.now();
              palpSend({finding: 'mark'});
              while (L[L.length - 1] === last && performance.now() - t0 < 10000) await new Promise(r => setTimeout(r, 10));
              if (L[L.length - 1] !== last) got++;
            }
            return [got, L.length, L[L.length - 1] && L[L.length - 1].ok];
          })()""")
        check(got == [40, 32, False], "40 refused finding requests answered, the newest 32 replies kept: %s" % got)

        # bob's station stalls 1.5 s: the server holds his session and his card says so; then it goes on.
        station_js = ("(function () { const c = Array.from(document.querySelectorAll('.card')).find(e => "
                      "e.querySelector('h3 span').textContent.startsWith('bob, session ')); if (!c) return null; "
                      "const r = Array.from(c.querySelectorAll('tr')).find(r => r.cells[0].textContent === "
                      "'trainee station'); return r ? [r.cells[1].textContent, r.cells[1].className] : null; })()")
        check(page.eval(station_js) == ["connected", ""], "bob's card shows his station connected: %s"
              % page.eval(station_js))
        bob_id = [s for s in page.eval("palpState.sessions.map(s => [s.id, s.trainee])") if s[1] == "bob"][0][0]
        bob = [p for p in procs.procs if p.name == "trainee-bob"][0]
        bob.send_signal(signal.SIGSTOP)
        t_stop = time.time()
        held = page.wait_for("(function (v) { return v && v[0].includes('held') && v[1] === 'warn'; })(%s)"
                             % station_js, 3)
        seen = page.eval(station_js)
        # polled (up to 1 s, bob still stopped): once among a fresh clone's first tests (session 84) a single read
        # found no badge on his card, which the page was drawing anew
        band_held = page.wait_for("(Array.from(document.querySelectorAll('.card')).filter(e => e.querySelector('h3 span')"
                                  ".textContent.startsWith('bob, session ')).map(e => { const b = e.querySelector('.band'); "
                                  "return b ? b.textContent : null; })[0] || null)", 1.0)
        page.screenshot(os.path.join(out, "dashboard-station-held.png"))
        time.sleep(max(0.0, t_stop + 1.5 - time.time()))
        bob.send_signal(signal.SIGCONT)
        check(held is True, "while bob's station was stopped (%.1f s) his card said so, in warning colour: %s"
              % (time.time() - t_stop, seen))
        check(band_held == "station lost", "and its force badge showed no stale force: %r" % band_held)
        back = page.wait_for("(function (v) { return v && v[0] === 'connected'; })(%s)" % station_js, 5)
        check(back is True and bob_id in page.eval("palpState.dashboard.cards"),
              "after SIGCONT bob's session %d went on and his card reads connected again: %s"
              % (bob_id, page.eval(station_js)))
        log = procs.log(server)
        check(re.search(r"session %d: trainee station \S+ came back after" % bob_id, log) is not None
              and "session %d closed" % bob_id not in log,
              "the server held bob's session %d and resumed it (its log)" % bob_id)
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
