#!/bin/sh
# An exercise session logged by palp-recorder is assessed as the server's own log is (session 60;
# docs/db.md, "palp-recorder"). palp-server hosts exercise_random.json (two lesions drawn for each
# session, debrief "lesions") on domain 182 with its own SQLite log and "session_exercise":
# "always" (no DDS Security here: a trusted bench); palp-recorder logs the same domain into a
# second file. Trainee dora takes the exercise with the simulated novice (five light presses at
# random places, a mark at the last), then with a press and a mark at polar 30, azimuth 0.
# Checked, between the two logs of each session:
#  - the recorder's exercise is the server's, byte for byte (the lesions as drawn, the seed);
#  - the same findings (mark id, operation, point within 1e-12 m) and the same debrief line;
#  - finger samples at the assessment's rate: at least 90 % of the server's count, and at every
#    frame both logged, the same device point, proxy, force and contact point (1e-12) and, since
#    session 71 (palp_finger_sample), the same touched triangles, byte for byte;
#  - palp-review show of each: the same "found" and "debrief" lines; each band's coverage and the
#    score within 0.1 point (their printed rounding: the same samples; until session 71, 3 points,
#    the recorder logging as many triangles under the fingertip as the local model counted, which
#    the review of its log said), and neither review says its footprints are patches.
# Then the same server without "session_exercise" (the default, "secured", and no DDS Security):
# the lesions stay on the server: its log names them, the recorder's has no exercise for the
# session (its review names the exercise and says its lesions are missing), and the server's log
# says why at start.
# usage: exercise_recorded.sh SERVER CLIENT RECORDER REVIEW CONFIG_DIR TEST_DIR
set -u
server=$1 client=$2 recorder=$3 review=$4 config_dir=$5 test_dir=$6
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= rpid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; [ -n "$rpid" ] && kill $rpid 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
serve() { # DB SESSION_EXERCISE_LINE
  cat > "$tmp/server.json" <<JSON
{ "domain_id": 182, "tick_rate_hz": 100, "tick_threads": 1, "database": "$1", $2
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step.json" } ],
  "exercises": [ { "id": 7, "file": "$test_dir/exercise_random.json", "physics_rate_hz": 250 } ] }
JSON
}
run() { # NAME: the recorder and the server up, dora's sessions, both stopped
  "$recorder" --domain 182 --db "$tmp/$1-rec.db" > "$tmp/$1-recorder.log" 2>&1 &
  rpid=$!
  "$server" --config "$tmp/server.json" > "$tmp/$1-server.log" 2>&1 &
  spid=$!
  "$client" --role trainee --domain 182 --phantom 7 --name dora --timeout 10 --print-period 0 --input sim:novice \
    > "$tmp/$1-dora1.log" 2>&1 || { echo "FAIL dora's first station ($1):"; cat "$tmp/$1-dora1.log"; fail=1; }
  if [ "$1" = always ]; then
    "$client" --role trainee --domain 182 --phantom 7 --name dora --timeout 10 --print-period 0 \
      --input sim:press,polar=30,azimuth=0,depth_mm=6,hold_s=1.5,mark_s=1 > "$tmp/$1-dora2.log" 2>&1 ||
      { echo "FAIL dora's second station ($1):"; cat "$tmp/$1-dora2.log"; fail=1; }
  fi
  sleep 2 # the recorder takes the debrief and the CLOSED state
  kill $spid; wait $spid; spid=
  kill $rpid; wait $rpid; rpid=
}
serve "$tmp/always.db" '"session_exercise": "always",'
run always
serve "$tmp/secured.db" ''
run secured
python3 - "$tmp" <<'PY' || fail=1
import sqlite3, sys
tmp = sys.argv[1]
bad = 0
def check(ok, what):
    global bad
    print(("ok   " if ok else "FAIL ") + what)
    bad += not ok
def sessions(db):
    return db.execute("select id, uid from session where trainee = 'dora' order by start_unix_s").fetchall()
srv, rec = sqlite3.connect(tmp + "/always.db"), sqlite3.connect(tmp + "/always-rec.db")
ss, rs = sessions(srv), sessions(rec)
check(len(ss) == 2 and len(rs) == 2, "two sessions of dora's in each log (server %d, recorder %d)" % (len(ss), len(rs)))
with open(tmp + "/uids", "w") as f:
    for (sid, suid), (rid, ruid) in zip(ss, rs):
        f.write("%s %s\n" % (suid, ruid))
for (sid, suid), (rid, ruid) in zip(ss, rs):
    ex = lambda db, i: db.execute("select exercise_name, exercise_json from session_exercise where session_id = ?", (i,)).fetchone()
    se, re_ = ex(srv, sid), ex(rec, rid)
    check(se is not None and se == re_, "%s: the recorder's exercise is the server's, byte for byte (%s)" %
          (ruid, "same" if se == re_ else "server %r, recorder %r" % (se and se[0], re_ and re_[0])))
    fq = "select mark_id, op, point_x_m, point_y_m, point_z_m from finding where session_id = ? order by id"
    sf, rf = srv.execute(fq, (sid,)).fetchall(), rec.execute(fq, (rid,)).fetchall()
    same = len(sf) == len(rf) and all(a[:2] == b[:2] and all((p is None and q is None) or abs(p - q) <= 1e-12 for p, q in zip(a[2:], b[2:]))
                                      for a, b in zip(sf, rf))
    check(len(sf) >= 1 and same, "%s: the same findings (server %s, recorder %s)" % (ruid, sf, rf))
    dq = "select detail from event where session_id = ? and kind = 'debrief'"
    sd, rd = srv.execute(dq, (sid,)).fetchall(), rec.execute(dq, (rid,)).fetchall()
    check(len(sd) == 1 and sd == rd, "%s: the same debrief (server %s, recorder %s)" % (ruid, sd, rd))
    sq = "select frame, device_x_m, device_y_m, device_z_m, proxy_x_m, proxy_y_m, proxy_z_m, force_x_n, force_y_n, force_z_n, point_x_m, point_y_m, point_z_m from finger_sample where session_id = ? order by frame"
    a = {r[0]: r[1:] for r in srv.execute(sq, (sid,))}
    b = {r[0]: r[1:] for r in rec.execute(sq, (rid,))}
    common = sorted(set(a) & set(b))
    worst = max((abs(p - q) for f in common for p, q in zip(a[f], b[f])), default=float("inf"))
    tq = "select frame, triangles from finger_sample where session_id = ? and in_contact = 1 order by frame"
    ta = {r[0]: r[1] for r in srv.execute(tq, (sid,))}
    tb = {r[0]: r[1] for r in rec.execute(tq, (rid,))}
    tcommon = sorted(set(ta) & set(tb))
    tdiff = sum(ta[f] != tb[f] for f in tcommon)
    check(len(tcommon) >= 0.9 * len(ta) and len(ta) > 0 and tdiff == 0,
          "%s: at the %d frames in contact both logged (server %d), the same touched triangles (%d differ)" %
          (ruid, len(tcommon), len(ta), tdiff))
    check(len(a) > 50 and len(b) >= 0.9 * len(a), "%s: finger samples at the assessment's rate (server %d, recorder %d)" % (ruid, len(a), len(b)))
    check(len(common) >= 0.9 * len(a) and worst <= 1e-12,
          "%s: at the %d frames both logged, the same device, proxy, force and contact point (largest difference %.3g)" % (ruid, len(common), worst))
srv, rec = sqlite3.connect(tmp + "/secured.db"), sqlite3.connect(tmp + "/secured-rec.db")
ss, rs = sessions(srv), sessions(rec)
check(len(ss) == 1 and len(rs) == 1, "without DDS Security: dora's session in both logs (server %d, recorder %d)" % (len(ss), len(rs)))
n_srv = srv.execute("select count(*) from session_exercise").fetchone()[0]
n_rec = rec.execute("select count(*) from session_exercise").fetchone()[0]
check(n_srv == 1 and n_rec == 0, "the lesions stay on the server: its log has the exercise (%d), the recorder's none (%d)" % (n_srv, n_rec))
sys.exit(1 if bad else 0)
PY
# ... and the review of the recorder's copy says which exercise it was, and that its lesions are missing
"$review" --db "$tmp/secured-rec.db" show 1 > "$tmp/show-secured.txt" 2>&1
if grep -q "^exercise   test-random, WITHOUT ITS LESIONS: they did not reach palp-recorder" "$tmp/show-secured.txt" &&
  grep -q "^metrics    from [1-9][0-9]* finger samples" "$tmp/show-secured.txt"; then
  echo "ok   the review of the recorder's copy names the exercise and says its lesions did not reach the recorder"
else
  echo "FAIL the review of the recorder's copy names the exercise and says its lesions did not reach the recorder:"
  cat "$tmp/show-secured.txt"; fail=1
fi
grep -q "exercise sessions' lesions stay on this server (no DDS Security: session_exercise \"always\" sends them anyway)" \
  "$tmp/secured-server.log" && ! grep -q "lesions stay on this server" "$tmp/always-server.log"
r=$?
[ $r -eq 0 ] && echo "ok   the server says at start when its exercises' lesions stay on it, and only then" ||
  { echo "FAIL the server says at start when its exercises' lesions stay on it, and only then"; fail=1; }
# The review of each log of each session: the same lumps found and debrief; coverage and score within
# their printed 0.1 point.
while read -r suid ruid; do
  "$review" --db "$tmp/always.db" show "$suid" > "$tmp/show-srv.txt" 2>&1
  "$review" --db "$tmp/always-rec.db" show "$ruid" > "$tmp/show-rec.txt" 2>&1
  python3 - "$tmp/show-srv.txt" "$tmp/show-rec.txt" "$ruid" <<'PY' || fail=1
import re, sys
srv, rec, uid = open(sys.argv[1]).read(), open(sys.argv[2]).read(), sys.argv[3]
bad = 0
def check(ok, what):
    global bad
    print(("ok   " if ok else "FAIL ") + what)
    bad += not ok
def line(text, key):
    m = re.search(r"^ *%s +(.*)$" % key, text, re.M)
    return m.group(1) if m else None
for key in ("exercise", "sensitivity", "false positives", "debrief"):
    a, b = line(srv, key), line(rec, key)
    check(a is not None and a == b, "%s: review show's %s line is the server log's (%r; recorder %r)" % (uid, key, a, b))
def numbers(text, key, pattern):
    m = re.search(r"^ *%s +%s" % (key, pattern), text, re.M)
    return [float(x) for x in m.groups()] if m else None
band = r"light ([0-9.]+)%, medium ([0-9.]+)%, deep ([0-9.]+)%, any ([0-9.]+)%"
a, b = numbers(srv, "thoroughness", band), numbers(rec, "thoroughness", band)
worst = max(abs(x - y) for x, y in zip(a, b)) if a and b else float("inf")
check(worst <= 0.1001, "%s: each band's coverage within 0.1 point of the server log's (server %s, recorder %s)" % (uid, a, b))
a, b = numbers(srv, "score", r"([0-9.]+) / 100"), numbers(rec, "score", r"([0-9.]+) / 100")
check(a and b and abs(a[0] - b[0]) <= 0.1001, "%s: the score within 0.1 point of the server log's (server %s, recorder %s)" % (uid, a, b))
check("recorded over DDS" in rec and "recorded over DDS" not in srv, "%s: the recorder's log says it was recorded over DDS" % uid)
check("patch of" not in rec and "patch of" not in srv,
      "%s: neither review says its footprints are patches (the recorder logged the server's finger samples)" % uid)
n = uid.split("-")[2]
check(re.search(r'^session +%s  \("session %s" on the stations; recorded over DDS\)$' % (uid, n), rec, re.M) is not None,
      "%s: review show names it \"session %s\", as dora's station did" % (uid, n))
sys.exit(1 if bad else 0)
PY
  # the number her station showed finds the recorder's log of the session too
  n=$(echo "$ruid" | cut -d- -f3)
  "$review" --db "$tmp/always-rec.db" show "$n" > "$tmp/show-n.txt" 2>&1
  grep -q "^session    $ruid " "$tmp/show-n.txt" && grep -q "$n\" on the stations is $ruid" "$tmp/show-n.txt" &&
    grep -q "joined session $n on phantom 7" "$tmp/always-dora1.log" "$tmp/always-dora2.log"; r=$?
  [ $r -eq 0 ] && echo "ok   show $n (dora's station's number) finds the recorder's $ruid" ||
    { echo "FAIL show $n (dora's station's number) finds the recorder's $ruid:"; cat "$tmp/show-n.txt"; fail=1; }
done < "$tmp/uids"
exit $fail
