#!/usr/bin/env python3
"""web_trainee_press: the trainee page in headless Chromium (WebGL on SwiftShader) loads, connects
to palp-web, draws the phantom, and its canvas changes where the phantom is pressed: screenshots
before and during a 3 N press (the paper's step, distribution II at polar 30 deg, azimuth 40 deg)
are compared around the projected press centre and far from it. DDS domain 191.
usage: test_trainee.py BUILD SOURCE OUT"""
import math
import os
import time

import harness
from harness import check

T_ON = 9.0  # s after the trainee starts: time enough for the page to load and draw the rest shape


def press_once(procs, page, out):
    """Starts alice pressing T_ON s later; screenshots at rest and during the press."""
    t_start = time.time()
    # The press lasts 120 s, as long as the test may (CTest's TIMEOUT): with 30 s, two of six runs beside two busy
    # loops failed (session 85): one ~40 s long read the band after the press had ended ("none"), one page drew
    # 0.1 frames a second and showed 3.9 mm when the wait below ran out.
    procs.trainee("alice", extra=["--profile", "step", "--magnitude", "3", "--t-on", str(T_ON), "--t-off", "120",
                                  "--distribution", "2", "--polar", "30", "--azimuth", "40", "--duration", "120"])
    ok = page.wait_for("palpState.trainee.session > 0 && palpState.trainee.rendered > 0 && "
                       "palpState.phantoms[palpState.trainee.phantom] !== undefined", 15)
    check(ok is True, "the page follows alice's session and has drawn its phantom")
    page.eval("palpShowFingers(false)")  # the phantom's own change only (fingers: a separate shot)
    time.sleep(1.0)  # a few frames of the resting phantom
    before = page.eval("JSON.stringify(palpState.trainee, (k, v) => k === \"arrivals\" ? undefined : v)")
    shot_before = page.screenshot(os.path.join(out, "trainee-before.png"))
    t_before = time.time() - t_start
    st = page.eval("[palpState.trainee.force, palpState.trainee.maxDispMm]")
    check(t_before < T_ON - 0.5 and st[0] == 0 and st[1] < 0.5,
          "'before' taken at rest: %.1f s after start (press at %.1f s), force %.2f N, max displacement %.2f mm"
          % (t_before, T_ON, st[0], st[1]))
    # up to 40 s after the station started (the press on from 9 s; until session 85 ~20 s): the property is what
    # the page shows, not when, and the press goes on past the wait
    ok = page.wait_for("palpState.trainee.maxDispMm > 15 && palpState.trainee.force > 2.9",
                       max(1.0, t_start + 40 - time.time()))
    check(ok is True, "during the press the page shows > 15 mm and the 3 N force: %s"
          % page.eval("JSON.stringify(palpState.trainee, (k, v) => k === \"arrivals\" ? undefined : v)"))
    time.sleep(1.0)  # let the renderer catch up with the newest frame
    # alice's one force contact is drawn, for every live message, by the same 2 objects: its marker and
    # its arrow (made anew each time, never disposed, they piled up over a class)
    made = page.eval("palpState.trainee.fingerObjects")
    check(made == 2, "2 objects made for alice's force contact in all, its marker and its arrow (%s)" % made)
    shot_during = page.screenshot(os.path.join(out, "trainee-during.png"))
    page.eval("palpShowFingers(true)")
    time.sleep(0.5)
    page.screenshot(os.path.join(out, "trainee-during-with-finger.png"))
    during = page.eval("JSON.stringify(palpState.trainee, (k, v) => k === \"arrivals\" ? undefined : v)")
    print("before:", before)
    print("during:", during)
    return shot_before, shot_during


def run(build, source, out):
    procs = harness.Procs(build, source, out, 191)
    browser = None
    try:
        procs.server()
        web = procs.web()
        browser = harness.cdp.Chromium(width=1000, height=700, out_dir=out)
        page = browser.new_page(web.base + "/trainee.html?trainee=alice")
        check(page.wait_for("window.palpState && palpState.connected", 20) is True, "page loaded and connected to palp-web")
        for attempt in (1, 2):
            try:
                shot_before, shot_during = press_once(procs, page, out)
                break
            except harness.Fail:
                # The one failure that is not the page's: on a starved machine the server may lose
                # the trainee station (its 0.5 s liveliness lease, docs/server.md). Then once more.
                if attempt == 2 or "lease expired" not in procs.log(procs.procs[0]):
                    raise
                print("note: the server lost the trainee station (liveliness lease, machine overloaded); "
                      "pressing once more with a new station")
                for p in procs.procs:
                    if p.name.startswith("trainee-"):
                        procs.stop(p)
        # Where the press is on screen: the dome point at polar 30, azimuth 40 (the client's own
        # geometry: R (sin t cos p, sin t sin p, cos t)), projected by the page's camera.
        R = page.eval("palpState.phantoms[palpState.trainee.phantom].radius")
        th, ph = math.radians(30), math.radians(40)
        x, y, z = R * math.sin(th) * math.cos(ph), R * math.sin(th) * math.sin(ph), R * math.cos(th)
        cx, cy = page.eval("palpProject(%r, %r, %r)" % (x, y, z))
        dpr = page.eval("window.devicePixelRatio")
        a, b = harness.read_png(shot_before), harness.read_png(shot_during)
        check(a[0] == b[0] and a[1] == b[1], "screenshots %dx%d" % (a[0], a[1]))
        r = 20 * dpr
        press = harness.disc_diff(a, b, cx * dpr, cy * dpr, r)
        # Far from the press: low on the side facing the camera (polar 70, azimuth -100), ~100 deg away.
        th2, ph2 = math.radians(70), math.radians(-100)
        fx, fy = page.eval("palpProject(%r, %r, %r)" % (R * math.sin(th2) * math.cos(ph2),
                                                         R * math.sin(th2) * math.sin(ph2), R * math.cos(th2)))
        far = harness.disc_diff(a, b, fx * dpr, fy * dpr, r)
        corner = harness.disc_diff(a, b, 15 * dpr, 60 * dpr, 10 * dpr)  # background at the top left of the view
        print("mean |RGB difference| around the press %.1f, far side %.1f, background %.1f" % (press, far, corner))
        check(press > 25, "the canvas changes where the phantom is pressed (%.1f > 25 of 255)" % press)
        check(press > 2 * far, "more there than far from it (%.1f > 2 x %.1f)" % (press, far))
        check(corner < 2, "the background does not change (%.1f < 2)" % corner)
        # Viridis: rest is dark purple; a 15+ mm press on the 30 mm scale is teal to yellow (green up).
        mb, md = harness.disc_mean(a, cx * dpr, cy * dpr, 6 * dpr), harness.disc_mean(b, cx * dpr, cy * dpr, 6 * dpr)
        check(md[1] > mb[1] + 40, "the pressed skin turned from purple to green-yellow (G %.0f -> %.0f)" % (mb[1], md[1]))
        check(page.eval("palpState.trainee.coverage[0] > 0"), "coverage counts the pressed area: %s"
              % page.eval("JSON.stringify(palpState.trainee.coverage)"))
        band = page.eval("document.getElementById('band').textContent")
        check(band == "medium", "3.00 N shows in the medium band (1-3 N): %s" % band)
        print("screenshots: %s, %s" % (shot_before, shot_during))
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
