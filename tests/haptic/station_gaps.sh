#!/bin/sh
# Gaps in a position-driven trainee's device points do not reach the phantom as force the hand never
# made (domain 179; server/playout.h, "A gap is caught up"; docs/haptics.md, "A starved machine's
# presses"). The paper's membrane, a 12 mm deep slide whose peak is ~0.36 N; phase 1, three trainees
# at once on three domes: one left alone (the baseline), one whose station is stopped 0.3 s mid-slide
# (its points resume 0.3 s on), one stopped 0.8 s (its lease lapses: the server lifts its finger and
# places it again, 12 mm deep, when it comes back); phase 2, one trainee while the server is stopped
# 0.3 s. Played at once, those gaps moved the finger millimetres within one 4 ms step and the
# phantom's viscous answer was 0.97 N, 4.96 N and 1.69 N (this test on the code before, 2026-12-07:
# 2.7-14 times the baseline's 0.36 N), all logged as the trainee's. Each session's peak force (the
# server's Fmax) must stay within twice the baseline's (since: 0.36, 0.46, 0.43 N), and the server
# must say what it caught up and brought in, in its log and in the session log the review reads.
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4 review=$5
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
. "$test_dir/stall.sh"
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
scene="$config_dir/paper_step.json"
slide=sim:slide,polar=15,azimuth=30,depth_mm=12,speed_mm_s=10,hold_s=0.5,slide_mm_s=20,slide_mm=20
start_server() { # $1: config name
  cat > "$tmp/$1.json" <<JSON
{ "domain_id": 179, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/$1.db",
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome1", "scene": "$scene", "physics_rate_hz": 250 },
                { "id": 2, "name": "dome2", "scene": "$scene", "physics_rate_hz": 250 },
                { "id": 3, "name": "dome3", "scene": "$scene", "physics_rate_hz": 250 } ] }
JSON
  "$server" --config "$tmp/$1.json" > "$tmp/$1.log" 2>&1 &
  spid=$!
}
trainee() { # $1 name, $2 phantom, $3 status print period [s] (default 0: none)
  "$client" --role trainee --domain 179 --phantom "$2" --name "$1" --timeout 10 --print-period "${3:-0}" \
    --input "$slide" > "$tmp/$1.log" 2>&1 &
}
stop_server() {
  kill $spid
  wait $spid
  spid=
}
# fmax LOG NAME: the Fmax column of NAME's row in the server's session summary
fmax() { awk -v n="$2" 'f && $2 == n { print $6 } /Fmax\[N\]/ { f = 1 }' "$1"; }

start_server one
trainee base 1
bpid=$!
trainee gap 2
gpid=$!
trainee lapse 3
lpid=$!
stall_station $gpid "$tmp/gap.log" 1.5 0.3 &
stall_station $lpid "$tmp/lapse.log" 1.0 0.8 &
wait $bpid; brc=$?
wait $gpid; grc=$?
wait $lpid; lrc=$?
stop_server

start_server two
trainee srv 1 0.05
rpid=$!
# Stopped once the station renders 0.1 N or more: a local model under its finger, which the server
# streams only for a finger whose device points it has played, so there is a played point for the
# gap to begin at however long the station's first points took (until 2026-12-08: 1.2 s after
# "joined session"). Session 87's CI run told no gap here: the stop came while the server caught up
# a loaded link's 40 ms bunch, and a gap was told only for a catch-up that began 50 ms behind
# (server/playout.c; test_server_playout's "bunch" case).
_n=0
until grep -Eq "finger touching .*rendered \|F\| = +([1-9]|0\.[1-9])" "$tmp/srv.log" || [ $_n -ge 100 ]; do
  sleep 0.1
  _n=$((_n + 1))
done
touched=$_n
kill -STOP $spid
sleep 0.3
kill -CONT $spid
wait $rpid; rrc=$?
stop_server

if [ $brc -eq 0 ] && [ $grc -eq 0 ] && [ $lrc -eq 0 ] && [ $rrc -eq 0 ]; then echo "ok   the four trainees exited 0"
else echo "FAIL trainee exits: base $brc, gap $grc, lapse $lrc, srv $rrc"; fail=1; fi
b=$(fmax "$tmp/one.log" base)
for who in gap lapse srv; do
  log="$tmp/one.log"
  [ $who = srv ] && log="$tmp/two.log"
  f=$(fmax "$log" $who)
  if [ -n "$b" ] && [ -n "$f" ] && awk -v f="$f" -v b="$b" 'BEGIN { exit !(b > 0.2 && b < 0.6 && f <= 2 * b) }'; then
    echo "ok   $who: the session's peak force $f N, within twice the baseline's $b N"
  else echo "FAIL $who: peak force '$f' N against the baseline's '$b' N (want a baseline of 0.2-0.6 N, at most twice it)"
    fail=1
  fi
done
if [ "$touched" -ge 100 ]; then
  echo "FAIL srv's station rendered no 0.1 N within 10 s of its start: the server was stopped without a point played"
  fail=1
fi
if grep -q "session [0-9]*: [1-9][0-9]* gap(s) in the station's device points .* caught up over [1-9][0-9]* steps" "$tmp/two.log"; then
  echo "ok   the server said it caught the gap up"
else echo "FAIL no 'caught up' line for the stopped server"; fail=1; fi
if grep -q "caught up over [1-9][0-9]* steps.*; 1 finger(s) placed below the surface brought in from it" "$tmp/one.log" &&
  grep -q "trainee station lost" "$tmp/one.log"; then
  echo "ok   the lapsed trainee's finger was placed again below the surface and brought in"
else echo "FAIL no finger brought in after the lease lapsed"; fail=1; fi
# The instructor's review tells the two apart from the trainee's own pressing (info events).
uid_of() { "$review" --db "$1" list 2>/dev/null | awk -v n="$2" '$2 == n { print $1 }'; }
gshow=$("$review" --db "$tmp/one.db" show "$(uid_of "$tmp/one.db" gap)" 2>&1)
lshow=$("$review" --db "$tmp/one.db" show "$(uid_of "$tmp/one.db" lapse)" 2>&1)
bshow=$("$review" --db "$tmp/one.db" show "$(uid_of "$tmp/one.db" base)" 2>&1)
if printf '%s' "$gshow" | grep -q "info .*device points resumed after a gap (a stalled station or server), the longest 0\.[2-9][0-9] s"; then
  echo "ok   the review of the stopped station's session names its gap (0.2-1 s)"
else echo "FAIL the review of 'gap' names no gap of 0.2-1 s"; printf '%s\n' "$gshow" | tail -n 12; fail=1; fi
if printf '%s' "$lshow" | grep -q "info .*a finger placed below the surface .*, the deepest [0-9.]* mm: brought in"; then
  echo "ok   the review of the lapsed station's session names its finger brought in"
else echo "FAIL the review of 'lapse' names no finger brought in"; printf '%s\n' "$lshow" | tail -n 12; fail=1; fi
# A loaded machine stalls an undisturbed station too (this test beside a full test run, 2026-12-08: in
# 4 of 14 runs the baseline's review named gaps of 0.06-0.27 s, the server's log up to 0.33 s behind):
# real gaps, rightly named. That none is named where none was is test_server_playout's (a steady and
# a jittery link); here, no finger brought in (a lapsed lease) and no gap of 0.5 s or more.
if printf '%s' "$bshow" | grep -q "resumed after a gap.*the longest \(0\.[5-9]\|[1-9]\)\|placed below the surface"; then
  echo "FAIL the undisturbed session's review names a gap of 0.5 s or more or a finger brought in"
  printf '%s\n' "$bshow" | grep "resumed after\|placed below"; fail=1
else echo "ok   the undisturbed session's review names no finger brought in and no gap of 0.5 s or more"; fi
[ $fail -eq 0 ] || { tail -n 25 "$tmp/one.log" "$tmp/two.log"; grep -v " t= " "$tmp/srv.log" | tail -n 8; }
exit $fail
