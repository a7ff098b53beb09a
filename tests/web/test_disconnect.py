#!/usr/bin/env python3
"""web_disconnect: palp-web keeps serving when browsers vanish abruptly: headless Chromium with a
trainee page and a dashboard streaming is killed with SIGKILL, and a raw client resets its
connection in the middle of a frame; afterwards the bridge is alive, leaves the session it no
longer needs (the server's member count drops), and a new client gets the stream again.
DDS domain 194. usage: test_disconnect.py BUILD SOURCE OUT"""
import json
import os
import re
import signal
import socket
import struct
import time

import harness
from harness import check


def run(build, source, out):
    procs = harness.Procs(build, source, out, 194)
    browser = None
    try:
        srv = procs.server()
        web = procs.web()
        procs.trainee("alice", 1, ["--profile", "sine", "--magnitude", "1", "--offset", "1.5", "--frequency", "1",
                                   "--t-on", "0.5", "--t-off", "60", "--duration", "60"])
        browser = harness.cdp.Chromium(out_dir=out)
        page = browser.new_page(web.base + "/trainee.html")
        dash = browser.new_page(web.base + "/dashboard.html")
        check(page.wait_for("window.palpState && palpState.trainee && palpState.trainee.frames > 10", 25) is True,
              "the trainee page streams frames")
        check(dash.wait_for("window.palpState && palpState.dashboard && palpState.dashboard.frames > 3", 15) is True,
              "the dashboard streams frames")
        browser.kill()  # its profile is removed by close(), below
        t_kill = time.time()
        time.sleep(0.3)
        check(web.poll() is None, "palp-web is alive after Chromium was killed")

        # A client that resets its connection halfway through a frame it was sending.
        s = socket.create_connection(("127.0.0.1", web.port), timeout=5)
        s.sendall(("GET /ws HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n" % web.port).encode())
        s.recv(4096)
        s.sendall(bytes([0x81, 0x80 | 126]) + struct.pack("!H", 200) + b"\x00\x00\x00\x00" + b"{\"follow\"")
        s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        s.close()  # RST
        time.sleep(0.3)
        check(web.poll() is None, "palp-web is alive after a connection reset mid-frame")

        # Nobody follows the session now: the bridge leaves it after its linger (2 s); ~2.1 s alone, 5.0 s in a
        # fresh clone's run at the suite's busiest start (2026-12-08), so within 8 s.
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % web.port, timeout=10)
        left = harness.ws_until(ws, 12, lambda m: m["type"] == "sessions" and bool(m["sessions"])
                                and m["sessions"][0]["visual"] == 0)
        left_after = time.time() - t_kill if left else None
        check(left_after is not None and left_after < 8,
              "the bridge left the session nobody watches: the server counts 0 visual members %.1f s after the kill"
              % (left_after or float("nan")))
        ws.send(json.dumps({"follow": "all"}))
        kinds, frames = harness.ws_messages(ws, 3.0)
        ws.close()
        check("sessions" in kinds and frames >= 15,
              "a new client following every session is served again: the session list and %d frames in 3 s "
              "(the dashboard rate is 10/s; >= 15)" % frames)
        status, body, _ = harness.http_get(web.base + "/trainee.html")
        check(status == 200 and b"trainee" in body, "pages are still served (%d)" % status)

        # palp-web not run for 0.8 s (SIGSTOP; a loaded machine): past its request writer's 0.5 s liveliness,
        # within its participant's 1 s lease, so DDS re-delivers nothing; the server drops the bridge from the
        # session. Its state then counts no visual station, and the bridge sends its JOIN again
        # (rejoin_if_dropped): a page following the session gets frames again. Before 2026-12-07 it stood still
        # until the session ended (a fresh clone's run of this test, dropped 0.97 s after joining).
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % web.port, timeout=10)
        ws.send(json.dumps({"follow": "all"}))
        _, before = harness.ws_messages(ws, 2.0)
        web.send_signal(signal.SIGSTOP)
        time.sleep(0.8)
        web.send_signal(signal.SIGCONT)
        _, after = harness.ws_messages(ws, 5.0)
        ws.close()
        lines = procs.log(srv)
        dropped = len(re.findall(r"web-s1 \(visual\) left session 1: lost", lines))
        check(dropped >= 1, "stopped 0.8 s, the bridge was dropped by the server (%d lines say so)" % dropped)
        # how: its JOIN sent again, or (a stop that outlasted its participant's lease too, on a loaded machine) DDS
        # re-delivering the JOIN as the server found it again; either way the client is served again
        how = "its JOIN sent again" if "JOIN sent again" in procs.log(web) else "the JOIN re-delivered by DDS"
        check(after >= 15, "and joined again (%s): %d frames in the 5 s after (>= 15; %d in the 2 s before)"
              % (how, after, before))
        # The same stop with another visual station in the session (palp-client --role visual): dropped, the
        # bridge leaves the server's count at 1, not 0, and rejoin_if_dropped's count test never fires. Its
        # own stall tells it (2026-12-08): a turn of its DDS thread 0.3 s or more late sends its JOIN again.
        # Before, it stayed out of the session (the deformation still came, for the other station) and the
        # server refused its trainee pages' marks.
        exe = os.path.join(build, "client", "palp-client")
        procs.start("visual-vic", [exe, "--role", "visual", "--domain", "194", "--phantom", "1", "--name", "vic",
                                   "--quiet"])
        ws = harness.cdp.WebSocket("ws://127.0.0.1:%d/ws" % web.port, timeout=10)
        ws.send(json.dumps({"follow": "all"}))
        two = harness.ws_until(ws, 15, lambda m: m["type"] == "sessions" and bool(m["sessions"])
                               and m["sessions"][0]["visual"] == 2)
        check(two is not None, "a visual station joins beside the bridge: the server counts 2 visual members")
        lost_re, join_re = r"web-s1 \(visual\) left session 1: lost", r"web-s1 joined session 1 as visual station"
        drops_before = len(re.findall(lost_re, procs.log(srv)))
        joins_before = len(re.findall(join_re, procs.log(srv)))
        said_before = procs.log(web).count("JOIN sent again to each")
        web.send_signal(signal.SIGSTOP)
        time.sleep(0.8)
        web.send_signal(signal.SIGCONT)
        t_cont = time.time()
        back_after = None
        while time.time() - t_cont < 6 and back_after is None:  # the server's word: it took the bridge again
            if len(re.findall(join_re, procs.log(srv))) > joins_before:
                back_after = time.time() - t_cont
            else:
                time.sleep(0.1)
        two_again = harness.ws_until(ws, 3, lambda m: m["type"] == "sessions" and bool(m["sessions"])
                                     and m["sessions"][0]["visual"] == 2)
        ws.close()
        lines = procs.log(srv)
        drops = len(re.findall(lost_re, lines)) - drops_before
        said = procs.log(web).count("JOIN sent again to each") > said_before
        check(drops >= 1, "stopped 0.8 s beside another visual station, the bridge was dropped by the server (%d "
              "line(s))" % drops)
        check(said and back_after is not None and two_again is not None,
              "and, having said it was away, joined again: the server took it %.1f s after the stop (within 6 s) and "
              "counts 2 visual members again" % (back_after if back_after is not None else float("nan")))
        rc = procs.stop(web)
        log = procs.log(web)
        check(rc == 0, "palp-web stops cleanly on SIGINT (exit %s)" % rc)
        print(log.strip().splitlines()[-1])
    finally:
        if browser:
            browser.close()
        procs.close()


if __name__ == "__main__":
    harness.main(run)
