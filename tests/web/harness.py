"""harness.py - real palp-server, palp-client and palp-web processes for the web tests and the
benchmark, on a DDS domain of the caller's (tests/web uses 191-199, bench/web 200-209), loopback
only. Standard library only."""
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cdp  # noqa: E402  (re-exported for the tests)


class Fail(Exception):
    pass


def check(cond, msg):
    """One assertion: prints it and raises Fail when it does not hold."""
    print(("ok   " if cond else "FAIL ") + msg, flush=True)
    if not cond:
        raise Fail(msg)


class Procs:
    """Starts processes with their output in files under out_dir; stops every one at the end."""

    def __init__(self, build, source, out_dir, domain):
        self.build, self.source, self.out, self.domain = build, source, out_dir, domain
        os.makedirs(out_dir, exist_ok=True)
        self.env = dict(os.environ)
        self.env["CYCLONEDDS_URI"] = "file://" + os.path.join(source, "config", "cyclonedds-loopback.xml")
        self.procs = []

    def start(self, name, args):
        log = open(os.path.join(self.out, name + ".log"), "wb")
        p = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=self.env)
        p.name, p.logpath = name, log.name
        self.procs.append(p)
        return p

    def log(self, p):
        with open(p.logpath, errors="replace") as f:
            return f.read()

    def wait_log(self, p, pattern, timeout):
        end = time.time() + timeout
        while time.time() < end:
            m = re.search(pattern, self.log(p))
            if m:
                return m
            if p.poll() is not None:
                break
            time.sleep(0.05)
        raise Fail("%s: no %r within %.0f s (exit %s); log:\n%s" % (p.name, pattern, timeout, p.poll(), self.log(p)))

    # Most web tests look for a deep dent (20-30 mm, the top of the pages' colour scale), so by default they
    # host the paper's literal reading (config/server-paper.json: 3 N dents ~20 mm); the shipped
    # long-term domes dent ~0.5 mm under 3 N (docs/materials.md).
    def server(self, tick_hz=None, extra=(), config="server-paper.json", db=None):
        """palp-server on the test's domain; its session log at db (a path), or none."""
        args = [os.path.join(self.build, "server", "palp-server"), "--config",
                os.path.join(self.source, "config", config), "--domain", str(self.domain)]
        args += ["--database", db] if db else ["--no-db"]
        if tick_hz:
            args += ["--tick-rate", str(tick_hz)]
        p = self.start("server", args + list(extra))
        self.wait_log(p, "tick thread", 20)
        return p

    def web(self, extra=(), name="web", prefix=()):
        p = self.start(name, list(prefix) + [os.path.join(self.build, "web", "palp-web"), "--domain",
                                             str(self.domain), "--port", "0"] + list(extra))
        m = self.wait_log(p, r"serving on \S+ port (\d+)", 20)
        p.port = int(m.group(1))
        p.base = "http://127.0.0.1:%d" % p.port
        return p

    def trainee(self, name, phantom=1, extra=()):
        return self.start("trainee-" + name, [os.path.join(self.build, "client", "palp-client"), "--role", "trainee",
                                              "--domain", str(self.domain), "--phantom", str(phantom), "--name", name,
                                              "--quiet"] + list(extra))

    def stop(self, p, sig=signal.SIGINT, timeout=10):
        if p.poll() is None:
            p.send_signal(sig)
            try:
                p.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        return p.returncode

    def close(self):
        for p in reversed(self.procs):
            self.stop(p, timeout=5)


def server_config(source, out, name, out_name, edit=None):
    """config/NAME with its paths (relative to that file) made absolute, edited by edit(cfg), written to
    OUT/out_name; its path."""
    cdir = os.path.join(source, "config")
    with open(os.path.join(cdir, name)) as f:
        cfg = json.load(f)
    cfg["dds_config"] = os.path.join(cdir, cfg["dds_config"])
    for p in cfg["phantoms"]:
        p["scene"] = os.path.join(cdir, p["scene"])
    for e in cfg.get("exercises", []):
        e["file"] = os.path.join(cdir, e["file"])
    if edit:
        edit(cfg)
    path = os.path.join(out, out_name)
    with open(path, "w") as f:
        json.dump(cfg, f)
    return path


def answers_config(source, out):
    """config/server-exercises.json with the lumps sent to instructors' readers without DDS Security
    ("session_exercise": "always", a trusted bench: docs/security.md)."""
    return server_config(source, out, "server-exercises.json", "server-exercises-answers.json",
                         lambda cfg: cfg.update(session_exercise="always"))


def http_get(url, headers=None, context=None):
    """(status, body) of a GET; errors are statuses, not exceptions (an https URL takes an
    ssl.SSLContext; its TLS errors are raised)."""
    req = urllib.request.Request(url, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=10, context=context) as r:
            return r.status, r.read(), dict(r.headers)
    except urllib.error.HTTPError as e:
        return e.code, e.read(), dict(e.headers)


def ws_read(ws, seconds):
    """Yields (opcode, payload) of what a WebSocket receives for some seconds."""
    ws.sock.settimeout(0.5)
    end = time.time() + seconds
    while time.time() < end:
        try:
            yield ws.recv()
        except socket.timeout:
            continue


def ws_messages(ws, seconds):
    """(text messages by type, number of deformation frames) a WebSocket received in some seconds."""
    kinds, frames = {}, 0
    for op, data in ws_read(ws, seconds):
        if op == 2:
            frames += 1
        elif op == 1:
            m = json.loads(data)
            kinds.setdefault(m["type"], []).append(m)
    return kinds, frames


def ws_until(ws, seconds, done):
    """Reads a WebSocket's text messages (parsed) until done(message) is true or `seconds` pass;
    returns that message, or None."""
    for op, data in ws_read(ws, seconds):
        if op == 1:
            m = json.loads(data)
            if done(m):
                return m
    return None


def read_png(path):
    """(width, height, bytes per pixel, rows) of an 8-bit RGB/RGBA PNG (tests/db/check_render.py)."""
    sys.path.insert(0, os.path.join(HERE, "..", "db"))
    from check_render import read_png as rp
    return rp(path)


def disc_diff(a, b, cx, cy, r):
    """Mean absolute RGB difference [0, 255] of two screenshots over a disc (device pixels)."""
    wa, ha, bpp, ra = a
    _, _, bpp_b, rb = b
    total, n = 0, 0
    for y in range(max(0, int(cy - r)), min(ha, int(cy + r) + 1)):
        for x in range(max(0, int(cx - r)), min(wa, int(cx + r) + 1)):
            if (x - cx) ** 2 + (y - cy) ** 2 > r * r:
                continue
            pa, pb = ra[y][x * bpp:x * bpp + 3], rb[y][x * bpp_b:x * bpp_b + 3]
            total += sum(abs(pa[k] - pb[k]) for k in range(3)) / 3
            n += 1
    return total / max(n, 1)


def disc_mean(img, cx, cy, r):
    w, h, bpp, rows = img
    s, n = [0, 0, 0], 0
    for y in range(max(0, int(cy - r)), min(h, int(cy + r) + 1)):
        for x in range(max(0, int(cx - r)), min(w, int(cx + r) + 1)):
            if (x - cx) ** 2 + (y - cy) ** 2 <= r * r:
                for k in range(3):
                    s[k] += rows[y][x * bpp + k]
                n += 1
    return [v / max(n, 1) for v in s]


# Chromium's lines that say nothing about palp (no D-Bus in a container, SwiftShader's read-backs)
NOISE = re.compile(r"dbus/|GL Driver Message|Fontconfig")


def print_log_tails(out, lines=40):
    """The last lines of every process log of the run, into the test's own output: CTest keeps that
    (LastTest.log, CI), where a rerun overwrites the files (a failure seen once, in a fresh clone's
    first run, could not be read afterwards). palp's own processes first and the browser last, its
    known noise left out: CI shows only part of a long output."""
    names = sorted(n for n in os.listdir(out) if n.endswith(".log"))
    names.sort(key=lambda n: n.startswith("chromium"))
    for name in names:
        try:
            with open(os.path.join(out, name), errors="replace") as f:
                tail = [ln for ln in f.read().splitlines() if not NOISE.search(ln)][-lines:]
        except OSError:
            continue
        print("---- %s (last %d lines) ----" % (name, len(tail)))
        for line in tail:
            print("   " + line)


def main(run):
    """usage: test.py BUILD_DIR SOURCE_DIR OUT_DIR; run(build, source, out) raises Fail or returns."""
    build, source, out = sys.argv[1:4]
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    try:
        run(build, source, out)
    except Fail as e:
        print("FAILED (%.1f s): %s" % (time.time() - t0, e))
        print_log_tails(out)
        sys.exit(1)
    print("passed in %.1f s" % (time.time() - t0))
