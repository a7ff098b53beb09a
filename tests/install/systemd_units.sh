#!/bin/sh
# The systemd units as installed: `systemd-analyze verify` must accept them with no
# message at all (it exits 0 on unknown keys and bad values, printing a warning, so
# the output is asserted empty), a deliberately broken copy must be reported (the
# checker works here), and the unit's ExecStart command line, run as systemd would run
# it (its state and log paths moved into a temporary directory), must start the server,
# log timestamped lines to the unit's --log-file and stop cleanly on the unit's
# KillSignal; palp-web's unit is ordered after time-sync.target; the three units name one
# User= and Group= (they share /var/lib/palp and /var/log/palp). What this cannot check
# without systemd as PID 1: DynamicUser, StateDirectory/LogsDirectory creation and the
# sandboxing options (docs/deploy.md).
# usage: systemd_units.sh BUILD_DIR DOMAIN
set -u
build=$(cd "$1" && pwd)
domain=$2
work=$(mktemp -d -t palp-systemd-test.XXXXXX)
pid=
cleanup() {
  [ -n "$pid" ] && kill "$pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
unset CYCLONEDDS_URI PALP_DATA_DIR
if ! command -v systemd-analyze > /dev/null; then
  echo "FAIL systemd-analyze is not installed (Debian package systemd, listed in scripts/debian-packages.txt)"
  exit 1
fi
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" > "$work/install.log" 2>&1 || { bad "cmake --install"; cat "$work/install.log"; exit 1; }
units=$prefix/lib/systemd/system
for u in palp-server palp-recorder palp-web; do
  f=$units/$u.service
  [ -f "$f" ] || { bad "$u.service not installed"; continue; }
  out=$(cd "$work" && systemd-analyze verify "$f" 2>&1); rc=$?
  if [ $rc -eq 0 ] && [ -z "$out" ]; then ok "systemd-analyze verify $u.service: exit 0, no warning"; else bad "verify $u.service: exit $rc: $out"; fi
  grep -q "^ExecStart=$prefix/bin/$u " "$f" && ok "$u.service runs the installed $prefix/bin/$u" || bad "$u.service ExecStart: $(grep ExecStart "$f")"
done
# One service user for the three units (session 81): they share StateDirectory/LogsDirectory palp, and
# each DynamicUser without User= got a UID of its own, so systemd chowned /var/lib/palp and /var/log/palp
# to whichever started last and the server lost its database and its log. One dynamic user name = one UID.
users=""
for u in palp-server palp-recorder palp-web; do
  f=$units/$u.service
  us=$(sed -n 's/^User=//p' "$f"); gs=$(sed -n 's/^Group=//p' "$f")
  if [ -n "$us" ] && [ "$(printf '%s\n' "$us" | wc -l)" -eq 1 ] && [ -n "$gs" ] && [ "$(printf '%s\n' "$gs" | wc -l)" -eq 1 ]; then
    users="$users $u:$us:$gs"
  else
    bad "$u.service names no single User= and Group= (User='$us' Group='$gs'): with DynamicUser each unit gets its own UID"
  fi
done
n=$(printf '%s\n' $users | sed 's/^[^:]*://' | sort -u | wc -l)
if [ "$(printf '%s\n' $users | wc -l)" -eq 3 ] && [ "$n" -eq 1 ]; then
  ok "the three units run as one user and group ($(printf '%s\n' $users | sed 's/^[^:]*://' | sort -u)), sharing /var/lib/palp and /var/log/palp"
else
  bad "the units' users and groups differ:$users"
fi

# Exit 2 is each program's refusal of its command line or configuration (a lab DDS config without --pki:
# palp-server exits 2); the units restarted it every 2 s until the start limit (session 81). Not restarted:
for u in palp-server palp-recorder palp-web; do
  if grep -qx 'RestartPreventExitStatus=2' "$units/$u.service" && grep -qx 'Restart=on-failure' "$units/$u.service"; then
    ok "$u.service: Restart=on-failure, but not after exit 2 (RestartPreventExitStatus=2)"
  else bad "$u.service restarts a refused configuration: $(grep -E '^Restart' "$units/$u.service" | tr '\n' ' ')"; fi
done

# Negative controls: an unknown key and a missing program must be reported.
sed 's/^Restart=/Restrat=/' "$units/palp-server.service" > "$work/broken-key.service"
out=$(cd "$work" && systemd-analyze verify "$work/broken-key.service" 2>&1)
printf '%s' "$out" | grep -q "Unknown key" && ok "a misspelt key is reported: $out" || bad "verify missed a misspelt key: $out"
sed "s|^ExecStart=$prefix/bin/palp-server|ExecStart=$work/nowhere/palp-server|" "$units/palp-server.service" > "$work/broken-exec.service"
out=$(cd "$work" && systemd-analyze verify "$work/broken-exec.service" 2>&1); rc=$?
[ $rc -ne 0 ] && ok "a missing program fails verify (exit $rc)" || bad "verify accepted a missing program: $out"

# The unit's own command line, with /var/lib/palp and /var/log/palp moved here and the
# site arguments a lab would put in /etc/default/palp.
exec_line=$(sed -n 's/^ExecStart=//p' "$units/palp-server.service")
mkdir -p "$work/state" "$work/log"
cmd=$(printf '%s' "$exec_line" | sed "s|/var/lib/palp|$work/state|g; s|/var/log/palp|$work/log|g")
PALP_SERVER_ARGS="--domain $domain --duration 30"
# shellcheck disable=SC2086 # split as systemd splits $VAR in ExecStart
eval "set -- $cmd"
"$@" > "$work/stdout" 2>&1 &
pid=$!
sleep 2
kill -TERM "$pid"; wait "$pid"; rc=$?; pid=
[ $rc -eq 0 ] && ok "unit command line started the server and stopped it on SIGTERM (exit 0)" || { bad "exit $rc"; cat "$work/stdout"; }
if grep -qE '^[0-9T:.-]+Z INFO  palp-server: SIGTERM: shutting down' "$work/log/server.log" && [ -f "$work/state/palp-sessions.db" ]; then
  ok "log at the unit's --log-file ($(wc -l < "$work/log/server.log") lines), database at its --database"
else
  bad "unit paths: $(ls -R "$work/state" "$work/log")"; cat "$work/log/server.log"
fi

# palp-web fixes its tokens' expiries from the wall clock at start (2026-12-06): its unit starts after the
# clock is synchronised, ordered after time-sync.target without pulling it in (systemd.special(7)).
wf=$units/palp-web.service
if grep -Eq '^After=.*\btime-sync\.target\b' "$wf" && ! grep -Eq '^(Wants|Requires)=.*\btime-sync\.target\b' "$wf"; then
  ok "palp-web.service: After=time-sync.target, not pulling it in"
else bad "palp-web.service ordering on time-sync.target: $(grep -E '^(After|Wants|Requires)=' "$wf" | tr '\n' ' ')"; fi

# palp-web's unit (2026-12-04): its command line as systemd runs it, the site arguments of a test
# (a free port on loopback, no join), SIGHUP re-opening its log as logrotate's postrotate asks,
# SIGTERM stopping it with exit 0.
exec_line=$(sed -n 's/^ExecStart=//p' "$units/palp-web.service")
cmd=$(printf '%s' "$exec_line" | sed "s|/var/log/palp|$work/log|g")
PALP_WEB_ARGS="--domain $domain --port 0 --no-join --duration 30"
# shellcheck disable=SC2086
eval "set -- $cmd"
"$@" > "$work/web.stdout" 2>&1 &
pid=$!
for k in $(seq 1 100); do grep -q "serving on 127.0.0.1 port" "$work/web.stdout" && break; sleep 0.1; done
mv "$work/log/web.log" "$work/log/web.log.1" 2>/dev/null
kill -HUP "$pid"; sleep 0.5
kill -TERM "$pid"; wait "$pid"; rc=$?; pid=
if [ $rc -eq 0 ] && grep -q "serving on 127.0.0.1 port" "$work/web.stdout" && grep -q "SIGHUP: log re-opened" "$work/log/web.log"; then
  ok "palp-web's unit command line served on loopback, re-opened $work/log/web.log on SIGHUP and stopped on SIGTERM (exit 0)"
else
  bad "palp-web unit: exit $rc"; cat "$work/web.stdout" "$work/log/web.log" 2>/dev/null
fi
exit $fail
