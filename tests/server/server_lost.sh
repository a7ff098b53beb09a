#!/bin/sh
# A station notices a crashed server: palp-server is killed with SIGKILL while a
# trainee presses; the trainee's session state turns not-alive when the server's
# participant lease (1 s) expires, and palp-client ends within 3 s with exit
# status 3 and says why. Domain 107.
set -u
server=$1 client=$2 config_dir=$3
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
trap 'kill $spid $cpid 2>/dev/null; rm -rf "$tmp"' EXIT
"$server" --config "$config_dir/server.json" --domain 107 --no-db > "$tmp/server.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 107 --phantom 1 --name frank --profile sine --t-on 0 --t-off 30 \
  --duration 30 --print-period 0 > "$tmp/client.log" 2>&1 &
cpid=$!
# wait until the session is open
i=0
until grep -q "session 1 opened" "$tmp/server.log" || [ $i -ge 100 ]; do sleep 0.1; i=$((i+1)); done
sleep 1
kill -9 $spid
t0=$(date +%s%N)
wait $cpid
crc=$?
t1=$(date +%s%N)
ms=$(( (t1 - t0) / 1000000 ))
fail=0
if [ $crc -eq 3 ] && [ $ms -le 3000 ] && grep -q "server lost" "$tmp/client.log"; then
  echo "ok   client ended ${ms} ms after the server's SIGKILL (want <= 3000 ms), exit 3: $(tail -c 80 "$tmp/client.log")"
else
  echo "FAIL client exit $crc after ${ms} ms (want 3 within 3000 ms):"; cat "$tmp/client.log"; fail=1
fi
exit $fail
