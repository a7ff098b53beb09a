#!/usr/bin/env python3
"""bench_web: 8 trainee sessions streaming their deformation at 30 Hz through palp-web to 8 trainee
pages and one dashboard, on this machine's real processes (palp-server, 8 palp-client trainees
pressing a 1 Hz sine so no phantom sleeps, palp-web, Debian's headless Chromium on SwiftShader).

Phases, in one run (same machine state, so the comparison is fair):
  A   baseline: server + trainees, no bridge                       } alternating, R rounds
  W   + palp-web streaming to 9 plain WebSocket clients (8 following } each, pooled
      one session, 1 all): the bridge's own cost, no browser competing for the 2 cores
  B   + palp-web streaming to headless Chromium: 8 trainee pages (WebGL) + the dashboard
  A2  baseline again (drift check)
For each: the server's tick figures (palp_server_status, read by bench_web_status, not the bridge),
the bridge's CPU share (of one core, from /proc), frames per second each page/client receives and
the gaps between frames (median, p99). DDS domain 202 (200 until session 82: a test's).

usage: bench_web.py BUILD_DIR [--seconds S] [--rounds R] [--sessions N] [--no-browser] [--domain D]
(default: 3 rounds of A and W, 10 s each, then B and A2 for 10 s: about 2.5 min)
"""
import json
import os
import re
import socket
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "tests", "web"))
import cdp  # noqa: E402
import harness  # noqa: E402

DOMAIN = 202  # not a test's: 200 is db_recorder_ends' (until session 82 the default)
TCK = os.sysconf("SC_CLK_TCK")


def pct(xs, q):
    xs = sorted(xs)
    if not xs:
        return float("nan")
    k = (len(xs) - 1) * q
    i = int(k)
    return xs[i] if i + 1 >= len(xs) else xs[i] + (xs[i + 1] - xs[i]) * (k - i)


def cpu_s(pid):
    with open("/proc/%d/stat" % pid) as f:
        s = f.read()
    fields = s[s.rindex(")") + 2:].split()
    return (int(fields[11]) + int(fields[12])) / TCK


class StatusReader:
    """bench_web_status for the phase's duration: the server's per-second tick figures."""

    def __init__(self, build, env, seconds):
        self.p = subprocess.Popen([os.path.join(build, "bench", "web", "bench_web_status"), str(DOMAIN), str(seconds)],
                                  stdout=subprocess.PIPE, text=True, env=env)

    def rows(self):
        out, _ = self.p.communicate()
        rows = [list(map(float, l.split()[1:])) for l in out.splitlines() if l.startswith("status ")]
        return rows[1:]  # the first period may straddle the phase change


def summarise(chunks):
    """Server figures over one or more phases' status rows (each chunk: consecutive periods)."""
    rows = [r for c in chunks for r in c]
    if len(rows) < 2:
        return None
    ticks = sum(c[-1][5] - c[0][5] for c in chunks if len(c) > 1)
    over = sum(c[-1][6] - c[0][6] for c in chunks if len(c) > 1)
    return {"periods": len(rows), "load_med": pct([r[1] for r in rows], 0.5),
            "p50_med": pct([r[2] for r in rows], 0.5), "p99_med": pct([r[3] for r in rows], 0.5),
            "p99_max": max(r[3] for r in rows), "max": max(r[4] for r in rows),
            "overrun_pct": 100.0 * over / ticks if ticks else float("nan"), "open": rows[-1][7]}


class CpuSampler(threading.Thread):
    """CPU share of one process, sampled every second [% of one core]."""

    def __init__(self, pid):
        super().__init__(daemon=True)
        self.pid, self.samples, self.stop_flag = pid, [], False
        self.t0, self.c0 = time.time(), cpu_s(pid)

    def run(self):
        t, c = self.t0, self.c0
        while not self.stop_flag:
            time.sleep(1.0)
            try:
                c2 = cpu_s(self.pid)
            except OSError:
                break
            t2 = time.time()
            self.samples.append(100.0 * (c2 - c) / (t2 - t))
            t, c = t2, c2

    def total(self):
        self.stop_flag = True
        return 100.0 * (cpu_s(self.pid) - self.c0) / (time.time() - self.t0)


class WsClient(threading.Thread):
    """A plain WebSocket client that follows one trainee's open session (or all sessions), as the
    trainee page does, and timestamps its frames. Following the trainee, not a fixed session id:
    on a loaded machine the server may drop a station for its liveliness lease, and the trainee
    comes back in a new session."""

    def __init__(self, port, trainee=None):
        super().__init__(daemon=True)
        self.ws = cdp.WebSocket("ws://127.0.0.1:%d/ws" % port, timeout=10)
        self.trainee, self.session = trainee, 0
        if trainee is None:
            self.ws.send(json.dumps({"follow": "all"}))
        self.arrivals, self.per_session, self.stop_flag = [], {}, False
        self.resessions = 0

    def run(self):
        self.ws.sock.settimeout(0.5)
        while not self.stop_flag:
            try:
                op, data = self.ws.recv()
            except socket.timeout:
                continue
            except (ConnectionError, OSError):
                break
            if op == 1 and self.trainee is not None and b'"sessions"' in data[:40]:
                ids = [s["id"] for s in json.loads(data)["sessions"] if s["trainee"] == self.trainee]
                sid = max(ids) if ids else 0
                if sid and sid != self.session:
                    self.resessions += self.session != 0
                    self.session = sid
                    self.ws.send(json.dumps({"follow": sid}))
            if op == 2:
                sid = int.from_bytes(data[4:8], "little")
                self.arrivals.append(time.time())
                self.per_session[sid] = self.per_session.get(sid, 0) + 1


def gaps_ms(arrivals):
    return [1000.0 * (b - a) for a, b in zip(arrivals, arrivals[1:])]


def main():
    build = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(SOURCE, "build"))
    seconds = 10.0
    n = 8
    rounds = 3
    for i, a in enumerate(sys.argv):
        if a == "--seconds":
            seconds = float(sys.argv[i + 1])
        if a == "--rounds":
            rounds = int(sys.argv[i + 1])
        if a == "--sessions":
            n = int(sys.argv[i + 1])
    no_browser = "--no-browser" in sys.argv
    global DOMAIN
    for i, a in enumerate(sys.argv):
        if a == "--domain":  # another engineer may be running this benchmark on 202 at the same time
            DOMAIN = int(sys.argv[i + 1])
    out = os.path.join(build, "bench", "web", "out")
    procs = harness.Procs(build, SOURCE, out, DOMAIN)
    results = {}
    browser = None
    try:
        server = procs.server()
        for k in range(n):
            procs.trainee("t%d" % k, 1 + k % 2, ["--profile", "sine", "--magnitude", "1", "--offset", "1.5",
                                                  "--frequency", "1", "--t-on", "0.5", "--t-off", "100000",
                                                  "--duration", "100000", "--polar", str(10 + 5 * k),
                                                  "--azimuth", str(45 * k)])
        end = time.time() + 30
        while time.time() < end and len(re.findall(r"session \d+ opened", procs.log(server))) < n:
            time.sleep(0.2)
        time.sleep(3)
        print("bench_web: %d sessions open, %.0f s per phase, DDS domain %d" % (n, seconds, DOMAIN), flush=True)

        # A and W alternate, so that the other work on this shared machine falls on both alike.
        chunks = {"A": [], "W": []}
        cpu_all, cpu_samples, fps, dash, g, clients_cpu, resessions = [], [], [], [], [], [], 0
        for rnd in range(rounds):
            chunks["A"].append(StatusReader(build, procs.env, seconds).rows())
            web = procs.web(name="web-w%d" % rnd)
            time.sleep(1)
            clients = [WsClient(web.port, "t%d" % k) for k in range(n)] + [WsClient(web.port)]
            for c in clients:
                c.start()
            time.sleep(3)  # joins, first frames
            for c in clients:
                c.arrivals.clear()
                c.per_session.clear()
            cpu = CpuSampler(web.pid)
            cpu.start()
            me0 = cpu_s(os.getpid())
            st = StatusReader(build, procs.env, seconds)
            t0 = time.time()
            chunks["W"].append(st.rows())
            wall = time.time() - t0
            cpu_all.append(cpu.total())
            clients_cpu.append(100.0 * (cpu_s(os.getpid()) - me0) / wall)
            cpu_samples += cpu.samples
            for c in clients:
                c.stop_flag = True
            fps += [len(c.arrivals) / wall for c in clients[:n]]
            resessions += sum(c.resessions for c in clients[:n])
            dash += [v / wall for v in clients[n].per_session.values()]
            g += [x for c in clients[:n] for x in gaps_ms(c.arrivals)]
            for c in clients:
                c.ws.close()
            procs.stop(web)
            print("  round %d of A/W done" % (rnd + 1), flush=True)
        results["A"] = {"server": summarise(chunks["A"])}
        results["W"] = {"server": summarise(chunks["W"]), "cpu": sum(cpu_all) / len(cpu_all),
                        "cpu_p50": pct(cpu_samples, 0.5), "cpu_p99": pct(cpu_samples, 0.99), "fps": fps,
                        "dash": dash, "gap50": pct(g, 0.5), "gap99": pct(g, 0.99),
                        "clients_cpu": sum(clients_cpu) / len(clients_cpu), "resessions": resessions}

        # B: the bridge and Chromium (skipped with --no-browser; if it fails, A and W are still reported)
        try:
            if no_browser:
                raise RuntimeError("skipped (--no-browser)")
            web = procs.web(name="web-b")
            browser = cdp.Chromium(width=800, height=600, out_dir=out)
            pages = [browser.new_window(web.base + "/trainee.html?trainee=t%d" % k, 480, 360) for k in range(n)]
            dpage = browser.new_window(web.base + "/dashboard.html", 1000, 700)
            for k, p in enumerate(pages):
                if not p.wait_for("window.palpState && palpState.trainee && palpState.trainee.frames > 5", 60):
                    raise SystemExit("page %d did not stream" % k)
            dpage.wait_for("window.palpState && palpState.dashboard && palpState.dashboard.frames > 5", 30)
            time.sleep(2)
            f0 = [p.eval("palpState.trainee.frames") for p in pages]
            r0 = [p.eval("palpState.trainee.rendered") for p in pages]
            d0 = dpage.eval("palpState.dashboard.frames")
            cpu = CpuSampler(web.pid)
            cpu.start()
            bc0 = browser.cpu_seconds()
            st = StatusReader(build, procs.env, seconds)
            t0 = time.time()
            srv = summarise([st.rows()])
            f1 = [p.eval("palpState.trainee.frames") for p in pages]
            r1 = [p.eval("palpState.trainee.rendered") for p in pages]
            d1 = dpage.eval("palpState.dashboard.frames")
            wall = time.time() - t0
            share = cpu.total()
            bshare = 100.0 * (browser.cpu_seconds() - bc0) / wall
            g = []
            for p in pages:
                arr = p.eval("palpState.trainee.arrivals")
                arr = [x for x in arr if x >= arr[-1] - 1000 * seconds]
                g += [b - a for a, b in zip(arr, arr[1:])]
            results["B"] = {"server": srv, "cpu": share, "cpu_p50": pct(cpu.samples, 0.5), "cpu_p99": pct(cpu.samples, 0.99),
                            "fps": [(b - a) / wall for a, b in zip(f0, f1)],
                            "rendered": [(b - a) / wall for a, b in zip(r0, r1)],
                            "dash": [(d1 - d0) / wall / n], "gap50": pct(g, 0.5), "gap99": pct(g, 0.99), "browser": bshare}
            dpage.screenshot(os.path.join(out, "bench-dashboard.png"))
            pages[0].screenshot(os.path.join(out, "bench-trainee.png"))
            browser.close()
            browser = None
            procs.stop(web)
            print("  B done", flush=True)
        except (SystemExit, RuntimeError, OSError, harness.Fail) as e:
            results["B_failed"] = str(e)
            print("  B: %s" % e, flush=True)
            if browser:
                browser.close()
                browser = None
            for p in procs.procs:
                if p.name == "web-b":
                    procs.stop(p)
        time.sleep(2)
        results["A2"] = {"server": summarise([StatusReader(build, procs.env, seconds).rows()])}
    finally:
        if browser:
            browser.close()
        procs.close()

    print()
    print("server tick figures (palp_server_status, %d sessions at %s Hz ticks, deformation 30 Hz while watched):" % (
        n, "100"))
    print("| phase | periods | tick work p50 (median) | p99 (median / worst) | max | overrun | load (worst thread) |")
    print("|---|---|---|---|---|---|---|")
    names = {"A": "A: no bridge (%d x %.0f s)" % (rounds, seconds),
             "W": "W: bridge + 9 WebSocket clients (%d x %.0f s, alternating with A)" % (rounds, seconds), "B": "B: bridge + Chromium (8 pages + dashboard)",
             "A2": "A2: no bridge, again"}
    for k in ["A", "W", "B", "A2"]:
        s = results.get(k, {}).get("server")
        if not s:
            print("| %s | no status |" % names[k])
            continue
        print("| %s | %d | %.0f us | %.0f / %.0f us | %.0f us | %.2f%% | %.0f%% |" % (
            names[k], s["periods"], s["p50_med"], s["p99_med"], s["p99_max"], s["max"], s["overrun_pct"],
            100 * s["load_med"]))
    print()
    print("| phase | bridge CPU (mean, of one core) | per second p50 / p99 | frames/s per trainee page (min / median) "
          "| dashboard frames/s per session | gap between frames p50 / p99 | rendered frames/s (median) | Chromium CPU |")
    print("|---|---|---|---|---|---|---|---|")
    for k in ["W", "B"]:
        r = results.get(k)
        if not r:
            continue
        rend = "%.1f" % pct(r["rendered"], 0.5) if "rendered" in r else "-"
        br = "%.0f%%" % r["browser"] if "browser" in r else "-"
        print("| %s | %.1f%% | %.1f / %.1f%% | %.1f / %.1f | %.1f | %.1f / %.1f ms | %s | %s |" % (
            names[k], r["cpu"], r["cpu_p50"], r["cpu_p99"], min(r["fps"]), pct(r["fps"], 0.5), pct(r["dash"], 0.5),
            r["gap50"], r["gap99"], rend, br))
    if "B_failed" in results:
        print("\nB (Chromium): %s" % results["B_failed"])
    w = results.get("W")
    if w:
        print()
        print("frames/s per light client (%d clients x %d rounds): median %.1f, p1 %.1f, p99 %.1f; the %d clients' own "
              "CPU (this Python process) %.1f%% of one core; %d times a trainee came back in a new session (the server "
              "dropped its station)" % (n, rounds, pct(w["fps"], 0.5), pct(w["fps"], 0.01), pct(w["fps"], 0.99), n + 1,
                                        w["clients_cpu"], w["resessions"]))
    # Ratios against the baseline without the bridge (A, which alternates with W in the same run;
    # A2 after B for the drift): 1.00 = unchanged.
    base = results.get("A", {}).get("server")
    if base:
        print()
        print("ratio against A (no bridge, same run): 1.00 = unchanged")
        print("| phase | tick work p50 (median) | p99 (median) | max | overrun share |")
        print("|---|---|---|---|---|")
        for k in ["W", "B", "A2"]:
            s = results.get(k, {}).get("server")
            if not s:
                continue
            def ratio(key):
                return s[key] / base[key] if base[key] else float("nan")
            print("| %s / A | %.2f | %.2f | %.2f | %.2f |" % (k, ratio("p50_med"), ratio("p99_med"), ratio("max"),
                                                           ratio("overrun_pct")))
    with open(os.path.join(out, "bench_web.json"), "w") as f:
        json.dump(results, f, indent=1)
    print("\nraw figures: %s" % os.path.join(out, "bench_web.json"))


if __name__ == "__main__":
    main()
