#!/bin/sh
# A trainee station stopped past its participant's lease (1.5 s; the server forgets the
# participant and holds the session) and interrupted as it runs again, while its server is
# itself stopped: the station asks to be found again (its JOIN, every 0.3 s) for
# PALP_CLI_LEAVE_WAIT_S (3 s), gets no answer, and then says so: its goodbye may be lost and
# the session may be logged as "not back" rather than as left. It leaves within the wait
# (not hanging on a silent server), and the server, running again, still closes the session.
# Before, the station left without a word and the log's "not back" looked like a crash.
# Domain 116 (docs/station.md, "A stalled station").
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= cpid=
trap '[ -n "$spid" ] && kill -CONT $spid 2>/dev/null; [ -n "$cpid" ] && kill -CONT $cpid 2>/dev/null; kill $spid $cpid 2>/dev/null; rm -rf "$tmp"' EXIT
"$server" --config "$config_dir/server.json" --domain 116 --no-db > "$tmp/server.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 116 --phantom 1 --name gus --profile sine --magnitude 1 --t-on 0 --t-off 60 \
  --duration 60 --print-period 0 > "$tmp/client.log" 2>&1 &
cpid=$!
i=0
until grep -q "session 1 opened" "$tmp/server.log" || [ $i -ge 100 ]; do sleep 0.1; i=$((i+1)); done
sleep 1.0
kill -STOP $cpid; sleep 1.5
kill -STOP $spid
kill -CONT $cpid; kill -INT $cpid
t0=$(date +%s.%N)
wait $cpid
crc=$?
t1=$(date +%s.%N)
cpid=
kill -CONT $spid
i=0
until grep -q "session 1 closed" "$tmp/server.log" || [ $i -ge 100 ]; do sleep 0.1; i=$((i+1)); done
kill $spid; wait $spid; spid=
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
[ $crc -eq 0 ] && ok "the interrupted station exited 0" || bad "the interrupted station exited $crc"
# The wait is 3 s of 0.3 s slices; 1.5 s more for a loaded machine and the 0.1 s before the
# participant goes.
left=$(printf "%.2f" "$(echo "$t1 - $t0" | bc)")
[ "$(echo "$left >= 2.9 && $left <= 4.5" | bc)" -eq 1 ] && ok "it left ${left} s after the interrupt (want 2.9-4.5 s: the whole wait, and no longer)" \
  || bad "it left ${left} s after the interrupt (want 2.9-4.5 s)"
grep -q "\[trainee gus\] the server did not answer within 3 s after this station's stall, so its goodbye may be lost: session 1 may be logged as closed \"not back\"" "$tmp/client.log" \
  && ok "the trainee was told its goodbye may be lost" || bad "the trainee was not told its goodbye may be lost"
n=$(grep -c "the server did not answer" "$tmp/client.log")
[ "$n" -eq 1 ] && ok "told once" || bad "told $n times (want 1)"
why=$(sed -n 's/.*session 1 closed after [^(]*(\(.*\))$/\1/p' "$tmp/server.log" | head -n 1)
[ -n "$why" ] && ok "the server, running again, closed session 1 ($why)" || bad "the server did not close session 1 within 10 s"
[ $fail -eq 0 ] || { cat "$tmp/client.log"; grep -v "^20.*DEBUG" "$tmp/server.log" | tail -20; }
exit $fail
