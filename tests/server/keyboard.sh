#!/bin/sh
# The keyboard input in a real terminal (a pty from script(1)): space presses with
# the default 1 N, "++" raises it to 1.5 N, space lifts, q quits. The station's
# peak feedback is the force the phantom pushes back with at quasi-static
# equilibrium: 1.5 N (Newton's third law), within 0.15 N. Domain 109.
# Each key waits for the station to show the last one's effect (fixed sleeps of 1.5 s, then 3 s,
# failed in the suite at -j2 beside FEM runs: a station that starts late gets its keys as one burst).
set -u
server=$1 client=$2 config_dir=$3
command -v script >/dev/null || { echo "FAIL script(1) not installed (util-linux)"; exit 1; }
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
trap 'kill $spid 2>/dev/null; rm -rf "$tmp"' EXIT
"$server" --config "$config_dir/server.json" --domain 109 --no-db > "$tmp/server.log" 2>&1 &
spid=$!
. "$(dirname "$0")/../wait_for.sh"
# The status line names the place and the distribution as every tool does (docs/naming.md; since session 83:
# "PRESS dist 3 at polar 0 deg azimuth 0 deg" before)
(wait_for "$tmp/client.log" "keyboard: arrows move"; sleep 0.5; printf ' '
 wait_for "$tmp/client.log" "PRESS at the pole, distribution III gaussian, 1.00 N"; sleep 0.8; printf '++'
 wait_for "$tmp/client.log" "PRESS at the pole, distribution III gaussian, 1.50 N"; sleep 1.5; printf ' '
 wait_for "$tmp/client.log" "lift  at the pole, distribution III gaussian, 1.50 N"; sleep 0.5; printf 'q') |
  script -qec "$client --role trainee --domain 109 --phantom 1 --name keys --input keyboard --print-period 0" \
    /dev/null > "$tmp/client.log" 2>&1
crc=$?
peak=$(tr '\r' '\n' < "$tmp/client.log" | sed -n 's/.*peak feedback \([0-9.]*\) N.*/\1/p' | tail -n 1)
if [ $crc -eq 0 ] && [ -n "$peak" ] && awk -v p="$peak" 'BEGIN { exit !(p >= 1.35 && p <= 1.65) }'; then
  echo "ok   keyboard session: exit 0, peak feedback $peak N (want 1.5 +- 0.15 N)"
  exit 0
fi
echo "FAIL exit $crc, peak feedback '$peak' (want 1.5 +- 0.15 N):"
tr '\r' '\n' < "$tmp/client.log"
exit 1
