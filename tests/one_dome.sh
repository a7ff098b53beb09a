# Sourced by the tests that run one palp-server hosting one dome (tests/haptic/station_first_press.sh,
# station_stalled.sh, station_signals.sh, tests/server/viewer_trainee.sh), which wrote the same
# config by hand until 2026-12-06.
# one_dome_server DOMAIN SCENE [PHYSICS_RATE_HZ]: writes $tmp/server.json (phantom 1 "dome" on SCENE,
# 100 Hz ticks on one thread, the session log in $tmp/log.db, the loopback DDS config) and starts
# "$server" on it in the background, its output in $tmp/server.log, its pid in spid. Needs server,
# config_dir and tmp set.
one_dome_server() {
  _rate=${3:+, \"physics_rate_hz\": $3}
  cat > "$tmp/server.json" <<JSON
{ "domain_id": $1, "tick_rate_hz": 100, "tick_threads": 1, "database": "$tmp/log.db",
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$2"$_rate } ] }
JSON
  "$server" --config "$tmp/server.json" > "$tmp/server.log" 2>&1 &
  spid=$!
}
