#!/bin/sh
# What the stations say is what the server did (session 83 review; domain 208). One palp-server, a
# force-driven trainee (lee: 2 N at polar 30 deg, azimuth 40 deg, from 0.8 s to 1.4 s of her profile), and
# another participant of this unsecured domain writing 15 N presses of finger 0 into her session's
# partition every 50 ms once the server and both viewers read it (test_finding_writer ... contacts: the
# server refuses them, foreign_participant). Then:
# - the observer tells one press, hers, from the server's feedback (it learns her station's writer from
#   the sample the feedback says was applied, and counts the peer's as another writer's): "trainee presses: force-driven,
#   distribution II uniform, at 1.7 o'clock, 21 mm from the pole, |F| commanded 2.00 N" (by hand: azimuth
#   40 deg from +x is 50 deg clockwise from +y, 1.67 h; the arc 40 mm x pi/6 = 20.9 mm), and her lift;
#   never 15 N, never "|F| applied" (it showed the peer's 15 N press as hers, "applied", before);
# - the server stopped (SIGSTOP) 0.4 s, its world falls behind the wall clock: lee's "t=" lines are the
#   world's time, as her feedback CSV's sim_time says (her last line its last sim_time within 0.02 s), not
#   her own clock since her loop started (by then >= 0.2 s ahead of the world; and her lines go on ~2 s
#   after the kill, until her station gives the server up);
# - the server SIGKILLed: the observer exits 3 (0 before), its summary "session ended: server lost";
#   lee's too ("session closed by the server: server lost" before); a visual station whose --svg
#   directory does not exist says its first unwritten snapshot and its final one, counts them, never
#   claims ", snapshot PATH", and exits 1 (0 before, the snapshot named as written);
# - a trainee asking for --phantom-name "dome A (calibrated)" is told the names the catalogue has
#   ("dome"), not the DDS Security hint.
# ~4.5 s (the server's lapse takes its 1 s lease and the stations' 1 s wait for it).
set -u
server=$1 client=$2 writer=$3 config_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= lpid= opid= vpid= wpid=
trap 'for p in $lpid $opid $vpid $wpid $spid; do kill -CONT $p 2>/dev/null; kill $p 2>/dev/null; done; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../one_dome.sh"
one_dome_server 208 "$config_dir/paper_step.json"
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
"$client" --role trainee --domain 208 --phantom 1 --name lee --timeout 10 --profile step --magnitude 2 --t-on 0.8 \
  --t-off 1.3 --polar 30 --azimuth 40 --duration 30 --print-period 0.1 --feedback-csv "$tmp/lee.csv" > "$tmp/lee.log" 2>&1 &
lpid=$!
"$writer" 208 lee contacts 10 3 > "$tmp/writer.log" 2>&1 &
wpid=$!
"$client" --role observer --domain 208 --trainee lee --timeout 10 --print-period 0.25 > "$tmp/observer.log" 2>&1 &
opid=$!
"$client" --role visual --domain 208 --trainee lee --timeout 10 --no-map --svg "$tmp/none/snap" --svg-every 0.2 \
  > "$tmp/visual.log" 2>&1 &
vpid=$!
"$client" --role trainee --domain 208 --phantom-name "dome A (calibrated)" --timeout 1 > "$tmp/name.log" 2>&1 &
npid=$!
# lee's profile runs on her own clock from her join: 0.8-1.3 s is her press; the stops come after the
# observer saw her lift (at most 10 s)
n=0
until grep -q "trainee lifts" "$tmp/observer.log" || [ $n -ge 100 ]; do sleep 0.1; n=$((n + 1)); done
kill -STOP $spid; sleep 0.4; kill -CONT $spid
sleep 0.5
kill -9 $spid; wait $spid 2>/dev/null; spid=
kill $wpid; wait $wpid 2>/dev/null; wpid=
wait $npid; nrc=$?
wait $opid; orc=$? opid=
wait $vpid; vrc=$? vpid=
wait $lpid; lrc=$? lpid=

# the observer
press='trainee presses: force-driven, distribution II uniform, at 1.7 o'"'"'clock, 21 mm from the pole, |F| commanded 2.00 N'
presses=$(grep -c "trainee presses" "$tmp/observer.log")
if [ "$presses" -eq 1 ] && grep -qF "$press" "$tmp/observer.log" && grep -q "trainee lifts the finger" "$tmp/observer.log"; then
  ok "the observer told lee's one press from the server's feedback, where and how hard she commanded it, and her lift"
else bad "the observer's presses ($presses, want 1: \"$press\", then a lift)"; fi
if ! grep -q "15\.00 N\||F| applied" "$tmp/observer.log" && grep -q "|F| commanded" "$tmp/observer.log" &&
  grep -q "^\[observer\] session [0-9]*: .* contact samples seen ([1-9][0-9]* of them from a writer not the trainee's station, ignored)" "$tmp/observer.log"; then
  ok "the peer's 15 N presses are nowhere in the observer's lines, its samples counted as another writer's; its force figure is \"commanded\""
else bad "the observer showed the peer's 15 N, said \"|F| applied\", or did not count the peer's samples"; fi
if [ $orc -eq 3 ] && grep -q "^\[observer\] session [0-9]*: .*; session ended: server lost" "$tmp/observer.log"; then
  ok "the observer: exit 3, \"session ended: server lost\""
else bad "the observer: exit $orc (want 3 and \"session ended: server lost\")"; fi
# the visual station's snapshots
if [ $vrc -eq 1 ] && grep -q "cannot write $tmp/none/snap-0001.svg" "$tmp/visual.log" &&
  grep -q "cannot write $tmp/none/snap\$" "$tmp/visual.log" &&
  grep -q "^\[visual\] session [0-9]*: .* snapshots not written" "$tmp/visual.log" && ! grep -q ", snapshot " "$tmp/visual.log"; then
  ok "the visual station: its unwritten snapshots said and counted, none claimed, exit 1"
else bad "the visual station: exit $vrc (want 1, its unwritten snapshots said and counted, no \", snapshot PATH\")"; fi
# lee's world time: her last "t=" line against her feedback CSV (t_s, frame, sim_time_s, ...)
last_t=$(sed -n 's/^\[trainee lee\] t= *\([0-9.]*\) s  finger 0:.*/\1/p' "$tmp/lee.log" | tail -n 1)
csv=$(awk -F, 'NR > 1 { if ($3 > w) w = $3; if ($1 > s) s = $1 } END { printf "%.3f %.3f", w, s }' "$tmp/lee.csv")
set -- $csv
# (her last line prints the newest feedback's sim_time, to 2 decimals: 0.02 s; the server's 0.4 s stop puts
# her clock >= 0.2 s ahead of the world, less the world's head start before her loop began, ~0.1 s)
if [ -n "$last_t" ] && awk -v t="$last_t" -v w="$1" -v s="$2" 'BEGIN { exit !(t - w <= 0.02 && w - t <= 0.02 && s - w >= 0.2) }'; then
  ok "lee's last line says t = $last_t s, the world's (last sim_time $1 s; her own clock $2 s, the server's stop behind)"
else bad "lee's last line t = '$last_t' s (want the last sim_time $1 s within 0.02 s; her clock $2 s must be >= 0.2 s ahead)"; fi
if [ $lrc -eq 3 ] && grep -q "; session ended: server lost" "$tmp/lee.log" && ! grep -q "closed by the server: server lost" "$tmp/lee.log"; then
  ok "lee: exit 3, \"session ended: server lost\""
else bad "lee: exit $lrc (want 3, \"session ended: server lost\")"; fi
if [ $nrc -eq 1 ] && grep -q 'no phantom named "dome A (calibrated)" within 1.0 s; the catalogue lists "dome"' "$tmp/name.log" &&
  ! grep -q "DDS Security" "$tmp/name.log"; then
  ok "--phantom-name with a name not in the catalogue: the names it has, exit 1"
else bad "--phantom-name \"dome A (calibrated)\": exit $nrc: $(cat "$tmp/name.log")"; fi
[ $fail -eq 0 ] || for f in lee observer visual name writer server; do echo "== $f"; cat "$tmp/$f.log"; done
exit $fail
