#!/usr/bin/env python3
"""web_trainee_nogl: the trainee page in a browser with no WebGL (Chromium's --disable-webgl, as a
classroom PC with a blocklisted GPU, a VM or remote desktop) loses its 3D view only (session 82's review:
three.js's throw stopped the whole script, and the page said "connecting" for ever). It says "3D view
unavailable: <reason>" where the view would be, connects, follows alice's session and shows her 3 N press
in the force panel (figure, band, gauge), the session table and coverage. Opened with ?token=, it takes
the token out of its address (the address bar and history of a projected page) and keeps its stream,
also across a reload. DDS domain 199.
usage: test_trainee_nogl.py BUILD SOURCE OUT"""
import os

import harness
from harness import check

TOKEN = "nogl-token-for-the-web-test_0123456789"


def run(build, source, out):
    procs = harness.Procs(build, source, out, 199)
    browser = None
    try:
        procs.server()
        web = procs.web(["--token", TOKEN])
        browser = harness.cdp.Chromium(width=1000, height=700, out_dir=out, extra_args=["--disable-webgl"])
        page = browser.new_page(web.base + "/trainee.html?trainee=alice&token=" + TOKEN)
        ok = page.wait_for("window.palpState && palpState.connected && palpState.hello !== null", 20)
        view = page.eval("palpState.trainee ? palpState.trainee.view : null")
        waiting = page.eval("document.getElementById('waiting').textContent")
        check(ok is True, "no WebGL: the page connected to palp-web all the same (%s)"
              % page.eval("document.getElementById('conn').textContent"))
        check(isinstance(view, str) and view.startswith("3D view unavailable: ") and len(view) > 21 and
              waiting.startswith(view) and page.eval("document.querySelectorAll('#view canvas').length") == 0,
              "and says why it shows no 3D view, where the view would be: %r" % waiting)
        href = page.eval("location.href")
        check("token" not in href and TOKEN not in href and "trainee=alice" in href,
              "the token taken out of the page's address, the rest kept: %s" % href)
        check(TOKEN not in page.eval("JSON.stringify(history.state) + document.referrer"),
              "and not in the history entry's state")
        procs.trainee("alice", extra=["--profile", "step", "--magnitude", "3", "--t-on", "2", "--t-off", "40",
                                      "--distribution", "2", "--polar", "30", "--azimuth", "40", "--duration", "40"])
        ok = page.wait_for("palpState.trainee.session > 0 && palpState.trainee.force > 2.9 && palpState.trainee.maxDispMm > 5", 30)
        shown = page.eval("JSON.stringify({force: document.getElementById('force').textContent, "
                          "band: document.getElementById('band').textContent, "
                          "info: document.getElementById('info').textContent, "
                          "cov: document.getElementById('cov0').textContent, "
                          "rows: document.getElementById('session').rows.length, "
                          "maxdisp: document.getElementById('maxdisp').textContent})")
        page.screenshot(os.path.join(out, "trainee-nogl.png"))
        print("shown:", shown)
        check(ok is True, "alice's 3 N press reaches the page without WebGL (force %s N)"
              % page.eval("palpState.trainee.force"))
        import json
        s = json.loads(shown)
        check(s["force"] in ("2.99", "3.00", "3.01") and s["band"] == "medium",
              "the force panel shows it: %s N, band %s (3 N: medium, 1-3 N)" % (s["force"], s["band"]))
        check("alice" in s["info"] and s["rows"] >= 5, "the header names her session, the session table is filled (%d rows)"
              % s["rows"])
        check(float(s["cov"]) > 0 and float(s["maxdisp"]) > 5,
              "coverage (%s%%) and the largest displacement (%s mm) still counted" % (s["cov"], s["maxdisp"]))
        # the gauge is drawn: its marker row at the force's height is dark, not the zone's colour
        dark = page.eval("(function(){const c=document.getElementById('gauge'),g=c.getContext('2d');"
                         "let n=0;const d=g.getImageData(0,0,30,c.height).data;"
                         "for(let i=0;i<d.length;i+=4) if(d[i+3]>0&&d[i]<60&&d[i+1]<60&&d[i+2]<80) n++;return n;})()")
        check(dark >= 30, "the force gauge is drawn with its marker (%d dark pixels, >= 30)" % dark)
        # a reload in the same tab finds the token in sessionStorage: connected again, still no token shown
        r0 = page.eval("palpState.messages")
        page.eval("location.reload()")
        ok = page.wait_for("window.palpState && palpState.connected && palpState.messages > 0 && "
                           "palpState.trainee.session > 0", 20)
        check(ok is True and "token" not in page.eval("location.href"),
              "reloaded (the address without the token): connected again and following alice (%s messages before)" % r0)
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
