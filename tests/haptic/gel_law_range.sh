#!/bin/sh
# The trainee is told when the scene's literal gel law leaves its stable range (LM_GEL_LAW_RANGE,
# added 2026-12-06; docs/model.md, "Steps of other lengths, and where a3 is stable"). The paper
# dome with the literal law and a3 = 0.9 (10 ms)^2 at 100 Hz (tests/data/literal_a3_scene.json):
# a whole step keeps the momentum term, a halved one (a3 / (h h_prev) = 1.8 or 3.6) leaves it out.
#  - cat's simulated device presses 15 mm at the pole and back out at 300 mm/s, 30 times: fast
#    presses halve steps, and her station says at once that the model is outside its valid range
#    because the gel's literal pressure law stepped outside its stable range, its summary counts
#    the time rendered from those models, and the instructor's review (palp-review show) says the
#    same part of the session in the same words; the two agree within 0.1 s plus 25% (the
#    station counts 1 kHz ticks rendered from the flagged models it received, best-effort and
#    only while the finger is down; the log counts the flagged 10 ms steps);
#  - dan presses 3 mm at 20 mm/s: no halved step, and neither his station nor his review
#    names the gel law.
# Before: the stations had no wire bit for it; cat's station said nothing (only the server's
# log and the review did). Domain 156.
set -u
server=$1 client=$2 config_dir=$3 review=$4 scene=$5
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
cat > "$tmp/server.json" <<JSON
{ "domain_id": 156, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db",
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "literal a3", "scene": "$scene" } ] }
JSON
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
"$client" --role trainee --domain 156 --phantom 1 --name cat --timeout 10 --print-period 0 \
  --input sim:cycles,depth_mm=15,speed_mm_s=300,cycles=30 > "$tmp/cat.log" 2>&1
crc=$?
"$client" --role trainee --domain 156 --phantom 1 --name dan --timeout 10 --print-period 0 \
  --input sim:press,depth_mm=3,speed_mm_s=20,hold_s=1 > "$tmp/dan.log" 2>&1
drc=$?
# the server writes a session's end when its station has left; stop it so the log is closed
kill -INT $spid; wait $spid; spid=
show() {
  uid=$("$review" --db "$tmp/log.db" list --trainee "$1" 2>/dev/null | awk -v n="$1" '$2 == n { print $1 }' | tail -n 1)
  "$review" --db "$tmp/log.db" show "$uid" 2>&1
}
show cat > "$tmp/cat.show"
show dan > "$tmp/dan.show"
GEL="the gel's literal pressure law stepped outside its stable range"
[ $crc -eq 0 ] && [ $drc -eq 0 ] && ok "both stations exit 0" || bad "exit $crc, $drc"
# as it happens: the episode's opening line names what its first look saw, its closing line every
# limit met in it (the first flagged models may be the skin's, a loaded machine's first look late)
if grep -q "OUTSIDE THE MODEL'S VALID RANGE: .*$GEL\|back inside the model's valid range (outside for .*$GEL" "$tmp/cat.log"
then ok "cat's station names the gel law as the episode runs"
else bad "cat's station never named the gel law"; fi
st=$(sed -n "s/.*outside the model's valid range (the device rendered those for .*; \([0-9.]*\) s $GEL).*/\1/p" "$tmp/cat.log")
rv=$(sed -n "s/^valid range OUTSIDE for .*[:;] \([0-9.]*\) s $GEL (its momentum term left out at [0-9]* frames).*/\1/p" "$tmp/cat.show")
echo "cat: station ${st:-none} s, review ${rv:-none} s rendered / stepped with the gel law outside its range"
if [ -n "$st" ] && [ -n "$rv" ] && awk -v a="$st" -v b="$rv" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 0 && d <= 0.1 + 0.25 * b) }'
then ok "cat's summary and review agree: $st s and $rv s (tolerance 0.1 s + 25%)"
else bad "cat's summary and review: '${st:-}' s and '${rv:-}' s"; grep -i "valid range" "$tmp/cat.log" "$tmp/cat.show"; fi
if grep -q "gel law\|gel's literal" "$tmp/dan.log" "$tmp/dan.show"; then bad "dan's station or review names the gel law"
  grep "gel law\|gel's literal" "$tmp/dan.log" "$tmp/dan.show"
else ok "dan's gentle press: the gel law is named nowhere (his review's gel line is its pressure)"; fi
grep -q "^valid range " "$tmp/dan.show" && ok "dan's review has its valid-range line" || bad "dan's review: no valid-range line"
[ $fail -eq 0 ] || { echo "--- cat"; cat "$tmp/cat.log"; echo "--- server"; tail -20 "$tmp/server.log"; }
exit $fail
