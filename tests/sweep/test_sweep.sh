#!/usr/bin/env bash
# A quick accuracy-vs-cost sweep (FEM level 1 reference, 40 frames) must produce a
# finite table with exactly one server-default point, and its Pareto marks must
# equal dominance recomputed here: a point is on the front iff no other point is at
# most as costly and at most as wrong, and strictly better in one of the two.
set -euo pipefail
tool=$1 scene=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$tool" --quick --ref-level 1 --frames 40 --scene "$scene" --out "$dir/out" >"$dir/log" 2>&1 || {
  cat "$dir/log"; echo "FAIL: palp-sweep exited non-zero"; exit 1; }
csv="$dir/out/sweep.csv"
[ -s "$csv" ] && [ -s "$dir/out/sweep.svg" ] && [ -s "$dir/out/sweep.md" ] || { echo "FAIL: missing outputs"; exit 1; }
awk -F, '
  NR == 1 { next }
  $2 == "fem" && $8 == "nan" { next }            # the reference row has no error
  { n++; cost[n] = $7 + 0; err[n] = $8 + 0; par[n] = $11 + 0; def += $12 + 0
    if (!(cost[n] > 0) || !(err[n] > 0) || $9 == "nan" || $9 == "inf") { print "FAIL: non-finite row " NR ": " $0; bad = 1 } }
  END {
    if (n < 5) { print "FAIL: expected at least 5 points, got " n; exit 1 }
    if (def != 1) { print "FAIL: expected exactly one server-default point, got " def; exit 1 }
    for (i = 1; i <= n; i++) {
      dominated = 0
      for (j = 1; j <= n; j++) if (j != i && cost[j] <= cost[i] && err[j] <= err[i] && (cost[j] < cost[i] || err[j] < err[i])) dominated = 1
      if (par[i] != !dominated) { print "FAIL: point " i " Pareto mark " par[i] " but dominated=" dominated; bad = 1 }
    }
    if (bad) exit 1
    print "sweep: " n " points, Pareto marks match dominance, one server default: ok"
  }' "$csv"
echo "1 passed, 0 failed"
