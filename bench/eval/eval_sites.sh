#!/bin/sh
# The per-distribution evaluation over random contact sites and force levels
# (docs/statistics.md, "Runs over random sites"): 4 distributions x SITES sites x the
# FORCES levels, FEM level 1 vs the real-time model, the paper's 2 s on / 2 s off step
# at 10 ms frames. Prints both tables and writes them (with runs.csv) to OUT.
# Cost: one cold FEM level-1 run per (distribution, site, force), 26-60 s each on the
# shared 2-core machine; reruns come from the FEM cache in seconds.
#
#   bench/eval/eval_sites.sh [BUILD_DIR] [OUT] [extra palp-eval options...]
#   SITES=8 FORCES=1,2,3 SEED=1 bench/eval/eval_sites.sh build out/eval-sites --params FILE
set -eu
BUILD=${1:-build}
OUT=${2:-out/eval-sites}
[ $# -ge 1 ] && shift
[ $# -ge 1 ] && shift
SITES=${SITES:-8}
FORCES=${FORCES:-1,2,3}
SEED=${SEED:-1}
LEVEL=${LEVEL:-1}
start=$(date +%s)
nice -n 15 "$BUILD/tools/eval/palp-eval" evaluate --sites "$SITES" --forces "$FORCES" --seed "$SEED" \
  --level "$LEVEL" --out "$OUT" --quiet "$@"
echo "eval_sites.sh: wall $(( $(date +%s) - start )) s"
