#!/usr/bin/env python3
"""The offline tools and the model benchmarks on inputs that break them (tests/tools/CMakeLists.txt).

Usage: test_tools_errors.py --config DIR [--run PALP_RUN] [--sweep PALP_SWEEP]
                            [--bench-step B] [--bench-effects B] [--netem PALP_NETEM] CASE

Scenes are written into a temporary directory (TMPDIR) and removed at the end. A "broken" scene
is config/paper_step.json with a gel pressure of 1e300 Pa: until session 81 the scene parser took any
positive pressure, and the world's first step under load was non-finite (PALP_EUNSTABLE); now the
parser refuses it (its bound is 1e7 Pa), and the tools say so at load.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time

failures = 0


def check(ok, msg):
    global failures
    print(("ok   " if ok else "FAIL ") + msg)
    if not ok:
        failures += 1


def scene(config, tmp, name, **time):
    """paper_step.json with its parameter file inlined (the scene may then live anywhere)."""
    with open(os.path.join(config, "paper_step.json")) as f:
        s = json.load(f)
    with open(os.path.join(config, s.pop("parameters"))) as f:
        p = json.load(f)
    for k in ("material", "membrane", "gel"):
        s[k] = p[k]
    s["time"].update(time)
    return s, os.path.join(tmp, name)


def write(s, path):
    with open(path, "w") as f:
        json.dump(s, f)
    return path


def run(cmd, timeout=100, cwd=None):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=cwd)
    return r.returncode, r.stdout + r.stderr


def broken_scene(a, tmp):
    s, path = scene(a.config, tmp, "broken.json")
    s["gel"]["pressure_Pa"] = 1e300
    return write(s, path)


def peak_rss_kb(cmd, timeout=60):
    """Runs cmd to its end; its exit status and its own peak resident set [kB] (VmHWM, read from
    /proc every 5 ms while it runs; 0 if never read). Not ru_maxrss: a child's counts the forking
    Python's resident set too (measured: /bin/true 14-65 MB), which would hide a palp-run's."""
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    peak, reads = 0, 0
    deadline = time.monotonic() + timeout
    while p.poll() is None and time.monotonic() < deadline:
        try:
            with open("/proc/%d/status" % p.pid) as f:
                m = re.search(r"VmHWM:\s+(\d+)", f.read())
            if m:
                peak, reads = max(peak, int(m.group(1))), reads + 1
        except OSError:
            pass
        time.sleep(0.005)
    if p.poll() is None:
        p.kill()
    return p.wait(), peak, reads


def case_run_long(a, tmp):
    # 1e8 frames of 1e5 steps (the parser's limits): one double per step was 8e13 bytes, never
    # checked (a NULL written through: SIGSEGV at the first step). The run must just go on: still
    # stepping after 3 s. Its resident memory then is checked loosely (an up-front array that the
    # kernel granted and the run touched would pass 200 MB); whether the step times stay in their
    # 2^20-sample reservoir is the finite run's check below.
    s, path = scene(a.config, tmp, "long.json", dt_s=1e-6, frames=100000000, frame_period_s=0.1)
    s["mesh"]["vertex_count"] = 19
    write(s, path)
    p = subprocess.Popen([a.run, path, "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        out, _ = p.communicate(timeout=3)
        check(False, "palp-run on 1e13 steps still running after 3 s (exited %d: %s)" % (p.returncode, out.strip()[-300:]))
        return
    except subprocess.TimeoutExpired:
        with open("/proc/%d/status" % p.pid) as f:
            rss = int(re.search(r"VmRSS:\s+(\d+)", f.read()).group(1))
        p.kill()
        p.communicate()
    check(True, "palp-run on 1e13 steps still running after 3 s")
    check(rss < 200000, "palp-run's resident memory %d kB < 200 MB after 3 s" % rss)
    # Bounded memory where bounded and unbounded differ: 4e6 steps (40 frames of 1e5 at 1 us) of a
    # world with no contact (asleep: ~0.3 us a step, ~1.5 s here; every step's time is still taken).
    # The step times' reservoir is 2^20 doubles (8 MB); one double a step kept for every step (an
    # array grown as the run goes) is 32 MB, and glibc's qsort (2.36 here) sorts through a copy as
    # large. Measured 2026-12-07: peak 23.1-23.3 MB; 69.4-69.5 MB with every step kept (palp_run.c's
    # nkeep = nsteps, scratch build). The bound, 30 MB, also holds against a qsort that sorts in
    # place (glibc 2.37-2.38; estimated, not measured: ~15 MB bounded, ~39 MB with every step kept).
    s, path = scene(a.config, tmp, "finite.json", dt_s=1e-6, frames=40, frame_period_s=0.1)
    s["mesh"]["vertex_count"] = 19
    s["contacts"] = []
    write(s, path)
    rc, peak, reads = peak_rss_kb([a.run, path, "--quiet"])
    check(rc == 0 and reads >= 10, "palp-run on 4e6 steps exits 0 (rc %d; its memory read %d times)" % (rc, reads))
    check(0 < peak < 30000, "palp-run's peak resident memory over 4e6 steps %d kB < 30 MB (its 8 MB reservoir: "
          "~23 MB; a step time kept for every step: ~69 MB)" % peak)


def case_run_reservoir(a, tmp):
    # 1,100,000 steps, past the 2^20 step times palp-run keeps: the median and p99 still come
    # from a full sample (finite, p99 >= median > 0) and the summary is printed.
    s, path = scene(a.config, tmp, "many.json", dt_s=0.001, frames=11000, frame_period_s=0.1)
    s["mesh"]["vertex_count"] = 19
    s["contacts"][0]["profile"]["t_off_s"] = 1e6  # pressed throughout: no step of a sleeping world (~0.0 us)
    write(s, path)
    rc, out = run([a.run, path, "--quiet"])
    m = re.search(r"step median ([0-9.eE+-]+|nan|inf) us, p99 ([0-9.eE+-]+|nan|inf) us", out)
    check(rc == 0 and m is not None, "palp-run over 1.1e6 steps exits 0 with a summary (rc %d)" % rc)
    if m:
        med, p99 = float(m.group(1)), float(m.group(2))
        check(math.isfinite(med) and math.isfinite(p99) and 0 < med <= p99,
              "step median %g us, p99 %g us: finite, 0 < median <= p99" % (med, p99))
    # 2 steps (2 frames of one step): st[n/2] and st[floor(0.99 (n - 1))] made the median the slower
    # step and the p99 the faster one. Type 7 (palp-stats' rule): median the mean of the two,
    # p99 = fast + 0.99 (slow - fast), never below it. Five runs: any one inverted is the fault.
    s, path = scene(a.config, tmp, "two.json", dt_s=0.001, frames=2, frame_period_s=0.001)
    s["mesh"]["vertex_count"] = 19
    write(s, path)
    for k in range(5):
        rc, out = run([a.run, path, "--quiet"])
        m = re.search(r"step median ([0-9.eE+-]+|nan|inf) us, p99 ([0-9.eE+-]+|nan|inf) us", out)
        med, p99 = (float(m.group(1)), float(m.group(2))) if m else (float("nan"), float("nan"))
        check(rc == 0 and 0 < med <= p99, "palp-run of 2 steps, run %d: median %g us <= p99 %g us" % (k + 1, med, p99))


def case_run_dt(a, tmp):
    # --dt 1e-15 on 10 ms frames asked for 1e13 steps a frame (an int overflow): refused.
    rc, out = run([a.run, os.path.join(a.config, "paper_step.json"), "--dt", "1e-15", "--quiet"])
    check(rc == 2 and "at most 100000 steps per frame" in out, "palp-run --dt 1e-15 refused (rc %d): %s" % (rc, out.strip()))
    # Numbers read whole or refused (atoi/atof took "1e3" for 1 frame, "10k" for 10, "338x" for 338,
    # ignored "abc", "-5", "0", "nan", and 99999999999 overflowed an int): exit 2, option and value named.
    bad = [("--frames", v) for v in ("1e3", "10k", "abc", "-5", "0", "99999999999", "")] + \
          [("--dt", v) for v in ("abc", "-1", "0", "nan", "inf", "1e-3s")] + \
          [("--vertices", v) for v in ("338x", "abc", "5", "-338")]
    for opt, v in bad:
        rc, out = run([a.run, os.path.join(a.config, "paper_step.json"), opt, v, "--quiet"])
        check(rc == 2 and opt in out and '"%s"' % v in out, "palp-run %s %r refused (rc %d): %s" % (opt, v, rc, out.strip()))
    # and whole values still taken as given: 3 frames of 19 vertices at 1 ms
    rc, out = run([a.run, os.path.join(a.config, "paper_step.json"), "--frames", "3", "--vertices", "19", "--dt", "0.001"])
    check(rc == 0 and "19 vertices, dt 0.001 s, 3 frames of" in out, "palp-run --frames 3 --vertices 19 --dt 0.001 runs (rc %d): %s"
          % (rc, out.strip()[:200]))
    # a run that ends before its release (2 s) says the recovery figures were not reached (session 90's
    # review: "1 s after release 0.000 mm (0.0%)", a perfect recovery, and "feedback at release (0, 0, 0) N")
    check(rc == 0 and "1 s after release (not reached: the run ends at" in out and
          "feedback at release (not reached: the run ends at" in out and "not back within 5% of its peak" in out and
          "0.000 mm (0.0%)" not in out, "palp-run's 3 frames: the recovery figures not reached, said so: %s"
          % out.strip()[-300:])


def case_run_write(a, tmp):
    # A CSV that cannot be written (a full disk: /dev/full; a missing directory) ended as exit 0
    # with the file truncated, its open failure without a reason. Now: exit 1, the file and why.
    scene_path = os.path.join(a.config, "paper_step.json")
    for which in ("frames", "vertices"):
        prefix = os.path.join(tmp, "full_" + which)
        os.symlink("/dev/full", "%s_%s.csv" % (prefix, which))
        rc, out = run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001", "--out", prefix, "--quiet"])
        check(rc != 0 and "full_%s_%s.csv: cannot write it: No space left on device" % (which, which) in out
              and "step median" not in out, "palp-run with %s_%s.csv on a full disk exits %d, naming it: %s"
              % ("full_" + which, which, rc, out.strip()[-200:]))
    # two levels missing: only one is created (as palp-server's log directory), so this still fails, saying why
    rc, out = run([a.run, scene_path, "--frames", "3", "--out", os.path.join(tmp, "no", "dir", "x"), "--quiet"])
    check(rc != 0 and "no/dir/x_frames.csv: No such file or directory" in out and not os.path.exists(os.path.join(tmp, "no")),
          "palp-run --out into a directory two levels missing exits %d with the reason: %s" % (rc, out.strip()[-200:]))
    # the summary on stdout to a full disk: written to nothing, so exit 1 and why
    with open("/dev/full", "w") as full:
        r = subprocess.run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001"], stdout=full,
                           stderr=subprocess.PIPE, text=True, timeout=100)
    check(r.returncode == 1 and "cannot write the summary to stdout: No space left on device" in r.stderr,
          "palp-run >/dev/full exits %d with the reason: %s" % (r.returncode, r.stderr.strip()[-200:]))
    # a log file that cannot be opened: the system's reason (it said "cannot open it")
    rc, out = run([a.run, scene_path, "--frames", "3", "--log-file", os.path.join(tmp, "no", "run.log")])
    check(rc == 2 and "cannot open it: No such file or directory" in out,
          "palp-run --log-file in a missing directory exits %d with the reason: %s" % (rc, out.strip()[-200:]))
    # (session 81) the README's `--out out/run` in a fresh clone: the prefix's directory is missing and its
    # parent exists. palp-run creates it (one level, as palp-server does its log's; 0777 & umask) and writes
    # there; relative to its working directory too. It said "cannot write nodir/run_frames.csv".
    old_umask = os.umask(0o027)
    try:
        rc, out = run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001", "--out",
                       "nodir/run", "--quiet"], cwd=tmp)
    finally:
        os.umask(old_umask)
    made = os.path.join(tmp, "nodir")
    mode = os.stat(made).st_mode & 0o7777 if os.path.isdir(made) else None
    lines = [sum(1 for _ in open(os.path.join(made, "run_%s.csv" % w))) for w in ("frames", "vertices")] \
        if rc == 0 and mode is not None else []
    check(rc == 0 and mode == 0o750 and lines == [4, 4],
          "palp-run --out nodir/run (nodir missing) creates nodir/ with mode 0777 & umask 027 (%s) and writes both "
          "CSVs, 4 lines each, exit %d (%s): %s" % (oct(mode) if mode is not None else "none", rc, lines,
                                                    out.strip()[-200:]))
    # and a writable prefix: both files whole (a header and 3 frames), exit 0
    prefix = os.path.join(tmp, "ok")
    rc, out = run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001", "--out", prefix, "--quiet"])
    lines = [sum(1 for _ in open("%s_%s.csv" % (prefix, w))) for w in ("frames", "vertices")] if rc == 0 else []
    check(rc == 0 and lines == [4, 4], "palp-run --out writes 4 lines to each CSV, exit 0 (rc %d, %s)" % (rc, lines))


def case_run_out_long(a, tmp):
    # (session 82) a --out PREFIX too long for palp-run's path buffers was cut without a word: with
    # --distribution all the "_d1".."_d4" were lost and the four runs overwrote one file, exit 0. Now
    # refused before any run: exit 2, naming --out and the limit (1000 bytes), no file written.
    scene_path = os.path.join(a.config, "paper_step.json")
    base = tmp
    while len(base) < 800:  # a real, existing directory deep enough for a long prefix
        base = os.path.join(base, "d" * 200)
        os.mkdir(base)
    for plen, dist in ((1001, "all"), (1027, "single")):
        d = os.path.join(base, "%d" % plen)
        os.mkdir(d)
        prefix = os.path.join(d, "p" * (plen - len(d) - 1))
        assert len(prefix) == plen
        rc, out = run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001", "--distribution", dist,
                       "--out", prefix, "--quiet"])
        written = [f for f in os.listdir(d) if f.endswith(".csv")]
        check(rc == 2 and "--out" in out and "limit of 1000" in out and "step median" not in out and not written,
              "palp-run --out PREFIX of %d bytes (--distribution %s) refused, exit %d, no CSV (%s): %s"
              % (plen, dist, rc, written, out.strip()[-200:]))
    # at the limit: taken, and --distribution all writes four distinct pairs of files
    d = os.path.join(base, "1000")
    os.mkdir(d)
    prefix = os.path.join(d, "p" * (1000 - len(d) - 1))
    rc, out = run([a.run, scene_path, "--frames", "3", "--vertices", "19", "--dt", "0.001", "--distribution", "all",
                   "--out", prefix, "--quiet"])
    want = sorted("%s_d%d_%s.csv" % (os.path.basename(prefix), k, w) for k in range(1, 5) for w in ("frames", "vertices"))
    got = sorted(f for f in os.listdir(d) if f.endswith(".csv"))
    check(rc == 0 and got == want, "palp-run --out PREFIX of 1000 bytes, --distribution all: 8 CSVs, exit %d (%d files)"
          % (rc, len(got)))


def case_run_log_full(a, tmp):
    # (session 82) a --log-file that cannot take its lines (a full disk: /dev/full) lost every line, errors
    # included, without a word: exit 2 and nothing on stderr. Now the failure is said once on stderr, naming
    # the file and why, the lines go to stderr too, and the program goes on to its own exit status.
    missing = os.path.join(tmp, "missing.json")
    r = subprocess.run([a.run, missing, "--log-file", "/dev/full"], capture_output=True, text=True, timeout=100)
    said = r.stderr.count("log file /dev/full: cannot write to it: No space left on device")
    check(r.returncode == 2 and said == 1 and "ERROR palp-run: %s:" % missing in r.stderr
          and "could not be written" in r.stderr,
          "palp-run MISSING.json --log-file /dev/full: exit %d, the scene's error and the log file's failure (said %d "
          "time(s)) on stderr: %s" % (r.returncode, said, r.stderr.strip()[-400:]))


def case_sweep_broken(a, tmp):
    # Every real-time point's world refused to step: each used to go on "stepping" in ~0.3 us, two
    # landed on the Pareto front and the sweep exited 0; then (2026-12) each was marked failed, its
    # reason printed, exit 1. Since session 81 the scene parser bounds the gel's pressure (1e7 Pa),
    # and no scene within the bounds was found that breaks the real-time model while the FE
    # reference runs (tried: pressure and a1 at their bounds under 3 N and 10 kN; the FE fails at
    # 10 kN): the broken scene is refused before the FE reference runs, naming the key, exit 2. The
    # sweep's failed-point code stays, for a failure the bounds do not foresee, untested here.
    # Since session 82 an unusable scene is exit 1 (an input error, as in palp-eval), not 2.
    out = os.path.join(tmp, "out")
    rc, log = run([a.sweep, "--quick", "--ref-level", "1", "--frames", "40", "--scene", broken_scene(a, tmp),
                   "--out", out], timeout=110, cwd=tmp)
    check(rc == 1 and "gel.pressure_Pa: must be <= 1e+07 (got 1e+300)" in log and "reference FEM" not in log,
          "palp-sweep refuses the broken scene up front, naming the key, exit 1 (rc %d): %s" % (rc, log.strip()[-200:]))
    check(not os.path.exists(os.path.join(out, "sweep.csv")), "and writes no sweep.csv")


def case_bench_step_broken(a, tmp):
    # The server core's view on a dome whose world refused to step stopped with the case, the step and
    # the reason; since session 81 that scene is refused at load, naming the key (see case_sweep_broken).
    rc, out = run([a.bench_step, "--core-only", "--quick", "--worlds", "2", "--scene", broken_scene(a, tmp)])
    check(rc == 1 and "gel.pressure_Pa: must be <= 1e+07 (got 1e+300)" in out and "median" not in out,
          "bench_model_step refuses the broken dome at load, naming the key, exit 1 (rc %d): %s" % (rc, out.strip()[-200:]))


def case_bench_step_zero(a, tmp):
    # --steps 0 read t[0] of a zero-size allocation and printed it as the median.
    rc, out = run([a.bench_step, "--steps", "0"])
    check(rc == 2 and "--steps must be a whole number from 1" in out, "bench_model_step --steps 0 refused (rc %d): %s" % (rc, out.strip()[-200:]))


def case_bench_effects_zero(a, tmp):
    rc, out = run([a.bench_effects, "--steps", "0"])
    check(rc == 2 and "--steps must be a whole number from 1" in out,
          "bench_model_effects --steps 0 refused (rc %d): %s" % (rc, out.strip()[-200:]))


def case_bench_effects_asleep(a, tmp):
    # Session 82 review: the asleep row ran with gravity on, a world that since session 81 never
    # sleeps, and said "the world sleeps"; the reduced models' rows timed a collapsed dome unmarked.
    rc, out = run([a.bench_effects, "--steps", "100"])
    asleep = [l for l in out.splitlines() if l.startswith("all but gravity, asleep")]
    check(rc == 0 and len(asleep) == 1 and "0 of 100 timed steps awake" in asleep[0],
          "bench_model_effects' asleep row slept in all its timed steps (rc %d): %s" % (rc, out.strip()[-300:]))
    # a row whose dome lay on its base (base_vtx > 0) says so; a row with none does not
    for l in out.splitlines()[2:-1]:
        f = l[34:].split()
        if len(f) >= 7:
            on_base = int(f[6]) > 0
            check(on_base == ("COLLAPSED" in l), "bench_model_effects marks a collapsed row, and only one: %s" % l)
    rc, out = run([a.bench_effects, "--load", "0"])
    check(rc == 2 and "--load must be a force in N above 0" in out, "bench_model_effects --load 0 refused (rc %d): %s" % (rc, out.strip()[-200:]))


def netem_config(a, tmp, address="192.0.2.1"):
    """The loopback DDS config with its interface moved to a documentation address (TEST-NET-1): a config
    that may reach a network. No host has that interface, so even a relay that took it would send
    nothing."""
    with open(os.path.join(a.config, "cyclonedds-loopback.xml")) as f:
        x = f.read()
    y = x.replace('<NetworkInterface address="127.0.0.1"', '<NetworkInterface address="%s"' % address)
    assert y != x, "the loopback config's NetworkInterface line changed: update this test"
    return write_text(y, os.path.join(tmp, "network.xml"))


def write_text(text, path):
    with open(path, "w") as f:
        f.write(text)
    return path


def case_netem_network(a, tmp):
    # Session 83 review "wire" #2: palp-netem (no DDS Security) started on any DDS config, so with a lab
    # config on one side it would bridge a loopback-only, unsecured palp-server onto the network, which
    # palp-server itself refuses. Now it refuses as the server does, before any participant: exit 2.
    want = "palp-netem: refusing: the DDS config %s may reach a network"
    cfg = netem_config(a, tmp)
    rc, out = run([a.netem, "--stations", "201", "--server", "202", "--duration", "1", "--dds-config", cfg], timeout=30)
    check(rc == 2 and (want % cfg) in out and "192.0.2.1" in out and "the relay is for loopback tests" in out,
          "palp-netem --dds-config (interface 192.0.2.1) refused, naming the config and why, exit %d: %s"
          % (rc, out.strip()[-300:]))
    lab = os.path.join(a.config, "cyclonedds-lab.xml.example")
    env = dict(os.environ, PALP_DDS_INTERFACE="palpnone0", PALP_DDS_PEER_1="192.0.2.2", PALP_DDS_PEER_2="192.0.2.3",
               PALP_DDS_PEER_3="192.0.2.4")
    env.pop("CYCLONEDDS_URI", None)
    r = subprocess.run([a.netem, "--stations", "201", "--server", "202", "--duration", "1", "--dds-config", lab],
                       capture_output=True, text=True, timeout=30, env=env)
    out = r.stdout + r.stderr
    check(r.returncode == 2 and (want % lab) in out,
          "palp-netem --dds-config cyclonedds-lab.xml.example refused, exit %d: %s" % (r.returncode, out.strip()[-300:]))
    # the same by CYCLONEDDS_URI, taken from the environment as it is
    env["CYCLONEDDS_URI"] = "file://" + cfg
    r = subprocess.run([a.netem, "--stations", "201", "--server", "202", "--duration", "1"], capture_output=True,
                       text=True, timeout=30, env=env)
    out = r.stdout + r.stderr
    check(r.returncode == 2 and "may reach a network" in out,
          "palp-netem with CYCLONEDDS_URI naming that config refused, exit %d: %s" % (r.returncode, out.strip()[-300:]))


def case_netem_args(a, tmp):
    # Session 83 review "wire" #7: a hidden 5 ms default jitter made --delay-ms 2 (or 0) fail with one
    # message naming no value, and fractional domains were truncated (201.9 -> 201). Each request that
    # passes the checks here goes on to the DDS config, refused (case_netem_network): so no participant
    # is made, and reaching that refusal shows the arguments were taken.
    cfg = netem_config(a, tmp)
    base = [a.netem, "--duration", "1", "--dds-config", cfg]
    past = "may reach a network"
    for args, ok, want, what in [
            (["--stations", "201", "--server", "202", "--delay-ms", "2"], True, past,
             "--delay-ms 2 alone taken (the default jitter: min(5 ms, the delay))"),
            (["--stations", "201", "--server", "202", "--delay-ms", "0", "--loss", "0.1"], True, past,
             "--delay-ms 0 --loss 0.1 taken"),
            (["--stations", "201", "--server", "202", "--delay-ms", "2", "--jitter-ms", "5"], False,
             "--jitter-ms 5 exceeds --delay-ms 2: give --jitter-ms <= 2", "--jitter-ms 5 with --delay-ms 2 refused"),
            (["--stations", "201", "--server", "202", "--jitter-ms", "30"], False,
             "--jitter-ms 30 exceeds --delay-ms 20 (the default): give --jitter-ms <= 20",
             "--jitter-ms 30 with the default delay refused, naming the default"),
            (["--stations", "201", "--server", "201"], False,
             "--stations 201 and --server 201: the two domains must differ", "equal domains refused, naming them"),
            (["--stations", "201.9", "--server", "201.2"], False,
             '--stations: expected a whole number from 0 to 232, got "201.9"', "a fractional domain refused"),
            (["--stations", "201", "--server", "202", "--seed", "1.5"], False,
             "--seed: expected a whole number", "a fractional seed refused")]:
        rc, out = run(base + args, timeout=30)
        check(rc == 2 and want in out and (ok or past not in out),
              "palp-netem %s: %s, exit %d: %s" % (" ".join(args), what, rc, out.strip()[-300:]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", required=True)
    ap.add_argument("--run")
    ap.add_argument("--sweep")
    ap.add_argument("--bench-step", dest="bench_step")
    ap.add_argument("--bench-effects", dest="bench_effects")
    ap.add_argument("--netem")
    ap.add_argument("case")
    a = ap.parse_args()
    fn = globals().get("case_" + a.case)
    if not fn:
        print("unknown case " + a.case)
        return 2
    with tempfile.TemporaryDirectory(prefix="palp_tools_") as tmp:
        fn(a, tmp)
    print("%d check(s) failed" % failures if failures else "passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
