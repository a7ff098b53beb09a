#!/bin/sh
# palp-server's own session log is exact: a trainee driven by the example device
# driver (a position-driven finger) and a flood-free session are logged, the
# session ends "normal" after the station leaves, and `palp-review replay`
# reproduces every logged frame bit for bit (exit 0) - the replay contract of
# db/palp_db.h. A second trainee, erin, stopped 1.5 s (SIGSTOP) mid-press, keeps her one
# session, the review lists her station's loss and return, and her session replays too.
# Also: SIGINT stops the server with exit 0; the config's session_log_max_mb (1000) is the cap the
# server's log says as it opens (session 66). Domain 106.
set -u
. "$(dirname "$0")/../stall.sh"
server=$1 client=$2 review=$3 driver=$4 config_dir=$5
tmp=$(mktemp -d)
trap 'kill $spid 2>/dev/null; [ -n "${KEEP_TMP:-}" ] || rm -rf "$tmp"' EXIT
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
cat > "$tmp/server.json" <<JSON
{"domain_id": 106, "tick_rate_hz": 1000, "database": "log/sessions.db", "session_log_max_mb": 1000,
 "dds_config": "$config_dir/cyclonedds-loopback.xml",
 "phantoms": [{"id": 1, "name": "dome", "scene": "$config_dir/paper_step.json"}]}
JSON
fail=0
"$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 106 --phantom 1 --name dana --quiet --duration 2 \
  --input "device:$driver:1" > "$tmp/client.log" 2>&1
crc=$?
# erin's station is stopped 1.5 s mid-press: the server holds her session and she comes back to it.
"$client" --role trainee --domain 106 --phantom 1 --name erin --duration 6 --profile sine --t-on 0 --t-off 60 \
  --print-period 0 > "$tmp/erin.log" 2>&1 &
epid=$!
stall_station $epid "$tmp/erin.log" 1.5 1.5
wait $epid
erc=$?
sleep 0.3
kill -INT $spid
wait $spid
src=$?
if [ $crc -eq 0 ] && [ $src -eq 0 ]; then echo "ok   client exit $crc, server exit $src after SIGINT"
else echo "FAIL client exit $crc, server exit $src"; cat "$tmp/server.log" "$tmp/client.log"; fail=1; fi
db="$tmp/log/sessions.db"
list=$("$review" --db "$db" list 2>&1)
n=$(printf '%s\n' "$list" | grep -c " dana ")
if [ "$n" -eq 1 ] && printf '%s' "$list" | grep " dana " | grep -q normal; then echo "ok   one session of dana logged, ended normal"
else echo "FAIL session list: $list"; fail=1; fi
uid=$(printf '%s\n' "$list" | awk '/ dana /{print $1}')
show=$("$review" --db "$db" show "$uid" 2>&1)
# 2 s at 1 kHz with a 1 Hz probe: the finger is down for most of it, so the log holds inputs.
if printf '%s' "$show" | grep -Eq "contacts +[1-9][0-9]* inputs"; then echo "ok   contact inputs logged: $(printf '%s' "$show" | grep -E '^contacts')"
else echo "FAIL no contact inputs: $show"; fail=1; fi
out=$("$review" --db "$db" replay "$uid" 2>&1); rrc=$?
if [ $rrc -eq 0 ]; then echo "ok   replay exit 0: $out"; else echo "FAIL replay exit $rrc: $out"; fail=1; fi
# Session 81: the same replay where glibc's math library takes its baseline code, not its FMA/AVX2
# variants (GLIBC_TUNABLES, as on a CPU without them): their last bits differ, and the replay
# mismatched from frame 1, "diverges" as from a damaged log. The log keeps the server's numerics
# fingerprint: where it differs here, the replay says so up front and calls the divergence expected;
# where the CPU has no FMA/AVX2 nothing changes and the replay is bit-identical still.
out2=$(GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA "$review" --db "$db" replay "$uid" 2>&1); rrc2=$?
if grep -qw fma /proc/cpuinfo && grep -qw avx2 /proc/cpuinfo; then
  if [ $rrc2 -eq 1 ] && printf '%s' "$out2" | grep -q "ran on a machine whose math library computes the model's exp, pow, atan2, sin and cos differently in the last bit (numerics [0-9a-f]\{16\} there, [0-9a-f]\{16\} here" &&
    printf '%s' "$out2" | grep -q "identical frames: expected on this machine, whose math library is not the logging machine's"; then
    echo "ok   replayed with glibc's baseline math (this CPU has FMA and AVX2): the other library named, the divergence expected (exit 1)"
  else echo "FAIL replay with glibc's baseline math (exit $rrc2): $out2"; fail=1; fi
elif [ $rrc2 -eq 0 ]; then echo "ok   this CPU has no FMA/AVX2: the tunable changes nothing, the replay is bit-identical"
else echo "FAIL replay with GLIBC_TUNABLES on a CPU without FMA/AVX2 (exit $rrc2): $out2"; fail=1; fi
list=$("$review" --db "$db" list 2>&1)
euid=$(printf '%s\n' "$list" | awk '/ erin /{print $1}')
eshow=$("$review" --db "$db" show "$euid" 2>&1)
if [ $erc -eq 0 ] && [ "$(printf '%s\n' "$list" | grep -c " erin ")" -eq 1 ] && printf '%s' "$list" | grep " erin " | grep -q normal \
  && printf '%s' "$eshow" | grep -q "leave .*(trainee, lost; session held)" && printf '%s' "$eshow" | grep -q "join .*(trainee, back from a stall)"; then
  echo "ok   erin, stopped 1.5 s, kept her one session (ended normal); review shows: $(printf '%s' "$eshow" | grep '(trainee' | sed 's/^ *//' | tr '\n' ';')"
else echo "FAIL erin (exit $erc): $list"; printf '%s\n' "$eshow"; cat "$tmp/erin.log"; fail=1; fi
out=$("$review" --db "$db" replay "$euid" 2>&1); rrc=$?
if [ $rrc -eq 0 ]; then echo "ok   erin's held and resumed session replays, exit 0: $out"; else echo "FAIL erin's replay exit $rrc: $out"; fail=1; fi
grep -q "session log: .* 0 shed" "$tmp/server.log" && echo "ok   nothing shed: $(grep 'session log: .* records written' "$tmp/server.log")" \
  || { echo "FAIL writer counts: $(grep 'session log' "$tmp/server.log")"; fail=1; }
# the config's session_log_max_mb, in MB, is the cap palp-server gives its log (session 66)
grep -q "INFO  palp-server: session log: 0\.[0-9][0-9] MB of its cap of 1000 MB (session_log_max_mb)$" "$tmp/server.log" \
  && echo "ok   the log's cap from the config said as it opens" \
  || { echo "FAIL no cap line: $(grep 'session log' "$tmp/server.log")"; fail=1; }
exit $fail
