#!/bin/sh
# One file, one option name (session 81, docs/naming.md): palp-server took --database, palp-recorder and
# palp-review --db; each now takes both. palp-server --check with --db (it was an unknown option, exit 2),
# a server run with --db and a recorder run with --database each write the file named (domain 209,
# loopback DDS config), and palp-review --database lists the server's file.
# usage: db_option.sh PALP_SERVER PALP_RECORDER PALP_REVIEW DOMAIN
set -u
server=$1 recorder=$2 review=$3 domain=$4
work=$(mktemp -d -t palp-db-option.XXXXXX)
trap 'rm -rf "$work"' EXIT
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
out=$("$server" --db "$work/unused.db" --check 2>&1); rc=$?
[ $rc -eq 0 ] && printf '%s' "$out" | grep -q ': ok (' && ok "palp-server --db FILE --check: exit 0: $out" \
  || bad "palp-server --db FILE --check: exit $rc: $out"
"$server" --db "$work/server.db" --domain "$domain" --duration 1.5 > "$work/server.out" 2>&1; rc=$?
[ $rc -eq 0 ] && grep -qF "logging sessions to $work/server.db" "$work/server.out" && [ -s "$work/server.db" ] \
  && ok "palp-server --db FILE writes its session log there (exit $rc)" || { bad "palp-server --db run: exit $rc"; cat "$work/server.out"; }
"$recorder" --database "$work/recorder.db" --domain "$domain" --duration 1 > "$work/recorder.out" 2>&1; rc=$?
[ $rc -eq 0 ] && grep -qF "into $work/recorder.db" "$work/recorder.out" && [ -s "$work/recorder.db" ] \
  && ok "palp-recorder --database FILE records into it (exit $rc)" || { bad "palp-recorder --database run: exit $rc"; cat "$work/recorder.out"; }
a=$("$review" --database "$work/server.db" list 2>&1); rc1=$?
b=$("$review" --db "$work/server.db" list 2>&1); rc2=$?
[ $rc1 -eq 0 ] && [ "$a" = "$b" ] && ok "palp-review --database FILE list = --db FILE list (exit $rc1)" \
  || bad "palp-review --database list: exit $rc1/$rc2: $a"
exit $fail
