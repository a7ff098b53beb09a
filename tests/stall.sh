# Sourced by the shell tests of a stalled station (tests/server/session_log.sh, tests/security/cli.sh):
# stall_station PID LOG PRESS STOP waits until the palp-client PID's LOG says it joined (at most
# 10 s), lets it press PRESS seconds, then stops it (SIGSTOP) for STOP seconds and continues it, as
# a machine that swaps or loses its core for that long would (docs/station.md, "A stalled station").
stall_station() {
  _n=0
  until grep -q "joined session" "$2" || [ $_n -ge 100 ]; do sleep 0.1; _n=$((_n + 1)); done
  sleep "$3"
  kill -STOP "$1"
  sleep "$4"
  kill -CONT "$1"
}
