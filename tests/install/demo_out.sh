#!/bin/sh
# scripts/demo.sh deletes only what it wrote (2026-12-06, found by review: it ran
# rm -f "$PALP_DEMO_OUT"/*.log *.svg *.csv wherever the variable pointed, so PALP_DEMO_OUT=/var/log or
# a home directory lost files palp never wrote). Without running the demo: a copy of the script with
# stub palp-server and palp-client (the server records that it was started and exits at once, so the
# demo stops with "palp-server failed to start" within a second) and PALP_SKIP_SETUP=1, PALP_SECURE=0.
#  - a directory holding a foreign .log, .svg and .csv (and no marker): refused before anything runs,
#    exit 2, the message naming PALP_DEMO_OUT and the directory; the files byte-identical;
#  - a file: refused, exit 2;
#  - a new directory: used (the server started), the marker .palp-demo-out left in it;
#  - that directory again: used, and the previous run's *.log deleted (the demo still cleans up after
#    itself); an empty existing directory: used;
#  - a relative PALP_DEMO_OUT and PALP_DEMO_DB given from another directory: that directory's;
#  - the default out/demo left by an older demo without the marker: used whether PALP_DEMO_OUT is unset
#    or names it (relative, absolute, through ..).
# usage: demo_out.sh SOURCE_DIR
set -u
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/repo/scripts" "$tmp/build/server" "$tmp/build/client"
cp "$src/scripts/demo.sh" "$src/scripts/debian-path.sh" "$tmp/repo/scripts/"
printf '#!/bin/sh\necho "started $*" >> "%s/started"\nexit 1\n' "$tmp" > "$tmp/build/server/palp-server"
printf '#!/bin/sh\nexit 1\n' > "$tmp/build/client/palp-client"
chmod +x "$tmp/build/server/palp-server" "$tmp/build/client/palp-client"
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
demo() { # OUT [DIR [DB]]: runs the copy from DIR (default $tmp) with PALP_DEMO_OUT=OUT ("" as unset) and
  # PALP_DEMO_DB=DB; $rc, $msg; $started 1 if the stub server ran, $args its arguments
  rm -f "$tmp/started"
  msg=$(cd "${2:-$tmp}" && PALP_SKIP_SETUP=1 PALP_SECURE=0 PALP_BUILD_DIR="$tmp/build" PALP_DEMO_OUT="$1" \
    PALP_DEMO_DB="${3:-}" PALP_DEMO_DOMAIN=229 timeout 30 bash "$tmp/repo/scripts/demo.sh" 2>&1)
  rc=$?
  started=0 args=
  [ -f "$tmp/started" ] && started=1 args=$(cat "$tmp/started")
}

home=$tmp/home
mkdir -p "$home/docs"
echo "my own notes" > "$home/notes.log"
echo "<svg/>" > "$home/drawing.svg"
echo "a,b" > "$home/data.csv"
echo "kept" > "$home/docs/letter.txt"
sums=$(cd "$home" && find . -type f | sort | xargs md5sum)
demo "$home"
after=$(cd "$home" && find . -type f | sort | xargs md5sum)
if [ $rc -eq 2 ] && [ $started -eq 0 ] && [ "$sums" = "$after" ] &&
   printf '%s' "$msg" | grep -qF "PALP_DEMO_OUT=$home holds files the demo did not make (no .palp-demo-out in it)"; then
  ok "a directory with foreign files: refused (exit 2) before anything ran, naming PALP_DEMO_OUT; its .log, .svg, .csv intact"
else bad "a directory with foreign files: exit $rc, server started $started, files intact: $([ "$sums" = "$after" ] && echo yes || echo no): $msg"; fi

: > "$tmp/afile"
demo "$tmp/afile"
if [ $rc -eq 2 ] && [ $started -eq 0 ] && printf '%s' "$msg" | grep -q "is not a directory"; then
  ok "a file: refused (exit 2)"
else bad "a file: exit $rc, server started $started: $msg"; fi

new=$tmp/new/demo
demo "$new"
if [ $started -eq 1 ] && [ -f "$new/.palp-demo-out" ] && printf '%s' "$msg" | grep -q "palp-server failed to start"; then
  ok "a new directory: used (the server started, then the stub stopped it), the marker left"
else bad "a new directory: exit $rc, server started $started, marker $(ls -A "$new" 2>&1): $msg"; fi

echo "an earlier run's" > "$new/alice.log"
demo "$new"
if [ $started -eq 1 ] && [ ! -e "$new/alice.log" ]; then
  ok "the demo's own directory again: used, the previous run's alice.log deleted"
else bad "the demo's own directory again: server started $started, $(ls -A "$new" | tr '\n' ' '): $msg"; fi

mkdir -p "$tmp/empty"
demo "$tmp/empty"
if [ $started -eq 1 ] && [ -f "$tmp/empty/.palp-demo-out" ]; then ok "an empty directory: used, the marker left"
else bad "an empty directory: server started $started: $msg"; fi

# Relative paths are the caller's (2026-12-06, found by review: the demo cd'd into the repository first,
# so PALP_DEMO_OUT=rel/demo from elsewhere wrote into the repository's rel/demo): from $tmp/caller,
# rel/demo and rel.db are $tmp/caller's.
mkdir -p "$tmp/caller"
demo rel/demo "$tmp/caller" rel.db
if [ $started -eq 1 ] && [ -f "$tmp/caller/rel/demo/.palp-demo-out" ] && [ ! -e "$tmp/repo/rel" ] &&
   printf '%s' "$args" | grep -qF -- "--database $tmp/caller/rel.db"; then
  ok "a relative PALP_DEMO_OUT and PALP_DEMO_DB from another directory: that directory's rel/demo (the marker there) and rel.db"
else bad "relative PALP_DEMO_OUT from $tmp/caller: server started $started ($args), $(ls -A "$tmp/caller" "$tmp/repo" | tr '\n' ' '): $msg"; fi

# The default directory however it is named (found by review: PALP_DEMO_OUT=out/demo, the default written
# out, refused an old demo directory without the marker that leaving the variable unset accepted): an
# earlier demo's out/demo holding its alice.log and no marker, named by PALP_DEMO_OUT unset, out/demo
# from the repository, its absolute path, and a path through ..: each used, the old log deleted.
for name in "" out/demo "$tmp/repo/out/demo" "$tmp/repo/out/../out/demo"; do
  mkdir -p "$tmp/repo/out/demo"
  rm -f "$tmp/repo/out/demo/.palp-demo-out"
  echo "an earlier run's" > "$tmp/repo/out/demo/alice.log"
  demo "$name" "$tmp/repo"
  if [ $started -eq 1 ] && [ ! -e "$tmp/repo/out/demo/alice.log" ] && [ -f "$tmp/repo/out/demo/.palp-demo-out" ]; then
    ok "the default out/demo, marker-less, as PALP_DEMO_OUT='$name': used, the previous run's alice.log deleted"
  else bad "the default out/demo as PALP_DEMO_OUT='$name': exit $rc, server started $started: $msg"; fi
done
exit $fail
