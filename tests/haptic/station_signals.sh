#!/bin/sh
# A position-driven trainee (the simulated device pressing, its 1 kHz haptic thread) ends gracefully on
# the signals a closed terminal window and a closed pipe send (domain 175):
#  - SIGHUP mid-press: the station ends as on SIGTERM (exit 0, its closing summary, within 3 s) and the
#    server logs the session closed as "trainee station left". Until 2026-12-06 SIGHUP's default action
#    killed it (exit 129): no LEAVE, the haptic thread's last 0 N never written, and the server logged
#    "trainee station lost" and held the session for station_grace;
#  - its output piped into `head -n 1`, which exits after the joined line: the station's later lines
#    fail (EPIPE) and it goes on to its --duration 3 (the server logs the session closed after >= 2.9 s,
#    "trainee station left") and exits 0. Until 2026-12-06 the first line after head went (SIGPIPE)
#    killed it mid-press, and the server logged it lost.
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= cpid=
trap '[ -n "$cpid" ] && kill -KILL $cpid 2>/dev/null; [ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../wait_for.sh"
. "$(dirname "$0")/../one_dome.sh"
one_dome_server 175 "$config_dir/paper_step_long_term.json" 250
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
# the server's close line of session $1, waited for up to 8 s (a lost station's: station_grace, 5 s)
closed_line() {
  n=0
  until grep -q "session $1 closed after" "$tmp/server.log" || [ $n -gt 80 ]; do n=$((n + 1)); sleep 0.1; done
  grep "session $1 closed after" "$tmp/server.log" | head -n 1
}

# 1. SIGHUP mid-press (a hold of 20 s: still pressing when it comes).
"$client" --role trainee --domain 175 --phantom 1 --name hup --timeout 20 --print-period 0.2 \
  --input sim:press,depth_mm=3,hold_s=20 > "$tmp/hup.log" 2>&1 &
cpid=$!
if wait_for "$tmp/hup.log" "finger touching"; then
  kill -HUP $cpid
  n=0
  while kill -0 $cpid 2>/dev/null && [ $n -lt 60 ]; do n=$((n + 1)); sleep 0.05; done
  if kill -0 $cpid 2>/dev/null; then
    kill -KILL $cpid; bad "SIGHUP: the station still ran 3 s after it"
  fi
  wait $cpid; rc=$?; cpid=
  sid=$(sed -n 's/.*joined session \([0-9]*\) .*/\1/p' "$tmp/hup.log" | head -n 1)
  line=$(closed_line "$sid")
  if [ "$rc" = 0 ] && grep -q "\[trainee hup\] session $sid: haptic loop" "$tmp/hup.log"; then
    ok "SIGHUP mid-press: exit $rc, its closing summary said (as on SIGTERM)"
  else bad "SIGHUP mid-press: exit $rc (want 0, as SIGTERM's), closing summary said: $(grep -c 'haptic loop' "$tmp/hup.log")"; fi
  if printf '%s' "$line" | grep -q "(trainee station left)" && ! grep -q "session $sid: trainee station lost" "$tmp/server.log"
  then ok "the server: $(printf '%s' "$line" | sed 's/^.*palp-server: //')"
  else bad "the server did not see hup leave session $sid: '$line' $(grep "session $sid: trainee station lost" "$tmp/server.log")"; fi
else
  kill -KILL $cpid; cpid=; bad "the SIGHUP station never pressed"
fi

# 2. stdout into head -n 1: the joined line, then the pipe closed; --duration 3 of a 10 s hold.
{ "$client" --role trainee --domain 175 --phantom 1 --name pipe --timeout 20 --print-period 0.1 --duration 3 \
    --input sim:press,depth_mm=3,hold_s=10 2> "$tmp/pipe.err"; echo $? > "$tmp/pipe.rc"; } | head -n 1 > "$tmp/pipe.head"
rc=$(cat "$tmp/pipe.rc")
sid=$(sed -n 's/.*joined session \([0-9]*\) .*/\1/p' "$tmp/pipe.head")
line=$(closed_line "$sid")
secs=$(printf '%s' "$line" | sed -n 's/.*closed after \([0-9.]*\) s.*/\1/p')
if [ "$rc" = 0 ]; then ok "stdout into head -n 1 ('$(cat "$tmp/pipe.head")'): exit $rc"
else bad "stdout into head -n 1: exit $rc (want 0; 141 is SIGPIPE's)"; fi
if [ -n "$sid" ] && printf '%s' "$line" | grep -q "(trainee station left)" && [ -n "$secs" ] &&
   awk -v s="$secs" 'BEGIN { exit !(s >= 2.9) }'; then
  ok "the server: $(printf '%s' "$line" | sed 's/^.*palp-server: //') (want >= 2.9 s of the 3 s duration, left)"
else bad "the piped station's session $sid: '$line' (want closed after >= 2.9 s, trainee station left)"; fi

kill $spid; wait $spid; spid=
[ $fail -eq 0 ] || { echo "--- hup.log"; cat "$tmp/hup.log"; echo "--- pipe.err"; cat "$tmp/pipe.err"
                     echo "--- server.log"; tail -30 "$tmp/server.log"; }
exit $fail
