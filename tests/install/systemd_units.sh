#!/bin/sh
# The systemd units as installed: `systemd-analyze verify` must accept them with no
# message at all (it exits 0 on unknown keys and bad values, printing a warning, so
# the output is asserted empty), a deliberately broken copy must be reported (the
# checker works here), and the unit's ExecStart command line, run as systemd would run
# it (its state and log paths moved into a temporary directory), must start the server,
# log timestamped lines to the unit's --log-file and stop cleanly on the unit's
# KillSignal. What this cannot check without systemd as PID 1: DynamicUser,
# StateDirectory/LogsDirectory creation and the sandboxing options (docs/deploy.md).
# usage: systemd_units.sh BUILD_DIR DOMAIN
set -u
build=$(cd "$1" && pwd)
domain=$2
work=$(mktemp -d /tmp/palp-systemd-test.XXXXXX)
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
for u in palp-server palp-recorder; do
  f=$units/$u.service
  [ -f "$f" ] || { bad "$u.service not installed"; continue; }
  out=$(cd "$work" && systemd-analyze verify "$f" 2>&1); rc=$?
  if [ $rc -eq 0 ] && [ -z "$out" ]; then ok "systemd-analyze verify $u.service: exit 0, no warning"; else bad "verify $u.service: exit $rc: $out"; fi
  grep -q "^ExecStart=$prefix/bin/$u " "$f" && ok "$u.service runs the installed $prefix/bin/$u" || bad "$u.service ExecStart: $(grep ExecStart "$f")"
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
exit $fail
