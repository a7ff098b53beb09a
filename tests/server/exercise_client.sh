#!/bin/sh
# issue 13 from the station's side: palp-server hosts an exercise (its own config, domain 61,
# a SQLite log); palp-client with the simulated device shows the exercise's title and
# instructions, marks a lump with the device's button while touching (accepted by the
# server, in the log) and withdraws it; a button pressed while not touching is refused on
# the station with a message, nothing sent. The finger keyboard (in a pty from script(1)) names the
# band of each press on its status line, as the assessment grades it: pressed to ~2.6, ~6.8 and
# ~16 mm (device +3, +8, +20 mm), each line's band is the one exercise_wire.json gives its depth.
set -u
server=$1 client=$2 config_dir=$3 test_dir=$4 finding_writer=$5
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
server_config() { # OUT EXERCISE_FILE [DATABASE_LINE]: the server's config on domain 61
  cat > "$1" <<JSON
{ "domain_id": 61, "tick_rate_hz": 100, "tick_threads": 1, ${3:-}
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step.json" } ],
  "exercises": [ { "id": 7, "file": "$2", "physics_rate_hz": 250 } ] }
JSON
}
server_config "$tmp/server.json" "$test_dir/exercise_wire.json" "\"database\": \"$tmp/log.db\","
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
fail=0
check() { # pattern file what
  if grep -q "$1" "$2"; then echo "ok   $3"; else echo "FAIL $3 (no \"$1\" in $2):"; cat "$2"; fail=1; fi
}
"$client" --role trainee --domain 61 --phantom 7 --name dora --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=2,mark_s=1.5,withdraw_s=2.2 > "$tmp/dora.log" 2>&1
"$client" --role trainee --domain 61 --phantom 7 --name ed --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=1,mark_s=0.1 > "$tmp/ed.log" 2>&1
if command -v script > /dev/null; then
  . "$(dirname "$0")/../wait_for.sh"
  type_keys "$tmp/kim.log" 1.5 "haptic thread at" '+++++' "device +3 mm (step 1 mm), fingertip" '+++++' \
    "device +8 mm (step 1 mm), fingertip" ']]+++' "device +20 mm (step 4 mm), fingertip" 'q' |
    script -qec "$client --role trainee --domain 61 --phantom 7 --name kim --timeout 10 --input keyboard-finger" \
      /dev/null > "$tmp/kim.log" 2>&1
else
  echo "script(1) missing (util-linux)" > "$tmp/kim.log"
fi
kill $spid; wait $spid; spid=
# exercise_wire.json's bands by depth alone: light [1, 5), medium [5, 12), deep [12, 25) mm; a line
# within 0.05 mm of a bound (its depth is printed to 0.1 mm) is not judged
tr '\r' '\n' < "$tmp/kim.log" | sed -n 's/.*fingertip \([0-9.]*\) mm deep (\([a-z ]*\)): force.*/\1 \2/p' > "$tmp/kim.bands"
verdict=$(awk 'function band(d) { return d < 1 ? "no band" : d < 5 ? "light" : d < 12 ? "medium" : d < 25 ? "deep" : "no band" }
  { near = 0; split("1 5 12 25", b, " "); for (i in b) if ($1 - b[i] < 0.05 && b[i] - $1 < 0.05) near = 1
    name = $2 (NF > 2 ? " " $3 : ""); if (!near && name != band($1)) { bad++; print "wrong: " $0 > "/dev/stderr" }
    seen[name] = 1 }
  END { printf "%d %d %d %d", NR, bad, seen["light"] + seen["medium"] + seen["deep"], bad == 0 }' "$tmp/kim.bands")
set -- $verdict
if [ "${4:-0}" = 1 ] && [ "$3" = 3 ] && [ "$1" -ge 3 ]; then
  echo "ok   the finger keyboard names each press's band as exercise_wire.json grades it ($1 status lines, light, medium and deep seen)"
else echo "FAIL the finger keyboard's bands: '$verdict' (lines, wrong, bands seen, ok):"; cat "$tmp/kim.bands"; tr '\r' '\n' < "$tmp/kim.log" | tail -20; fail=1; fi
check 'exercise "test-wire": Test: findings over the wire' "$tmp/dora.log" "the station shows the exercise's title"
check 'Examine the dome and mark every lump you feel.' "$tmp/dora.log" "  and its instructions"
check 'time limit 120 s' "$tmp/dora.log" "  and its time limit"
check 'finding 1 accepted: 1 mark standing' "$tmp/dora.log" "the button marks a lump while touching: accepted"
check 'finding 1 accepted: 0 marks standing' "$tmp/dora.log" "  and withdraws it"
check 'mark refused here: the fingertip is not touching' "$tmp/ed.log" "a mark while not touching is refused on the station"
if grep -q "mark 1 sent" "$tmp/ed.log"; then echo "FAIL ed sent a mark"; fail=1; else echo "ok     and not sent"; fi
# Session 64: a practice exercise (debrief "lesions") on a server that keeps no session log: after her
# debrief the station is told at once that no score will come, and why (palp_debrief_score), rather
# than waiting its 5 s. The same exercise with "debrief": "lesions", on a server without "database".
sed -e 's|"\.\./assess/phantom_stiff\.json"|"'"$test_dir"'/../assess/phantom_stiff.json"|' \
  -e 's|"time_limit_s": 120,|"time_limit_s": 120, "debrief": "lesions",|' "$test_dir/exercise_wire.json" > "$tmp/practice.json"
server_config "$tmp/nolog.json" "$tmp/practice.json"
"$server" --config "$tmp/nolog.json" > "$tmp/nolog-server.log" 2>&1 &
spid=$!
# Her mark at 1.0 s, in the hold (the press, 3 mm above to 9 mm deep at 20 mm/s, ends at 0.6 s): at 0.5 s,
# on the ramp, a loaded run's station had no model in contact yet and refused it (2026-12-07).
"$client" --role trainee --domain 61 --phantom 7 --name fia --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=1,mark_s=1.0 > "$tmp/fia.log" 2>&1
# Session 72: a peer writes into gus's partition (an unsecured classroom, or a trainee into her own):
# first one withdrawal of a mark 9 naming his session, which the server refuses unanswered for its
# writer (since 2026-12-06: not of the participant that joined the session; its log names it), then
# the same from a peer that joined his session as a visual station first (as palp-web does to write a
# trainee page's marks), which the server answers (his station says, once, that someone else writes
# findings into his session: mark 9 is none of his), then findings
# naming made-up sessions, 20 every 100 ms for 4 s, through his press and mark. Those became
# instances of the server's finding reader, which refused the 65th and on for its resource limits,
# and Cyclone retried each on its delivery path: every session's contacts stalled (his fingertip never
# reached the dome: 37 of ~1,050 contacts arrived) and the flood spent his findings rate. Now the
# reader's filter drops them, counted and logged, unanswered; his mark over lump 1 stands.
"$client" --role trainee --domain 61 --phantom 7 --name gus --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=3,mark_s=2 > "$tmp/gus.log" 2>&1 &
gpid=$!
# The first two side by side: each lingers 1 s after writing, so that a loaded server still finds its
# writer when it takes the finding, and the flood still runs through his mark.
"$finding_writer" 61 gus 9 1 0.1 own > "$tmp/writer-own.log" 2>&1 &
wpid=$!
"$finding_writer" 61 gus 9 1 0.1 own-visual > "$tmp/writer.log" 2>&1
wait $wpid
cat "$tmp/writer-own.log" >> "$tmp/writer.log"
"$finding_writer" 61 gus 9 20 4 >> "$tmp/writer.log" 2>&1
wait $gpid
# 2026-12-07: a peer joined as a visual station (as palp-web does for jo's trainee page) marks lump "1"
# at the pole early in jo's session; jo's station, which numbers its marks from 1 too, then marks at
# 5 s. Her mark took id 1 and the server refused it "already made"; now her station follows the ids it
# hears answered, and her mark is 2, accepted, with the peer's standing beside it.
"$client" --role trainee --domain 61 --phantom 7 --name jo --timeout 12 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=6,mark_s=5 > "$tmp/jo.log" 2>&1 &
jpid=$!
"$finding_writer" 61 jo 1 1 0.1 own-visual-mark > "$tmp/jo-writer.log" 2>&1
wait $jpid
kill $spid; wait $spid; spid=
check 'finding_writer: 1 findings naming the session itself written' "$tmp/writer.log" "a peer writes a finding into gus's session"
check 'findings from a writer of participant [0-9a-f:]* refused' "$tmp/nolog-server.log" \
  "  refused for its writer, which never joined his session, and named in the server's log"
check 'finding_writer: joined session [0-9]* as a visual station' "$tmp/writer.log" \
  "  a second peer joins his session as a visual station and writes the same"
check 'finding_writer: [0-9]* findings naming other sessions written' "$tmp/writer.log" "  then floods it with findings naming other sessions"
check 'debrief: you found 1 of 2 lumps with 1 mark standing' "$tmp/gus.log" "  his press reaches the lump and his mark through the flood stands"
check 'the server answered finding 9, which this station did not send: someone else writes findings into this session' "$tmp/gus.log" \
  "  his station says once that someone else writes findings into his session"
if grep -q "the server refused finding 9" "$tmp/gus.log" || [ "$(grep -c 'did not send' "$tmp/gus.log")" != 1 ]; then
  echo "FAIL gus's station took the peer's answer for his own, or said it more than once:"; cat "$tmp/gus.log"; fail=1
else echo "ok     said once, and not taken for his"; fi
# Session 77: a peer writes the session's first finger sample in contact and its first local model back
# into hal's partition with frame 2^64 - 1, early in his press. The station took the sample, and every
# later genuine one was "older" than it: refused as malformed, his coverage stopped there. Now a frame
# past what the server can have stepped since his join is refused without moving the mark: at most
# that one sample refused, his coverage counted through the press.
"$server" --config "$tmp/server.json" > "$tmp/server3.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 61 --phantom 7 --name hal --timeout 10 --print-period 0 \
  --input sim:press,polar=31,azimuth=41,depth_mm=9,hold_s=3 > "$tmp/hal.log" 2>&1 &
hpid=$!
"$finding_writer" 61 hal frames > "$tmp/frames.log" 2>&1
wait $hpid
kill $spid; wait $spid; spid=
check 'finding_writer: 1 finger sample(s) and 1 local model(s) of session [0-9]* written again' "$tmp/frames.log" \
  "a peer writes a finger sample and a local model into hal's session with frame 2^64 - 1"
refused=$(sed -n 's/.* and \([0-9]*\) refused as malformed.*/\1/p' "$tmp/hal.log")
covered=$(sed -n 's/.*you covered light \([0-9.]*\)%, medium \([0-9.]*\)%, deep \([0-9.]*\)% of the dome.*/\1 \2 \3/p' "$tmp/hal.log")
if [ "${refused:-0}" -le 1 ] && [ -n "$covered" ] &&
  awk -v c="$covered" 'BEGIN { split(c, b, " "); exit !(b[1] + b[2] + b[3] > 0) }'; then
  echo "ok     at most that sample refused (${refused:-0}), his coverage counted (light, medium, deep: $covered %)"
else echo "FAIL hal's samples refused: '${refused:-0}' (want <= 1), coverage '$covered':"; cat "$tmp/hal.log"; fail=1; fi
check "finding(s) of another writer dropped unanswered at the reader; the last names session" "$tmp/nolog-server.log" \
  "  the server logs the findings naming other sessions it dropped"
check 'finding_writer: 1 findings naming the session itself written' "$tmp/jo-writer.log" \
  "a visual peer marks 1 in jo's session, as her palp-web page would"
check 'the server answered finding 1, which this station did not send' "$tmp/jo.log" "  her station hears the answer"
check 'mark 2 sent' "$tmp/jo.log" "  her own mark then takes id 2, above the peer's"
check 'finding 2 accepted: 2 marks standing' "$tmp/jo.log" "  and is accepted beside the peer's"
if grep -q "already made" "$tmp/jo.log"; then echo "FAIL jo's mark was refused as already made:"; cat "$tmp/jo.log"; fail=1
else echo "ok     not refused as already made"; fi
check 'debrief: you found 1 of 2 lumps' "$tmp/fia.log" "a practice exercise on a server without a log: her debrief tells the lumps"
check 'no score: this server keeps no session log to score it from; your instructor grades the session' "$tmp/fia.log" \
  "  and her station is told at once why no score comes"
if grep -q "no score came from the server within" "$tmp/fia.log"; then echo "FAIL fia's station waited for a score"; fail=1
else echo "ok     not left waiting for one"; fi
exit $fail
