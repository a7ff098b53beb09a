#!/bin/sh
# The breast-tissue fingertip FE curves on meshes refined where the finger presses (issue 12;
# docs/fem.md, "The fingertip's mesh"): level 5 with the mesh graded at each site (grading 0.5,
# cells ~1.6 mm there), and the pole and the lesion again with grading 0.3. ~15-25 min of one core a site.
#   tests/data/make_refined_refs.sh BUILD_DIR [OUT_DIR]
# writes OUT_DIR/fem_refined_breast_tissue_finger.csv and fem_refined_breast_tissue_pole_a03.csv
# (OUT_DIR defaults to tests/data), each headed by the commit, the code's sha256 lines that
# test_finger_refined.py's guard checks, and the commands; and fem_graded4_breast_tissue_finger.csv:
# the same sites to 14 mm on level 4 graded 0.5 at each site (~15-40 min of one core a site), which
# carries the validated table beyond where the level-5 curves end.
# With a third argument, long_term (or all): fem_graded4_long_term_finger.csv, the default long-term
# dome (config/paper_step_long_term.json) on level 4 graded 0.5 at the pole, 45 deg, 70 deg and the pole
# over the lesion, until the FE force passes 5 N (70 deg: 11 N), ~3-15 min of one core a site, and
# fem_graded5_long_term_finger.csv, level 5 graded at the pole and at 45 deg to 4 mm (~20-35 min each) (docs/materials.md,
# "The long-term set against the graded fingertip").
#   tests/data/make_refined_refs.sh BUILD_DIR [OUT_DIR [breast_tissue|long_term|all]]
set -eu
build=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${2:-$root/tests/data}
which=${3:-breast_tissue}
tmp=$(mktemp -d)
fem=$build/tools/fem/palp-fem
scene=$root/config/phantoms/dome.json
run() { # site grading polar max_force out [level]
  printf '{"mesh": {"level": %s, "grading": %s, "grading_polar_deg": %s}}\n' "${6:-5}" "$2" "$3" > "$tmp/$1_$2.json"
  "$fem" finger --scene "$scene" --config "$tmp/$1_$2.json" --site "$1" --max-force "$4" --no-force-table --out "$5"
}
header() { # file what
  {
    echo "# written by tests/data/make_refined_refs.sh at commit $(git -C "$root" rev-parse --short HEAD); $2"
    echo "# sha256 of src/fem/fem_finger.c $(sha256sum "$root/src/fem/fem_finger.c" | cut -d' ' -f1)"
    echo "# sha256 of src/fem/fem_mesh.c $(sha256sum "$root/src/fem/fem_mesh.c" | cut -d' ' -f1)"
  } > "$1"
}
if [ "$which" != long_term ]; then
run pole 0.5 0 1.3 "$tmp/pole.csv"
run 45deg 0.5 45 3 "$tmp/45.csv"
run 70deg 0.5 70 3 "$tmp/70.csv"
run 60deg 0.5 60 3 "$tmp/60.csv"
run pole_lesion 0.5 0 2 "$tmp/lesion.csv"
run pole 0.3 0 1.0 "$tmp/pole03.csv"
run pole_lesion 0.3 0 1.0 "$tmp/lesion03.csv"
f=$out/fem_refined_breast_tissue_finger.csv
header "$f" "level 5, grading 0.5 at each site: palp-fem finger --scene config/phantoms/dome.json --config {\"mesh\": {\"level\": 5, \"grading\": 0.5, \"grading_polar_deg\": SITE_DEG}} --site SITE --max-force F (pole 1.3, 45/60/70 deg 3, pole_lesion 2) --no-force-table"
sed -n 1p "$tmp/pole.csv" >> "$f"
for c in pole 45 60 70 lesion; do sed 1d "$tmp/$c.csv" >> "$f"; done
f=$out/fem_refined_breast_tissue_pole_a03.csv
header "$f" "level 5, grading 0.3 at the pole: the same with {\"grading\": 0.3} --site pole (and pole_lesion) --max-force 1.0"
cat "$tmp/pole03.csv" >> "$f"
sed 1d "$tmp/lesion03.csv" >> "$f"
# level 4 graded 0.5, to 14 mm: each curve ends at the first depth past its force (the level-4 graded
# forces at 12 mm are 4.64 / 4.91 N at the pole / 45 deg)
run pole 0.5 0 5.3 "$tmp/g4pole.csv" 4
run 45deg 0.5 45 5.5 "$tmp/g445.csv" 4
run 60deg 0.5 60 5.8 "$tmp/g460.csv" 4
run 70deg 0.5 70 8.5 "$tmp/g470.csv" 4
f=$out/fem_graded4_breast_tissue_finger.csv
header "$f" "level 4, grading 0.5 at each site, to 14 mm: the same with {\"level\": 4} --max-force F (pole 5.3, 45deg 5.5, 60deg 5.8, 70deg 8.5)"
sed -n 1p "$tmp/g4pole.csv" >> "$f"
for c in g4pole g445 g460 g470; do sed 1d "$tmp/$c.csv" >> "$f"; done
fi
if [ "$which" != breast_tissue ]; then
scene=$root/config/paper_step_long_term.json
run pole 0.5 0 5.6 "$tmp/lpole.csv" 4
run 45deg 0.5 45 5.6 "$tmp/l45.csv" 4
run 70deg 0.5 70 11 "$tmp/l70.csv" 4
run pole_lesion 0.5 0 6.2 "$tmp/llesion.csv" 4
f=$out/fem_graded4_long_term_finger.csv
header "$f" "the long-term dome on level 4, grading 0.5 at each site: palp-fem finger --scene config/paper_step_long_term.json --config {\"mesh\": {\"level\": 4, \"grading\": 0.5, \"grading_polar_deg\": SITE_DEG}} --site SITE --max-force F (pole 5.6, 45deg 5.6, 70deg 11, pole_lesion 6.2) --no-force-table"
sed -n 1p "$tmp/lpole.csv" >> "$f"
for c in lpole l45 l70 llesion; do sed 1d "$tmp/$c.csv" >> "$f"; done
run pole 0.5 0 5.6 "$tmp/l5pole.csv" 5
run 45deg 0.5 45 5.6 "$tmp/l545.csv" 5
f=$out/fem_graded5_long_term_finger.csv
header "$f" "the long-term dome on level 5, grading 0.5 at the pole and at 45 deg: the same with {\"level\": 5} --site pole / 45deg --max-force 5.6"
cat "$tmp/l5pole.csv" >> "$f"
sed 1d "$tmp/l545.csv" >> "$f"
fi
rm -rf "$tmp"
