#!/usr/bin/env python3
"""web_trainee_stiff: on the shipped default dome (the paper's Tables I-II read long-term, ~0.6 mm
under the paper's 3 N step) the trainee page's colour scale starts small and grows with the
session's deepest dent, so the dent shows: the page's scale stays at 0.5 mm or grows to 1 mm (the
smallest of the 0.5-1-2-5 ladder holding the deepest dent seen; the bridge's default bounds 0.5 ..
30 mm) and the pressed skin turns from purple to green. On the old fixed 30 mm scale the same dent moved the colour by 2%
of the map (G channel +5 at most): the check below fails there. DDS domain 197.
usage: test_trainee_stiff.py BUILD SOURCE OUT"""
import math
import os
import time

import harness
from harness import check

# s after the trainee starts: time enough for the page to follow the session (at most 13 s, below)
# and check the rest shape first; 8 s flaked once on a loaded machine (the page followed late
# and saw the press already under way).
T_ON = 16.0


def run(build, source, out):
    procs = harness.Procs(build, source, out, 197)
    browser = None
    try:
        procs.server(config="server.json")  # phantom 1: dome A, the long-term reading (the default)
        web = procs.web()
        browser = harness.cdp.Chromium(width=1000, height=700, out_dir=out)
        page = browser.new_page(web.base + "/trainee.html?trainee=bob")
        check(page.wait_for("window.palpState && palpState.connected", 20) is True, "page loaded and connected to palp-web")
        procs.trainee("bob", extra=["--profile", "step", "--magnitude", "3", "--t-on", str(T_ON), "--t-off", "30",
                                    "--distribution", "2", "--polar", "30", "--azimuth", "40", "--duration", "30"])
        ok = page.wait_for("palpState.trainee.session > 0 && palpState.trainee.rendered > 0 && "
                           "palpState.phantoms[palpState.trainee.phantom] !== undefined", 13)
        check(ok is True, "the page follows bob's session and has drawn its phantom")
        page.eval("palpShowFingers(false)")
        time.sleep(1.0)
        st = page.eval("[palpState.trainee.force, palpState.trainee.maxDispMm, palpState.trainee.scaleMm]")
        check(st[0] == 0 and st[1] < 0.05 and st[2] == 0.5,
              "at rest: force %.2f N, max displacement %.3f mm, scale %s mm (expected the smallest, 0.5)" % tuple(st))
        shot_before = page.screenshot(os.path.join(out, "stiff-before.png"))
        ok = page.wait_for("palpState.trainee.maxDispMm > 0.4 && palpState.trainee.force > 2.9", T_ON + 10)
        check(ok is True, "during the press the page shows the 3 N force and a dent > 0.4 mm: %s"
              % page.eval("JSON.stringify(palpState.trainee, (k, v) => k === \"arrivals\" ? undefined : v)"))
        time.sleep(1.5)  # the step's creep, and the renderer catching up
        st = page.eval("[palpState.trainee.maxDispMm, palpState.trainee.scaleMm]")
        check(0.4 < st[0] <= 1.0 and st[1] in (0.5, 1) and st[1] >= st[0],
              "the scale holds the dent: %.3f mm deep on a %s mm scale (expected 0.5 or 1, the ladder's "
              "smallest at or above the deepest dent seen)" % tuple(st))
        shot_during = page.screenshot(os.path.join(out, "stiff-during.png"))
        R = page.eval("palpState.phantoms[palpState.trainee.phantom].radius")
        th, ph = math.radians(30), math.radians(40)
        x, y, z = R * math.sin(th) * math.cos(ph), R * math.sin(th) * math.sin(ph), R * math.cos(th)
        cx, cy = page.eval("palpProject(%r, %r, %r)" % (x, y, z))
        dpr = page.eval("window.devicePixelRatio")
        a, b = harness.read_png(shot_before), harness.read_png(shot_during)
        mb, md = harness.disc_mean(a, cx * dpr, cy * dpr, 6 * dpr), harness.disc_mean(b, cx * dpr, cy * dpr, 6 * dpr)
        print("pressed skin RGB before %s, during %s" % (mb, md))
        check(md[1] > mb[1] + 40, "the pressed skin turned from purple to green (G %.0f -> %.0f, > +40)" % (mb[1], md[1]))
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
