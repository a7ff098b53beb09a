#!/usr/bin/env python3
"""chromium_render.py - several pages rendered by one headless Chromium (tests/web/cdp.py): for each page a
screenshot of the window and the DOM after its scripts, what `chromium --screenshot --dump-dom` gives for one.
Each Chromium start costs ~1.5 s of CPU (~4 s on a loaded machine), so the reports of one test share one
(tests/chromium.sh, palp_chromium_render_many). No network: file:// pages only. The same pages through
--screenshot and through this (2026-12-07): the two session reports' PNGs byte for byte the same, the class
report's 939 of its 7.9 million bytes different, and check_review.py's checks all passing on both.
usage: chromium_render.py WIDTHxHEIGHT LOG HTML PNG DOM [HTML PNG DOM ...]"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "web"))
import cdp  # noqa: E402


def main():
    size, log, rest = sys.argv[1], sys.argv[2], sys.argv[3:]
    if len(rest) == 0 or len(rest) % 3:
        sys.exit("usage: chromium_render.py WIDTHxHEIGHT LOG HTML PNG DOM [HTML PNG DOM ...]")
    w, h = (int(v) for v in size.split("x"))
    out_dir = os.path.dirname(os.path.abspath(log))
    browser = cdp.Chromium(width=w, height=h, out_dir=out_dir)
    try:
        for i in range(0, len(rest), 3):
            html, png, dom = rest[i:i + 3]
            url = "file://" + os.path.abspath(html)
            page = browser.new_page("about:blank")
            # the viewport of --window-size (a DevTools page's is the window less ~90 px) at 1 pixel per CSS pixel,
            # as --screenshot takes it
            page.call("Emulation.setDeviceMetricsOverride", width=w, height=h, deviceScaleFactor=1, mobile=False)
            page.call("Page.navigate", url=url)
            # the document loaded and its scripts run, then two frames painted: what --screenshot waits for
            ok = page.wait_for("location.href === %s && document.readyState === 'complete'" % json.dumps(url), 60)
            if not ok:
                sys.exit("chromium_render: %s did not load in 60 s" % html)
            page.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(true))))")
            got = page.eval("[window.innerWidth, window.innerHeight]")
            if got != [w, h]:
                sys.exit("chromium_render: the window is %s, not %dx%d" % (json.dumps(got), w, h))
            page.screenshot(png)
            with open(dom, "w") as f:
                f.write(page.eval("document.documentElement.outerHTML") + "\n")
            page.close()
    finally:
        browser.close()
    # the log Chromium wrote (cdp.Chromium: OUT_DIR/chromium.log) under the name asked for
    src = os.path.join(out_dir, "chromium.log")
    if os.path.abspath(log) != src and os.path.exists(src):
        os.replace(src, log)


if __name__ == "__main__":
    main()
