#!/usr/bin/env python3
"""A real palp-server session lands in the log and comes back out.

Starts palp-server (1 kHz, loopback, domain 162, its own database) and one palp-client trainee
pressing with the paper's profile, which records what it sent (--contact-csv) and the feedback it
received (--feedback-csv). Then, from the database, through palp-review:
  - the session is there, ended normally, with the trainee's name and the tick rate;
  - every logged contact force equals one the client sent (relative 1e-8: the client prints
    9 significant digits), for at least 100 contacts;
  - every logged feedback sample whose frame the client also received equals it (relative 1e-5:
    the client prints 6 significant digits), for at least 50 frames (10 in the sleep run);
  - replay reproduces every logged frame bit-identically.
With the optional MODE "sleep" the trainee presses for 0.8 s only and stays 2.6 s more, until
the phantom has fallen asleep, before leaving, so its closing release arrives with nothing pressed: the
server must not wake the world for an input that changes nothing in it (it did, and the replay
diverged at the station's last frame).
usage: check_server_log.py PALP_SERVER PALP_CLIENT PALP_REVIEW CONFIG_DIR TMPDIR [sleep]"""
import csv
import json
import os
import subprocess
import sys
import time

server, client, review, config_dir, tmp = sys.argv[1:6]
sleep_mode = len(sys.argv) > 6 and sys.argv[6] == "sleep"
domain = "163" if sleep_mode else "162"
work = os.path.join(tmp, "server_log_sleep" if sleep_mode else "server_log")
os.makedirs(work, exist_ok=True)
db = os.path.join(work, "server.db")
for suffix in ("", "-wal", "-shm"):
    if os.path.exists(db + suffix):
        os.unlink(db + suffix)

cfg = json.load(open(os.path.join(config_dir, "server.json")))
# The main run: a 100 Hz server whose phantoms step at 1 kHz (issue 11's per-phantom physics
# rate); the log's cadence must follow the session's 1 kHz, not the server's 100 Hz.
cfg.update({"domain_id": int(domain), "tick_rate_hz": 1000 if sleep_mode else 100, "database": db,
            "dds_config": os.path.join(config_dir, "cyclonedds-loopback.xml")})
for ph in cfg["phantoms"]:
    ph["scene"] = os.path.join(config_dir, ph["scene"])
    if not sleep_mode:
        ph["physics_rate_hz"] = 1000
cfg_path = os.path.join(work, "server.json")
json.dump(cfg, open(cfg_path, "w"))

fails = []
srv = subprocess.Popen([server, "--config", cfg_path, "--duration", "7"], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True)
time.sleep(1.0)
fb_csv, ct_csv = os.path.join(work, "feedback.csv"), os.path.join(work, "contact.csv")
# The sleep run's press was 0.3 s until 2026-12-07: in a full run a 1 kHz server starved of CPU
# stepped only ~17% of its ticks during it (40 contacts and 5 feedback frames logged of the 229
# sent; 141 of 190 alone); 0.8 s keeps >= 100 contacts at that rate and the same 2.6 s to sleep.
extra = (["--profile", "step", "--t-on", "0.1", "--t-off", "0.9", "--duration", "3.5"] if sleep_mode
         else ["--duration", "2.5"])
cli = subprocess.run([client, "--role", "trainee", "--domain", domain, "--phantom", "1", "--name", "ivy",
                      "--quiet", "--feedback-csv", fb_csv, "--contact-csv", ct_csv] + extra,
                     capture_output=True, text=True, timeout=60)
out, _ = srv.communicate(timeout=60)
if cli.returncode != 0:
    fails.append("palp-client exit %d: %s" % (cli.returncode, cli.stderr[-500:]))
if srv.returncode != 0:
    fails.append("palp-server exit %d: %s" % (srv.returncode, out[-800:]))


def rv(*args):
    return subprocess.run([review, "--db", db] + list(args), capture_output=True, text=True, timeout=60)


ls = rv("list", "--trainee", "ivy")
uids = [l.split()[0] for l in ls.stdout.splitlines()[1:] if l and not l.endswith("session") and not l.endswith("sessions")]
if len(uids) != 1:
    print(out)
    print("FAIL: expected one session of ivy, list said:\n" + ls.stdout + ls.stderr)
    sys.exit(1)
uid = uids[0]
exp = rv("export", uid, "--format", "json")
doc = json.loads(exp.stdout)
s = doc["session"]
if s["trainee"] != "ivy" or s["end_reason"] != "normal" or s["tick_hz"] != 1000:
    fails.append("session fields: %r" % {k: s[k] for k in ("trainee", "end_reason", "tick_hz")})
frames, contacts, feedback = doc["frames"], doc["contacts"], doc["feedback"]
print("logged: %d frames, %d contact inputs, %d feedback samples" % (len(frames), len(contacts), len(feedback)))
if len(frames) < 100 or len(contacts) < 100:
    fails.append("too little logged: %d frames, %d contacts (want >= 100 each)" % (len(frames), len(contacts)))

# Cadence (db/README: frames at ~100 Hz, meshes at ~2 Hz of the session's physics rate): at 1 kHz
# every logged frame is a multiple of 10, and 2.5 s of pressing leaves at most 2 Hz x 7 s + 1
# meshes. Logging every 1 kHz frame (the server's 100 Hz rate used by mistake) fails both.
off = [f["frame"] for f in frames if f["frame"] % 10 != 0]
if off:
    fails.append("%d logged frames are not multiples of 10 (first %r): the log follows the wrong rate"
                 % (len(off), off[:3]))
import sqlite3
con = sqlite3.connect("file:%s?mode=ro" % db, uri=True)
meshes = con.execute("SELECT COUNT(*) FROM mesh").fetchone()[0]
con.close()
print("cadence: %d frames off the 10-frame grid, %d meshes" % (len(off), meshes))
if not 1 <= meshes <= 15:
    fails.append("%d meshes logged (want 1..15: ~2 per second of a <= 7 s session)" % meshes)


def close(a, b, rel, floor):
    return all(abs(x - y) <= rel * max(abs(x), abs(y)) + floor for x, y in zip(a, b))


sent = [tuple(float(r[k]) for k in ("fx_N", "fy_N", "fz_N")) for r in csv.DictReader(open(ct_csv))]
unmatched = compared = 0
for c in contacts:
    if "force_n" not in c:  # a release or a removal carries no force
        continue
    compared += 1
    if not any(close(c["force_n"], v, 1e-8, 1e-12) for v in sent):
        unmatched += 1
print("contacts: %d logged forces compared with the %d the client sent, %d unmatched" % (compared, len(sent), unmatched))
# counted, not only the mismatches: an export without force_n (or a client driving by finger) would
# compare none and pass (measured 2026-12-07: 1,860 compared; 283 in the sleep run of a 0.3 s press, 291-744 of a 0.8 s press)
if compared < 100 or unmatched:
    fails.append("contacts: %d logged forces compared (want >= 100), %d never sent by the client (relative 1e-8)"
                 % (compared, unmatched))

got = {int(r["frame"]): (float(r["fx_N"]), float(r["fy_N"]), float(r["fz_N"]))
       for r in csv.DictReader(open(fb_csv)) if r["active"] == "1"}
common = bad = 0
for f in feedback:
    if f["frame"] in got:
        common += 1
        if not close(f["force_n"], got[f["frame"]], 1e-5, 1e-9):
            bad += 1
print("feedback: %d logged frames also received by the client, %d differ" % (common, bad))
want = 10 if sleep_mode else 50  # the sleep run presses for 0.8 s only
if common < want or bad:
    fails.append("feedback: %d common frames (want >= %d), %d differ beyond relative 1e-5" % (common, want, bad))

rp = rv("replay", uid)
print(rp.stdout.strip())
if rp.returncode != 0 or "bit-identically" not in rp.stdout:
    fails.append("replay exit %d: %s %s" % (rp.returncode, rp.stdout[-600:], rp.stderr[-300:]))
for f in fails:
    print("FAIL:", f)
sys.exit(1 if fails else 0)
