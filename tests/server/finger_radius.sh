#!/bin/sh
# A station whose fingertip the server refuses is told so (session 81's review; domain 207). palp-client
# takes --finger-radius from 0.1 mm, the server (config/server.json's defaults) from 2 mm: a trainee
# pressing with a 1 mm fingertip had every contact sample refused (bad_radius, named only in the
# server's log) while her station printed "finger free ... 0.00 N" to the end and exited 0. Now the
# station says, from the session state's rejected_samples, that the server refuses her samples and
# that its log says why, naming her radius; with an 8 mm fingertip nothing of the kind is said.
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
"$server" --config "$config_dir/server.json" --domain 207 --no-db > "$tmp/server.log" 2>&1 &
spid=$!
fail=0
for r in 1 8; do
  "$client" --role trainee --domain 207 --phantom 1 --name r$r --timeout 10 --print-period 0 --finger-radius $r \
    --input sim:press,depth_mm=3,hold_s=2 > "$tmp/r$r.log" 2>&1
done
kill $spid; wait $spid; spid=
if grep -q "the server refused [0-9]* contact samples of session [0-9]* so far: they reach nothing. Its log says why: a finger radius outside its range (this station's is 1 mm)" "$tmp/r1.log" &&
  grep -q "bad_radius" "$tmp/server.log"; then
  echo "ok   a 1 mm fingertip: the station says the server refuses its samples, naming its radius (the server's log: bad_radius)"
else echo "FAIL a 1 mm fingertip: no word of the refusals:"; cat "$tmp/r1.log"; fail=1; fi
if grep -q "contact samples sent" "$tmp/r8.log" && ! grep -q "the server refused" "$tmp/r8.log"; then
  echo "ok   an 8 mm fingertip: its session runs, nothing refused is said"
else echo "FAIL an 8 mm fingertip:"; cat "$tmp/r8.log"; fail=1; fi
exit $fail
