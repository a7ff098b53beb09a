#!/bin/sh
# The version every palp program prints and every session log records (cmake/PalpVersion.cmake, run at
# each build since 2026-12-06; before, it was read only when CMake configured, and a build of later
# commits named the configure's). Checks, on a git repository of the test's own:
# - the script writes PROJECT_VERSION+`git describe` and follows a new commit and an edit (-dirty);
# - it leaves the header untouched (same mtime) when the version did not change, so nothing rebuilds;
# - out of any git checkout, PROJECT_VERSION alone;
# and, on this build: the five programs print the version its last build read, which names a commit of
# this checkout, and a session log records it.
# usage: version.sh SOURCE_DIR BUILD_DIR PROJECT_VERSION DOMAIN
set -u
src=$1 build=$2 pv=$3 domain=$4
out=$(mktemp -d)
fail=0
check() { if eval "$2"; then echo "ok   $1"; else echo "FAIL $1"; fail=1; fi; }
script=$src/cmake/PalpVersion.cmake
gen() { cmake -DSRC="$1" -DOUT="$out/v.h" -DPROJECT_VERSION=9.8.7 -P "$script"; }
of() { sed -n 's/^#define PALP_VERSION_STRING "\(.*\)"$/\1/p' "$out/v.h"; }

mkdir "$out/repo" "$out/plain"
git -C "$out/repo" init -q
git -C "$out/repo" -c user.name=t -c user.email=t@t commit -q --allow-empty -m one
h1=$(git -C "$out/repo" rev-parse --short HEAD)
gen "$out/repo"
v1=$(of)
check "a commit: 9.8.7+its hash ($v1)" "[ '$v1' = '9.8.7+$h1' ]"
touch -d '2000-01-01' "$out/v.h"
gen "$out/repo"
check "unchanged: the header is not rewritten (mtime kept)" "[ \$(stat -c %Y '$out/v.h') = \$(date -d 2000-01-01 +%s) ]"
git -C "$out/repo" -c user.name=t -c user.email=t@t commit -q --allow-empty -m two
h2=$(git -C "$out/repo" rev-parse --short HEAD)
gen "$out/repo"
v2=$(of)
check "a later commit: its hash ($v2)" "[ '$v2' = '9.8.7+$h2' ] && [ '$h1' != '$h2' ]"
echo x >"$out/repo/f" && git -C "$out/repo" add f && git -C "$out/repo" -c user.name=t -c user.email=t@t commit -q -m three
echo y >"$out/repo/f"
h3=$(git -C "$out/repo" rev-parse --short HEAD)
gen "$out/repo"
v3=$(of)
check "an edit: -dirty ($v3)" "[ '$v3' = '9.8.7+$h3-dirty' ]"
GIT_CEILING_DIRECTORIES=$out gen "$out/plain"
v4=$(of)
check "no git checkout: the project version alone ($v4)" "[ '$v4' = '9.8.7' ]"

# This build's programs print the version its last build read (the header; a commit made since is
# this build's to catch up with, not this test's to fail on), and it names this checkout's project
# version and a commit of its history (or, out of git, the project version alone).
want=$(sed -n 's/^#define PALP_VERSION_STRING "\(.*\)"$/\1/p' "$build/generated/palp_version.h")
hash=$(printf '%s' "$want" | sed -n "s/^$pv+\(.*-g\)\{0,1\}\([0-9a-f]\{7,\}\)\(-dirty\)\{0,1\}\$/\2/p")
known=0
if git -C "$src" rev-parse --git-dir >/dev/null 2>&1; then
  [ -n "$hash" ] && git -C "$src" merge-base --is-ancestor "$hash" HEAD 2>/dev/null && known=1
else
  [ "$want" = "$pv" ] && known=1
fi
check "the build read $want, this checkout's project version and a commit of its history" "[ $known = 1 ]"
vs="" first="" same=1
for p in server/palp-server client/palp-client client/review/palp-review db/recorder/palp-recorder web/palp-web; do
  v=$("$build/$p" --version 2>&1 | sed -n 's/^palp-[a-z]* //p')
  vs="$vs $v"
  [ -n "$first" ] || first=$v
  [ "$v" = "$want" ] || same=0
done
check "the five programs print it:$vs" "[ $same = 1 ]"
"$build/server/palp-server" --config "$src/config/server.json" --domain "$domain" --database "$out/s.db" \
  --duration 0.5 >"$out/server.log" 2>&1
logged=$(python3 -c "import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute(\"select value from meta where key = 'app_version'\").fetchone()[0])" "$out/s.db" 2>&1)
check "a session log records it ($logged)" "[ '$logged' = '$first' ]"
[ $fail -eq 0 ] && rm -rf "$out"
exit $fail
