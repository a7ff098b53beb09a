#!/bin/sh
# A viewer finds a trainee by name (--trainee NAME) past the 8th session on the domain (domain 173).
# Ten force-driven trainees hold sessions open on one server, joined one after another (sessions 1-10
# in that order, as the server republishes their states); then an observer follows t9, t10 and t1 by
# name. The station read the session states 8 at a time with a plain read, which returns the same
# first 8 on every pass: t9 and t10 were "no open session of that trainee within 3 s" (session 77).
# Each observer must exit 0 having followed the session its trainee was told it joined.
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= tpids=
trap 'for p in $tpids $spid; do kill $p 2>/dev/null; done; for p in $tpids $spid; do wait $p 2>/dev/null; done; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../one_dome.sh"
one_dome_server 173 "$config_dir/paper_step.json"
fail=0
# a trainee holding its session open without pressing (0 N), until killed
for k in 1 2 3 4 5 6 7 8 9 10; do
  "$client" --role trainee --domain 173 --phantom 1 --name "t$k" --timeout 10 --print-period 0 --input script \
    --profile step --magnitude 0 --t-on 0 --t-off 120 --duration 120 --rate 10 > "$tmp/t$k.log" 2>&1 &
  tpids="$tpids $!"
  n=0
  until grep -q "joined session" "$tmp/t$k.log" || [ $n -ge 100 ]; do sleep 0.1; n=$((n + 1)); done
done
for k in 9 10 1; do
  sid=$(sed -n 's/.*joined session \([0-9]*\) .*/\1/p' "$tmp/t$k.log")
  out=$("$client" --role observer --domain 173 --trainee "t$k" --timeout 3 --duration 0.3 --print-period 0 2>&1)
  rc=$?
  if [ -n "$sid" ] && [ $rc -eq 0 ] && printf '%s\n' "$out" | grep -q "^\[observer\] session $sid:"; then
    echo "ok   --trainee t$k found session $sid"
  else
    echo "FAIL --trainee t$k (session '$sid'): exit $rc: $out"; fail=1
  fi
done
# gone before the next test on this domain starts (server_station_text: its catalogue must be the only one)
for p in $tpids; do kill $p; wait $p; done
kill $spid; wait $spid
tpids= spid=
[ $fail -eq 0 ] || { for k in 1 2 3 4 5 6 7 8 9 10; do cat "$tmp/t$k.log"; done; tail -20 "$tmp/server.log"; }
exit $fail
