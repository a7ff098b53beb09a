#!/bin/sh
# A position-driven trainee's first press on a phantom without an exercise is felt from the moment
# the fingertip touches (the simulated device's press, its 1 kHz haptic thread over 250 Hz physics;
# domain 172). The haptic thread reads the device and sends its contact samples from its start, and
# the station's main loop feeds it the server's local models; until 2026-12-06 the main thread first
# waited up to 1 s for an exercise the phantom does not have, feeding nothing: the server deformed
# the phantom under the finger while the device rendered 0 N (flag NO_MODEL), and the force faded in
# ~1 s after the loop started (docs/haptics.md, "Onsets fade in too").
# From the station's --trace-csv (every tick: t, on, device point, force, flags):
#  - the first tick whose device point is inside the dome (|x| < R + r: R = 40 mm, the scene's
#    radius, r = 8 mm, the simulated fingertip's; the press is at the pole, 3 mm at 20 mm/s after
#    3 mm of approach from 0.2 s: ~0.35 s);
#  - the first tick rendering a contact (flag CONTACT, 4) comes within 0.4 s of it, and the first
#    finger-on tick with a model (flag NO_MODEL, 8, clear) no later. Measured 2026-12-06 on this
#    2-core machine: the contact rendered 3-6 ms after the device entered the dome, the first model
#    1-60 ms after the finger went down (before the touch); without the fix the first model came at
#    ~1.0 s, 0.65 s after the touch. 0.4 s (0.15 s at first; widened by review, 2026-12-06) leaves a
#    loaded machine's discovery and stepping room and still fails the 0.65 s the wait cost.
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/../one_dome.sh"
one_dome_server 172 "$config_dir/paper_step_long_term.json" 250
fail=0
"$client" --role trainee --domain 172 --phantom 1 --name flo --timeout 10 --print-period 0 \
  --input sim:press,depth_mm=3,hold_s=1 --trace-csv "$tmp/trace.csv" > "$tmp/flo.log" 2>&1
rc=$?
# An output file that cannot all be written is an error, said, exit 1 (until 2026-12-07: exit 0, a cut
# CSV that looked whole): the trace of a haptic trainee and the CSVs of a force-driven one, on /dev/full.
"$client" --role trainee --domain 172 --phantom 1 --name flo2 --timeout 10 --print-period 0 \
  --input sim:press,depth_mm=1,hold_s=0.1 --trace-csv /dev/full > "$tmp/full1.log" 2>&1
rc_full1=$?
"$client" --role trainee --domain 172 --phantom 1 --name flo3 --timeout 10 --print-period 0 --duration 0.3 \
  --feedback-csv /dev/full --contact-csv /dev/full > "$tmp/full2.log" 2>&1
rc_full2=$?
kill $spid; wait $spid; spid=
if [ $rc_full1 -eq 1 ] && grep -q "cannot write /dev/full" "$tmp/full1.log" && [ $rc_full2 -eq 1 ] &&
   [ "$(grep -c "cannot write /dev/full" "$tmp/full2.log")" -eq 2 ]; then
  echo "ok   --trace-csv, --feedback-csv and --contact-csv on a full disk (/dev/full): said, exit 1"
else
  echo "FAIL outputs on a full disk: exit $rc_full1 and $rc_full2"; cat "$tmp/full1.log" "$tmp/full2.log"; fail=1
fi
if [ $rc -eq 0 ]; then echo "ok   the trainee pressed and exited 0"; else echo "FAIL exit $rc"; fail=1; fi
# t of the first tick inside the dome, of the first rendering a contact, of the first finger-on with a model
times=$(awk -F, -v R=0.040 -v r=0.008 'NR > 1 {
    t = $1; on = $3; fl = $11 + 0
    if (on == 1 && sqrt($4 * $4 + $5 * $5 + $6 * $6) < R + r && inside == "") inside = t
    if (int(fl / 4) % 2 == 1 && touch == "") touch = t
    if (on == 1 && int(fl / 8) % 2 == 0 && model == "") model = t
  } END { print (inside == "" ? "-" : inside), (touch == "" ? "-" : touch), (model == "" ? "-" : model) }' "$tmp/trace.csv")
set -- $times
inside=$1 touch=$2 model=$3
echo "     the device entered the dome at $inside s, a contact was rendered at $touch s, the first model at $model s"
if [ "$inside" != - ] && [ "$touch" != - ] && awk -v a="$inside" -v b="$touch" 'BEGIN { exit !(b - a <= 0.4) }'; then
  echo "ok   the press was felt $(awk -v a="$inside" -v b="$touch" 'BEGIN { printf "%.3f", b - a }') s after the touch (want <= 0.4 s)"
else echo "FAIL the press was not felt within 0.4 s of the touch"; fail=1; fi
if [ "$inside" != - ] && [ "$model" != - ] && awk -v a="$inside" -v b="$model" 'BEGIN { exit !(b - a <= 0.4) }'; then
  echo "ok   the first local model was rendered at $model s, within 0.4 s of the touch"
else echo "FAIL no local model within 0.4 s of the touch (NO_MODEL until $model s)"; fail=1; fi
[ $fail -eq 0 ] || { cat "$tmp/flo.log"; tail -20 "$tmp/server.log"; }
exit $fail
