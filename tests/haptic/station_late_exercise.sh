#!/bin/sh
# A position-driven trainee whose station receives its exercise late still gets it (domain 217).
# A station looks for the joined phantom's exercise (palp_exercise, transient-local, one per
# phantom) as its haptic loop runs; until 2026-12-08 one that found none in the first second
# decided the phantom ran none, and a trainee on a loaded machine (install_demo, session 87) was
# shown no exercise, no coverage and no debrief while the server graded her session. Here the
# server is stopped (SIGSTOP) for 2 s as the station joins, so the exercise's sample, which the
# server sends to the station's reader of its own writer made after the join, comes 2 s late
# (participant leases of 5 s, this test's own DDS config, so that neither side takes the other for
# gone). The station must then show the exercise, say it came late, debrief its trainee, and exit 0;
# and on a phantom without an exercise it shows none (exit 0). On the code before (2026-12-08, 3 runs
# of 3): no exercise, no debrief, exit 0, the server grading her session all the same.
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill -CONT $spid 2>/dev/null; [ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
. "$test_dir/stall.sh"
sed 's|<LeaseDuration>1s</LeaseDuration>|<LeaseDuration>5s</LeaseDuration>|' "$config_dir/cyclonedds-loopback.xml" \
  > "$tmp/dds.xml"
export CYCLONEDDS_URI="file://$tmp/dds.xml"
fail=0
if ! grep -q "<LeaseDuration>5s</LeaseDuration>" "$tmp/dds.xml"; then
  echo "FAIL the loopback config names no 1 s lease to lengthen"; exit 1
fi
cat > "$tmp/server.json" <<JSON
{ "domain_id": 217, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db",
  "dds_config": "$tmp/dds.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step.json", "physics_rate_hz": 250 } ],
  "exercises": [ { "id": 7, "file": "$test_dir/server/exercise_wire.json", "physics_rate_hz": 250 } ] }
JSON
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 217 --phantom 7 --name lea --timeout 15 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=3,mark_s=2.5 > "$tmp/lea.log" 2>&1 &
cpid=$!
# Stopped the moment the station says it joined (a busy poll, at most 20 s): it has its session's
# endpoints matched by then, and starts its loop, whose reader of the server's own exercise writer
# (made in the loop's first turn) waits for the server to send it the sample. Stopped at the
# server's "session opened" instead, the station's join waited for the server and its loop started
# after it, in time.
_end=$(($(date +%s) + 20))
until grep -q "joined session" "$tmp/lea.log" || [ "$(date +%s)" -ge $_end ]; do :; done
kill -STOP $spid
sleep 2
kill -CONT $spid
wait $cpid
rc=$?
# the same server, a phantom without an exercise: none shown, however long the station looks
"$client" --role trainee --domain 217 --phantom 1 --name ned --timeout 15 --print-period 0 \
  --input sim:press,depth_mm=3,hold_s=1.5 > "$tmp/ned.log" 2>&1
nrc=$?
kill $spid; wait $spid; spid=
check() { # pattern file what
  if grep -q "$1" "$2"; then echo "ok   $3"; else echo "FAIL $3 (no \"$1\" in $2)"; fail=1; fi
}
if [ $rc -eq 0 ] && [ $nrc -eq 0 ]; then echo "ok   both trainees exited 0"
else echo "FAIL exits: lea $rc, ned $nrc"; fail=1; fi
check 'joined session' "$tmp/lea.log" "lea joined the exercise"
check 'exercise "test-wire": Test: findings over the wire' "$tmp/lea.log" "her station shows the exercise, 2 s late"
# "(the exercise reached this station N s into the session ...": N at least the stop's 2 s, less
# the poll that saw the join (0.1 s) and the station's own start
late=$(sed -n 's/.*(the exercise reached this station \([0-9.]*\) s into the session.*/\1/p' "$tmp/lea.log")
if [ -n "$late" ] && awk -v l="$late" 'BEGIN { exit !(l >= 1.5 && l <= 10) }'; then
  echo "ok   and says it came $late s into the session (1.5-10 s)"
else echo "FAIL no line saying the exercise came 1.5-10 s into the session ('$late')"; fail=1; fi
check 'debrief: ' "$tmp/lea.log" "she is debriefed as the session ends"
if grep -q 'exercise "' "$tmp/ned.log"; then echo "FAIL ned's phantom runs no exercise, yet his station shows one"; fail=1
else echo "ok   the phantom without an exercise shows none"; fi
[ $fail -eq 0 ] || { cat "$tmp/lea.log"; tail -n 20 "$tmp/server.log"; }
exit $fail
