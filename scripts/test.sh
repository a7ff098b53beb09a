#!/usr/bin/env bash
# Sets up, builds and runs every test through CTest.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
bash scripts/setup.sh
build=${PALP_BUILD_DIR:-build}
cd "$build"
# two slots per core: the CPU-bound tests take two each, and the cores are a resource that keeps
# the timing-sensitive tests apart from them (tests/CMakeLists.txt, "Slots")
ctest --output-on-failure -j"$((2 * $(nproc)))" --timeout 300 --resource-spec-file "$here/tests/resources.json"
