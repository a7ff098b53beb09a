#!/bin/sh
# A --log-file that cannot be opened is a refused setting in every program: one plain line,
# "PROG: --log-file PATH: cannot open it: REASON", and exit 2, which the systemd units do not
# restart (RestartPreventExitStatus=2, docs/deploy.md). Until session 83 palp-server and palp-netem
# exited 1 without "cannot open it:" (the server's unit restarted it every 2 s until the start
# limit), and palp-web's line lacked the words. The other programs are asserted by their own CLI
# tests (server_client_cli, review_cli, stats_cli). Each exits before any DDS participant (timeout
# 10: a program that went on to serve fails here, not at CTest's limit).
# Usage: log_file_refused.sh PALP_SERVER PALP_NETEM PALP_WEB CONFIG_DIR
set -u
config_dir=$4
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
log=/nonexistent-palp-dir/x.log
fail=0
for exe in "$1" "$2" "$3"; do
  prog=$(basename "$exe")
  case $prog in
    palp-server) args="--config $config_dir/server.json --check" ;; # the log opens before the config is read
    *) args= ;;
  esac
  # shellcheck disable=SC2086 # options, several words
  out=$(timeout 10 "$exe" $args --log-file "$log" 2>&1); rc=$?
  want="$prog: --log-file $log: cannot open it: No such file or directory"
  if [ $rc -eq 2 ] && [ "$out" = "$want" ]; then echo "ok   $prog: exit 2: $out"
  else echo "FAIL $prog: exit $rc (want 2 and exactly \"$want\"): $out"; fail=1; fi
done
exit $fail
