#!/bin/sh
# Several servers on one domain, on four "hosts": network namespaces this test creates
# (a bridge in a switch namespace, one veth per host, addresses 10.77.0.1-4/24 that
# exist only inside them; nothing is sent anywhere else). Host 1 and 2 run palp-server
# "room-a" (number 1) and "room-b" (number 2), host 3 the recorder, host 4 the trainees:
#   - a second "room-a" (host 3) refuses to start (exit 1, names the holder);
#   - ann (phantom "dome A" by name on room-a, --rejoin), cid (room-a's phantom 2,
#     --rejoin) and bob (room-b's phantom 1) press; room-a is killed (SIGKILL)
#     mid-session; ann and cid are told (their session state turns not-alive) and
#     rejoin the phantom of the same name on room-b, and go on pressing;
#   - the recorder's one database holds all five sessions of both servers, the two on
#     the dead server ended "error" (server lost), the others normal; room-b's own log
#     holds the three it served; palp-review lists ann's sessions across both servers.
# If network namespaces cannot be made here (no CAP_NET_ADMIN, no ip), the test says so
# and runs the same scenario as processes on loopback with the loopback DDS config.
# usage: multi_server.sh PALP_SERVER PALP_CLIENT PALP_RECORDER PALP_REVIEW LOOPBACK_DDS_CONFIG DOMAIN
set -u
server=$1 client=$2 recorder=$3 review=$4 loopback=$5 domain=$6
work=$(mktemp -d -t palp-multi-test.XXXXXX)
tag=pm$$
pids=
netns=0
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
cleanup() {
  for p in $pids; do kill -9 "$p" 2>/dev/null; done
  if [ $netns -eq 1 ]; then
    for n in sw h1 h2 h3 h4; do ip netns del "$tag$n" 2>/dev/null; done
  fi
  rm -rf "$work"
}
trap cleanup EXIT
unset CYCLONEDDS_URI

# With --server the ids are that server's own (20 bits): a larger one was OR-ed into the server number
# and joined another server's phantom without a word (until 2026-12-07). Refused before any DDS.
"$client" --role trainee --server room-a --phantom 1048577 --dds-config "$loopback" --domain "$domain" \
  > "$work/bigid.out" 2>&1
rc=$?
if [ $rc -eq 2 ] && grep -q -- "--server room-a: --phantom and --session are that server's own ids, 1..1048575" "$work/bigid.out"; then
  ok "--server room-a --phantom 1048577 refused (exit 2): $(head -n 1 "$work/bigid.out" | sed 's/^palp-client: //')"
else
  bad "--server room-a --phantom 1048577: exit $rc"; head -n 3 "$work/bigid.out"
fi

make_netns() {
  [ -n "${PALP_TEST_NO_NETNS:-}" ] && { echo "PALP_TEST_NO_NETNS is set"; return 1; }
  command -v ip > /dev/null || { echo "no ip(8)"; return 1; }
  ip netns add "${tag}sw" 2>&1 || return 1
  netns=1
  ip -n "${tag}sw" link add br0 type bridge && ip -n "${tag}sw" link set br0 up || return 1
  for i in 1 2 3 4; do
    ip netns add "$tag"h$i || return 1
    ip -n "${tag}sw" link add p$i type veth peer name e$i netns "$tag"h$i || return 1
    ip -n "${tag}sw" link set p$i master br0 && ip -n "${tag}sw" link set p$i up || return 1
    ip -n "$tag"h$i addr add 10.77.0.$i/24 dev e$i && ip -n "$tag"h$i link set e$i up \
      && ip -n "$tag"h$i link set lo up || return 1
    # Cyclone on host i: its own address, unicast discovery of the other hosts, no multicast.
    cat > "$work/dds$i.xml" <<XML
<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any">
  <General><Interfaces><NetworkInterface address="10.77.0.$i" multicast="false"/></Interfaces>
    <AllowMulticast>false</AllowMulticast><MaxMessageSize>65500B</MaxMessageSize></General>
  <Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>
    <Peers><Peer Address="10.77.0.1"/><Peer Address="10.77.0.2"/><Peer Address="10.77.0.3"/><Peer Address="10.77.0.4"/></Peers>
    <LeaseDuration>1s</LeaseDuration></Discovery>
</Domain></CycloneDDS>
XML
  done
  # A path from host 4 to host 1: one datagram (bash's /dev/udp), then the neighbour entry (ARP answered).
  ip netns exec "$tag"h4 bash -c 'echo palp > /dev/udp/10.77.0.1/9' 2>/dev/null
  for k in 1 2 3 4 5 6 7 8 9 10; do
    ip -n "$tag"h4 neigh show 10.77.0.1 | grep -q lladdr && return 0
    sleep 0.2
  done
  echo "no path between the namespaces"; return 1
}

if out=$(make_netns 2>&1); then
  netns=1 # make_netns ran in the $( ) subshell: its netns=1 did not reach this shell, so until
          # 2026-12-03 the cleanup never deleted the namespaces (105 were left on this machine)
  ok "four hosts in network namespaces ${tag}h1-4 on a bridge in ${tag}sw (10.77.0.1-4, inside them only)"
  on() { h=$1; shift; ip netns exec "$tag$h" "$@"; }
  on_bg() { h=$1; shift; exec ip netns exec "$tag$h" "$@"; } # run with &: the pid is the program's
  dds() { echo "$work/dds${1#h}.xml"; }
else
  echo "NOTE network namespaces are not permitted here ($out): falling back to processes on loopback with"
  echo "     distinct server identities (the same scenario, one host)"
  for n in sw h1 h2 h3 h4; do ip netns del "$tag$n" 2>/dev/null; done
  netns=0
  on() { shift; "$@"; }
  on_bg() { shift; exec "$@"; }
  dds() { echo "$loopback"; }
fi

# The namespaces' network is the test's alone: the servers run plain DDS on it only because they
# are told so (--insecure); without it a server refuses to serve beyond loopback unsecured.
if [ $netns -eq 1 ]; then
  on h3 "$server" --dds-config "$(dds h3)" --domain "$domain" --server-name room-c --no-db --duration 1 \
    > "$work/plain.out" 2>&1
  rc=$?
  if [ $rc -eq 2 ] && grep -q 'refusing to serve beyond loopback without DDS Security' "$work/plain.out" \
     && grep -q 'NetworkInterface 10.77.0.3> is not loopback' "$work/plain.out"; then
    ok "a plain server on the namespaces' network without --insecure is refused before it joins (exit 2)"
  else
    bad "a plain server beyond loopback: exit $rc"; cat "$work/plain.out"
  fi
fi
srv() { # host name number
  on_bg "$1" "$server" --dds-config "$(dds "$1")" --domain "$domain" --server-name "$2" --server-number "$3" \
    --threads 1 --database "$work/$2.db" --log-file "$work/$2.log" --insecure
}
srv h1 room-a 1 > "$work/room-a.out" 2>&1 & pid_a=$!; pids="$pids $pid_a"
srv h2 room-b 2 > "$work/room-b.out" 2>&1 & pid_b=$!; pids="$pids $pid_b"
on_bg h3 "$recorder" --dds-config "$(dds h3)" --domain "$domain" --db "$work/recorder.db" --log-file "$work/recorder.log" \
  > "$work/recorder.out" 2>&1 &
pid_r=$!; pids="$pids $pid_r"
sleep 2
# The same identity again, from another host: refused.
on h3 "$server" --dds-config "$(dds h3)" --domain "$domain" --server-name room-a --server-number 7 --no-db \
  --identity-wait 1.5 --insecure > "$work/dup.out" 2>&1
rc=$?
if [ $rc -eq 1 ] && grep -q 'server name "room-a" (number 1) is already running on this domain' "$work/dup.out"; then
  ok "a second \"room-a\" refuses to start: $(grep 'already running' "$work/dup.out" | sed 's/^.*palp-server: //')"
else
  bad "duplicate identity: exit $rc"; cat "$work/dup.out"
fi
trainee() { # name args...
  n=$1; shift
  on_bg h4 "$client" --dds-config "$(dds h4)" --domain "$domain" --role trainee --name "$n" --profile step --t-on 0.2 \
    --t-off 60 --magnitude 2 --duration 9 --timeout 10 --print-period 0 "$@"
}
trainee ann --server room-a --phantom-name "dome A (long-term)" --rejoin > "$work/ann.out" 2>&1 & pid_ann=$!
trainee cid --server room-a --phantom 2 --rejoin > "$work/cid.out" 2>&1 & pid_cid=$!
trainee bob --server room-b --phantom 1 > "$work/bob.out" 2>&1 & pid_bob=$!
pids="$pids $pid_ann $pid_cid $pid_bob"
sleep 4
kill -9 "$pid_a"
t_kill=$(date +%s%N)
echo "room-a killed (SIGKILL) mid-session"
# Time from the kill to each rejoin (the rejoin line is flushed when it happens): the
# participant lease (1 s) plus finding the phantom and joining.
for k in $(seq 1 80); do
  for n in ann cid; do
    if [ ! -e "$work/$n.rejoin_ms" ] && grep -q "rejoined as session" "$work/$n.out" 2>/dev/null; then
      echo $(( ($(date +%s%N) - t_kill) / 1000000 )) > "$work/$n.rejoin_ms"
    fi
  done
  [ -e "$work/ann.rejoin_ms" ] && [ -e "$work/cid.rejoin_ms" ] && break
  sleep 0.05
done
echo "kill -> rejoined: ann $(cat "$work/ann.rejoin_ms" 2>/dev/null || echo never) ms, cid $(cat "$work/cid.rejoin_ms" 2>/dev/null || echo never) ms (polled every 50 ms)"
for p in $pid_ann $pid_cid $pid_bob; do wait "$p"; echo "trainee exit $?" >> "$work/exits"; done
grep -qv "exit 0" "$work/exits" && { bad "a trainee failed: $(cat "$work/exits")"; }
for n in ann cid; do
  line=$(grep "rejoined as session" "$work/$n.out")
  new_phantom=$(printf '%s' "$line" | sed -n 's/.*on phantom \([0-9]*\).*/\1/p')
  if [ -n "$new_phantom" ] && [ $((new_phantom >> 20)) -eq 2 ] && grep -q "peak feedback 2\.[0-9]* N" "$work/$n.out"; then
    ok "$n rejoined on room-b: $(printf '%s' "$line" | sed 's/^\[[^]]*\] //')"
  else
    bad "$n did not rejoin on room-b"; cat "$work/$n.out"
  fi
done
grep -q "peak feedback 2\.[0-9]* N" "$work/bob.out" && ok "bob (room-b) unaffected: $(grep -o 'peak feedback [0-9.]* N' "$work/bob.out")" \
  || { bad "bob"; cat "$work/bob.out"; }
grep -q 'server "room-a" (number 1, .*) is gone from the domain' "$work/room-b.log" && ok "room-b logged room-a's loss" \
  || bad "room-b did not notice room-a's loss"
kill -INT "$pid_b"; wait "$pid_b"; rc_b=$?
sleep 0.5
kill -INT "$pid_r"; wait "$pid_r"; rc_r=$?
pids=
[ $rc_b -eq 0 ] && [ $rc_r -eq 0 ] && ok "room-b and the recorder stopped cleanly" || bad "exits: room-b $rc_b, recorder $rc_r"

q() { sqlite3 "$1" "$2" 2>&1; }
rows=$(q "$work/recorder.db" "SELECT trainee || ' ' || (CAST(phantom_id AS INTEGER) >> 20) || ' ' || IFNULL(end_reason,'running') FROM session ORDER BY trainee, start_unix_s")
echo "recorder database (trainee, server number, end):"; printf '%s\n' "$rows" | sed 's/^/     /'
want="ann 1 error
ann 2 normal
bob 2 normal
cid 1 error
cid 2 normal"
[ "$rows" = "$want" ] || { echo "--- room-a log"; cat "$work/room-a.log"; echo "--- room-b log"; cat "$work/room-b.log"; }
[ "$rows" = "$want" ] && ok "one recorder gathered all 5 sessions of both servers; the dead server's 2 ended 'error' (server lost)" \
  || bad "recorder database: want
$want"
n_b=$(q "$work/room-b.db" "SELECT count(*) FROM session WHERE end_reason = 'normal'")
[ "$n_b" = "3" ] && ok "room-b's own database: 3 sessions, all ended normally" || bad "room-b database: $n_b normal sessions"
list=$("$review" --db "$work/recorder.db" list --trainee ann 2>&1)
[ "$(printf '%s\n' "$list" | grep -c '^dds-.* ann ')" -eq 2 ] && ok "palp-review lists ann's sessions on both servers:" \
  && printf '%s\n' "$list" | sed 's/^/     /' || bad "palp-review: $list"
exit $fail
