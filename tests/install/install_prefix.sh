#!/bin/sh
# Installs palp into a staging prefix (DESTDIR + --prefix, so the tree is also
# moved from where it was configured to be: it must be relocatable), then, from a
# directory outside the source tree and with no CYCLONEDDS_URI:
#   - no installed file contains the source (or build) tree's path (grep -c);
#   - the installed palp-server runs on its installed config, loopback DDS config and
#     database location; an installed palp-client trains on it (scripted, then with a
#     device driver built against the installed input.h); palp-review lists both
#     sessions from the installed database;
#   - a program outside palp builds against the installed library through pkg-config
#     and through find_package, and runs the installed scene.
# usage: install_prefix.sh BUILD_DIR SOURCE_DIR DOMAIN
set -u
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
domain=$3
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d -t palp-install-test.XXXXXX)
stage=$work/stage
prefix=/opt/palp-test
root=$stage$prefix
server_pid=
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
unset CYCLONEDDS_URI PALP_DATA_DIR PALP_DB

# 1. Install.
if DESTDIR=$stage cmake --install "$build" --prefix "$prefix" > "$work/install.log" 2>&1; then
  ok "cmake --install into DESTDIR=$stage, prefix $prefix ($(grep -c Installing "$work/install.log") files)"
else
  bad "cmake --install"; cat "$work/install.log"; exit 1
fi
f0=$fail; fail=0
for f in bin/palp-server bin/palp-client bin/palp-review bin/palp-recorder bin/palp-run bin/palp-stats bin/palp-fem \
         bin/palp-eval bin/palp-sweep bin/palp-web share/palp/www/dashboard.html share/palp/scripts/make-classroom-pki.sh \
         lib/libpalp.a include/palp/palp.h include/palp/input.h lib/pkgconfig/palp.pc \
         lib/cmake/palp/palpConfig.cmake lib/cmake/palp/palpConfigVersion.cmake lib/palp/libpalp_device_example.so \
         share/palp/config/server.json share/palp/config/paper_step.json share/palp/config/params/calibrated.json \
         share/palp/config/cyclonedds-loopback.xml share/palp/config/cyclonedds-lab.xml.example \
         share/palp/db/migrations/0001_init.sql share/palp/systemd/palp-server.service \
         share/palp/systemd/palp-recorder.service share/palp/systemd/palp-web.service lib/systemd/system/palp-server.service \
         share/doc/palp/README.md share/doc/palp/docs/deploy.md share/doc/palp/examples/device_example.c; do
  if [ -e "$root/$f" ]; then :; else bad "missing $f"; fi
done
[ $fail -eq 0 ] && ok "every expected file is installed"
fail=$((fail | f0)); f0=$fail; fail=0

# 2. No path into the source or build tree anywhere in the installed tree.
# One grep over the tree (-c: a "FILE:COUNT" line for every file, binaries too), not one grep an installed
# file (84 of them, session 84).
counts=$(grep -r -c -F -e "$src" -e "$build" "$root")
n=$(printf '%s\n' "$counts" | grep -c .)
nf=$(find "$root" -type f | wc -l)
[ "$n" -eq "$nf" ] || bad "grep -r -c read $n of the $nf installed files"
for fc in $(printf '%s\n' "$counts" | grep -v ':0$'); do
  f=${fc%:*} c=${fc##*:}
  bad "$f names the source/build tree ($c lines): $(strings "$f" | grep -F -e "$src" -e "$build" | head -3)"
done
[ $fail -eq 0 ] && ok "none of the $n installed files contains $src or $build"
fail=$((fail | f0)); f0=$fail; fail=0
help=$("$root/bin/palp-server" --help 2>&1)
if printf '%s' "$help" | grep -qF "$src"; then bad "palp-server --help names the source tree"; else ok "palp-server --help names no source path"; fi

# 3. Run the installed programs from outside the source tree.
cd "$work" || exit 1
for p in palp-server palp-client palp-review palp-recorder palp-run palp-stats palp-fem palp-eval palp-sweep palp-web; do
  v=$("$root/bin/$p" --version 2>&1); rc=$?
  if [ $rc -eq 0 ] && printf '%s' "$v" | grep -q "^$p [0-9]"; then :; else bad "$p --version: exit $rc: $v"; fi
done
[ $fail -eq 0 ] && ok "--version in every program ($("$root/bin/palp-server" --version))"
fail=$((fail | f0))
out=$("$root/bin/palp-server" --check 2>&1) && printf '%s' "$out" | grep -qF "$root/share/palp/config/server.json: ok" \
  && ok "installed server finds its installed config: $out" || bad "palp-server --check: $out"
"$root/bin/palp-server" --domain "$domain" --duration 25 --log-file "$work/server.log" > "$work/server.out" 2>&1 &
server_pid=$!
sleep 1.5
"$root/bin/palp-client" --role trainee --phantom 1 --name installed-ann --domain "$domain" --duration 2 --timeout 10 \
  > "$work/ann.out" 2>&1 && grep -q "peak feedback" "$work/ann.out" \
  && ok "installed client (scripted): $(grep 'peak feedback' "$work/ann.out")" || { bad "installed client"; cat "$work/ann.out"; }
# A device driver built against the installed headers only, loaded by the installed client.
export PKG_CONFIG_PATH=$root/lib/pkgconfig
if cc -std=c17 -Wall -Wextra -Wpedantic -shared -fPIC $(pkg-config --cflags palp) \
     "$root/share/doc/palp/examples/device_example.c" -o "$work/libmydevice.so" -lm 2> "$work/dev.err"; then
  "$root/bin/palp-client" --role trainee --phantom 2 --name installed-dev --domain "$domain" --duration 2 \
    --timeout 10 --input "device:$work/libmydevice.so:1" > "$work/dev.out" 2>&1 \
    && grep -qE "peak (feedback|rendered force) [0-9.]*[1-9]" "$work/dev.out" \
    && ok "driver (position in, force out) built against installed input.h: $(grep -oE 'peak (feedback|rendered force) [0-9.]+ N' "$work/dev.out")" \
    || { bad "installed client with the out-of-tree driver"; cat "$work/dev.out"; }
else
  bad "device driver does not build against the installed headers"; cat "$work/dev.err"
fi
kill -INT "$server_pid"; wait "$server_pid"; rc=$?; server_pid=
[ $rc -eq 0 ] && ok "installed server stopped cleanly on SIGINT" || bad "server exit $rc"
grep -qF "DDS config $root/share/palp/config/cyclonedds-loopback.xml" "$work/server.log" \
  && ok "server used the installed loopback DDS config" || { bad "server DDS config"; cat "$work/server.log"; }
if grep -qE '^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3}Z (ERROR|WARN |INFO |DEBUG) palp-server: ' \
     "$work/server.log" && ! grep -vqE '^[0-9]{4}-[0-9]{2}-[0-9]{2}T|^session |^[0-9]+ ' "$work/server.log"; then
  ok "every server log line is timestamped and levelled ($(wc -l < "$work/server.log") lines)"
else
  bad "server log lines"; cat "$work/server.log"
fi
db=$root/var/lib/palp/palp-sessions.db
list=$("$root/bin/palp-review" --db "$db" list 2>&1)
if printf '%s' "$list" | grep -q installed-ann && printf '%s' "$list" | grep -q installed-dev; then
  ok "installed palp-review lists both sessions from the installed database $db"
else
  bad "palp-review list: $list"
fi
[ -e "$src/out/palp-sessions.db" ] && [ "$src/out/palp-sessions.db" -nt "$work/install.log" ] \
  && bad "the installed server wrote into the source tree"

# 3a. Every installed server config (session 81: only server.json's database was moved out of ../out/, so
# server-exercises.json, server-classroom.json and server-paper.json logged into <prefix>/share/palp/out/,
# and server-classroom.json's PKI was share/palp/out/pki): its database resolves into the prefix's
# var/lib/palp, its PKI into etc/palp/certs, nothing leads into ../out/, and --check passes (the
# classroom's with a PKI made where its config says, by the installed script).
f0=$fail; fail=0
cfgdir=$root/share/palp/config
resolve_dir() { (cd "$cfgdir" && cd "$(dirname "$1")" 2>/dev/null && pwd); }
n=0
for cf in server.json server-exercises.json server-classroom.json server-paper.json; do
  f=$cfgdir/$cf
  [ -f "$f" ] || { bad "$cf not installed"; continue; }
  dbp=$(sed -n 's/^ *"database": *"\([^"]*\)".*/\1/p' "$f")
  if [ -n "$dbp" ] && [ "$(resolve_dir "$dbp")" = "$root/var/lib/palp" ] && [ "$(basename "$dbp")" = palp-sessions.db ]; then :
  else bad "installed $cf: \"database\": \"$dbp\" is not in $root/var/lib/palp"; fi
  grep -q '\.\./out/' "$f" && bad "installed $cf still leads into ../out/: $(grep -n '\.\./out/' "$f" | head -2)"
  n=$((n + 1))
done
pkip=$(sed -n 's/.*"pki": *"\([^"]*\)".*/\1/p' "$cfgdir/server-classroom.json")
# (with the trainee of 3b below: one classroom made for both, not two)
bash "$root/share/palp/scripts/make-classroom-pki.sh" "$root/etc/palp/certs" classroom --trainees installed-sec \
  > "$work/cpki.log" 2>&1 || { bad "make-classroom-pki.sh into etc/palp/certs"; cat "$work/cpki.log"; }
[ -n "$pkip" ] && [ "$(cd "$cfgdir" && cd "$pkip" 2>/dev/null && pwd)" = "$root/etc/palp/certs" ] \
  || bad "installed server-classroom.json: \"pki\": \"$pkip\" is not $root/etc/palp/certs"
for cf in server.json server-exercises.json server-classroom.json server-paper.json; do
  out=$("$root/bin/palp-server" --config "$cfgdir/$cf" --check 2>&1) || bad "palp-server --config installed $cf --check: $out"
done
[ $fail -eq 0 ] && ok "the $n installed server configs keep their database in $root/var/lib/palp (server-classroom.json its PKI in etc/palp/certs), none leads into ../out/, each passes --check"
fail=$((fail | f0))

# 3b. A secured classroom from the installed tree alone: the installed PKI script made the
# certificates (3a, into etc/palp/certs), the installed server and client find Debian's DDS Security plugins.
if [ -f "$root/etc/palp/certs/trainee/installed-sec.cert.pem" ]; then
  "$root/bin/palp-server" --domain "$domain" --duration 20 --pki "$root/etc/palp/certs" --no-db > "$work/sserver.log" 2>&1 &
  server_pid=$!
  sleep 1.5
  "$root/bin/palp-client" --role trainee --phantom 1 --pki "$root/etc/palp/certs" --identity trainee/installed-sec \
    --domain "$domain" --duration 2 --timeout 10 > "$work/sec.out" 2>&1 && grep -q "peak feedback" "$work/sec.out" \
    && ok "installed make-classroom-pki.sh, server --pki and client --identity: $(grep 'peak feedback' "$work/sec.out")" \
    || { bad "installed secured session"; cat "$work/sec.out" "$work/sserver.log"; }
  kill -INT "$server_pid"; wait "$server_pid"; server_pid=
else
  bad "installed make-classroom-pki.sh made no trainee/installed-sec"; cat "$work/cpki.log"
fi
rm -rf "$root/etc/palp"

# 4. A program outside palp against the installed library: pkg-config, then find_package.
if cc -std=c17 -Wall -Wextra -Wpedantic $(pkg-config --cflags palp) "$here/consumer.c" -o "$work/consumer-pc" \
     $(pkg-config --libs palp) 2> "$work/pc.err"; then
  out=$("$work/consumer-pc" "$root/share/palp/config/paper_step.json" 2>&1) \
    && ok "pkg-config build: $(printf '%s' "$out" | head -1)" || bad "pkg-config consumer: $out"
else
  bad "build through pkg-config"; cat "$work/pc.err"
fi
mkdir -p "$work/fp"
cp "$here/consumer.c" "$work/fp/"
cp "$here/CMakeLists.txt.consumer" "$work/fp/CMakeLists.txt"
if cmake -S "$work/fp" -B "$work/fp/build" -DCMAKE_PREFIX_PATH="$root" > "$work/fp.log" 2>&1 \
   && cmake --build "$work/fp/build" >> "$work/fp.log" 2>&1; then
  out=$("$work/fp/build/consumer" "$root/share/palp/config/paper_step.json" 2>&1) \
    && ok "find_package(palp) build: $(printf '%s' "$out" | head -1)" || bad "find_package consumer: $out"
else
  bad "build through find_package"; cat "$work/fp.log"
fi
exit $fail
