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
# the reference row (the last, "(reference)" in its name) has no error against itself: its
# disp_rmse_m, force_rmse_N and agreement are empty (session 82: force 0 and agreement 0.0000
# were written, read as a perfect force and no agreement)
ref=$(grep -c '(reference)' "$csv" || true)
[ "$ref" = 1 ] || { echo "FAIL: expected one reference row, got $ref"; exit 1; }
awk -F, '/\(reference\)/ { if ($8 != "" || $9 != "" || $10 != "") { print "FAIL: reference row has error values: " $0; exit 1 } }' "$csv"
awk -F, '
  NR == 1 { next }
  /\(reference\)/ { next }                       # the reference row has no error
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
# session 82: a file that cannot be written is an error (exit 1, named), not a missing plot and
# exit 0; sweep.svg as a directory makes its fopen fail (the sweep's cost: a second quick run)
mkdir -p "$dir/svgdir/sweep.svg"
if "$tool" --quick --ref-level 1 --frames 12 --scene "$scene" --out "$dir/svgdir" >"$dir/log2" 2>&1; then
  cat "$dir/log2"; echo "FAIL: palp-sweep exited 0 with sweep.svg unwritable"; exit 1
else rc=$?; fi
[ "$rc" = 1 ] && grep -q "cannot write $dir/svgdir/sweep.svg" "$dir/log2" || {
  cat "$dir/log2"; echo "FAIL: unwritable sweep.svg: exit $rc (want 1) and the file named"; exit 1; }
# command-line errors (exit 2, the option named): atoi read 2x as 2 and abc as all frames;
# an unknown option printed the usage without naming it; a missing scene is an input (exit 1),
# its path named once
for args in "--ref-level 2x" "--frames abc" "--ref-level 7" "--frames" "--bogus"; do
  set +e; "$tool" $args --out "$dir/bad" >"$dir/log3" 2>&1; rc=$?; set -e
  opt=${args%% *}
  [ "$rc" = 2 ] && grep -q -- "palp-sweep: .*$opt" "$dir/log3" && [ ! -e "$dir/bad/sweep.csv" ] || {
    cat "$dir/log3"; echo "FAIL: palp-sweep $args: exit $rc (want 2), the option named, nothing written"; exit 1; }
done
set +e; "$tool" --scene "$dir/nonexist.json" --out "$dir/bad" >"$dir/log3" 2>&1; rc=$?; set -e
[ "$rc" = 1 ] && [ "$(grep -o "nonexist.json" "$dir/log3" | wc -l)" = 1 ] || {
  cat "$dir/log3"; echo "FAIL: missing scene: exit $rc (want 1), its path named once"; exit 1; }
echo "1 passed, 0 failed"
