#!/usr/bin/env python3
"""web_findings: an exercise session on the trainee page in headless Chromium. The page shows the
exercise's instructions, time left and marks; a mouse click on "lump here" while the trainee's
position-driven finger presses reaches the domain as a Finding at the fingertip's contact point
(read by a listening DDS reader, web_exercise_peer with phantom 0) and palp-server, hosting the
shipped exercises (config/server-exercises.json; "easy" is phantom 11), answers: the page then
shows 1 mark; key W withdraws it; the class dashboard shows where the lump is hidden (palp-server
runs with "session_exercise": "always"), not found yet, and hides it when told; a dashboard
page's and an observer page's attempts to send a finding are refused and nothing is written. When
pat's station leaves, her page shows the server's debrief (the lump missed, where it is), and so does
the class dashboard, under "Ended exercise sessions", both the one open meanwhile and one opened after;
the latter is also sent what her marks found, as the server's debrief said it, and the score the server
graded from its session log (as palp-review show prints it from that log). sam then examines on
"hard", whose debrief tells the count only: his ended row on the dashboard shows where the lump was,
missed, under the "show hidden lumps" box. A bare trainee page that moved on from lee's closed session to
max's shows no debrief of lee's, even one that comes late. fay's exercise, easy banded by force alone,
has her page's force gauge shade its bands, as the band badge names them.
DDS domain 75. usage: test_findings.py BUILD SOURCE OUT"""
import json
import math
import os
import re
import subprocess
import time

import harness
from harness import check

DOMAIN = 75


def findings(procs, peer):
    return [m.groupdict() for m in re.finditer(
        r"FINDING session=(?P<session>\d+) op=(?P<op>\w+) mark=(?P<mark>\d+) "
        r"point=(?P<x>\S+),(?P<y>\S+),(?P<z>\S+) time=(?P<time>\S+)", procs.log(peer))]


def wait_findings(procs, peer, n, timeout):
    end = time.time() + timeout
    while time.time() < end:
        f = findings(procs, peer)
        if len(f) >= n:
            return f
        time.sleep(0.05)
    return findings(procs, peer)


def click(page, element_id):
    """A real mouse click (DevTools Input events) at the element's centre."""
    x, y = page.eval("(function(){const e=document.getElementById(%r); e.scrollIntoView({block:'center'});"
                     "const r=e.getBoundingClientRect(); return [r.left+r.width/2, r.top+r.height/2];})()" % element_id)
    for kind in ("mousePressed", "mouseReleased"):
        page.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=1)


def key(page, k):
    for kind in ("keyDown", "keyUp"):
        page.call("Input.dispatchKeyEvent", type=kind, key=k, text=k if kind == "keyDown" else "",
                  code="Key" + k.upper(), windowsVirtualKeyCode=ord(k.upper()))


# Run before a page's scripts: every WebSocket it opens is kept, the debriefs they receive are kept, and
# deliver(m) hands a socket's handler a message as if the bridge sent it.
HOOK = """(function(){const W=window.WebSocket, socks=[], debriefs=[];
window.WebSocket=function(u,p){const w=p===undefined?new W(u):new W(u,p); socks.push(w);
w.addEventListener('message',function(ev){if(typeof ev.data!=='string')return;
try{const m=JSON.parse(ev.data); if(m.type==='debrief')debriefs.push(m);}catch(e){}}); return w;};
window.WebSocket.prototype=W.prototype;
window.palpTest={debriefs:debriefs, deliver:function(m){const w=socks[socks.length-1];
w.onmessage(new MessageEvent('message',{data:JSON.stringify(m)}));},
close:function(){socks[socks.length-1].close();}};})();"""


def hooked_page(browser, url):
    page = browser.new_page("about:blank")
    page.call("Page.enable")  # without it the script is not run on the next document
    page.call("Page.addScriptToEvaluateOnNewDocument", source=HOOK)
    page.call("Page.navigate", url=url)
    return page


FORCE_BANDS = {"light": [0.2, 2], "medium": [2, 8], "deep": [8, 15]}  # easy_force's bands [N]
# the gauge's zone colours, light / medium / deep (web/www/js/trainee.js drawGauge)
ZONE = {"light": [204, 232, 248], "medium": [248, 227, 180], "deep": [179, 226, 213]}


def config_with_force_bands(source, out):
    """harness.answers_config plus phantom 15, "easy_force": easy's exercise banded by fingertip force alone
    (FORCE_BANDS; docs/assessment.md allows force_N without depth_mm), which no shipped exercise is."""
    with open(os.path.join(source, "config", "exercises", "easy.json")) as f:
        ex = json.load(f)
    ex["name"], ex["title"] = "easy_force", "easy, banded by force"
    ex["phantom"] = os.path.join(source, "config", "phantoms", "dome.json")
    ex["pressure_bands"] = {k: {"force_N": v} for k, v in FORCE_BANDS.items()}
    path = os.path.join(out, "easy_force.json")
    with open(path, "w") as f:
        json.dump(ex, f)

    def edit(cfg):
        cfg.update(session_exercise="always")
        cfg["exercises"].append({"id": 15, "file": path, "physics_rate_hz": 250})
    return harness.server_config(source, out, "server-exercises.json", "server-exercises-answers.json", edit)


# The gauge's pixels where its marker (the force) stands: the zone's colour just above and below the marker,
# the band badge's band, the force and the legend.
GAUGE = """(function(){const c=document.getElementById('gauge'), W=c.width,
d=c.getContext('2d').getImageData(0, 0, W, c.height).data;
const px=function(x, y){const i=4*(y*W+x); return [d[i], d[i+1], d[i+2]];};
const rows=[]; for (let y=0; y<c.height; y++){const p=px(26, y); if (p[0]===29 && p[1]===35 && p[2]===48) rows.push(y);}
return {band: palpState.trainee.band, force: palpState.trainee.force, rows: rows.length,
 above: rows.length ? px(10, rows[0]-3) : null, below: rows.length ? px(10, rows[rows.length-1]+3) : null,
 legend: document.getElementById('band-legend').textContent};})()"""


def run(build, source, out):
    procs = harness.Procs(build, source, out, DOMAIN)
    browser = None
    try:
        # the shipped exercises; lumps and scores to instructors; its own session log, which it grades each
        # closed exercise session from (palp_session_score, session 63)
        db = os.path.join(out, "sessions.db")
        procs.server(config=config_with_force_bands(source, out), db=db)
        peer = procs.start("peer", [os.path.join(build, "tests", "web", "web_exercise_peer"), str(DOMAIN), "0", "110"])
        procs.wait_log(peer, r"READY", 10)
        web = procs.web()
        browser = harness.cdp.Chromium(width=1000, height=760, out_dir=out)
        page = hooked_page(browser, web.base + "/trainee.html?trainee=pat")
        check(page.wait_for("window.palpState && palpState.connected", 20) is True, "trainee page loaded and connected")
        pat = procs.trainee("pat", phantom=11, extra=["--input", "sim:press,hold_s=45", "--duration", "80"])

        ok = page.wait_for("palpState.trainee.exercise !== null && palpState.trainee.timeLeft !== null && "
                           "!document.getElementById('ex-controls').hidden", 20)
        check(ok is True, "the page shows the exercise and its controls")
        instr = page.eval("document.getElementById('ex-instructions').textContent")
        title = page.eval("document.getElementById('ex-title').textContent")
        left = page.eval("palpState.trainee.timeLeft")
        check("vertical strips" in instr and title == "One 2 cm lesion just under the surface",
              "title %r and instructions %r shown" % (title, instr))
        check(0 < left <= 300, "time left %.1f s within the 300 s limit" % left)
        check(page.eval("document.getElementById('ex-marks').textContent") == "0", "0 marks standing at first")

        ok = page.wait_for("(function(){const f=palpState.trainee.proxy;"
                           "return !!f && f.in_contact === true && palpState.trainee.maxDispMm > 3;})()", 25)
        check(ok is True, "pat presses (proxy in contact, dent > 3 mm): %s"
              % page.eval("JSON.stringify(palpState.trainee.proxy)"))
        # The band is the exercise's, by the fingertip's indentation as the assessment grades it
        # (light 1-4, medium 4-9, deep 9-18 mm), not the gauge's force bands; the legend says so.
        ok = page.wait_for("palpState.trainee.bandRule === 'exercise' && palpState.trainee.depthMm !== null", 10)
        st = page.eval("JSON.stringify([palpState.trainee.band, palpState.trainee.depthMm, palpState.trainee.force, "
                       "document.getElementById('band-legend').textContent, document.getElementById('depth').textContent])")
        band, depth_mm, force, legend, depth_text = __import__("json").loads(st)
        want = next((n for n, lo, hi in (("light", 1, 4), ("medium", 4, 9), ("deep", 9, 18)) if lo <= depth_mm < hi), "none")
        check(ok is True and band == want and "by how deep the fingertip presses: light 1-4 mm, medium 4-9 mm, deep 9-18 mm"
              in legend and re.match(r"pressed \d+\.\d mm deep", depth_text),
              "the page bands the press by the exercise: %s at %.2f mm (%.2f N), legend %r, %r"
              % (band, depth_mm if depth_mm is not None else float("nan"), force, legend, depth_text))
        # ... in the colours the review and reports give the bands (docs/naming.md, Okabe-Ito)
        colour = {"light": "rgb(86, 180, 233)", "medium": "rgb(230, 159, 0)", "deep": "rgb(0, 158, 115)"}
        shown = page.eval("[document.getElementById('band').textContent, "
                          "getComputedStyle(document.getElementById('band')).backgroundColor, "
                          "getComputedStyle(document.querySelector('.bar.deep > div')).backgroundColor]")
        check(shown[0] in colour and shown[1] == colour[shown[0]] and shown[2] == colour["deep"],
              "the band badge and the deep coverage bar in the reports' colours: %s" % shown)
        names = page.eval("[0, 1, 2].map(function(k){return document.getElementById('covname' + k).textContent;})")
        check(names == ["light", "medium", "deep"], "coverage named per band, as the review's thoroughness: %s" % names)
        proxy = page.eval("palpState.trainee.proxy.proxy")
        t_click = time.time()
        click(page, "lump")
        got = wait_findings(procs, peer, 1, 5)
        replies = page.eval("palpState.trainee.replies")
        if not got and replies and not replies[0]["ok"] and "no server takes findings" in replies[0]["reason"]:
            # The bridge's findings writer had not yet matched the server's reader (DDS discovery on a
            # loaded machine): the page said so; the trainee clicks again, as this test does.
            print("note: first click refused (%s); clicking again" % replies[0]["reason"])
            time.sleep(1.0)
            t_click = time.time()
            click(page, "lump")
            got = wait_findings(procs, peer, 1, 5)
        check(len(got) == 1 and got[0]["op"] == "mark" and got[0]["mark"] == "1",
              "the click reached the domain as a Finding, mark 1, in %.2f s: %s; the bridge's replies: %s"
              % (time.time() - t_click, got, page.eval("JSON.stringify(palpState.trainee.replies)")))
        f = got[0]
        pt = [float(f["x"]), float(f["y"]), float(f["z"])]
        R = page.eval("palpState.phantoms[palpState.trainee.phantom].radius")
        rp = math.sqrt(sum(x * x for x in pt))
        d = math.sqrt(sum((a - b) ** 2 for a, b in zip(pt, proxy)))
        print("finding at %s (|p| %.4f m, R %.4f m), %.4f m from the proxy seen before the click" % (pt, rp, R, d))
        # The contact point lies in the dent: inside the rest dome by at most the 10 mm press and a
        # margin, and about one fingertip radius (8 mm) from the proxy (the finger barely moves while held).
        check(R - 0.015 < rp < R + 0.001, "the point lies on the pressed skin: R - 15 mm < |p| < R + 1 mm")
        check(0.004 < d < 0.012, "about a fingertip radius (8 mm) from the proxy: %.1f mm" % (d * 1e3))
        # (the server's status goes server -> bridge -> page; 5 s ran out once in a full run beside a build,
        # session 82: the property is that it comes, its speed is the click's, asserted above)
        check(page.wait_for("palpState.trainee.marks === 1 && document.getElementById('ex-marks').textContent === '1'", 15)
              is True, "the page shows 1 mark (the server's finding status)")
        reply = page.eval("palpState.findingReplies[palpState.findingReplies.length-1]")
        check(reply["ok"] is True and reply["mark_id"] == 1, "the bridge answered ok, mark 1: %s" % reply)
        # her page dots the skin she has pressed so far (docs/web.md, "The pressed skin")
        check(page.wait_for("palpState.trainee.coverVertices > 0", 5) is True,
              "her page dots the skin she pressed: %s vertices" % page.eval("palpState.trainee.coverVertices"))
        page.eval("palpShowFingers(true)")
        print("screenshot:", page.screenshot(os.path.join(out, "trainee-marked.png")))

        time.sleep(0.6)  # the bridge's rate: one request per 0.5 s
        key(page, "w")
        got = wait_findings(procs, peer, 2, 5)
        check(len(got) == 2 and got[1]["op"] == "withdraw" and got[1]["mark"] == "1", "key W withdrew mark 1: %s" % got[1:])
        check(page.wait_for("palpState.trainee.marks === 0", 5) is True, "the page shows 0 marks again")
        # Her page's socket closed (session 90's review): the readouts are marked stale, and a mark then says
        # it was not sent (before: dropped without a word, "mark 1 sent" and the last force standing); live
        # again once the page reconnects (1 s).
        time.sleep(0.6)
        page.eval("window.palpTest.close()")
        check(page.wait_for("!palpState.connected && document.body.classList.contains('stale')", 5) is True,
              "her page's socket closed: the page says so and its readouts are marked stale")
        key(page, "l")
        msg = page.eval("document.getElementById('ex-msg').textContent")
        check(msg.startswith("mark not sent: disconnected from palp-web"), "key L while disconnected: %r" % msg)
        check(len(findings(procs, peer)) == 2, "  and no Finding reached the domain (2 as before)")
        check(page.wait_for("palpState.connected && !document.body.classList.contains('stale')", 15) is True,
              "her page reconnected and is live again")

        dash = browser.new_page(web.base + "/dashboard.html")
        ok = dash.wait_for("palpState.sessions.some(function(s){return s.trainee === 'pat' && s.exercise === 'easy' "
                           "&& s.findings === 0 && s.late_haptic !== null})", 15)
        check(ok is True, "the dashboard lists pat's exercise session, 0 findings, a late-haptic figure: %s"
              % dash.eval("JSON.stringify(palpState.sessions)"))
        check(dash.wait_for("document.body.textContent.indexOf(' (by depth)') >= 0 && "
                            "document.body.textContent.indexOf('coverage l / m / d') >= 0", 5) is True and
              dash.eval("palpState.sessions.find(function(s){return s.trainee==='pat'}).band_rule") == "exercise",
              "the dashboard's card says pat's band is the exercise's, by depth, and gives coverage per level")
        late = dash.eval("palpState.sessions.find(function(s){return s.trainee==='pat'})")
        print("dashboard: late haptic updates %s, lost %s, coverage %s" % (late["late_haptic"], late["lost_haptic"],
                                                                            late["coverage"]))
        check(late["coverage"][0] > 0, "coverage from the local model's contact > 0 (%.4f)" % late["coverage"][0])
        # the time left of easy's 300 s limit on pat's card, counting down (the server's finding status, 2 Hz)
        tl = ("(function(){const s=palpState.sessions.find(function(s){return s.trainee==='pat'});"
              "const r=Array.from(document.querySelectorAll('.card tr')).find(function(r){"
              "return r.cells[0].textContent==='time left';});"
              "return [s.time_left, s.duration, r ? r.cells[1].textContent : null];})()")
        t1 = dash.eval(tl)
        t_a = time.time()
        # counting down: the first figure at least 0.7 s lower, within 6 s (a loaded machine's statuses come
        # late: under a busy core one fell 0.4 s in 1.5 s), and never faster than the wall clock
        t2 = dash.wait_for("(function(){const r=%s; return r[0] !== null && r[0] <= %.3f ? r : null;})()"
                           % (tl, (t1[0] if t1[0] is not None else 0) - 0.7), 6)
        waited = time.time() - t_a
        # tolerances: the session's age comes with the server's session state (1 Hz), the time left is
        # the status's figure less its age, and the list is rebuilt as the statuses come (2 Hz): 1 s of
        # slack on the wall clock's fall
        check(t1[0] is not None and abs(t1[0] + t1[1] - 300) <= 2.0 and t2 is not None and
              0.7 - 1e-9 <= t1[0] - t2[0] <= waited + 1.0 and
              re.match(r"^4:[0-5]\d$", t2[2]) and int(t2[2][2:]) == int(t2[0] % 60),
              "pat's card gives the time left of easy's 300 s, counting down: %s then, %.1f s later, %s "
              "(time left + the session's age = 300 s within 2 s; fallen 0.7 s to the wall clock's fall + 1 s; "
              "m:ss of it)" % (t1, waited, t2))
        dash.eval("palpSend({finding: 'mark'})")
        r = dash.wait_for("palpState.findingReplies.length > 0 && palpState.findingReplies[0]", 5)
        check(r is not None and r["ok"] is False and "viewer" in r["reason"],
              "the dashboard's finding is refused: %s" % r)
        # where pat's lump is hidden, under her card's top view, for the instructor alone (docs/web.md,
        # "The hidden lumps"): her one mark was withdrawn, so none found yet; in the debrief's words
        lumps = ("Array.from(document.querySelectorAll('.card ul.lumps li')).map(function(l){"
                 "return [l.className, l.textContent];})")
        ok = dash.wait_for("document.querySelectorAll('.card ul.lumps li').length === 2", 10)
        got = dash.eval(lumps)
        check(ok is True and got[0][1] == "hidden lumps, the trainee does not see them: found 0 of 1 lump; "
              "0 marks standing, 0 near no lump" and got[0][0] == "warn" and
              re.match(r"lump 1 not found yet: at 11\.0 o'clock, 21 mm from the pole; 20 mm across, "
                       r"its centre 12 mm deep$", got[1][1]),
              "the dashboard shows where pat's lump is hidden, not found yet: %s" % got)
        # where she has pressed so far (docs/web.md, "The pressed skin"): a digit per vertex of her phantom
        cover = dash.wait_for("(function(){const s=palpState.sessions.find(function(s){return s.trainee==='pat'});"
                              "const b=s && palpState.dashboard.cover && palpState.dashboard.cover[s.id];"
                              "return b && /[1-7]/.test(b) ? [b, palpState.phantoms[s.phantom].rest.length / 3] : null;})()",
                              10)
        check(cover is not None and len(cover[0]) == cover[1] and 0 < sum(ch != "0" for ch in cover[0]) < cover[1] / 4,
              "the dashboard has pat's pressed-skin map, a digit per vertex, her one press's few vertices marked: %s"
              % (cover and "%d of %d" % (sum(ch != "0" for ch in cover[0]), cover[1])))
        print("screenshot:", dash.screenshot(os.path.join(out, "dashboard.png")))
        click(dash, "show-answers")
        got = dash.eval(lumps)
        check(got == [["muted", "hidden lumps: not shown (the box above)"]],
              "unticking 'show hidden lumps' takes them off the page: %s" % got)
        click(dash, "show-answers")

        obs = browser.new_page(web.base + "/trainee.html?trainee=pat&role=observer")
        check(obs.wait_for("palpState.trainee.exercise !== null", 15) is True, "an observer page shows the exercise")
        hid = obs.eval("[document.getElementById('ex-controls').hidden, palpState.trainee.role, location.search]")
        check(hid[0] is True, "... without the controls: %s" % hid)
        time.sleep(0.6)
        obs.eval("palpSend({finding: 'mark'})")
        r = obs.wait_for("palpState.findingReplies.length > 0 && palpState.findingReplies[0]", 5)
        check(r is not None and r["ok"] is False, "the observer's finding is refused: %s" % r)
        time.sleep(1.0)
        check(len(findings(procs, peer)) == 2, "nothing more was written to the domain (2 findings in all)")

        # pat's station leaves: the server debriefs her session ("easy" tells its lesion), and her page
        # shows it, the missed lump drawn on the phantom; the observer (an instructor's page following
        # the session) is sent it too (docs/assessment.md, "Debrief").
        procs.stop(pat)
        ok = page.wait_for("palpState.trainee.debrief !== null && !document.getElementById('debrief').hidden", 10)
        shown = page.eval("[document.getElementById('debrief-text').textContent, "
                          "Array.from(document.querySelectorAll('#debrief-lumps li')).map(function(l){"
                          "return [l.className, l.textContent];})]")
        check(ok is True and shown[0].startswith("You found 0 of 1 lump with 0 marks standing") and len(shown[1]) == 1 and
              shown[1][0][0] == "missed" and re.match(r"lump 1 MISSED: at 11\.0 o'clock, 21 mm from the pole; 20 mm "
                                                      r"across, its centre 12 mm deep$", shown[1][0][1]),
              "pat's page shows her debrief: %s" % shown)
        check(page.eval("palpState.trainee.coverVertices") > 0,
              "the pressed skin stays beside the debrief's rings (%s vertices)" % page.eval("palpState.trainee.coverVertices"))
        # (her station runs --quiet here; web_coverage compares the page's debrief with the station's lines)
        check(obs.wait_for("palpState.trainee.debrief !== null", 5) is True, "the observer's page is sent it too")
        # A random exercise's session may hide no lump (docs/assessment.md, "Lesions drawn for each session"):
        # the page's words for such a debrief, as the station prints them (tests/server/exercise_random.sh)
        none = page.eval("palpDebriefText({level: 'lesions', lesions: 0, found: 0, marks: 1, false_marks: 1, "
                         "duplicates: 0, lumps: []})")
        check(none == ["You had no lump to find this time with 1 mark standing; 1 mark was near no lump."],
              "a debrief that hid no lump, in the page's words: %s" % none)

        # The class dashboard, open since pat's session ran, lists it under "Ended exercise sessions" with what
        # her page was told: the counts of the server's debrief her page got, each lump in her page's words
        # (a missed one in red), and the exercise the dashboard's session list named while the session was open.
        told = page.eval("palpState.trainee.debrief")
        check(told["session"] == late["id"] and told["trainee"] == "pat",
              "her page's debrief is of the session the dashboard listed (%s, session %s)" % (told["trainee"], told["session"]))
        row = ("(function(){const rs=document.querySelectorAll('#debriefs tr[data-session=\"%d\"]');"
               "if(!rs.length) return null; const r=rs[0]; return {rows: rs.length,"
               "cells: Array.from(r.cells).slice(0, 9).map(function(c){return c.textContent;}),"
               "lumps: Array.from(r.querySelectorAll('li')).map(function(l){"
               "return [l.textContent, getComputedStyle(l).color];})};})()" % told["session"])
        cov = told.get("coverage") or [0, 0, 0]
        want = [str(told["session"]), "pat", "easy", "found %d of %d lump%s" % (told["found"], told["lesions"],
                "" if told["lesions"] == 1 else "s"), str(told["marks"]), str(told["false_marks"]),
                str(told["duplicates"]), "%s after %d:%02d" % (told["reason"], told["duration"] // 60, told["duration"] % 60)]
        # how long it ran, the server's figure: the test's steps since her station started (a few seconds)
        check(0 < told["duration"] < 60, "her session's debrief says how long it ran: %.1f s" % told["duration"])
        # the bridge's coverage at the end (her one press, a few percent light and medium), in her debrief
        # in the station's words and on the dashboard's row as its card gave it
        said = re.search(r"You covered light ([0-9.]+)%, medium ([0-9.]+)%, deep ([0-9.]+)% of the dome", shown[0])
        check(told.get("band_rule") == "exercise" and 0 < cov[0] < 0.1 and said is not None and
              all(abs(float(x) - 100 * c) <= 0.05 + 1e-9 for x, c in zip(said.groups(), cov)),
              "her debrief gives what she covered (within its 0.1 point rounding): %s in %r" % (cov, shown[0]))
        # ... counted from the server's finger samples, as the review counts it, and her page says so (session 71)
        check(told.get("coverage_rule") == "touched" and
              "of the dome (counted as the review counts it, from the triangles you touched)." in shown[0],
              "her page says her coverage was counted as the review counts it (coverage_rule %r)" % told.get("coverage_rule"))
        page_lumps = [t for _, t in shown[1]]
        red = "rgb(176, 0, 32)"  # the dashboard's warning colour (the cards' "warn", the server's "bad")

        def shows_it(r, exercise):
            # %, 1 decimal (docs/naming.md; 0 decimals before session 82)
            covered = re.match(r"^(\d+\.\d) / (\d+\.\d) / (\d+\.\d) %$", r["cells"][8]) if r is not None else None
            return (r is not None and r["rows"] == 1 and r["cells"][:8] == want[:2] + [exercise] + want[3:] and
                    covered is not None and all(abs(float(x) - 100 * c) <= 0.05 + 1e-9 for x, c in zip(covered.groups(), cov)) and
                    [t for t, _ in r["lumps"]] == page_lumps and
                    all((c == red) == (l["found_by"] == 0) for (_, c), l in zip(r["lumps"], told["lumps"])))

        check(dash.wait_for("document.querySelector('#debriefs tr') !== null", 5) is True and
              shows_it(dash.eval(row), "easy") and told["reason"] != "" and
              dash.eval("document.getElementById('no-debriefs').hidden") is True,
              "the dashboard shows pat's ended session as her page's debrief told it: %s (her page: %s, %s)"
              % (dash.eval(row), want, page_lumps))
        # A dashboard opened only now is sent the debriefs the bridge still holds (docs/web.md): the same row,
        # the exercise named by the debrief message itself (the session closed before this page connected).
        dash2 = browser.new_page(web.base + "/dashboard.html")
        check(dash2.wait_for("document.querySelector('#debriefs tr') !== null", 15) is True and
              shows_it(dash2.eval(row), "easy") and dash2.eval("document.querySelectorAll('#debriefs tr').length") == 1,
              "a dashboard opened after the session ended shows it too, once: %s" % dash2.eval(row))
        # The bridge keeps what the ended session's marks found (docs/web.md, "The hidden lumps"), matched by
        # its own reading of the exercise and the marks: it says what the server's debrief said.
        kept = dash2.wait_for("palpState.dashboard.endedAnswers && palpState.dashboard.endedAnswers[%d]"
                              % told["session"], 10)
        check(kept is not None and kept["ended"] is True and
              [kept["found"], kept["lesions"], kept["marks"], kept["false_marks"]] ==
              [told["found"], told["lesions"], told["marks"], told["false_marks"]] and
              [[l["found_by"], l["clock_h"], l["arc_mm"], l["across_mm"], l["deep_mm"]] for l in kept["lumps"]] ==
              [[l["found_by"], l["clock_h"], l["arc_mm"], l["across_mm"], l["deep_mm"]] for l in told["lumps"]],
              "a dashboard opened after the session ended is sent what its marks found, as the server's debrief "
              "said it: %s" % kept)

        # The server grades pat's closed session from its own log and sends the score to the instructors
        # (palp_session_score): both dashboards show it on her row, with the command that prints it in full,
        # and it is what palp-review show prints from the same log (to its 0.1 rounding).
        score_cell = ("(function(){const r=document.querySelector('#debriefs tr[data-session=\"%d\"]');"
                      "const c=r && r.querySelector('td.score'); return c ? [c.textContent, c.className, c.title] : null;})()"
                      % told["session"])
        sc = dash2.wait_for("palpState.dashboard.scores && palpState.dashboard.scores[%d]" % told["session"], 20)
        cells = [d.wait_for("(function(){const c=%s; return c && c[0] !== 'n/a' ? c : null;})()" % score_cell, 5)
                 for d in (dash, dash2)]
        shown_ok = sc is not None and sc["graded"] is True and sc["exercise"] == "easy" and all(
            c is not None and c[0] == "%.1f %spalp-review show %s" % (sc["score"], "pass" if sc["pass"] else "fail",
                                                                       sc["log_uid"]) and
            ("pass" if sc["pass"] else "bad") in c[1].split() and "sensitivity" in c[2] for c in cells)
        check(shown_ok and sc["found"] == told["found"] and sc["lesions"] == told["lesions"] and
              sc["false_marks"] == told["false_marks"] and sc["log_complete"] is True and
              sc["log_health"].startswith("complete: ") and all("damaged" not in c[0] for c in cells),
              "pat's score on both dashboards, its found / lesions / false marks the debrief's: %s; cells %s"
              % (sc, cells))
        # "easy" tells its lesions (a practice exercise): pat's own page is sent her score too, after her
        # debrief, with what to work on in her words (the metrics she did not pass)
        words = [("sensitivity", "finding the lumps"), ("false_positives", "marking only lumps"),
                 ("thoroughness", "covering the whole dome at each pressure"),
                 ("pattern", "a systematic search pattern"), ("time", "finishing within the time"),
                 ("force", "pressing within the force limit")]
        mine = page.wait_for("palpState.trainee.score", 10)
        text = page.eval("document.getElementById('debrief-score').hidden ? null : "
                         "document.getElementById('debrief-score').textContent")
        work = [w for k, w in words if sc and not sc["passed"][k]]
        want_text = ("Your score: %.1f of 100, %s (the automatic score, as the review gives it; your instructor "
                     "grades you).%s" % (sc["score"], "passed" if sc["pass"] else "not passed",
                                         " To work on: %s." % ", ".join(work) if work else "")) if sc else None
        check(mine is not None and mine["session"] == told["session"] and mine["score"] == sc["score"] and
              text == want_text,
              "pat's page (easy tells its lesions) shows her score after her debrief: %r (want %r)" % (text, want_text))
        review = subprocess.run([os.path.join(build, "client", "review", "palp-review"), "--db", db, "show",
                                         sc["log_uid"] if sc else "none"], capture_output=True, text=True, timeout=60)
        said = re.search(r"score\s+([0-9.]+) / 100 \(pass at \d+\): (PASS|FAIL)", review.stdout)
        check(sc is not None and said is not None and abs(float(said.group(1)) - sc["score"]) < 0.05 + 1e-9 and
              (said.group(2) == "PASS") == sc["pass"],
              "the score the dashboard shows is palp-review show's from the server's log: %s vs %s (rc %d %s)"
              % (said and said.groups(), sc and [sc["score"], sc["pass"]], review.returncode, review.stderr[-300:]))
        # Each page is closed once the test is done with it: an open page keeps its animation frames running and a
        # dashboard draws every later session's card (software WebGL), which the test asserts nothing of (the pages
        # had all stayed open to the end: Chromium ~29 s of CPU of the test's ~43, 2026-12-07).
        for p in (page, obs, dash):
            p.close()

        # sam examines on "hard" (phantom 13), whose debrief tells the count only: the trainee is not
        # told where the lump was, the instructor's dashboard is, under the "show hidden lumps" box,
        # in the debrief's words: polar 35 deg azimuth 200 deg on the 40 mm dome is at 8.3 o'clock
        # (clockwise from +y: atan2(cos 200, sin 200) = -110 deg), 40 mm x 35 pi/180 = 24.4 mm from
        # the pole; 10 mm across, 10 mm deep (config/exercises/hard.json).
        sam = procs.trainee("sam", phantom=13, extra=["--input", "sim:press,hold_s=1", "--duration", "6"])
        sam_row = ("(function(){const r=Array.from(document.querySelectorAll('#debriefs tr')).find(function(r){"
                   "return r.cells[1].textContent === 'sam';}); if(!r) return null; return {session: Number(r.dataset.session), "
                   "found: r.cells[3].textContent, ended: r.cells[7].textContent,"
                   "lumps: r.cells[10].textContent, items: Array.from(r.cells[10].querySelectorAll('li')).map(function(l){"
                   "return [l.className, l.textContent];})};})()")
        got = dash2.wait_for("(function(){const r=%s; return r && r.items.length === 2 ? r : null;})()" % sam_row, 30)
        check(got is not None and got["found"] == "found 0 of 1 lump" and re.match(r"^trainee station left after 0:[01]\d$", got["ended"]) and
              got["items"][0] == ["warn", "hidden lumps, the trainee was not told: found 0 of 1 lump; 0 marks standing, "
                                          "0 near no lump"] and
              got["items"][1] == ["bad", "lump 1 MISSED: at 8.3 o'clock, 24 mm from the pole; 10 mm "
                                         "across, its centre 10 mm deep"],
              "sam's ended examination on the dashboard (his station runs 6 s, joining included: ended after at most 0:19): told the count, "
              "the instructor shown where the lump was: %s (sam's station %s)" % (got or dash2.eval(sam_row), sam.poll()))
        # a lump within 1 mm of the pole has no clock worth reading (src/palp_place.h): the pages say
        # "at the pole", as the station and the review do, from the bridge's at_pole (a hand-made lump:
        # the shipped exercises place none there)
        words = dash2.eval("[PALP.debriefLump({found_by: 0, clock_h: 12, at_pole: true, arc_mm: 0.4, across_mm: 15, "
                           "deep_mm: 10}, 0, false), PALP.debriefLump({found_by: 2, clock_h: 1.67, at_pole: false, "
                           "arc_mm: 20.9, across_mm: 15, deep_mm: 10}, 1, false)]")
        check(words == ["lump 1 MISSED: at the pole; 15 mm across, its centre 10 mm deep",
                        "lump 2 found by mark 2: at 1.7 o'clock, 21 mm from the pole; 15 mm across, "
                        "its centre 10 mm deep"],
              "the pages' words for a lump at the pole and one away from it: %s" % words)
        click(dash2, "show-answers")
        got = dash2.eval(sam_row)
        check(got is not None and got["items"] == [] and got["lumps"] == "not told where: the exercise tells the count "
              "only; hidden lumps: not shown (the box above)",
              "unticking 'show hidden lumps' takes them off the ended row too: %s" % got)
        click(dash2, "show-answers")
        print("screenshot:", dash2.screenshot(os.path.join(out, "dashboard-ended.png")))

        # palp-web restarted (session 65): its new dashboard lists the ended sessions from the scores the
        # server keeps for late readers, though their debriefs are gone with their sessions' writers: pat's
        # and sam's rows, sam's (the later session) on top, each with its score as the first bridge showed
        # it, its trainee's name (the score carries none: the server's palp_session_closed does, since
        # session 69; before, "n/a") and where the rest is.
        sam_sc = dash2.wait_for("palpState.dashboard.scores && palpState.dashboard.scores[%d]" % got["session"], 20)
        check(sam_sc is not None and sam_sc["exercise"] == "hard", "sam's session scored: %s" % sam_sc)
        dash2.close()
        procs.stop(web)
        web2 = procs.web(name="web-restarted")
        dash3 = browser.new_page(web2.base + "/dashboard.html")
        rows = ("Array.from(document.querySelectorAll('#debriefs tr')).map(function(r){return {session: "
                "Number(r.dataset.session), fromScore: r.dataset.fromScore === '1', cells: Array.from(r.cells).map("
                "function(c){return c.textContent;})};})")
        listed = dash3.wait_for("(function(){const r=%s; return r.filter(function(x){return x.cells[1] !== 'n/a';})"
                                ".length >= 2 ? r : null;})()" % rows, 20)
        by = {r["session"]: r for r in (listed or [])}
        def shows(sc, r, name):
            want_score = ("%.1f %s" % (sc["score"], "pass" if sc["pass"] else "fail") if sc["graded"] else "not scored") + \
                "palp-review show " + sc["log_uid"]
            found = "found %d of %d lump%s" % (sc["found"], sc["lesions"], "" if sc["lesions"] == 1 else "s") \
                if sc["graded"] else "n/a"
            return r is not None and r["fromScore"] and r["cells"][1] == name and r["cells"][2] == sc["exercise"] and \
                r["cells"][3] == found and r["cells"][9] == want_score and r["cells"][10] == \
                "not seen by this bridge: palp-review show %s gives it from the server's log" % sc["log_uid"]
        order = [r["session"] for r in (listed or []) if r["session"] in (told["session"], got["session"])]
        check(sc is not None and shows(sc, by.get(told["session"]), "pat") and shows(sam_sc, by.get(got["session"]), "sam") and
              order == [got["session"], told["session"]],
              "a restarted palp-web's dashboard lists pat's and sam's ended sessions from the server's scores, "
              "named (palp_session_closed), newest on top: %s" % listed)
        dash3.close()
        # A practice session the server cannot score (session 66): kim presses "easy" by force, so her log
        # holds no finger samples; her page says why no score comes, in her station's words
        # (palp_cli_score_text's "no score: REASON"; this test's stations run --quiet).
        kim_page = browser.new_page(web2.base + "/trainee.html?trainee=kim")
        check(kim_page.wait_for("window.palpState && palpState.connected", 20) is True, "kim's page connected")
        kim = procs.trainee("kim", phantom=11, extra=["--duration", "4"])
        reason = "no finger samples logged (a session of force contacts only, or logged before schema 3)"
        kim_text = kim_page.wait_for("(function(){const e=document.getElementById('debrief-score');"
                                     "return e && !e.hidden && e.textContent ? e.textContent : null;})()", 30)
        check(kim_text == "No score: %s." % reason,
              "kim's page (easy, pressed by force) says why no score comes: %r (her station: %s)"
              % (kim_text, kim.poll()))
        kim_page.close()
        # (no screenshot here: with the dashboard and observer pages opened since, this page is a background
        # tab, which Chromium may not paint: a capture timed out once in a full run)

        # A bare page (no ?session= or ?trainee=) follows the newest session, lee's; max's opens beside it.
        # lee's station leaves: the page moves on to max's session, and lee's debrief, which the bridge sends
        # the page as the session it followed last, may come after that (docs/web.md, "The debrief": it did in
        # 3 of 11 runs). The test hands the page lee's debrief again once it follows max's, as the bridge sends
        # it when late: the page must not show it over max's session (its rings would show max where his lump
        # is). When max's station leaves too, the page follows none and shows his debrief.
        bare = hooked_page(browser, web2.base + "/trainee.html")
        check(bare.wait_for("window.palpState && palpState.connected", 20) is True, "a bare trainee page connected")
        lee = procs.trainee("lee", phantom=11, extra=["--duration", "60"])
        lee_id = bare.wait_for("(function(){const s=palpState.sessions.find(function(s){return s.trainee==='lee'});"
                               "return s && palpState.trainee.session === s.id ? s.id : 0;})()", 20)
        mx = procs.trainee("max", phantom=11, extra=["--duration", "60"])
        max_id = bare.wait_for("(function(){const s=palpState.sessions.find(function(s){return s.trainee==='max'});"
                               "return s ? s.id : 0;})()", 20)
        check(lee_id and max_id and max_id > lee_id and bare.eval("palpState.trainee.session") == lee_id,
              "the bare page follows lee's session %s, the newest when it came, with max's %s open beside it"
              % (lee_id, max_id))
        procs.stop(lee)
        late = bare.wait_for("(function(){const d=window.palpTest.debriefs.find(function(d){return d.session===%d;});"
                             "return d && palpState.trainee.session === %d ? d : null;})()" % (lee_id, max_id), 20)
        check(late is not None, "lee's debrief reached the bare page and the page follows max's session "
              "(debriefs received of sessions %s; following %s)"
              % tuple(bare.eval("[palpTest.debriefs.map(function(d){return d.session;}), palpState.trainee.session]")))
        mine = "JSON.stringify([palpState.trainee.session, palpState.trainee.debrief && palpState.trainee.debrief.session, " \
               "document.getElementById('debrief').hidden])"
        before = bare.eval(mine)
        bare.eval("window.palpTest.deliver(%s)" % json.dumps(late))
        after = bare.eval(mine)
        check(json.loads(before) == [max_id, None, True] and json.loads(after) == [max_id, None, True],
              "the page following max's session shows no debrief of lee's, as it came nor handed again: "
              "[followed, debrief's session, debrief hidden] %s then %s" % (before, after))
        procs.stop(mx)
        check(bare.wait_for("palpState.trainee.session === 0 && palpState.trainee.debrief && "
                            "palpState.trainee.debrief.session === %d && !document.getElementById('debrief').hidden"
                            % max_id, 20) is True,
              "with no session left the page shows the debrief of max's, the session it followed last")
        bare.close()

        # An exercise banded by fingertip force alone (easy_force, FORCE_BANDS): fay presses and holds (~3.7 N,
        # the exercise's medium, the bridge's own --bands' deep, > 3 N); the force gauge shades the exercise's
        # bands, as the band badge and the legend name them: the zone at its marker is the badge's band. (Until
        # 2026-12-06 it drew the bridge's 1 N / 3 N: the marker stood in its deep zone under a "medium" badge.)
        fay_page = browser.new_page(web2.base + "/trainee.html?trainee=fay")
        check(fay_page.wait_for("window.palpState && palpState.connected", 20) is True, "fay's page connected")
        # 45 s and a 40 s hold: a wait, not a property (25 s once ran out with her press not yet in, the suite
        # beside five builds, 2026-12-07); the condition ends it at once when met
        procs.trainee("fay", phantom=15, extra=["--input", "sim:press,hold_s=40", "--duration", "50"])
        g = fay_page.wait_for("(function(){const t=palpState.trainee; if (!(t.bandRule === 'exercise' && t.proxy && "
                              "t.proxy.in_contact && t.band === 'medium' && t.force > 3)) return null; return %s;})()"
                              % GAUGE, 45)
        check(g is not None and g["rows"] >= 2 and g["above"] == ZONE["medium"] and g["below"] == ZONE["medium"] and
              "light 0.2-2 N, medium 2-8 N, deep 8-15 N" in g["legend"],
              "fay's gauge (easy_force, by force) shades the exercise's medium band at its marker, as the badge "
              "says: %s" % (g or fay_page.eval(GAUGE)))
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
