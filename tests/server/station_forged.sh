#!/bin/sh
# The joined phantom's catalogue entry and exercise come from the session's server alone (review s83 #1;
# domain 180). The server hosts phantom 1 ("dome", no exercise) and the exercise test-wire as phantom 7
# (tests/server/exercise_wire.json), 338 vertices each. A forger participant (tests/server/
# catalogue_forger.c) writes an entry ("FORGED", 4 vertices, a 0.1 N max_force) and an exercise ("FORGED
# EXERCISE") for both every 5 ms, from before the stations start to after they end. Before, the forger's
# newer sample replaced the server's in the station's keep-last-1 readers: a trainee joined "FORGED", took
# its 0.1 N for her safe force and was told the forged exercise, and said nothing of it. Now:
# - eve, position-driven (--input sim:press) on phantom 7, joins the server's phantom with its 338
#   vertices, her safe force is not the forger's 0.1 N, she is told test-wire and not the forged exercise,
#   says she ignored samples from the forger's participant, and exits 0;
# - eve was given --rejoin, which a position-driven trainee does not do: she says so (review s83 #12);
# - ray, force-driven at --rate 2 on phantom 1 (a contact every 0.5 s, past the 0.4 s a stall is), beside
#   her: his state is still checked every 100 ms, so no check is taken for a stall of his station (#6:
#   before, "this station did not run for 0.50 s" every half second); he joins "dome" (338 vertices).
# ~2 s.
set -u
server=$1 client=$2 forger=$3 config_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
test_dir=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
spid= fpid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; [ -n "$fpid" ] && kill $fpid 2>/dev/null; rm -rf "$tmp"' EXIT
cat > "$tmp/server.json" <<JSON
{ "domain_id": 180, "tick_rate_hz": 100, "tick_threads": 1, "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step_long_term.json" } ],
  "exercises": [ { "id": 7, "file": "$test_dir/exercise_wire.json", "physics_rate_hz": 250 } ] }
JSON
"$server" --config "$tmp/server.json" --no-db > "$tmp/server.log" 2>&1 &
spid=$!
"$forger" 180 30 1 7 > "$tmp/forger.out" 2>&1 &
fpid=$!
"$client" --role trainee --domain 180 --phantom 1 --name ray --rate 2 --profile step --magnitude 1 --t-on 0 \
  --t-off 30 --duration 1.1 --print-period 0 --timeout 10 > "$tmp/ray.log" 2>&1 &
rpid=$!
"$client" --role trainee --domain 180 --phantom 7 --name eve --rejoin --input sim:press,depth_mm=3,hold_s=5 \
  --duration 1.1 --print-period 0 --timeout 10 > "$tmp/eve.log" 2>&1
erc=$?
wait $rpid
rrc=$?
kill $fpid; wait $fpid; fpid=
kill $spid; wait $spid; spid=
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
who=$(sed -n 's/.*written by \(participant [0-9a-f:]*\).*/\1/p' "$tmp/forger.out")
[ -n "$who" ] || bad "the forger did not say what it wrote: $(cat "$tmp/forger.out")"
if grep -q 'joined session [0-9]* on phantom 7 "Test: findings over the wire" (338 vertices' "$tmp/eve.log" &&
   ! grep -q FORGED "$tmp/eve.log"; then
  ok "eve joined the server's phantom: $(grep -o 'phantom 7 "[^"]*" ([0-9]* vertices' "$tmp/eve.log")"
else bad "eve did not join the server's phantom 7 (338 vertices), or FORGED is in her output"; fi
if grep -q 'safe force' "$tmp/eve.log" && ! grep -q 'safe force 0.1 N' "$tmp/eve.log"; then
  ok "her safe force is not the forger's 0.1 N: $(grep -o 'safe force [0-9.]* N' "$tmp/eve.log")"
else bad "her safe force is the forger's 0.1 N, or not said"; fi
if grep -q 'exercise "test-wire": Test: findings over the wire' "$tmp/eve.log" && ! grep -q 'exercise "forged"' "$tmp/eve.log"; then
  ok "the server's exercise told, not the forger's"
else bad "the server's exercise not told, or the forger's: $(grep 'exercise "' "$tmp/eve.log" | head -2)"; fi
if [ -n "$who" ] && grep -q "ignored [0-9]* samples\{0,1\} of session [0-9]* from $who, which is not this session's server" "$tmp/eve.log"; then
  ok "she said she ignored the forger's samples: $(grep -o "ignored [0-9]* samples\{0,1\}" "$tmp/eve.log" | head -1) from $who"
else bad "she did not say she ignored samples from the forger ($who)"; fi
if [ $erc -eq 0 ]; then ok "eve exit 0"; else bad "eve exit $erc"; fi
if grep -q -- '--rejoin is for force-driven trainees' "$tmp/eve.log"; then ok "eve said --rejoin is not hers"
else bad "eve said nothing of --rejoin"; fi
n=$(grep -c 'this station did not run for' "$tmp/ray.log")
if [ "$n" -eq 0 ] && [ $rrc -eq 0 ] && grep -q 'joined session [0-9]* on phantom 1 "dome" (338 vertices' "$tmp/ray.log" &&
   grep -q 'contact samples sent at 2 Hz' "$tmp/ray.log"; then
  ok "ray at --rate 2: no stall taken, exit 0, the server's phantom"
else bad "ray at --rate 2: $n stall line(s), exit $rrc"; fi
[ $fail -eq 0 ] || for f in "$tmp"/*.log "$tmp"/forger.out; do echo "== $f"; cat "$f"; done
exit $fail
