#!/bin/sh
# issue 13 from the station's side: palp-server hosts an exercise (its own config, domain 61,
# a SQLite log); palp-client with the simulated device shows the exercise's title and
# instructions, marks a lump with the device's button while touching (accepted by the
# server, in the log) and withdraws it; a button pressed while not touching is refused on
# the station with a message, nothing sent.
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
cat > "$tmp/server.json" <<JSON
{ "domain_id": 61, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db",
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step.json" } ],
  "exercises": [ { "id": 7, "file": "$test_dir/exercise_wire.json", "physics_rate_hz": 250 } ] }
JSON
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
fail=0
check() { # pattern file what
  if grep -q "$1" "$2"; then echo "ok   $3"; else echo "FAIL $3 (no \"$1\" in $2):"; cat "$2"; fail=1; fi
}
"$client" --role trainee --domain 61 --phantom 7 --name dora --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=2,mark_s=1.5,withdraw_s=2.2 > "$tmp/dora.log" 2>&1
"$client" --role trainee --domain 61 --phantom 7 --name ed --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=1,mark_s=0.1 > "$tmp/ed.log" 2>&1
kill $spid; wait $spid; spid=
check 'exercise "test-wire": Test: findings over the wire' "$tmp/dora.log" "the station shows the exercise's title"
check 'Examine the dome and mark every lump you feel.' "$tmp/dora.log" "  and its instructions"
check 'time limit 120 s' "$tmp/dora.log" "  and its time limit"
check 'finding 1 accepted: 1 mark standing' "$tmp/dora.log" "the button marks a lump while touching: accepted"
check 'finding 1 accepted: 0 marks standing' "$tmp/dora.log" "  and withdraws it"
check 'mark refused here: the fingertip is not touching' "$tmp/ed.log" "a mark while not touching is refused on the station"
if grep -q "mark 1 sent" "$tmp/ed.log"; then echo "FAIL ed sent a mark"; fail=1; else echo "ok     and not sent"; fi
exit $fail
