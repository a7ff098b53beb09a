#!/usr/bin/env python3
"""`palp-fem finger`'s options (tools/fem/finger_compare.c), at level 1 (224 hexahedra, ~1 s):

    test_finger_cli.py PALP_FEM SCENE

- `--depths 2 --no-force-table` computes two depths and no depth-for-force table (the options are
  independent: --no-force-table once reset --depths to "all", and a level-4 run asked for 14
  depths went on to 18 mm for hours);
- each FE depth is printed to stderr as it is computed ("FE row K: " and the CSV row with the
  real-time columns empty), and those rows carry the same FE force and gap as the CSV (exactly:
  the same printf format);
- since session 82: a failed FE press (70 deg pressed towards 1000 N: the level-1 press stops
  converging long before) exits nonzero with a message, leaves --out untouched and its rows in
  --out.partial; a --site token that names no site is refused; `--fe-from X --out X` keeps the
  stored FE columns (it used to truncate X before reading it); a scene whose dome radius differs
  from the FE mesh's by more than 2% is refused with both radii; `palp-fem run` refuses a negative
  --dt and its --reading alias switches a paper profile's load map with its name.
"""
import json
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

    # --fe-from X --out X: the FE columns come back unchanged (X is read before it is replaced)
    ref = open(out).read()
    r = subprocess.run([tool, "finger", "--scene", scene, "--level", "1", "--site", "pole", "--depths", "2",
                        "--no-force-table", "--fe-from", out, "--out", out], capture_output=True, text=True,
                       timeout=240)
    check(r.returncode == 0, "--fe-from X --out X exited %d: %s" % (r.returncode, r.stderr[-400:]))
    again = list(csv.DictReader(l for l in open(out) if not l.startswith("#")))
    check([(x["depth_m"], x["fem_N"], x["fem_min_gap_m"]) for x in again] ==
          [(x["depth_m"], x["fem_N"], x["fem_min_gap_m"]) for x in rows],
          "--fe-from X --out X: X still holds the same FE columns (%d rows)" % len(again))
    left = [n for n in os.listdir(os.path.dirname(out)) if n.startswith(os.path.basename(out) + ".")]
    check(not left, "no temporary file left beside --out (%s)" % left)

    # a failed FE press is an error, and the file named by --out is not replaced by a short curve
    deep = os.path.join(scratch, "deep.csv")
    with open(deep, "w") as f:
        f.write(ref)
    r = subprocess.run([tool, "finger", "--scene", scene, "--level", "1", "--site", "70deg", "--no-force-table",
                        "--max-force", "1000", "--out", deep], capture_output=True, text=True, timeout=240)
    check(r.returncode != 0, "a press that fails before --max-force exits nonzero (exit %d)" % r.returncode)
    check("press failed" in r.stderr and "70deg" in r.stderr, "the message says the press failed and where: %s" %
          r.stderr.strip().splitlines()[-1:] if r.stderr.strip() else "no message")
    check(open(deep).read() == ref, "--out is left as it was")
    part = deep + ".partial"
    prow = list(csv.DictReader(l for l in open(part) if not l.startswith("#"))) if os.path.exists(part) else []
    check(0 < len(prow) < 24 and all(float(x["fem_N"]) < 1000 for x in prow),
          "the rows computed before the failure are in --out.partial (%d rows, all below 1000 N)" % len(prow))

    # a --site token naming no site
    r = subprocess.run([tool, "finger", "--scene", scene, "--level", "1", "--site", "pol", "--depths", "1",
                        "--no-force-table", "--out", os.path.join(scratch, "typo.csv")], capture_output=True,
                       text=True, timeout=240)
    check(r.returncode != 0 and '"pol"' in r.stderr, "--site pol refused naming the token (exit %d)" % r.returncode)
    check(not os.path.exists(os.path.join(scratch, "typo.csv")), "nothing written for a refused --site")

    # a scene whose dome is not the FE mesh's
    sc = json.load(open(scene))
    sc["mesh"]["radius_m"] = 0.03
    # the scene names files relative to its folder (../params/...): the copy sits at the same depth
    os.makedirs(os.path.join(scratch, "phantoms"), exist_ok=True)
    for name in os.listdir(os.path.dirname(os.path.dirname(os.path.abspath(scene)))):
        if not os.path.exists(os.path.join(scratch, name)):
            os.symlink(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(scene))), name),
                       os.path.join(scratch, name))
    small = os.path.join(scratch, "phantoms", "small.json")
    with open(small, "w") as f:
        json.dump(sc, f)
    r = subprocess.run([tool, "finger", "--scene", small, "--level", "1", "--site", "pole", "--depths", "1",
                        "--no-force-table"], capture_output=True, text=True, timeout=240)
    check(r.returncode != 0 and "0.04" in r.stderr and "0.03" in r.stderr,
          "a 30 mm scene against the 40 mm FE dome refused naming both radii (exit %d): %s" %
          (r.returncode, r.stderr.strip()[-300:]))

    # palp-fem run's options (since session 82): a negative --dt is refused (it was the "unset"
    # sentinel, silently ignored); --reading instantaneous on a paper profile runs the profile's
    # point map, and the summary names the map
    r = subprocess.run([tool, "run", "--scene", scene, "--level", "1", "--frames", "1", "--dt", "-0.005",
                        "--no-cache", "--quiet"], capture_output=True, text=True, timeout=240)
    check(r.returncode != 0 and "--dt" in r.stderr, "--dt -0.005 refused (exit %d)" % r.returncode)
    paper = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(scene))), "paper_step.json")
    r = subprocess.run([tool, "run", "--scene", paper, "--level", "1", "--frames", "1", "--material",
                        "paper_long_term", "--reading", "instantaneous", "--no-cache"], capture_output=True,
                       text=True, timeout=240)
    lines = [l for l in r.stdout.splitlines() if l.startswith("material") or l.startswith("load map")]
    check(r.returncode == 0 and len(lines) == 2 and "paper_instantaneous" in lines[0] and "point" in lines[1],
          "--reading instantaneous: the paper_instantaneous profile with its point map (%s)" % lines)


if __name__ == "__main__":
    scratch = tempfile.mkdtemp(prefix="palp_finger_cli_")
    main()
    if failures:
        print("kept for inspection: " + scratch, file=sys.stderr)
    else:
        shutil.rmtree(scratch, ignore_errors=True)
    sys.exit(1 if failures else 0)
