#!/usr/bin/env bash
# Fuzzes every parser that reads the network or a file (issue 15), for a bounded time each.
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     # default 60 s, all 14 targets
#
# Builds build-fuzz/ with clang-14, -DPALP_FUZZ=ON (libFuzzer + AddressSanitizer +
# UndefinedBehaviorSanitizer), then runs each fuzz_<target> with tests/fuzz/corpus/<target>/ as
# its seeds (read-only: new coverage goes to build-fuzz/corpus/<target>/). A crash, leak, hang
# (> 10 s on one input) or sanitizer report stops that target; its input is written to
# build-fuzz/artifacts/<target>/. Fix the bug, then copy the input into
# tests/fuzz/corpus/<target>/ so the CTest test fuzz_corpus_<target> replays it for good.
# Exit status: 0 when no target found anything. Not run by scripts/test.sh (it takes minutes).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
. scripts/debian-path.sh # Debian's programs first (its comment)
all=(scene server_config fem_config inp stats_csv replay contact valid_range refusal local_model exercise web_access debrief playout)
usage() {
  echo "usage: bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]   (targets: ${all[*]})" >&2
  exit 2
}
# Checked before anything is installed or built: `fuzz.sh scene` took "scene" for the seconds,
# and libFuzzer read -max_total_time=scene as no limit at all.
secs=${1:-60}
[[ $secs =~ ^[1-9][0-9]{0,6}$ ]] || { echo "fuzz: SECONDS_PER_TARGET must be a whole number > 0, got \"$secs\"" >&2; usage; }
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz: unknown target \"$t\"" >&2; usage; }
done

need=()
command -v clang-14 >/dev/null || need+=(clang-14)
dpkg-query -W -f='${Status}' libclang-rt-14-dev 2>/dev/null | grep -q "install ok installed" || need+=(libclang-rt-14-dev)
if [ ${#need[@]} -gt 0 ]; then
  echo "fuzz: installing ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${need[@]}"
fi
bash scripts/setup.sh >/dev/null # the Debian packages of the project itself

build=build-fuzz
CC=clang-14 cmake -S . -B "$build" -DPALP_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j"$(nproc)" --target $(printf 'fuzz_%s ' "${targets[@]}") >/dev/null

export CYCLONEDDS_URI="file://$here/config/cyclonedds-loopback.xml"
# ASan's leak check at exit is on: a parser that leaks on some input is a finding too.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
found=0
printf '%-14s %10s %8s %7s  %s\n' target executions exec/s corpus result
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t
  art=$build/artifacts/$t
  mkdir -p "$corpus" "$art"
  log=$build/fuzz-$t.log
  dict=()
  case $t in
    scene|server_config|fem_config|exercise) dict=(-dict=tests/fuzz/json.dict) ;;
    inp) dict=(-dict=tests/fuzz/inp.dict) ;;
  esac
  set +e
  "$build/tests/fuzz/fuzz_$t" "${dict[@]}" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$art/" "$corpus" "tests/fuzz/corpus/$t" >"$log" 2>&1
  rc=$?
  set -e
  # A fuzzer that stops before libFuzzer's final stats (a bad flag or dictionary, a crash at start)
  # leaves none: under set -e the failed grep ended the script unsaid until session 82.
  execs=$(grep -m1 '^stat::number_of_executed_units' "$log" | awk '{print $2}' || true)
  rate=$(grep -m1 '^stat::average_exec_per_sec' "$log" | awk '{print $2}' || true)
  n=$(ls "$corpus" | wc -l)
  if [ $rc -eq 0 ] && [ -z "$execs" ]; then
    res="NO libFuzzer STATS (exit 0): see $log"
    found=1
  elif [ $rc -eq 0 ]; then
    res=ok
  else
    res="FOUND SOMETHING (exit $rc): $(ls "$art" | head -3 | tr '\n' ' ')see $log"
    found=1
  fi
  printf '%-14s %10s %8s %7s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "$n" "$res"
done
exit $found
