#!/usr/bin/env python3
"""`palp-fem finger`'s options (tools/fem/finger_compare.c), at level 1 (224 hexahedra, ~1 s):

    test_finger_cli.py PALP_FEM SCENE

- `--depths 2 --no-force-table` computes two depths and no depth-for-force table (the options are
  independent: --no-force-table once reset --depths to "all", and a level-4 run asked for 14
  depths went on to 18 mm for hours);
- each FE depth is printed to stderr as it is computed ("FE row K: " and the CSV row with the
  real-time columns empty), and those rows carry the same FE force and gap as the CSV (exactly:
  the same printf format).
"""
import csv
import os
import shutil
import subprocess
import sys
import tempfile

failures = 0


def check(ok, what):
    global failures
    print("%s: %s" % ("ok" if ok else "FAIL", what))
    failures += 0 if ok else 1


def main():
    tool, scene = sys.argv[1], sys.argv[2]
    out = os.path.join(scratch, "finger.csv")
    r = subprocess.run([tool, "finger", "--scene", scene, "--level", "1", "--site", "pole", "--depths", "2",
                        "--no-force-table", "--out", out], capture_output=True, text=True, timeout=240)
    check(r.returncode == 0, "palp-fem finger exited %d: %s" % (r.returncode, r.stderr[-400:]))
    if r.returncode:
        return
    rows = list(csv.DictReader(l for l in open(out) if not l.startswith("#")))
    check(len(rows) == 2, "--depths 2 with --no-force-table: %d CSV rows (expected 2)" % len(rows))
    check([round(float(x["depth_m"]) * 1e3, 6) for x in rows] == [0.25, 0.5],
          "the first two depths of the sequence, 0.25 and 0.5 mm")
    check("force N  FE depth mm" not in r.stdout, "no depth-for-force table")
    prog = [l.split(": ", 1)[1].split(" (")[0] for l in r.stderr.splitlines() if l.startswith("FE row ")]
    check(len(prog) == 2, "%d progress rows on stderr (expected 2)" % len(prog))
    for p, x in zip(prog, rows):
        f = p.split(",")
        check(len(f) == 7 and f[0] == "pole" and f[1] == x["depth_m"] and f[2] == x["fem_N"] and
              f[3:6] == ["", "", ""] and f[6] == x["fem_min_gap_m"],
              "progress row %s matches the CSV's FE columns" % p)


if __name__ == "__main__":
    scratch = tempfile.mkdtemp(prefix="palp_finger_cli_")
    main()
    if failures:
        print("kept for inspection: " + scratch, file=sys.stderr)
    else:
        shutil.rmtree(scratch, ignore_errors=True)
    sys.exit(1 if failures else 0)
