#!/bin/sh
# SIGHUP never loses a session. palp-server with --log-file serves a trainee; mid-session
# the log is rotated (moved away) and SIGHUP sent twice: the server keeps running, writes
# a new log file, and the session goes on (the trainee finishes its 3 N press and sees
# the feedback). A second trainee is still pressing when SIGTERM stops the server: its
# session is closed ("server shutdown"), summarised in the log, and ended in the
# database (not left "(running)"). SIGHUP also re-reads the config's log_level: set to "warn",
# the next session's INFO line is not written; back to "info", lines return. palp-recorder
# re-opens its log on SIGHUP the same way.
# usage: sighup.sh PALP_SERVER PALP_CLIENT PALP_REVIEW PALP_RECORDER DDS_CONFIG DOMAIN
set -u
server=$1 client=$2 review=$3 recorder=$4 dds=$5 domain=$6
work=$(mktemp -d -t palp-sighup-test.XXXXXX)
spid= rpid=
cleanup() {
  [ -n "$spid" ] && kill "$spid" 2>/dev/null
  [ -n "$rpid" ] && kill "$rpid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
unset CYCLONEDDS_URI
cfgdir=$(cd "$(dirname "$dds")" && pwd)
mkcfg() { # log_level
  sed -e "s|\"scene\": \"\([^\"/]*\)\"|\"scene\": \"$cfgdir/\1\"|g" \
      -e "s|\"dds_config\": \"cyclonedds-loopback.xml\"|\"dds_config\": \"$cfgdir/cyclonedds-loopback.xml\", \"log_level\": \"$1\"|" \
      "$cfgdir/server.json" > "$work/server.json.new" && mv "$work/server.json.new" "$work/server.json"
}
mkcfg info
grep -q '"log_level": "info"' "$work/server.json" || { echo "FAIL cannot make the test config"; exit 1; }
"$server" --config "$work/server.json" --dds-config "$dds" --domain "$domain" --database "$work/s.db" --log-file "$work/server.log" \
  > "$work/server.out" 2>&1 &
spid=$!
"$recorder" --dds-config "$dds" --domain "$domain" --db "$work/rec.db" --log-file "$work/recorder.log" \
  > "$work/recorder.out" 2>&1 &
rpid=$!
sleep 1.5
"$client" --dds-config "$dds" --domain "$domain" --role trainee --phantom 1 --name hup-ann --profile step --t-on 0.2 \
  --t-off 3.5 --duration 4 --timeout 10 > "$work/ann.out" 2>&1 &
ann=$!
"$client" --dds-config "$dds" --domain "$domain" --role trainee --phantom 2 --name hup-bob --profile step --t-on 0.2 \
  --t-off 60 --duration 60 --timeout 10 > "$work/bob.out" 2>&1 &
bob=$!
sleep 1.5
mv "$work/server.log" "$work/server.log.1"
mv "$work/recorder.log" "$work/recorder.log.1"
kill -HUP "$spid" "$rpid"
sleep 0.5
kill -HUP "$spid"
sleep 0.3
kill -0 "$spid" 2>/dev/null && ok "palp-server alive after two SIGHUPs" || bad "palp-server died on SIGHUP"
kill -0 "$rpid" 2>/dev/null && ok "palp-recorder alive after SIGHUP" || bad "palp-recorder died on SIGHUP"
n=$(grep -c "SIGHUP: log re-opened" "$work/server.log" 2>/dev/null || echo 0)
[ "$n" -eq 2 ] && ok "server wrote to a new log file after rotation (2 SIGHUP lines)" || bad "new server log: $n SIGHUP lines"
# a plain server says so when it starts (its DDS config is loopback; since 2026-12-04)
grep -q "DDS Security off: every participant on domain $domain is trusted" "$work/server.log.1" \
  && ok "the first log says the server runs without DDS Security" || bad "no 'DDS Security off' line at start"
[ "$(grep -cE "session [0-9]+ opened" "$work/server.log.1")" -eq 2 ] && ! grep -qE "session [0-9]+ opened" "$work/server.log" \
  && ok "the rotated file kept the lines before SIGHUP" || bad "rotation split"
grep -q "SIGHUP: log re-opened" "$work/recorder.log" 2>/dev/null && ok "recorder wrote to a new log file" || bad "recorder log"
mkcfg warn
kill -HUP "$spid"
wait "$ann"; rc=$?
# The absence of the close line proves the level only once the server has closed ann's session: wait
# (up to 5 s) until the database has her session ended, then 0.2 s more (the server logs the close
# just after it hands the end to its log writer); not closed by then is a failure, not a pass.
closed=0
for _ in $(seq 50); do
  if "$review" --db "$work/s.db" list 2>/dev/null | grep hup-ann | grep -q normal; then closed=1; break; fi
  sleep 0.1
done
sleep 0.2
grep -q "SIGHUP: log level INFO -> WARN" "$work/server.log" && ok "SIGHUP re-read log_level: INFO -> WARN" || bad "log level not re-read"
[ $closed -eq 1 ] && ok "hup-ann's session ended in the database while the level was WARN" \
  || bad "hup-ann's session not ended in the database 5 s after her station exited: $("$review" --db "$work/s.db" list 2>&1)"
[ $closed -eq 1 ] && grep -q 'opened: trainee "hup-ann"' "$work/server.log.1" && ! grep -qE "session [0-9]+ closed after .*trainee station left" "$work/server.log" \
  && ok "at WARN the session's INFO close line was not written" || bad "INFO line written at WARN (or the session not closed)"
mkcfg info
kill -HUP "$spid"
sleep 0.3
grep -q "SIGHUP: log level WARN -> INFO" "$work/server.log" && ok "and back: WARN -> INFO" || bad "log level not restored"
grep -q "beyond log_level" "$work/server.log" && bad "a log_level-only change was reported as more" || true
# (session 90's review) a change beyond log_level is said at each SIGHUP while it waits for a restart, and
# not once the file is as the run has it again (the baseline moved with each SIGHUP: said once, then never)
sed -i 's|"max_force": 20.0|"max_force": 19.0|' "$work/server.json"
grep -q '"max_force": 19.0' "$work/server.json" || bad "cannot change the test config's max_force"
kill -HUP "$spid"; sleep 0.3
kill -HUP "$spid"; sleep 0.3
said=$(grep -c "differs from the configuration this run started with beyond log_level" "$work/server.log")
mkcfg info
kill -HUP "$spid"; sleep 0.3
said_after=$(grep -c "differs from the configuration this run started with beyond log_level" "$work/server.log")
[ "$said" -eq 2 ] && [ "$said_after" -eq 2 ] && ok "max_force changed: said at both SIGHUPs; the file put back: not said ($said, $said_after)" \
  || bad "a pending change: said $said time(s) at two SIGHUPs (want 2), $said_after after the file was put back (want 2)"
if [ $rc -eq 0 ] && grep -q "peak feedback 3\.[0-9]* N" "$work/ann.out"; then
  ok "the session across SIGHUP went on to its end: $(grep 'peak feedback' "$work/ann.out")"
else
  bad "trainee across SIGHUP: exit $rc"; cat "$work/ann.out"
fi
kill -TERM "$spid"; wait "$spid"; rc=$?; spid=
[ $rc -eq 0 ] && ok "SIGTERM: server exit 0" || bad "SIGTERM: server exit $rc"
wait "$bob"
grep -qE "session [0-9]+ closed after .* \(server shutdown\)" "$work/server.log" \
  && ok "open session closed: $(grep 'server shutdown)' "$work/server.log" | sed 's/^.*palp-server: //')" \
  || { bad "the open session was not closed by the shutdown"; cat "$work/server.log"; }
grep -qE "^[0-9]+ +hup-bob .*server shutdown" "$work/server.log" && ok "session table in the log" || bad "no summary table in the log"
list=$("$review" --db "$work/s.db" list 2>&1)
if printf '%s\n' "$list" | grep hup-bob | grep -qv running && printf '%s\n' "$list" | grep hup-ann | grep -q normal; then
  ok "both sessions ended in the database:"; printf '%s\n' "$list"
else
  bad "database: $list"
fi
kill -INT "$rpid"; wait "$rpid"; rc=$?; rpid=
[ $rc -eq 0 ] && ok "recorder stopped cleanly" || bad "recorder exit $rc"
exit $fail
