#!/bin/sh
# A position-driven trainee (the simulated device's press, its 1 kHz haptic thread over 250 Hz
# physics) whose process is stopped for 1 s early in its press (SIGSTOP/SIGCONT, as a machine that swaps
# or loses its core would; domain 115): the session goes on (exit 0), the station says it did not
# run, and its summary tells the stall apart from the haptic loop's late ticks: one stall of
# ~1 s (0.9-3 s), and the late ticks' worst under the stall threshold (0.4 s), where it read
# "worst 1004 ms" before (the stop counted as one late tick; docs/station.md, "A stalled station").
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
. "$test_dir/stall.sh"
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../one_dome.sh"
one_dome_server 115 "$config_dir/paper_step_long_term.json" 250
fail=0
"$client" --role trainee --domain 115 --phantom 1 --name fay --timeout 10 --print-period 0 \
  --input sim:press,depth_mm=3,hold_s=4 > "$tmp/fay.log" 2>&1 &
cpid=$!
# 0.5 s after the join: early in the press, the station's main loop already running. Until
# 2026-12-06 this fell inside the station's first second, spent waiting for an exercise the phantom
# does not have, before its loop's first check (a stop there was blamed on the server until
# 2026-12-03, mended in palp_cli_station_exercise); that wait is gone since (station_first_press.sh),
# so the stop no longer exercises it: this checks a stall in the press as such.
stall_station $cpid "$tmp/fay.log" 0.5 1.0
wait $cpid
rc=$?
kill $spid; wait $spid; spid=
if [ $rc -eq 0 ]; then echo "ok   the stopped trainee went on and exited 0"; else echo "FAIL exit $rc"; fail=1; fi
if grep -q "this station did not run for" "$tmp/fay.log"; then echo "ok   it said it did not run"; else
  echo "FAIL no 'did not run'"; fail=1; fi
# "was not run 1 time(s) for X s in all (longest Y s"
stall=$(sed -n 's/.*was not run 1 time(s) for \([0-9.]*\) s in all.*/\1/p' "$tmp/fay.log")
if [ -n "$stall" ] && awk -v s="$stall" 'BEGIN { exit !(s >= 0.9 && s <= 3.0) }'; then
  echo "ok   one stall of $stall s told apart (want 0.9-3 s)"
else echo "FAIL no single stall of 0.9-3 s reported ('$stall')"; fail=1; fi
# The deadlines the stop skipped are said beside the late ticks: ~1000 for 1 s at 1 kHz (the
# stop's own length, 1 s, up to the 3 s the stall check allows).
skipped=$(sed -n 's/.*haptic loop .*, \([0-9]*\) deadline(s) skipped (the device held its last force).*/\1/p' "$tmp/fay.log")
if [ -n "$skipped" ] && [ "$skipped" -ge 900 ] && [ "$skipped" -le 3000 ]; then
  echo "ok   $skipped deadlines skipped, the stop's (want 900-3000)"
else echo "FAIL deadlines skipped: '$skipped' (want 900-3000)"; fail=1; fi
worst=$(sed -n 's/.*haptic loop .* late by > 0.5 ms ([0-9.]*%, worst \([0-9.]*\) ms).*/\1/p' "$tmp/fay.log")
if [ -n "$worst" ] && awk -v w="$worst" 'BEGIN { exit !(w < 400) }'; then
  echo "ok   the late ticks' worst is $worst ms, the stall not among them (want < 400 ms)"
else echo "FAIL the late ticks' worst '$worst' ms (want < 400: the stall counted as a late tick?)"; fail=1; fi
[ $fail -eq 0 ] || { cat "$tmp/fay.log"; tail -20 "$tmp/server.log"; }
exit $fail
