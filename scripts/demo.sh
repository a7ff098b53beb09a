#!/usr/bin/env bash
# The classroom demo, on loopback only: a palp-server hosting two phantoms, two
# trainee stations palpating their own phantom with scripted profiles, a visual
# station showing one of them and an instructor observer following the other,
# for about 8 s. Then everything stops cleanly and a summary of every session is
# printed. Builds first through scripts/setup.sh (idempotent: installs only missing
# packages, rebuilds only what changed) unless PALP_SKIP_SETUP=1; PALP_BUILD_DIR
# selects the build directory (default build/).
#
#   bash scripts/demo.sh            # logs and the SVG snapshot go to out/demo/
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
build=${PALP_BUILD_DIR:-build}
if [ "${PALP_SKIP_SETUP:-0}" != 1 ]; then
  bash scripts/setup.sh
fi
server=$build/server/palp-server
client=$build/client/palp-client
for exe in "$server" "$client"; do
  if [ ! -x "$exe" ]; then
    echo "demo: $exe not found; build first: cmake -S . -B $build && cmake --build $build -j2" >&2
    exit 1
  fi
done
# Loopback-only DDS unless the caller chose a config; a domain of its own so the
# demo does not meet a test run or a real class.
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$here/config/cyclonedds-loopback.xml}
domain=${PALP_DEMO_DOMAIN:-42}
out=${PALP_DEMO_OUT:-out/demo}
mkdir -p "$out"
rm -f "$out"/*.log "$out"/*.svg "$out"/*.csv

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

# Sessions of this run only, for the review at the end (the log keeps every run).
since=$(date +%Y-%m-%dT%H:%M:%S)
echo "demo: palp-server on DDS domain $domain (loopback only), logs in $out/"
"$server" --config config/server.json --domain "$domain" >"$out/server.log" 2>&1 &
server_pid=$!
pids+=("$server_pid")
for _ in $(seq 50); do
  grep -q "tick thread" "$out/server.log" 2>/dev/null && break
  if ! kill -0 "$server_pid" 2>/dev/null; then
    echo "demo: palp-server failed to start:" >&2
    cat "$out/server.log" >&2
    exit 1
  fi
  sleep 0.1
done

# Trainee alice: the paper's protocol on phantom 1 - a 3 N step held 2 s with
# distribution II (5.2 cm^2 uniform patch), then release and recovery.
"$client" --role trainee --domain "$domain" --phantom 1 --name alice \
  --profile step --magnitude 3 --t-on 0.5 --t-off 2.5 --distribution 2 --polar 30 --azimuth 40 \
  --duration 7 --print-period 1 --plot --feedback-csv "$out/alice-feedback.csv" --contact-csv "$out/alice-contact.csv" \
  >"$out/alice.log" 2>&1 &
pids+=($!)
alice=$!
# Trainee bob: a distal-finger press (distribution IV) oscillating 1.5 +- 1 N at 1 Hz on phantom 2.
"$client" --role trainee --domain "$domain" --phantom 2 --name bob \
  --profile sine --magnitude 1 --offset 1.5 --frequency 1 --t-on 0.5 --t-off 5.5 --distribution 4 \
  --polar 20 --azimuth 200 --duration 7 --print-period 1 >"$out/bob.log" 2>&1 &
pids+=($!)
bob=$!
# The visual station shows bob's phantom; the instructor follows alice.
"$client" --role visual --domain "$domain" --phantom 2 --name screen --no-color --map-every 2 \
  --svg "$out/bob-peak.svg" --duration 8 >"$out/visual.log" 2>&1 &
pids+=($!)
visual=$!
"$client" --role observer --domain "$domain" --trainee alice --name instructor --print-period 1 --duration 8 \
  >"$out/observer.log" 2>&1 &
pids+=($!)
observer=$!

status=0
for p in "$alice" "$bob" "$visual" "$observer"; do wait "$p" || status=$?; done
kill -INT "$server_pid"
wait "$server_pid" || status=$?
pids=()

echo
echo "== instructor observer (following alice) =="
grep -E "presses|lifts|pressing" "$out/observer.log" | head -12 || true
echo
echo "== visual station (bob's phantom), last terminal map =="
awk '/^session [0-9]+, phantom/{buf=""} {buf=buf $0 "\n"} END{printf "%s", buf}' "$out/visual.log" | head -24
echo
echo "== alice's haptic station: the force she felt =="
sed -n '/^feedback |F|/,$p' "$out/alice.log"
echo
echo "== stations =="
for f in alice bob visual observer; do grep -E "^\[[a-z]+[^]]*\] session [0-9]+:" "$out/$f.log" | tail -n 1; done
echo
echo "== sessions (palp-server) =="
sed -n '/palp-server session summary/,$p' "$out/server.log" | tail -n +2
echo
echo "demo: peak-displacement snapshot of bob's phantom: $out/bob-peak.svg; alice's feedback: $out/alice-feedback.csv"
grep -E "logging sessions to|session log:" "$out/server.log" | sed 's/^.*palp-server: /demo: /' || true

# The instructor's review, read back from the SQLite session log: every session of
# this run listed, summarised, re-simulated from its logged inputs (bit-identical
# replay of every frame) and written as a self-contained HTML report.
review=$build/client/review/palp-review
db=$(sed -n 's/^.*palp-server: logging sessions to //p' "$out/server.log" | tail -n 1)
if [ -x "$review" ] && [ -n "$db" ] && [ -f "$db" ]; then
  echo
  echo "== instructor review (palp-review, from $db) =="
  "$review" --db "$db" list --since "$since"
  for uid in $("$review" --db "$db" list --since "$since" | awk 'NR > 1 && $1 ~ /-/ { print $1 }'); do
    echo
    "$review" --db "$db" show "$uid" | sed -n '1,/^events/p' | sed '$d'
    "$review" --db "$db" replay "$uid" || status=1
    "$review" --db "$db" report "$uid" --out "$out/report-$uid.html" >/dev/null &&
      echo "report: $out/report-$uid.html (opens in any browser, no server needed)"
  done
fi
exit "$status"
