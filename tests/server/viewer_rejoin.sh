#!/bin/sh
# A visual station that did not run for 0.8 s is taken back into its session (domain 218). The server
# drops a viewer whose request writer's 0.5 s liveliness lapses, as it does a crashed one, and holds
# nothing for it; and it streams the deformation only to members that want it. A visual station its
# machine stopped (SIGSTOP, 1.5 s after its join) was left out of the session, the only viewer, and its
# view stood still until the session ended: deformation frames for its first ~1.5 s only. It now sends
# its accepted JOIN again, naming its session, after a stall of its own or when the state counts no
# visual station (client/station.c, viewer_ask): the server drops it and takes it back, the station says
# it asked, and frames come again. Then the same stop beside another visual station, whose count keeps
# the state's above zero: taken back on its own stall's word. A force-driven trainee presses throughout.
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= tpid=
trap '[ -n "$tpid" ] && kill $tpid 2>/dev/null; [ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
. "$test_dir/one_dome.sh"
. "$test_dir/stall.sh"
one_dome_server 218 "$config_dir/paper_step.json"
fail=0
"$client" --role trainee --domain 218 --phantom 1 --name tia --timeout 10 --print-period 0 --input script \
  --profile sine --magnitude 1 --offset 1.5 --frequency 1 --t-on 0 --t-off 30 --duration 30 --rate 100 \
  > "$tmp/tia.log" 2>&1 &
tpid=$!
_n=0
until grep -q "joined session" "$tmp/tia.log" || [ $_n -ge 100 ]; do sleep 0.1; _n=$((_n + 1)); done
visual() { # NAME DURATION: a visual station of session 1 in the background, its output in $tmp/NAME.log
  "$client" --role visual --domain 218 --phantom 1 --name "$1" --timeout 10 --duration "$2" --print-period 0 \
    > "$tmp/$1.log" 2>&1 &
}
visual vic 7
vpid=$!
stall_station $vpid "$tmp/vic.log" 1.5 0.8
wait $vpid
vrc=$?
# The same stop beside another visual station (val, not stopped): the count stays at 1 and only the
# stopped station's own stall tells it to ask (two JOINs, at once and a second later).
visual val 8
apid=$!
visual vik 6
kpid=$!
stall_station $kpid "$tmp/vik.log" 1.5 0.8
wait $kpid
krc=$?
wait $apid
kill $tpid; wait $tpid; tpid=
kill $spid; wait $spid; spid=
frames=$(sed -n 's/.*session [0-9]*: \([0-9]*\) deformation frames.*/\1/p' "$tmp/vic.log" | tail -n 1)
drops=$(grep -c "vic (visual) left session 1: lost" "$tmp/server.log")
joins=$(grep -c "vic joined session 1 as visual station" "$tmp/server.log")
echo "     vic: exit $vrc, $frames deformation frames in 7 s, dropped $drops time(s), joined $joins time(s)"
if [ $vrc -eq 0 ]; then echo "ok   the visual station exited 0"; else echo "FAIL the visual station's exit $vrc"; fail=1; fi
if [ "$drops" -ge 1 ]; then echo "ok   stopped 0.8 s, it was dropped by the server"
else echo "FAIL the server did not drop the stopped visual station"; fail=1; fi
if [ "$joins" -ge 2 ] && grep -q "asked the server again to stream session 1 to this station" "$tmp/vic.log"; then
  echo "ok   it asked again and the server took it back"
else echo "FAIL not taken back ($joins join line(s)), or the station did not say it asked"; fail=1; fi
# frames after the stop too: 189 in 7 s with the JOIN again, 56 without (2026-12-08); at least 90
if [ -n "$frames" ] && [ "$frames" -ge 90 ]; then echo "ok   its view moved on after the stop: $frames frames in 7 s (>= 90)"
else echo "FAIL '$frames' deformation frames in 7 s (want >= 90: the stream did not come back)"; fail=1; fi
kdrops=$(grep -c "vik (visual) left session 1: lost" "$tmp/server.log")
kjoins=$(grep -c "vik joined session 1 as visual station" "$tmp/server.log")
echo "     vik (beside val): exit $krc, dropped $kdrops time(s), joined $kjoins time(s)"
if [ $krc -eq 0 ] && [ "$kdrops" -ge 1 ] && [ "$kjoins" -ge 2 ] &&
   grep -q "asked the server again to stream session 1 to this station (it may have dropped it: this station did not run)" "$tmp/vik.log"; then
  echo "ok   beside another visual station, the stopped one was dropped and, asking after its own stall, taken back"
else echo "FAIL beside another visual station: exit $krc, dropped $kdrops, joined $kjoins, or no word of its asking"; cat "$tmp/vik.log"; fail=1; fi
[ $fail -eq 0 ] || { cat "$tmp/vic.log"; tail -n 20 "$tmp/server.log"; }
exit $fail
