#!/usr/bin/env python3
"""The exercise phantom's fingertip against the level-3 and level-4 FE fingertip (issue 12).

SINCE 2026-11-30 the set's validated table and its lesion's gain rest on the FE refined where the
finger presses (test_finger_refined.py; docs/materials.md, "Refitted against the refined
fingertip"): uniform levels 3 and 4 are 9-27% stiff under a fingertip, and the refitted set stands
at 0.90-1.11 of uniform level 4 at the pole from 1.5 mm. Here the set's ratios against them,
the lesion's gain and the level-3 cyst's loss are PRINTED; what stays asserted is the references'
own convergence (level 4 no stiffer than level 3 from 2 mm), both curves' rise, the proxy's reach
and, against the level-4 cyst, the cyst's loss within 2 points (measured within 1.1). The bounds
below are what held while the table rested on these curves.

    test_finger_breast_tissue.py PALP_FEM SCENE FINGER_CSV [stored|guard [--level4 LEVEL4_CSV] [--cyst CYST_CSV]
                                                                 [--cyst4 CYST4_CSV]]

SCENE is config/phantoms/dome.json (the breast-tissue set, config/params/breast_tissue.json);
FINGER_CSV (tests/data/fem_level3_breast_tissue_finger.csv, written by
tests/data/make_breast_tissue_refs.py: 13-45 min of FE a site at level 3) holds the FE
curves: a rigid 8 mm sphere pressed by position into the relaxed breast-tissue FE dome,
level 3 (4,320 hexahedra), at the pole, 45, 60 and 70 deg and at the pole over the 10 mm lesion
(5x the gel, centre 10 mm deep). Against level 2, which the
set was first validated against, level 3 is 7-19% softer at the pole and 14-36% at 70 deg
(docs/materials.md, "The fingertip references at level 3"). Asserted:

- the real-time proxy reached each FE depth up to the table's within 5 um or 0.5% of it (matched
  positions);
- the set's `"validated"` table (the parameter file) is what the curves say: at every site
  it names that has no level-4 curve (below), every depth from the FE's 0.3 N (the issue's range
  starts there) up to the table's depth has real-time / FE within 15% (the compliance discrimination threshold),
  and the table's depth is no deeper than the first depth past 0.3 N where the ratio leaves
  15% (a table that claimed more, or a set that drifted, fails);
- both curves rise with depth;
- over the lesion (issue 12: the FEM and the real-time model agree on it): from the plain pole's
  0.3 N up to the pole's validated depth, real-time / FE within 15% and the lesion's gain
  (F_lesion / F_pole - 1 at equal depth, each model against itself) within 3 points of the FE's
  (measured 2026-11-29, the refitted set: at most 2.9 points, at 1.5 mm, FE +12.4% / real-time
  +15.3%, ratio 0.99-1.12; 2026-11-28 with the hinges' gel part seeing the lesion: at most 2.4 points;
  with the support alone up to 6.2 points, at 2.5 mm: +15.2% / +9.0%, which fails; docs/haptics.md,
  "The hinges see the lesion").

At the sites with a level-4 curve (all four since 2026-11-29) the level-3 ratios are printed, not
asserted: level 3 is up to 17% stiff there, and the refitted set stands at 0.81-0.94 of it at 70 deg
(1.5-7 mm) while within 0.96-1.06 of level 4. The proxy's reach is checked to the table's depth.

With LEVEL4_CSV (tests/data/fem_level4_breast_tissue_finger.csv: level 4, 10,496 hexahedra, the pole,
45, 60 and 70 deg to ~3 N, 1-1.5 h of FE a site; since 2026-11-29, latest, also the lesion, and 45 and 60 deg to 12 mm, ~6 min a site), where level 3 is not converged for a fingertip:
- from 2 mm, the level-4 FE is no stiffer than level 3 at equal depth (1%: a finer mesh of these
  elements converges from the stiff side; measured from 2 mm 0.89-0.99 at the pole, 0.90-0.97 at 45
  deg, 0.88-0.97 at 60 deg, 0.83-0.91 at 70 deg). Shallower, the faceted FE surface's offset from the
  sphere is a fair part of the depth and refining it can stiffen the contact: at 60 deg level 4 is
  1.04-1.11 of level 3 at 0.5-1.5 mm (70 deg 1.02 at 0.25 mm), so those depths are not checked;
- from the FE's 0.3 N to the validated depth, or the level-4 curve's end if shallower, real-time /
  level-4 FE within 15%, and the table no deeper than the first depth past 0.3 N where it leaves 15%
  (measured 2026-11-29, the set refitted with the fingertip's contact at the current positions:
  pole 1.096-1.144, 45 deg 1.073-1.146, 60 deg 0.934-1.095, 70 deg 0.870-1.058, to the curves' end
  at 14 mm at every site, 6.231 / 6.57 / 7.98 / 12.14 N (70 deg to 7 mm, 3.0 N, until 2026-11-29, later;
  45 and 60 deg to 10 mm and 70 deg to 12 mm until 2026-11-29, latest); 45 deg at 6 mm within 0.4 point
  of the bound, 70 deg at 14 mm within 2 points (0.870).
  The set before, read with the contact at the free positions: pole 1.039-1.133, 45 deg 1.043-1.127,
  60 deg 0.933-1.140, 70 deg 1.007-1.098; read soundly, up to 1.198 at the pole, which fails; with the
  rim clamped 70 deg was 1.155 at 1.5 mm, which fails);
- the table claims no site deeper than its level-4 curve reaches (since 2026-11-29 it rests on
  level 4: 14 mm at every site; the level-3 range above, to 14 / 15.6 / 18 / 10 mm, is what it
  claimed before, and at the level-4 curves' ends the set already stands at 1.11-1.14 of them);
- over the lesion at level 4 (since 2026-11-29, latest; level 3 had been its only reference): as over
  it at level 3 (below), the forces within 15% (measured 1.071-1.143 from 1.5 mm), the gain within 4
  points, a regression bound: measured at most 3.5 points, at 6 mm, FE +17.6% / real-time +14.2%; the
  issue's 15% of the FE's gain is missed at 2.5-8 mm (0.81-0.87 of it; docs/materials.md).

With CYST_CSV (tests/data/fem_level3_breast_tissue_cyst.csv: level 3, the pole and a 0.2x cyst where
the lesion is): over the cyst both models press softer than at the plain pole, real-time / FE within
15% and the cyst's loss (F_cyst / F_pole - 1) within 2 points of the FE's, from the plain pole's 0.3 N
to its validated depth (measured 2026-11-29: FE -4.0..-5.5%, real-time -4.5..-5.9%, within 1.4
points, ratio 0.94-1.07; the refitted set -4.5..-6.1%, within 1.6 points, ratio 0.99-1.10; src/lesion.c: the cyst strains as Eshelby's sphere, and the hinges see it.
The series sum before it lost 15-21%, ratio 0.81-0.95, which fails both).

With CYST4_CSV (tests/data/fem_level4_breast_tissue_cyst.csv, since 2026-11-29, latest: the same at
level 4, its plain pole the level-4 one): the same checks (measured: FE -4.2..-6.5%, real-time
-4.7..-6.1% from 1.5 mm to 12 mm, within 0.6 points, ratio 1.090-1.139).

guard: the stored curves were made by today's fingertip FE code (PALP_FEM_CODE_VERSION and the
sha256 of src/fem/fem_finger.c in the file's header equal today's), as eval_finger_level4_guard
checks the long-term ones.
"""
import csv
import json
import os
import sys
import tempfile

import test_eval_evaluate as common  # check() and the failure count (this folder is on sys.path)
import test_finger_long_term as lt  # read(), columns() and guard()

check = common.check
run = common.run

SITES = {"pole": 0.0, "45deg": 45.0, "60deg": 60.0, "70deg": 70.0}
# [m] From here the level-4 curve is checked no stiffer than level 3 (module docstring): shallower,
# the faceted FE surface's offset from the sphere is a fair part of the depth, and refining it
# can stiffen the first millimetre (60 deg: level 4 / level 3 1.04-1.11 at 0.5-1.5 mm).
STIFF_SIDE_FROM = 2e-3


def proxy_tol(depth):
    """Matched positions [m]: 5 um, or 0.5% of the depth where a deep press on the stiffening support
    leaves the six secant corrections up to ~30 um short (measured 29 um at 70 deg and 10 mm; at
    F ~ d^1.8 that is at most ~1% of the force, against the 15% compared)."""
    return max(5e-6, 0.005 * depth)


def validated(scene):
    sc = json.load(open(scene))
    params = os.path.join(os.path.dirname(os.path.abspath(scene)), sc["parameters"])
    return {round(e["polar_deg"], 6): e["depth_m"] for e in json.load(open(params))["validated"]["finger"]}


def stored(tool, scene, data, level4=None, cyst=None, cyst4=None):
    out = os.path.join(tempfile.mkdtemp(prefix="palp_finger_bt_"), "finger.csv")
    r = run([tool, "finger", "--scene", scene, "--level", "3", "--site", "pole,45deg,60deg,70deg,pole_lesion",
             "--fe-from", data, "--no-force-table", "--max-force", "13", "--out", out])
    check(r.returncode == 0, "palp-fem finger exited %d: %s" % (r.returncode, r.stderr[-500:]))
    if r.returncode:
        return
    rows = lt.read(out)
    table = validated(scene)
    # The table is checked against the refined curves (test_finger_refined.py); level 3, up to 17%
    # stiff under a fingertip (level 4 / level 3 0.83-0.91 at 70 deg from 2 mm), is printed.
    for site in SITES:
        d, fe, rt, dr = lt.columns(rows, site)
        check(len(d) >= 8, "%s: only %d depths" % (site, len(d)))
        check(all(fe[k + 1] > fe[k] for k in range(len(fe) - 1)), "%s: FE force not increasing: %r" % (site, fe))
        check(all(rt[k + 1] > rt[k] for k in range(len(rt) - 1)), "%s: real-time force not increasing: %r" % (site, rt))
        check(round(SITES[site], 6) in table, "the parameter file's validated table has no %g deg entry" % SITES[site])
        limit = table.get(round(SITES[site], 6), 0.0)
        for k in range(len(d)):
            # matched positions to the table's depth; deeper, the step-independent fingertip
            # (2026-11-29) left the secant 0.09-0.13 mm short at 60 deg and 16-18 mm (13-14 N on the
            # virtual coupling), where nothing is claimed
            if d[k] <= limit + 1e-9:
                check(abs(dr[k] - d[k]) <= proxy_tol(d[k]),
                      "%s: proxy at %.4f mm for the FE's %.4f mm" % (site, 1e3 * dr[k], 1e3 * d[k]))
            if fe[k] >= 0.3:
                print("%s %.2f mm: FE %.3f N, real-time %.3f N, ratio %.3f%s" % (site, 1e3 * d[k], fe[k], rt[k], rt[k] / fe[k],
                      "" if d[k] <= limit + 1e-9 else " (beyond the table)"))
        print("%s: level 3 printed only; the table is checked against the refined curves (test_finger_refined.py)" % site)
    lesion(rows, table)
    if level4:
        finer(tool, scene, level4, rows, table)
    if cyst:
        # the level-3 cyst printed where the level-4 one is checked (level 3 is up to 17% stiff under a
        # fingertip; since the refit of 2026-11-30 the loss stands 2.1 points from level 3's at 1.5-2 mm,
        # within 1.1 of level 4's)
        soft(tool, scene, cyst, table, loss_tol=None if cyst4 else 0.02)
    if cyst4:
        soft(tool, scene, cyst4, table, "4")


def finer(tool, scene, data, rows3, table):
    """The level-4 curves: no stiffer than level 3 from 2 mm; the real-time set's ratios against them and
    its lesion's gain printed (the table rests on the refined curves since 2026-11-30; until then it was
    checked here: within 15% from the FE's 0.3 N to its depth, measured 1.096-1.144 at the pole)."""
    stored_sites = {x["site"] for x in lt.read(data)}
    sites = sorted(stored_sites & set(SITES), key=list(SITES).index)
    check(sites[:1] == ["pole"] and len(sites) >= 2, "level-4 sites: %r (want the pole and another)" % sites)
    over_lesion = "pole_lesion" in stored_sites  # the lesion at level 4 (since 2026-11-29, latest)
    rows = lt.realtime_rows(tool, scene, data, sites + (["pole_lesion"] if over_lesion else []), label=" (level 4)")
    if rows is None:
        return
    for site in sites:
        d, fe, rt, _ = lt.columns(rows, site)
        d3, fe3, _, _ = lt.columns(rows3, site)
        at3 = {round(x, 9): f for x, f in zip(d3, fe3)}
        check(len(d) >= 8, "level 4, %s: only %d depths" % (site, len(d)))
        worst = 0.0
        for k in range(len(d)):
            f3 = at3.get(round(d[k], 9))
            if f3 is not None and d[k] >= STIFF_SIDE_FROM - 1e-12:
                worst = max(worst, fe[k] / f3)
                check(fe[k] <= 1.01 * f3, "%s at %.2f mm: level 4 %.4f N stiffer than level 3 %.4f N" %
                      (site, 1e3 * d[k], fe[k], f3))
            if fe[k] >= 0.3:
                print("level 4, %s %.2f mm: FE %.3f N, real-time %.3f N, ratio %.3f (printed: level 4 is stiff under a "
                      "fingertip)" % (site, 1e3 * d[k], fe[k], rt[k], rt[k] / fe[k]))
        print("level 4, %s: level 4 / level 3 at most %.3f" % (site, worst))
    if over_lesion:
        # the lesion at level 4, printed (level 4 raises the FE's gain to +15.4..+18.0% from 1.5 to 6 mm,
        # level 3 +12.4..+15.2%; the refined FE +18.1..+20.8%, which test_finger_refined.py checks)
        lesion(rows, table, "level 4, ")


def soft(tool, scene, data, table, level="3", loss_tol=0.02):
    """A 0.2x cyst where the lesion is: the loss of force over it, both models against their plain pole."""
    rows = lt.cyst_rows(tool, scene, data, level, "6")
    if not rows:
        return
    # from the plain pole's 0.3 N to its validated depth
    limit = table.get(0.0, 0.0)
    lt.cyst_losses(rows, lambda depth, f_plain: f_plain >= 0.3 and depth <= limit + 1e-9, proxy_tol, 8,
                   force_ratio=False, loss_tol=loss_tol)


def lesion(rows, table, label=""):
    """The pole over the lesion against the plain pole, both models at the same depths, printed (the
    gain is checked against the refined FE by test_finger_refined.py); the proxy at each FE depth."""
    d, fe, rt, dr = lt.columns(rows, "pole_lesion")
    d0, fe0, rt0, _ = lt.columns(rows, "pole")
    check(len(d) >= 8, label + "pole_lesion: only %d depths" % len(d))
    plain = {round(x, 9): k for k, x in enumerate(d0)}
    limit, n, worst = table.get(0.0, 0.0), 0, 0.0
    for k in range(len(d)):
        check(abs(dr[k] - d[k]) <= proxy_tol(d[k]),
              label + "pole_lesion: proxy at %.4f mm for the FE's %.4f mm" % (1e3 * dr[k], 1e3 * d[k]))
        j = plain.get(round(d[k], 9))
        if j is None or fe0[j] < 0.3 or d[k] > limit + 1e-9:
            continue
        q, gf, gr = rt[k] / fe[k], fe[k] / fe0[j] - 1.0, rt[k] / rt0[j] - 1.0
        n, worst = n + 1, max(worst, abs(gr - gf))
        print(label + "pole_lesion %.2f mm: FE %.3f N (gain %+.1f%%), real-time %.3f N (gain %+.1f%%), ratio %.3f" %
              (1e3 * d[k], fe[k], 100 * gf, rt[k], 100 * gr, q))
    check(n >= 8, label + "pole_lesion: %d depths compared from the pole's 0.3 N to its validated depth" % n)
    print(label + "pole_lesion: %d depths, lesion gain within %.1f points of the FE's (printed: checked against the "
          "refined FE in test_finger_refined.py)" % (n, 100 * worst))


def guard(tool, scene, data, level4=None, cyst=None, cyst4=None):
    """Cheap: the stored curves were made by today's fingertip FE code (recomputing one level-3 site
    takes 13-45 min, a level-4 one ~1.5 h)."""
    lt.guard(tool, scene, data, "level-3 breast-tissue fingertip curves", "tests/data/make_breast_tissue_refs.py BUILD compute")
    if level4:
        lt.guard(tool, scene, level4, "level-4 breast-tissue fingertip curves",
                 "tests/data/make_breast_tissue_refs.py BUILD --level4 compute")
    if cyst:
        lt.guard(tool, scene, cyst, "level-3 breast-tissue cyst curves", "tests/data/make_breast_tissue_refs.py BUILD --cyst compute")
    if cyst4:
        lt.guard(tool, scene, cyst4, "level-4 breast-tissue cyst curves",
                 "tests/data/make_breast_tissue_refs.py BUILD --cyst4 compute")


def main():
    tool, scene, data = sys.argv[1], sys.argv[2], sys.argv[3]
    mode = sys.argv[4] if len(sys.argv) > 4 else "stored"
    extra = dict(zip(sys.argv[5::2], sys.argv[6::2]))  # --level4 FILE, --cyst FILE
    {"stored": stored, "guard": guard}[mode](tool, scene, data, extra.get("--level4"), extra.get("--cyst"),
                                             extra.get("--cyst4"))
    return 1 if common.failures else 0


if __name__ == "__main__":
    sys.exit(main())
