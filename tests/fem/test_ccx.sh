#!/bin/sh
# fem_ccx (issue 12): the FEM reference against an independent FE code, CalculiX (Debian's
# calculix-ccx, installed by the set-up script: missing, the test fails, it does not skip), on
# the project's own hemisphere mesh made quadratic (C3D20R, midside nodes on the true sphere),
# relaxed moduli of the paper_long_term profile, distribution II at 3 N, levels 1 and 2.
# Asserted: ccx solves both decks and its pole moves down; the two codes approach each other
# from opposite sides between levels 1 and 2 (palp's linear Q1/P0 hexahedra on the faceted sphere too stiff, growing with
# refinement; ccx's coarse quadratic bricks too soft, shrinking); at level 2 they agree within
# 20% (measured 15.7%: neither is converged at level 2; docs/materials.md has levels 1-7).
# ccx solves the quarter deck (--ccx-quarter, symmetry planes x = 0, y = 0, as for ccx levels 4-5
# in docs/materials.md): level 2's full deck took ccx 37 s of wall time and ~60 s of CPU, the quarter
# 3 s, with the same pole uz to the 4 decimals the tool prints (-0.6378 mm both, 2026-12-04). Level 1
# is solved again on the full deck (--ccx-only) and by palp alone (--palp-only): both must give the
# quarter run's pole uz as the tool prints it (0.1 um; the quarter deck's .dat agrees with the
# full deck's to all 7 printed digits; both decks in the same increments). ~3 s more.
# The same two levels for breast_tissue (the exercises' material: E 15 kPa gel under 334 kPa skin,
# ~5 mm at the pole), ccx on the quarter deck with load increments of 0.1: the same opposite-side
# approach and 20% at level 2 (measured 14.6%; docs/materials.md has ccx to level 5). ~20 s more.
# The converged comparison is bench/fem/ccx_crosscheck.
# ccx runs on one thread here (--ccx-threads 1; the tool's default is both cores): its two OpenMP
# threads beside the suite's other computations spun, 57-63 s against 15 s alone (2026-12-06).
# ccx is most of the test's CPU (2026-12-07: ~19 of ~21 s; SPOOLES, which orders and factors the
# system at every iteration, ~65% of ccx's). paper_long_term's load goes in increments of 0.5
# (--ccx-inc 0.5; the tool's default 0.25): 2 increments of 3-4 iterations at levels 1 and 2, 7
# each against 14 (1.0: a cut-back, 18 at level 2), the same pole uz to the 4 decimals the tool
# prints (full precision: -0.7182113 / -0.6378107 mm against -0.7182162 / -0.6378185 with 0.25,
# ccx's own tolerance). Breast tissue keeps 0.1: 31 iterations at level 2; 0.125 / 0.2 / 0.25 / 0.5
# took 35 / 31 / 43 / 53 (0.25 and 0.5 cut back; 0.2 no cheaper).
# usage: test_ccx.sh CCX_CROSSCHECK TMPDIR
set -u
tool=$1 tmp=$2
command -v ccx >/dev/null 2>&1 || { echo "FAIL ccx (calculix-ccx) is not installed: scripts/debian-packages.txt lists it"; exit 1; }
dir=$tmp/ccx
rm -rf "$dir"
"$tool" --levels 1,2 --profile paper_long_term --ccx-quarter --ccx-inc 0.5 --force 3 --ccx-threads 1 --dir "$dir" > "$dir.txt" 2>&1
st=$?
cat "$dir.txt"
[ $st -eq 0 ] || { echo "FAIL ccx_crosscheck exit $st"; exit 1; }
"$tool" --levels 1 --profile paper_long_term --ccx-only --ccx-inc 0.5 --force 3 --ccx-threads 1 --dir "$dir/full" > "$dir.f.txt" 2>&1
st=$?
cat "$dir.f.txt"
[ $st -eq 0 ] || { echo "FAIL ccx_crosscheck --ccx-only (full deck) exit $st"; exit 1; }
"$tool" --levels 1 --palp-only --dir "$dir/palp" > "$dir.p.txt" 2>&1
st=$?
cat "$dir.p.txt"
[ $st -eq 0 ] || { echo "FAIL ccx_crosscheck --palp-only exit $st"; exit 1; }
awk '
  FNR == 1 { file++ }
  $1 == 1 && NF >= 8 && file == 1 { p1 = $3; c1 = $6 }
  $1 == 1 && NF >= 8 && file == 2 { cf = $6 }
  $1 == 1 && NF >= 8 && file == 3 { pp = $3 }
  END {
    fail = 0
    d = (cf - c1) / cf; if (d < 0) d = -d
    if (cf != 0 && d <= 1e-5) print "ok   ccx quarter deck " c1 " mm = full deck " cf " mm at level 1"
    else { print "FAIL ccx quarter deck " c1 " mm against full deck " cf " mm at level 1"; fail = 1 }
    # numeric and finite (a failed palp side printed "nan", and "nan" == "nan" passed)
    if (p1 !~ /^-?[0-9]+(\.[0-9]+)?$/ || pp !~ /^-?[0-9]+(\.[0-9]+)?$/) { print "FAIL palp pole displacement not a finite number: " pp " / " p1; fail = 1 }
    else if (pp == p1) print "ok   palp alone " pp " mm = palp beside ccx at level 1"
    else { print "FAIL palp alone " pp " mm against " p1 " mm at level 1"; fail = 1 }
    exit fail
  }' "$dir.txt" "$dir.f.txt" "$dir.p.txt" || exit 1
"$tool" --levels 1,2 --profile breast_tissue --ccx-quarter --ccx-inc 0.1 --force 3 --ccx-threads 1 --dir "$dir/bt" > "$dir.bt.txt" 2>&1
st=$?
cat "$dir.bt.txt"
[ $st -eq 0 ] || { echo "FAIL ccx_crosscheck --profile breast_tissue exit $st"; exit 1; }
check_pair() { # FILE PROFILE: the two codes at levels 1 and 2
awk -v prof="$2" '
  $1 == 1 && NF >= 8 { p1 = -$3; c1 = -$6 }
  $1 == 2 && NF >= 8 { p2 = -$3; c2 = -$6 }
  END {
    fail = 0
    if (!(c1 > 0 && c2 > 0)) { print "FAIL " prof ": ccx pole uz not downward: " c1 ", " c2; fail = 1 } else print "ok   " prof ": ccx pole moves down at levels 1 and 2"
    if (p2 > p1 && c2 < c1) print "ok   " prof ": palp grows (" p1 " -> " p2 " mm), ccx shrinks (" c1 " -> " c2 " mm): they converge from opposite sides"
    else { print "FAIL " prof ": not converging from opposite sides: palp " p1 " -> " p2 ", ccx " c1 " -> " c2; fail = 1 }
    d = (c2 - p2) / c2; if (d < 0) d = -d
    if (d <= 0.20) printf "ok   %s: level 2: palp %.4f mm, ccx %.4f mm, within %.1f%% <= 20%%\n", prof, p2, c2, 100 * d
    else { printf "FAIL %s: level 2: palp %.4f mm, ccx %.4f mm differ by %.1f%% > 20%%\n", prof, p2, c2, 100 * d; fail = 1 }
    exit fail
  }' "$1"
}
check_pair "$dir.txt" paper_long_term; a=$?
check_pair "$dir.bt.txt" breast_tissue; b=$?
[ $a -eq 0 ] && [ $b -eq 0 ]
