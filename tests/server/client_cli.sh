#!/bin/sh
# palp-client refuses bad input with a non-zero exit and a message naming what is
# wrong, before touching the network where it can; with no server it gives up
# after --timeout with a clear message, and a Ctrl-C ends its wait at once. Domain 108 (no server
# runs there).
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
# A bad value of --profile or --input is a command-line mistake: exit 2, as a bad number is (docs/deploy.md;
# exit 1 until session 83). What only opening the input tells (no terminal, no file, no driver) stays 1.
expect 2 "--profile: expected paper, step, ramp or sine, got \"square\"" --role trainee --phantom 1 --profile square --domain 108
expect 2 "--input: expected script, replay:FILE" --role trainee --phantom 1 --input joystick --domain 108
expect 1 "needs a terminal" --role trainee --phantom 1 --input keyboard --domain 108
expect 1 "cannot open" --role trainee --phantom 1 --input replay:/nonexistent.csv --domain 108
# session 81: a simulated device's counts are whole (circles=2.5 ran 2), its azimuth signed as --azimuth's
expect 2 "\"circles=2.5\": a count, expected a whole number" --role trainee --phantom 1 --input sim:circles,circles=2.5 --domain 108
expect 2 "\"azimuth=-400\": expected key=value with a number in [-360, 1e4]" --role trainee --phantom 1 --input sim:press,azimuth=-400 --domain 108
expect 2 "scripted trainee: unknown key or bad value \"nonsense\"" --role trainee --phantom 1 --input sim:expert,nonsense=1 --domain 108
expect 1 "device driver" --role trainee --phantom 1 --input device:/nonexistent.so --domain 108
# Strings the station would have cut (session 83): a name the wire's 63 bytes cannot carry whole, or that is
# not UTF-8 text (a cut one named the trainee otherwise in the server's log and the review); a driver's path
# past its 1,024-byte copy (the cut path was dlopen()ed); an --svg prefix its snapshots' names cannot hold.
long=$(printf '%064d' 0)
expect 2 "--name: at most 63 bytes (the session's records carry that many), got 64" --role trainee --phantom 1 --name "$long" --domain 108
expect 2 "--name: not UTF-8 text (byte 4)" --role trainee --phantom 1 --name "$(printf 'ann\377')" --domain 108
expect 2 "--trainee: at most 63 bytes" --role observer --trainee "$long" --domain 108
expect 2 "--input device:...: at most 1023 bytes of path and argument, got 1100" --role trainee --phantom 1 \
  --input "device:/$(printf '%01099d' 0)" --domain 108
expect 2 "--svg: at most 1084 bytes, got 1100" --role visual --svg "/$(printf '%01099d' 0)" --domain 108
# a log file it cannot open: the reason with it (session 77; it said only "cannot open it")
expect 2 "--log-file /nonexistent/dir/c.log: cannot open it: No such file or directory" --role trainee --phantom 1 \
  --log-file /nonexistent/dir/c.log --domain 108
# ... and a name of 63 bytes, 31 two-byte characters and an "x", is taken whole (to the join, unanswered here)
expect 1 "no answer from palp-server" --role trainee --phantom 1 --domain 108 --timeout 0.5 \
  --name "$(printf '\303\251%.0s' $(seq 31))x"
# Ctrl-C while it waits for a server that is not there ends it at once, as a Ctrl-C during the
# session does: exit 0 within 1 s of the SIGINT (its waits look at the stop every <= 100 ms; DDS's
# teardown takes the rest), nothing said. Until 2026-12-06 it waited out --timeout (twice) and exited
# 1 with "no answer". A station still running 3 s after it is killed and counted as a failure.
interrupted() { # what args...
  what=$1
  shift
  "$client" "$@" --domain 108 --timeout 30 > "$tmp_out" 2>&1 </dev/null &
  pid=$!
  sleep 0.5
  t0=$(date +%s%N)
  kill -INT $pid
  n=0
  while kill -0 $pid 2>/dev/null && [ $n -lt 60 ]; do n=$((n + 1)); sleep 0.05; done
  ms=$((($(date +%s%N) - t0) / 1000000))
  if kill -0 $pid 2>/dev/null; then
    kill -KILL $pid; wait $pid 2>/dev/null
    echo "FAIL $what: still running ${ms} ms after SIGINT (want it gone within 1000 ms, exit 0)"; fail=1
    return
  fi
  wait $pid
  rc=$?
  if [ $rc -eq 0 ] && [ $ms -le 1000 ] && ! grep -q "no answer\|no open session" "$tmp_out"; then
    echo "ok   $what: SIGINT 0.5 s in, exit $rc ${ms} ms after it (bound 1000 ms), nothing said"
  else
    echo "FAIL $what: SIGINT 0.5 s in, exit $rc ${ms} ms after it (want 0 within 1000 ms, no \"no answer\"): $(cat "$tmp_out")"
    fail=1
  fi
}
tmp_out=$(mktemp)
trap 'rm -f "$tmp_out"' EXIT
interrupted "a trainee waiting for its join's answer" --role trainee --phantom 1
interrupted "an observer looking for --trainee bob's session" --role observer --trainee bob
interrupted "a trainee looking for --phantom-name dome" --role trainee --phantom-name dome
exit $fail
