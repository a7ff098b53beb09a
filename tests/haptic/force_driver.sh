#!/bin/sh
# A force-mode device driver (poll and feedback only, tests/haptic/force_driver.c: a fingertip 4 mm into
# the pole from 0.3 s on) on the force-driven station's loop (domain 174; the long-term dome, ~3.7 N
# held). The driver logs every force it is given.
#  - The server stopped (SIGSTOP) 1.5 s after the join: the driver's force fades to 0 N within 0.5 s of
#    the stop (the haptic thread's rule: stale after 0.25 s without a sample, 0 N 0.1 s later; the last
#    sample came within a 10 ms step of the stop, the loop runs at 100 Hz; 0.5 s leaves a loaded
#    machine room). Before (session 77): feedback() was called only as samples came, and the driver
#    held the server's last ~3.7 N until the station closed, ~2 s later.
#  - A station ending (--duration) while the device presses gives it 0 N before closing it, where it
#    left the last force on it.
#  - A driver whose poll() fails (1 s in): the station exits 1 with the driver's own message (error()),
#    as the haptic path does; it exited 0, saying only "input/output error".
#  - A server whose max_force is 2 N (the phantom's, in the catalogue; the server reports the finger's
#    force above it, ~5 N at the press's peak): the driver is never given more than 2 N (+0.1%), the
#    haptic path's limit (the smaller of the station's safe force and the phantom's). It was given up
#    to the station's 10 N.
set -u
server=$1 client=$2 config_dir=$3 driver=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && { kill -CONT $spid; kill $spid; } 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
start_server() { # extra config
  cat > "$tmp/server.json" <<JSON
{ "domain_id": 174, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db", $1
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step_long_term.json" } ] }
JSON
  rm -f "$tmp"/log.db*
  "$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
  spid=$!
}
stop_server() { kill -CONT $spid; kill $spid; wait $spid; spid=; }
wait_joined() {
  n=0
  until grep -q "joined session" "$1" || [ $n -ge 100 ]; do sleep 0.1; n=$((n + 1)); done
}

# ---- the server stopped: the force fades to 0 N
start_server ""
"$client" --role trainee --domain 174 --phantom 1 --name fay --timeout 10 --print-period 0 --duration 8 \
  --input "device:$driver:log=$tmp/stop.log" > "$tmp/stop.out" 2>&1 &
cpid=$!
wait_joined "$tmp/stop.out"
sleep 1.5
stop=$(date +%s.%N)
kill -STOP $spid
wait $cpid
stop_server
held=$(awk -v s="$stop" '$1 != "close" && $1 < s { f = sqrt($3 * $3 + $4 * $4 + $5 * $5) } END { printf "%.2f", f }' "$tmp/stop.log")
zero=$(awk -v s="$stop" '$1 != "close" && $1 >= s && $3 == 0 && $4 == 0 && $5 == 0 { printf "%.3f", $1 - s; exit }' "$tmp/stop.log")
if awk -v h="$held" 'BEGIN { exit !(h >= 1) }'; then ok "the device was given $held N when the server stopped"
else bad "the device was given $held N when the server stopped (want >= 1 N: did it press?)"; fi
if [ -n "$zero" ] && awk -v z="$zero" 'BEGIN { exit !(z <= 0.5) }'; then ok "0 N reached it $zero s after the stop (want <= 0.5 s)"
else bad "no 0 N within 0.5 s of the server's stop (at '$zero' s)"; fi
after=$(awk -v s="$stop" -v z="$zero" '$1 != "close" && z != "" && $1 > s + z && ($3 != 0 || $4 != 0 || $5 != 0)' "$tmp/stop.log" | wc -l)
if [ "$after" -eq 0 ]; then ok "no force given after it while the server stayed stopped"; else bad "$after forces given after the 0 N"; fi

# ---- the station ends while the device presses: 0 N before the driver is closed
start_server ""
"$client" --role trainee --domain 174 --phantom 1 --name gus --timeout 10 --print-period 0 --duration 2.5 \
  --input "device:$driver:log=$tmp/end.log" > "$tmp/end.out" 2>&1
rc=$?
stop_server
peak=$(awk '$1 != "close" { f = sqrt($3 * $3 + $4 * $4 + $5 * $5); if (f > p) p = f } END { printf "%.2f", p }' "$tmp/end.log")
last=$(awk '$1 == "close" { printf "%g", sqrt($2 * $2 + $3 * $3 + $4 * $4) }' "$tmp/end.log")
if [ $rc -eq 0 ] && [ "$last" = 0 ] && awk -v p="$peak" 'BEGIN { exit !(p >= 1) }'; then
  ok "the station ended (exit 0) with the device given 0 N before its close (up to $peak N before)"
else bad "exit $rc, the device closed holding '$last' N (up to $peak N before; want exit 0 and 0 N)"; fi

# ---- the driver fails: exit 1 with its message
start_server ""
"$client" --role trainee --domain 174 --phantom 1 --name hal --timeout 10 --print-period 0 --duration 5 \
  --input "device:$driver:fail=1" > "$tmp/fail.out" 2>&1
rc=$?
stop_server
if [ $rc -eq 1 ] && grep -q "input test force driver failed: test driver: the device stopped answering at 1.0 s (its USB link was lost)" \
  "$tmp/fail.out"; then ok "a failing driver ends the station with exit 1 and the driver's own message"
else bad "a failing driver: exit $rc (want 1), its message: $(grep -i failed "$tmp/fail.out")"; fi

# ---- the phantom's limit below the station's: the driver's force is held to it
start_server '"max_force": 2,'
"$client" --role trainee --domain 174 --phantom 1 --name ida --timeout 10 --print-period 0 --duration 2.5 \
  --input "device:$driver:log=$tmp/limit.log" > "$tmp/limit.out" 2>&1
rc=$?
stop_server
peak=$(awk '$1 != "close" { f = sqrt($3 * $3 + $4 * $4 + $5 * $5); if (f > p) p = f } END { printf "%.4f", p }' "$tmp/limit.log")
if [ $rc -eq 0 ] && awk -v p="$peak" 'BEGIN { exit !(p >= 1.5 && p <= 2.002) }'; then
  ok "the driver was given at most $peak N, the phantom's 2 N limit (want 1.5-2.002 N: pressed to it, not past it)"
else bad "exit $rc, the driver was given up to $peak N (want 1.5-2.002 N: the phantom's limit is 2 N)"; fi

[ $fail -eq 0 ] || { cat "$tmp"/*.out; tail -20 "$tmp/server.log"; }
exit $fail
