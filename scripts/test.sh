#!/usr/bin/env bash
# Sets up, builds and runs every test through CTest.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
. scripts/debian-path.sh # Debian's programs first (its comment)
bash scripts/setup.sh
build=${PALP_BUILD_DIR:-build}
cd "$build"
# The tests' temporary files go to a directory of this run's own, so that a test that leaves
# files behind is caught here rather than filling /tmp run after run (~45 MB a run until
# 2026-12-05: docs/robustness.md, "Temporary files").
tmp=$(mktemp -d "${TMPDIR:-/tmp}/palp-tests.XXXXXX")
# three slots per core: a computation takes two slots and one core (the cores are a CTest resource,
# which also keeps the flood tests apart from the computations) and runs at nice 19, and the tests
# that mostly wait fill the other slots (tests/CMakeLists.txt, "Slots")
rc=0
TMPDIR=$tmp ctest --no-tests=error --output-on-failure -j"$((3 * $(nproc)))" --timeout 300 \
  --resource-spec-file "$here/tests/resources.json" || rc=$?
left=$(find "$tmp" -mindepth 1 -maxdepth 1 | sort)
if [ "$rc" -ne 0 ]; then
  if [ -n "$left" ]; then echo "The failed tests' temporary files are kept in $tmp"; else rmdir "$tmp"; fi
  exit "$rc"
fi
if [ -n "$left" ]; then
  echo "FAIL: the tests passed but left $(echo "$left" | wc -l) temporary file(s) behind in $tmp (kept):"
  echo "$left" | sed 's|^|  |' | head -40
  exit 1
fi
rmdir "$tmp"
echo "No temporary file left behind (TMPDIR $tmp, removed)."
