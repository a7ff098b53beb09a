# Sourced by the keyboard tests (tests/server/keyboard.sh, tests/haptic/keyboard_finger.sh,
# tests/server/exercise_client.sh):
# wait_for FILE PATTERN waits until FILE (a terminal log, carriage returns as line ends)
# shows PATTERN, at most 30 s; 1 if it never does. Keys typed on a timer alone flaked on a
# loaded machine: a station that starts late gets its keys as one burst.
wait_for() {
  _n=0
  until tr '\r' '\n' < "$1" | grep -qF -- "$2"; do
    _n=$((_n + 1)); [ $_n -gt 300 ] && return 1; sleep 0.1
  done
}

# type_keys FILE SETTLE PATTERN KEYS [PATTERN KEYS ...]: for each pair, waits until FILE shows
# PATTERN, lets the station settle SETTLE seconds, then types KEYS (to standard output, piped
# into the station's terminal).
type_keys() {
  _f=$1 _s=$2
  shift 2
  while [ $# -ge 2 ]; do
    wait_for "$_f" "$1"; sleep "$_s"; printf '%s' "$2"
    shift 2
  done
}
