#!/bin/sh
# Text from the network reaches a station's terminal terminal-safe (docs/station.md, "Session 77 review
# fixes"; domain 173, shared with server_viewer_trainee under a lock). A forged server
# (tests/server/hostile_server.c, as any peer of an unsecured classroom may be) puts an OSC retitle, a
# screen clear, a bell and a carriage return into the phantom's name, the session's partition, its close
# reason and a join's refusal. A trainee's "joined session" line, a visual station's map header and
# closing line, and the refusal must carry none of those bytes (ESC, BEL, CR), and must still be written.
# Before (session 77): all four were written raw.
set -u
client=$1 hostile=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
hpid=
trap '[ -n "$hpid" ] && kill $hpid 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
raw() { tr -dc '\033\007\015' < "$1" | wc -c; } # ESC, BEL, CR bytes in a file

"$hostile" 173 accept 12 > "$tmp/hostile.out" 2>&1 &
hpid=$!
"$client" --role visual --domain 173 --session 1 --map --no-color --map-every 0.2 --duration 12 --timeout 10 \
  > "$tmp/visual.out" 2>&1 &
vpid=$!
"$client" --role trainee --domain 173 --phantom 1 --name eve --duration 12 --timeout 10 --print-period 0 \
  > "$tmp/trainee.out" 2>&1
wait $vpid
wait $hpid; hpid=
n=$(raw "$tmp/trainee.out")
if [ "$n" -eq 0 ] && grep -q 'joined session 1 on phantom 1 "dome?' "$tmp/trainee.out"; then
  ok "the trainee's joined line names the phantom and partition terminal-safe"
else bad "the trainee's output has $n ESC/BEL/CR bytes, or no joined line"; fi
n=$(raw "$tmp/visual.out")
if [ "$n" -eq 0 ] && grep -q '^session 1, phantom 1 "dome?' "$tmp/visual.out" &&
  grep -q 'session closed: closed?' "$tmp/visual.out"; then
  ok "the visual station's map header and closing reason are terminal-safe"
else bad "the visual station's output has $n ESC/BEL/CR bytes, or no map header or closing reason"; fi

"$hostile" 173 reject 3 > "$tmp/hostile2.out" 2>&1 &
hpid=$!
"$client" --role trainee --domain 173 --phantom 1 --name eve --duration 2 --timeout 3 --print-period 0 \
  > "$tmp/rejected.out" 2>&1
rc=$?
wait $hpid; hpid=
n=$(raw "$tmp/rejected.out")
if [ $rc -eq 1 ] && [ "$n" -eq 0 ] && grep -qF 'join rejected: no room\x1b]0;owned\x07' "$tmp/rejected.out"; then
  ok "a refusal's reason is written escaped (exit 1)"
else bad "exit $rc, $n ESC/BEL/CR bytes in the refusal"; fi
[ $fail -eq 0 ] || for f in "$tmp"/*.out; do echo "== $f"; cat -v "$f"; done
exit $fail
