#!/bin/sh
# scripts/fuzz.sh checks its arguments before it installs or builds anything (Session 75 review:
# `fuzz.sh scene` took "scene" for the seconds, and libFuzzer read -max_total_time=scene as no
# limit). Runs a copy of the script in an empty directory, with apt-get stubbed out, so that a
# script without the check cannot install or build here: it would fail some other way.
set -u
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/scripts" "$tmp/bin"
cp "$src/scripts/fuzz.sh" "$src/scripts/debian-path.sh" "$tmp/scripts/"
printf '#!/bin/sh\necho "apt-get stub: not here" >&2; exit 1\n' > "$tmp/bin/apt-get"
chmod +x "$tmp/bin/apt-get"
fail=0
expect() { # want-message args...
  want=$1; shift
  out=$(PATH="$tmp/bin:$PATH" bash "$tmp/scripts/fuzz.sh" "$@" 2>&1); rc=$?
  left=$(ls -A "$tmp" | tr '\n' ' ')
  if [ $rc -eq 2 ] && printf '%s' "$out" | grep -qF "$want" && printf '%s' "$out" | grep -q '^usage:' &&
     [ "$left" = "bin scripts " ]; then
    echo "ok   fuzz.sh $*: exit 2, $(printf '%s' "$out" | head -1)"
  else
    echo "FAIL fuzz.sh $* (want exit 2, \"$want\", a usage line and nothing built): exit $rc, left [$left]: $out"
    fail=1
  fi
}
expect 'SECONDS_PER_TARGET must be a whole number > 0, got "scene"' scene
expect 'got "0"' 0
expect 'got "1.5"' 1.5 scene
expect 'got "-5"' -5
expect 'unknown target "scenes"' 5 scenes
exit $fail
