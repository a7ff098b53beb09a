#!/usr/bin/env python3
"""Writes the level-4 FEM references of the long-term dome that the tests
eval_evaluate_long_term, eval_level4_guard, eval_finger_long_term and
eval_finger_level4_guard compare with (docs/materials.md, "Refitted against the
level-4 FEM"):

    tests/data/make_long_term_level4.py BUILD_DIR [FINGER_CSV | compute]
    tests/data/make_long_term_level4.py BUILD_DIR --cyst [FINGER_CSV... | compute]

- fem_level4_long_term_d2.csv: the FEM column (fem_cm, |u| of every real-time
  vertex) of displacement_d2.csv written by
  `palp-eval evaluate --scene config/paper_step_long_term.json --level 4
  --distributions 2`, compacted: every vertex at frames 0-11 (the guard recomputes
  them) and at every 20th frame (19, 39, ..., 399), and the FEM's most displaced
  vertex at every frame (so the stored peak is the run's). The level-2 FEM peak of
  the same distribution is recorded too (eval_evaluate_long_term checks that the
  FEM still gives it).
- fem_level4_long_term_finger.csv: `palp-fem finger --scene
  config/paper_step_long_term.json --level 4 --site all`, ~1 h of CPU (each site's
  FE curve 10-20 min on this 2-core machine), with `compute`; FINGER_CSV: an existing
  output of that command (or the sites' outputs joined) to reuse for its FE
  columns, the real-time columns then recomputed with the current parameters
  (`--fe-from`). Without either, only the displacement file is written.

- fem_level4_long_term_cyst.csv (`--cyst`): the pole and a 0.2x cyst where the lesion is
  (`--site pole,pole_lesion --lesion-ratio 0.2 --max-force 5`, ~30 min of FE); FINGER_CSV...: the
  cyst's run first, then fem_level4_long_term_finger.csv for the plain pole (each site from the
  first file that has it).

PALP_REF_CACHE=DIR reuses a FEM cache (palp-eval --cache-dir) for the displacement runs;
PALP_REF_NOTE=TEXT adds a line to the fingertip file's header (how a reused FINGER_CSV was made).
"""
import csv
import hashlib
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = "config/paper_step_long_term.json"


def sh(args):
    print("+ " + " ".join(args), flush=True)
    subprocess.run(args, check=True, cwd=ROOT)


def provenance(cmd, script="make_long_term_level4.py"):
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "src/fem"], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    ver = [l for l in open(os.path.join(ROOT, "src/fem/palp_fem.h")) if "define PALP_FEM_CODE_VERSION" in l][0]
    # the fingertip's FE code, hashed: eval_finger_level4_guard compares it (recomputing a level-4
    # fingertip depth takes 60-75 s, over the test budget)
    sha = hashlib.sha256(open(os.path.join(ROOT, "src/fem/fem_finger.c"), "rb").read()).hexdigest()
    return ("# written by tests/data/%s at commit %s%s, PALP_FEM_CODE_VERSION %s\n"
            "# sha256 of src/fem/fem_finger.c %s\n# %s\n" %
            (script, commit, " (src/fem modified)" if dirty else "", ver.split()[2], sha, cmd))


def write_finger(path, how, fe, finger, script="make_long_term_level4.py"):
    """A `palp-fem finger` CSV (finger) as a stored reference: the provenance header, a line saying
    which FE (fe) the curves come from, then the CSV itself."""
    with open(path, "w") as f:
        f.write(provenance(how, script))
        f.write("# FE: rigid 8 mm sphere, relaxed static, %s; the tests read the FE columns only (depth_m, fem_N, "
                "fem_min_gap_m)\n" % fe)
        f.write(open(finger).read())
    print("wrote " + path)


def write_level4_d2(ev, scene, cache, tmp, path, about, script="make_long_term_level4.py"):
    """Distribution II's level-4 FEM field of scene (and the level-2 peak, in the header), compacted:
    every vertex at frames 0-11 and every 20th, the FEM's most displaced vertex at every frame.
    about: the header line saying what the field is."""
    peaks = {}
    for level in (2, 4):
        out = os.path.join(tmp, "l%d" % level)
        sh([ev, "evaluate", "--scene", scene, "--level", str(level), "--distributions", "2", "--no-plots", "--quiet",
            "--cache-dir", cache, "--out", out])
        rows = list(csv.DictReader(open(os.path.join(out, "displacement_d2.csv"))))
        fem_cm = {(int(r["frame"]), int(r["vertex"])): float(r["fem_cm"]) for r in rows}
        peaks[level] = max(fem_cm.values())
    (pf, pv), peak = max(fem_cm.items(), key=lambda kv: kv[1])
    last = max(f for f, _ in fem_cm)
    full = set(range(12)) | set(range(19, last + 1, 20))
    with open(path, "w") as f:
        f.write(provenance("palp-eval evaluate --scene %s --level 4 --distributions 2 (the fem_cm column of "
                           "displacement_d2.csv; the FEM does not depend on the real-time parameters)" % scene, script))
        f.write("# " + about + "\n")
        f.write("# level-2 FEM peak %.9g cm (the same command with --level 2)\n" % peaks[2])
        f.write("# level-4 FEM peak %.9g cm at vertex %d, frame %d; every vertex at frames 0-11 and 19, 39, ..., %d; "
                "vertex %d at every frame\n" % (peak, pv, pf, last, pv))
        f.write("frame,vertex,fem_cm\n")
        for (fr, v), u in sorted(fem_cm.items()):
            if fr in full or v == pv:
                f.write("%d,%d,%.9g\n" % (fr, v, u))
    print("wrote %s (level-4 peak %.6g cm, level-2 peak %.6g cm)" % (path, peak, peaks[2]))


def join(paths, tmp):
    """One CSV of the sites of paths, each site from the first file that has it."""
    joined, seen, header, rows = os.path.join(tmp, "joined.csv"), set(), None, []
    for path in paths:
        with open(path) as f:
            rs = list(csv.DictReader(l for l in f if not l.startswith("#")))
        for site in dict.fromkeys(r["site"] for r in rs):
            if site not in seen:
                seen.add(site)
                rows += [r for r in rs if r["site"] == site]
        header = header or list(rs[0].keys())
    with open(joined, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=header)
        w.writeheader()
        w.writerows(rows)
    return joined


def finger_ref(fem, cmd, args, tmp, path, fe, script="make_long_term_level4.py"):
    """A stored fingertip reference at path: `palp-fem` cmd run afresh (args: ["compute"]), or its FE
    columns taken from the curves args names (joined) and the real-time ones recomputed (--fe-from)."""
    out = os.path.join(tmp, "finger.csv")
    if args and args[0] != "compute":
        sh([fem] + cmd + ["--fe-from", join(args, tmp), "--out", out])
        how = ("palp-fem %s (FE columns), real-time columns recomputed with the parameters of this commit by --fe-from"
               % " ".join(cmd))
        if os.environ.get("PALP_REF_NOTE"):
            how += "\n# " + os.environ["PALP_REF_NOTE"]
    else:
        sh([fem] + cmd + ["--out", out])
        how = "palp-fem " + " ".join(cmd)
    write_finger(os.path.join(ROOT, path), how, fe, out, script)


def cyst(fem, tmp, args):
    """fem_level4_long_term_cyst.csv: the pole and a 0.2x cyst where the 5x lesion is."""
    finger_ref(fem, ["finger", "--scene", SCENE, "--level", "4", "--site", "pole,pole_lesion", "--lesion-ratio", "0.2",
                     "--max-force", "5", "--no-force-table"], args, tmp, "tests/data/fem_level4_long_term_cyst.csv",
               "level 4 (10,496 hexahedra), pole_lesion = a 0.2x cyst (10 mm, centre 10 mm deep)")


def main():
    build = os.path.abspath(sys.argv[1])
    ev, fem = os.path.join(build, "tools/eval/palp-eval"), os.path.join(build, "tools/fem/palp-fem")
    tmp = tempfile.mkdtemp(prefix="palp_level4_ref_")
    if len(sys.argv) > 2 and sys.argv[2] == "--cyst":
        cyst(os.path.join(build, "tools/fem/palp-fem"), tmp, sys.argv[3:])
        return
    cache = os.environ.get("PALP_REF_CACHE", os.path.join(tmp, "cache"))  # an existing FEM cache may be reused
    write_level4_d2(ev, SCENE, cache, tmp, os.path.join(ROOT, "tests/data/fem_level4_long_term_d2.csv"),
                    "paper_long_term, distribution II (3 N uniform over the 5.2 cm^2 polar cap, step 0-2 s), 400 "
                    "frames of 10 ms; |u| [cm] of the real-time vertices (FE patch map: each vertex's hat-weighted "
                    "average, docs/fem.md \"Surface map\")")

    finger = os.path.join(tmp, "finger.csv")
    if len(sys.argv) < 3:
        return
    if sys.argv[2] != "compute":
        sh([fem, "finger", "--scene", SCENE, "--level", "4", "--site", "all", "--fe-from", os.path.abspath(sys.argv[2]),
            "--out", finger])
        how = ("palp-fem finger --scene %s --level 4 --site all (FE columns), real-time columns recomputed with the "
               "parameters of this commit by --fe-from %s" % (SCENE, os.path.basename(sys.argv[2])))
        if os.environ.get("PALP_REF_NOTE"):  # how the reused FE curves were made, if not by one --site all run
            how += "\n# " + os.environ["PALP_REF_NOTE"]
    else:
        sh([fem, "finger", "--scene", SCENE, "--level", "4", "--site", "all", "--out", finger])
        how = "palp-fem finger --scene %s --level 4 --site all" % SCENE
    write_finger(os.path.join(ROOT, "tests/data/fem_level4_long_term_finger.csv"), how, "level 4 (10,496 hexahedra)",
                 finger)


if __name__ == "__main__":
    main()
