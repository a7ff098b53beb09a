#!/usr/bin/env python3
"""Writes the converged FE references of the breast-tissue set (the exercise phantom) that
eval_evaluate_breast_tissue, eval_finger_breast_tissue and eval_finger_breast_tissue_guard compare
with (docs/materials.md, "The fingertip references at level 3"):

    tests/data/make_breast_tissue_refs.py BUILD_DIR [FINGER_CSV... | compute]

(with neither, only the displacement file is written)

fem_level4_breast_tissue_d2.csv: the FEM column of `palp-eval evaluate --scene
config/paper_step_breast_tissue.json --level 4 --distributions 2` (17 min of FEM), compacted as
tests/data/make_long_term_level4.py compacts the long-term one (every vertex at frames 0-11 and
every 20th, the FEM's most displaced vertex at every frame), with the level-2 FEM peak of the
same distribution in its header. PALP_REF_CACHE=DIR reuses a FEM cache (palp-eval --cache-dir).

fem_level3_breast_tissue_finger.csv: `palp-fem finger --scene config/phantoms/dome.json --level 3
--site pole,45deg,60deg,70deg,pole_lesion --max-force 13 --no-force-table` (the FE: 13-45 min a site
on this 2-core machine) with `compute`; FINGER_CSV...: outputs of that command (one or several runs,
e.g. one per site; each site taken from the first file that has it) to reuse for the FE columns, the
real-time columns then recomputed with the current parameters (`--fe-from`).
PALP_REF_NOTE=TEXT adds a line to the header (how the reused curves were made).

    tests/data/make_breast_tissue_refs.py BUILD --level4 [FINGER_CSV... | compute]

fem_level4_breast_tissue_finger.csv: the same at level 4 (`--level 4 --site pole,45deg,60deg,70deg,pole_lesion
--max-force 3`; 1-1.5 h of FE a site here until 2026-11-29, ~6 min to 12 mm since the FE finger's faster Newton), where level 3 is up to 17% stiff for a fingertip from 2 mm.

    tests/data/make_breast_tissue_refs.py BUILD --cyst [FINGER_CSV... | compute]

fem_level3_breast_tissue_cyst.csv: level 3 at the pole and over a 0.2x cyst where the 5x lesion is
(`--site pole,pole_lesion --lesion-ratio 0.2 --max-force 6`); FINGER_CSV: the cyst's run first, then
fem_level3_breast_tissue_finger.csv for the plain pole (each site from the first file that has it).

    tests/data/make_breast_tissue_refs.py BUILD --cyst4 [FINGER_CSV... | compute]

fem_level4_breast_tissue_cyst.csv: the same at level 4 (`--max-force 4.5`, to 12 mm); FINGER_CSV: the
cyst's run first, then fem_level4_breast_tissue_finger.csv for the plain pole.
"""
import os
import sys
import tempfile

import make_long_term_level4 as lt  # the compacted level-4 field and finger_ref() (this folder is on sys.path)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = "config/phantoms/dome.json"
D2_SCENE = "config/paper_step_breast_tissue.json"
SITES = "pole,45deg,60deg,70deg,pole_lesion"
CMD = ["finger", "--scene", SCENE, "--level", "3", "--site", SITES, "--max-force", "13", "--no-force-table"]


def write_d2(build, tmp):
    lt.write_level4_d2(os.path.join(build, "tools/eval/palp-eval"), D2_SCENE,
                       os.environ.get("PALP_REF_CACHE", os.path.join(tmp, "cache")), tmp,
                       os.path.join(ROOT, "tests/data/fem_level4_breast_tissue_d2.csv"),
                       "breast_tissue, distribution II (3 N uniform over the 5.2 cm^2 polar cap, step 0-2 s), 400 "
                       "frames of 10 ms; |u| [cm] of the real-time vertices (FE patch map, HHT-alpha)",
                       "make_breast_tissue_refs.py")


# What each reference is: its `palp-fem` command, the file it goes to, and what the header says of its FE.
REFS = {
    "level3": (CMD, "tests/data/fem_level3_breast_tissue_finger.csv", "breast_tissue profile, level 3 (4,320 hexahedra)"),
    # level 4 (10,496 hexahedra, ~1.5 h of FE a site here before 2026-11-29 (latest), ~6 min since): where level 3 is not converged for a fingertip
    # and, since 2026-11-29 (latest), the pole over the 10 mm 5x lesion (level 3 had been its only reference)
    "level4": (["finger", "--scene", SCENE, "--level", "4", "--site", "pole,45deg,60deg,70deg,pole_lesion", "--max-force", "3",
                "--no-force-table"],
               "tests/data/fem_level4_breast_tissue_finger.csv", "breast_tissue profile, level 4 (10,496 hexahedra)"),
    # a soft cyst (0.2x the gel) where the 5x lesion is; its pole_lesion rows are the cyst's
    "cyst": (["finger", "--scene", SCENE, "--level", "3", "--site", "pole,pole_lesion", "--lesion-ratio", "0.2",
              "--max-force", "6", "--no-force-table"],
             "tests/data/fem_level3_breast_tissue_cyst.csv",
             "breast_tissue profile, level 3 (4,320 hexahedra), pole_lesion = a 0.2x cyst (10 mm, centre 10 mm deep)"),
    # the same at level 4 (since 2026-11-29, latest: ~6 min of FE to 12 mm); FINGER_CSV: the cyst's run
    # first, then fem_level4_breast_tissue_finger.csv for the plain pole
    "cyst4": (["finger", "--scene", SCENE, "--level", "4", "--site", "pole,pole_lesion", "--lesion-ratio", "0.2",
               "--max-force", "4.5", "--no-force-table"],
              "tests/data/fem_level4_breast_tissue_cyst.csv",
              "breast_tissue profile, level 4 (10,496 hexahedra), pole_lesion = a 0.2x cyst (10 mm, centre 10 mm deep)"),
}


def main():
    build = os.path.abspath(sys.argv[1])
    tmp = tempfile.mkdtemp(prefix="palp_bt_refs_")
    args = sys.argv[2:]
    which = "level3"
    if args and args[0] in ("--level4", "--cyst", "--cyst4"):
        which, args = args[0][2:], args[1:]
    else:
        write_d2(build, tmp)
        if not args:  # neither stored curves nor `compute`: the displacement file only
            return
    cmd, path, fe = REFS[which]
    lt.finger_ref(os.path.join(build, "tools/fem/palp-fem"), cmd, args, tmp, path, fe, "make_breast_tissue_refs.py")


if __name__ == "__main__":
    main()
