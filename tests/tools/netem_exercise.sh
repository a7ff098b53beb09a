#!/bin/sh
# palp-netem relays a session's every topic (2026-12-07): a trainee behind the relay (station on DDS
# domain 159, palp-server on 160, 20 +- 5 ms one way and 5% loss, seeded) marks a lump of a practice
# exercise (debrief "lesions") and withdraws nothing. Until now the relay carried only the five
# streams (contact, feedback, deformation, local model, finger sample): her mark went out and nobody
# answered it, her station waited for a debrief and a score that never came. Asserted, from the
# station's output: the server accepts her mark (its answer, palp_finding_status, crossed back), she
# is debriefed (palp_debrief: 1 of exercise_wire.json's 2 lumps, at the press over lump 1) and told
# her score (palp_debrief_score); from the server's log, that it heard the mark; from the relay's
# summary, that it ran with the delay asked (its one-way delay's range starts at 15 ms).
set -u
server=$1 client=$2 netem=$3 config_dir=$4 test_dir=$5
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= npid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; [ -n "$npid" ] && kill $npid 2>/dev/null; rm -rf "$tmp"' EXIT
sed -e 's|"\.\./assess/phantom_stiff\.json"|"'"$test_dir"'/../assess/phantom_stiff.json"|' \
  -e 's|"time_limit_s": 120,|"time_limit_s": 120, "debrief": "lesions",|' "$test_dir/exercise_wire.json" > "$tmp/practice.json"
cat > "$tmp/server.json" <<JSON
{ "domain_id": 160, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db",
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step.json" } ],
  "exercises": [ { "id": 7, "file": "$tmp/practice.json", "physics_rate_hz": 250 } ] }
JSON
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
"$netem" --stations 159 --server 160 --delay-ms 20 --jitter-ms 5 --loss 0.05 --seed 7 > "$tmp/netem.log" 2>&1 &
npid=$!
"$client" --role trainee --domain 159 --phantom 7 --name ivy --timeout 15 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=2,mark_s=1.5 > "$tmp/ivy.log" 2>&1
kill $npid; wait $npid; npid=
kill $spid; wait $spid; spid=
fail=0
check() { # pattern file what
  if grep -q "$1" "$2"; then echo "ok   $3"; else echo "FAIL $3 (no \"$1\" in $2):"; cat "$2"; fail=1; fi
}
check 'joined session [0-9]* on phantom 7' "$tmp/ivy.log" "the trainee joins the exercise's session through the relay"
check 'mark 1 sent at' "$tmp/ivy.log" "  marks a lump while touching"
check 'finding 1 accepted: 1 mark standing' "$tmp/ivy.log" "  and the server's answer comes back: accepted"
check 'debrief: you found 1 of 2 lumps with 1 mark standing' "$tmp/ivy.log" "  she is debriefed as the session closes"
check 'score: [0-9.]* of 100' "$tmp/ivy.log" "  and told her score"
check 'debrief sent (with the lesions.* places): lesions found 1 of 2; marks standing 1' "$tmp/server.log" \
  "the server heard her mark and debriefed her"
if grep -q "no debrief came\|no score came" "$tmp/ivy.log"; then echo "FAIL her station waited in vain:"; cat "$tmp/ivy.log"; fail=1
else echo "ok     her station was not left waiting"; fi
check 'one-way delay 1[5-9]\.[0-9]\.\.' "$tmp/netem.log" "the relay delayed every sample by at least 15 ms (20 - 5)"
exit $fail
