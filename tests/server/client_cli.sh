#!/bin/sh
# palp-client refuses bad input with a non-zero exit and a message naming what is
# wrong, before touching the network where it can; with no server it gives up
# after --timeout with a clear message. Domain 108 (no server runs there).
set -u
client=$1 config_dir=$2
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
fail=0
expect() { # want_status text args...
  want=$1 text=$2
  shift 2
  out=$("$client" "$@" 2>&1 </dev/null)
  rc=$?
  if [ $rc -eq "$want" ] && printf '%s' "$out" | grep -qF -- "$text"; then
    echo "ok   exit $rc: $(printf '%s' "$out" | head -n 1)"
  else
    echo "FAIL exit $rc (want $want and \"$text\"): $out"; fail=1
  fi
}
expect 2 "--role" --phantom 1
expect 2 "--role" --role pilot
expect 2 "--phantom" --role trainee
expect 2 "--distribution" --role trainee --phantom 1 --distribution 7
expect 2 "--polar" --role trainee --phantom 1 --polar 120
expect 2 "whole number" --role trainee --phantom 1.5
expect 2 "unknown option" --role trainee --phantom 1 --force 3
expect 1 "--profile" --role trainee --phantom 1 --profile square --domain 108
expect 1 "needs a terminal" --role trainee --phantom 1 --input keyboard --domain 108
expect 1 "cannot open" --role trainee --phantom 1 --input replay:/nonexistent.csv --domain 108
expect 1 "device driver" --role trainee --phantom 1 --input device:/nonexistent.so --domain 108
# a log file it cannot open: the reason with it (session 77; it said only "cannot open it")
expect 2 "--log-file /nonexistent/dir/c.log: cannot open it: No such file or directory" --role trainee --phantom 1 \
  --log-file /nonexistent/dir/c.log --domain 108
expect 1 "no answer from palp-server" --role trainee --phantom 1 --domain 108 --timeout 0.5
exit $fail
