#!/bin/sh
# The keyboard inputs leave the terminal as they found it when a signal ends the station: in a real
# terminal (a pty from script(1)), the finger keyboard's station is ended by SIGQUIT (Ctrl-\ still
# works in the raw terminal) and the force keyboard's by SIGHUP, each once the keyboard has made the
# terminal raw (its help line is written after). stty then reads the pty: line editing (icanon) and
# echo on, as before the station, where they stayed off (the keyboards restore it in close(), which
# SIGINT and SIGTERM reach and these did not). SIGQUIT still ends the station by its default action
# (exit status 128 + 3); SIGHUP, since 2026-12-06, ends it as SIGTERM does (exit 0, its closing
# summary said, the server logging "trainee station left"), where its default action had killed it
# (129, the session "lost"). A SIGHUP the station was started ignoring (nohup) stays ignored.
# Domain 158.
set -u
server=$1 client=$2 config_dir=$3
command -v script >/dev/null || { echo "FAIL script(1) not installed (util-linux)"; exit 1; }
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
trap 'kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
"$server" --config "$config_dir/server.json" --domain 158 --no-db > "$tmp/server.log" 2>&1 &
spid=$!
. "$(dirname "$0")/../wait_for.sh"
# Inside the pty: each station in the foreground (a background job of a shell without job control
# ignores SIGQUIT), its pid written by the shell it replaces, its output to a file; stty before and
# after, and echo and icanon set again between the two, so that each case shows its own.
cat > "$tmp/inner.sh" <<INNER
ulimit -c 0
stty -a > "$tmp/before"
sh -c 'echo \$\$ > "$tmp/pid1"; exec "\$0" "\$@"' "$client" --role trainee --domain 158 --phantom 4 --name quit \
  --input keyboard-finger > "$tmp/c1.log" 2>&1
echo \$? > "$tmp/rc1"
stty -a > "$tmp/after1"
stty icanon echo
sh -c 'echo \$\$ > "$tmp/pid2"; exec "\$0" "\$@"' "$client" --role trainee --domain 158 --phantom 1 --name hup \
  --input keyboard --print-period 0 > "$tmp/c2.log" 2>&1
echo \$? > "$tmp/rc2"
stty -a > "$tmp/after2"
trap '' HUP
sh -c 'echo \$\$ > "$tmp/pid3"; exec "\$0" "\$@"' "$client" --role trainee --domain 158 --phantom 1 --name nohup \
  --input keyboard --print-period 0 > "$tmp/c3.log" 2>&1
echo \$? > "$tmp/rc3"
touch "$tmp/done"
INNER
touch "$tmp/c1.log" "$tmp/c2.log" "$tmp/c3.log"
# The keys' side of the pty stays open until the end (script may end on its input's end). A third
# station, started with SIGHUP ignored (as by nohup), keeps it ignored: a SIGHUP, then q ends it, exit 0.
(wait_for "$tmp/c1.log" "keyboard (finger): arrows move" && sleep 0.3 && kill -QUIT "$(cat "$tmp/pid1")"
 wait_for "$tmp/c2.log" "keyboard: arrows move" && sleep 0.3 && kill -HUP "$(cat "$tmp/pid2")"
 wait_for "$tmp/c3.log" "keyboard: arrows move" && sleep 0.3 && kill -HUP "$(cat "$tmp/pid3")" && sleep 0.5 && printf q
 n=0; until [ -e "$tmp/done" ] || [ $n -gt 100 ]; do n=$((n + 1)); sleep 0.1; done) |
  script -qec "sh $tmp/inner.sh" /dev/null > "$tmp/script.log" 2>&1
# a flag on: "icanon", not "-icanon", among stty's words
on() { tr ' ' '\n' < "$1" 2>/dev/null | grep -qx "$2"; }
state() { for f in icanon echo; do on "$1" $f && printf '%s ' $f || printf -- '-%s ' $f; done; }
rc1=$(cat "$tmp/rc1" 2>/dev/null) rc2=$(cat "$tmp/rc2" 2>/dev/null) rc3=$(cat "$tmp/rc3" 2>/dev/null)
# SIGHUP's station left: its closing summary, and the server closed its session as left (not lost)
sid2=$(tr '\r' '\n' < "$tmp/c2.log" | sed -n 's/.*joined session \([0-9]*\) .*/\1/p' | head -n 1)
left2=no
n=0
until grep -q "session $sid2 closed after" "$tmp/server.log" || [ $n -gt 80 ]; do n=$((n + 1)); sleep 0.1; done
tr '\r' '\n' < "$tmp/c2.log" | grep -q "\[trainee hup\] session $sid2: .*contact samples sent" &&
  grep -q "session $sid2 closed after .* (trainee station left)" "$tmp/server.log" && left2=yes
if on "$tmp/before" icanon && on "$tmp/before" echo && on "$tmp/after1" icanon && on "$tmp/after1" echo &&
   on "$tmp/after2" icanon && on "$tmp/after2" echo && [ "$rc1" = 131 ] && [ "$rc2" = 0 ] && [ $left2 = yes ] &&
   [ "$rc3" = 0 ]; then
  echo "ok   the terminal before: $(state "$tmp/before"); after SIGQUIT ended the finger keyboard's station (exit $rc1):" \
       "$(state "$tmp/after1"); after SIGHUP ended the force keyboard's as SIGTERM does (exit $rc2, its summary said," \
       "the server: $(grep "session $sid2 closed after" "$tmp/server.log" | sed 's/^.*palp-server: //')): $(state "$tmp/after2");" \
       "with SIGHUP ignored, a SIGHUP ends nothing and q does (exit $rc3)"
  exit 0
fi
echo "FAIL the terminal before: '$(state "$tmp/before")' (want icanon echo); after SIGQUIT: '$(state "$tmp/after1")'" \
     "(want icanon echo), exit '$rc1' (want 131); after SIGHUP: '$(state "$tmp/after2")' (want icanon echo), exit '$rc2'" \
     "(want 0, as SIGTERM's), left: $left2 (want its summary said and the server's 'trainee station left' for session" \
     "'$sid2'); with SIGHUP ignored, after a SIGHUP and q: exit '$rc3' (want 0)"
for f in c1.log c2.log c3.log script.log server.log; do echo "--- $f"; tr '\r' '\n' < "$tmp/$f"; done
exit 1
