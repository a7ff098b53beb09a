#!/usr/bin/env python3
"""The exercise phantom's fingertip against the level-3 and level-4 FE fingertip (issue 12).

SINCE 2026-11-30 the set's validated table and its lesion's gain rest on the FE refined where the
finger presses (test_finger_refined.py; docs/materials.md, "Refitted against the refined
fingertip"): uniform levels 3 and 4 are 9-27% stiff under a fingertip, and the refitted set stands
at 0.90-1.11 of uniform level 4 at the pole from 1.5 mm. SINCE 2026-12-02 this test runs the
real-time set only over the level-4 cyst: what it asserts is the references' own convergence (level 4
no stiffer than level 3 from 2 mm), the level-3 FE's rise with depth and its gain over the lesion,
both FE meshes softer over the cyst, and, against the level-4 cyst, the real-time cyst's loss within 2
points (measured within 1.1). The real-time set's ratios against level 3 (printed, not asserted, since
2026-11-30), its rise and its proxy's reach came from a run at the level-3 depths; test_finger_refined.py
runs the same depth sequence against the refined curves and asserts the rise and the reach there.
The list below is what held while the table rested on these curves, kept as the record.

    test_finger_breast_tissue.py PALP_FEM SCENE FINGER_CSV [stored|guard [--level4 LEVEL4_CSV] [--cyst CYST_CSV]
                                                                 [--cyst4 CYST4_CSV]]

SCENE is config/phantoms/dome.json (the breast-tissue set, config/params/breast_tissue.json);
FINGER_CSV (tests/data/fem_level3_breast_tissue_finger.csv, written by
tests/data/make_breast_tissue_refs.py: 13-45 min of FE a site at level 3) holds the FE
curves: a rigid 8 mm sphere pressed by position into the relaxed breast-tissue FE dome,
level 3 (4,320 hexahedra), at the pole, 45, 60 and 70 deg and at the pole over the 10 mm lesion
(5x the gel, centre 10 mm deep). Against level 2, which the
set was first validated against, level 3 is 7-19% softer at the pole and 14-36% at 70 deg
(docs/materials.md, "The fingertip references at level 3"). Asserted while the table rested on these
curves (until 2026-11-30; the record, no longer run: what runs now is the first paragraph's list):

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

The level-3 ratios are printed, not asserted: level 3 is up to 17% stiff under a fingertip, and the
refitted set stands at 0.81-0.94 of it at 70 deg (1.5-7 mm). The proxy's reach is checked to the
table's depth.

With LEVEL4_CSV (tests/data/fem_level4_breast_tissue_finger.csv: level 4, 10,496 hexahedra, the pole,
45, 60 and 70 deg and the lesion, to 12-14 mm), where level 3 is not converged for a fingertip: from 2 mm
the level-4 FE is no stiffer than level 3 at equal depth (1%: a finer mesh of these elements converges
from the stiff side; measured from 2 mm 0.89-0.99 at the pole, 0.90-0.97 at 45 deg, 0.88-0.97 at 60 deg,
0.83-0.91 at 70 deg). Shallower, the faceted FE surface's offset from the sphere is a fair part of the
depth and refining it can stiffen the contact (60 deg: 1.04-1.11 at 0.5-1.5 mm), so those depths are
not checked. FE side only since 2026-12-02: the real-time set's ratios against level 4 (measured
2026-11-29: pole 1.096-1.144, 45 deg 1.073-1.146, 60 deg 0.934-1.095, 70 deg 0.870-1.058; over the
lesion 1.071-1.143, its gain within 3.5 points) were printed, not asserted, since the table moved to
the refined curves, and cost half of this test's time.

With CYST_CSV (tests/data/fem_level3_breast_tissue_cyst.csv: level 3, the pole and a 0.2x cyst where
the lesion is): the FE presses softer over the cyst than at the plain pole (measured -4.0..-5.5%); with
no CYST4_CSV also the real-time checks below against it (measured 2026-11-29: real-time -4.5..-6.1%,
within 1.6 points, ratio 0.99-1.10; src/lesion.c: the cyst strains as Eshelby's sphere, and the
hinges see it; the series sum before it lost 15-21%, ratio 0.81-0.95, which fails both).

With CYST4_CSV (tests/data/fem_level4_breast_tissue_cyst.csv: the same at level 4, its plain pole the
level-4 one): over the cyst both models press softer than at the plain pole and the real-time loss
(F_cyst / F_pole - 1) is within 2 points of the FE's, from the plain pole's 0.3 N to its validated depth
(measured 2026-12-02: FE -4.2..-6.5%, real-time -4.9..-6.8% from 1.5 mm to 12 mm, within 1.1 points,
ratio 0.894-1.098, printed: level 4 is stiff under a fingertip).

guard: the stored curves were made by today's fingertip FE code (PALP_FEM_CODE_VERSION and the
sha256 of src/fem/fem_finger.c in the file's header equal today's), as eval_finger_level4_guard
checks the long-term ones.
"""
import sys

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


def fe_rows(path):
    """A stored curve's FE side as rows for lt.columns: the real-time columns it was written with (an
    older set's) blanked to NaN, so nothing here can read them."""
    return [dict(x, realtime_N="nan", realtime_depth_m="nan") for x in lt.read(path)]


def stored(tool, scene, data, level4=None, cyst=None, cyst4=None):
    """The FE side of the level-3 curves (their rise; the set's real-time side runs against the refined
    curves in test_finger_refined.py, which since 2026-12-02 also asserts its rise: a run here at the
    level-3 depths, the same depth sequence, only repeated it), the level-4 ones against them, and
    the cysts."""
    rows = fe_rows(data)
    table = lt.validated_table(scene)
    for site in SITES:
        d, fe, _, _ = lt.columns(rows, site)
        check(len(d) >= 8, "%s: only %d depths" % (site, len(d)))
        check(all(fe[k + 1] > fe[k] for k in range(len(fe) - 1)), "%s: FE force not increasing: %r" % (site, fe))
        check(round(SITES[site], 6) in table, "the parameter file's validated table has no %g deg entry" % SITES[site])
    # the lesion's FE gain (measured +12.4..+15.2%; the real-time gain is checked against the refined
    # FE's in test_finger_refined.py)
    fe_gain(rows, table, "level 3, pole_lesion", +1)
    if level4:
        finer(tool, scene, level4, rows, table)
    if cyst and cyst4:
        # the level-3 cyst, FE side only where the level-4 one is checked with the real-time set
        # (level 3 is up to 17% stiff under a fingertip; since the refit of 2026-11-30 the real-time
        # loss stood 2.1 points from level 3's at 1.5-2 mm, within 1.1 of level 4's)
        fe_gain(fe_rows(cyst), table, "level-3 cyst", -1)  # measured -4.0..-5.5%
    elif cyst:
        soft(tool, scene, cyst, table)
    if cyst4:
        soft(tool, scene, cyst4, table, "4")


def fe_gain(rows, table, label, sign):
    """The FE over the inclusion (site pole_lesion) against its plain pole, rows of one stored curve:
    its gain F / F_pole - 1 of sign `sign` (+1 a lesion, stiffer; -1 a cyst, softer) at every depth
    from the plain pole's 0.3 N to the pole's validated depth, at least 8 of them."""
    d, fe, _, _ = lt.columns(rows, "pole_lesion")
    d0, fe0, _, _ = lt.columns(rows, "pole")
    plain = {round(x, 9): k for k, x in enumerate(d0)}
    limit, n = table.get(0.0, 0.0), 0
    for k in range(len(d)):
        j = plain.get(round(d[k], 9))
        if j is None or fe0[j] < 0.3 or d[k] > limit + 1e-9:
            continue
        n += 1
        gain = fe[k] / fe0[j] - 1.0
        print("%s %.2f mm: FE %+.1f%%" % (label, 1e3 * d[k], 100 * gain))
        check(sign * gain > 0.0, "%s at %.2f mm: the FE %s over it (%+.1f%%)" %
              (label, 1e3 * d[k], "not stiffer" if sign > 0 else "not softer", 100 * gain))
    check(n >= 8, "%s: %d depths from the pole's 0.3 N to its validated depth (want 8)" % (label, n))


def finer(tool, scene, data, rows3, table):
    """The level-4 curves, FE side only: no stiffer than level 3 from 2 mm, and the lesion's FE gain
    printed. The real-time set is not run against them (since 2026-12-02: the table and the lesion's
    gain rest on the refined curves, test_finger_refined.py, and the real-time ratios against level 4
    were only printed; until 2026-11-30 they were checked here, measured 1.096-1.144 at the pole).
    To see them: palp-fem finger --scene SCENE --level 4 --site pole,45deg,60deg,70deg,pole_lesion
    --fe-from LEVEL4_CSV --no-force-table --max-force 3."""
    l4 = lt.read(data)
    stored_sites = {x["site"] for x in l4}
    sites = sorted(stored_sites & set(SITES), key=list(SITES).index)
    check(sites[:1] == ["pole"] and len(sites) >= 2, "level-4 sites: %r (want the pole and another)" % sites)
    for site in sites:
        d = [float(x["depth_m"]) for x in l4 if x["site"] == site]
        fe = [float(x["fem_N"]) for x in l4 if x["site"] == site]
        d3, fe3, _, _ = lt.columns(rows3, site)
        at3 = {round(x, 9): f for x, f in zip(d3, fe3)}
        check(len(d) >= 8, "level 4, %s: only %d depths" % (site, len(d)))
        worst, n = 0.0, 0
        for k in range(len(d)):
            f3 = at3.get(round(d[k], 9))
            if f3 is not None and d[k] >= STIFF_SIDE_FROM - 1e-12:
                worst, n = max(worst, fe[k] / f3), n + 1
                check(fe[k] <= 1.01 * f3, "%s at %.2f mm: level 4 %.4f N stiffer than level 3 %.4f N" %
                      (site, 1e3 * d[k], fe[k], f3))
        check(n >= 4, "level 4, %s: %d depths shared with level 3 from %.0f mm (want 4)" % (site, n, 1e3 * STIFF_SIDE_FROM))
        print("level 4, %s: level 4 / level 3 at most %.3f over %d depths from %.0f mm" %
              (site, worst, n, 1e3 * STIFF_SIDE_FROM))
    if "pole_lesion" in stored_sites:
        # printed (level 4 raises the FE's gain to +15.4..+18.0% from 1.5 to 6 mm, level 3 +12.4..+15.2%;
        # the refined FE +18.1..+20.8%, against which test_finger_refined.py checks the real-time gain)
        p = {round(float(x["depth_m"]), 9): float(x["fem_N"]) for x in l4 if x["site"] == "pole"}
        for x in l4:
            key = round(float(x["depth_m"]), 9)
            if x["site"] == "pole_lesion" and key in p and p[key] >= 0.3:
                print("level 4, pole_lesion %.2f mm: FE gain %+.1f%%" % (1e3 * key, 100 * (float(x["fem_N"]) / p[key] - 1)))


def soft(tool, scene, data, table, level="3"):
    """A 0.2x cyst where the lesion is: the loss of force over it, both models against their plain pole."""
    rows = lt.cyst_rows(tool, scene, data, level, "6")
    if not rows:
        return
    # from the plain pole's 0.3 N to its validated depth
    limit = table.get(0.0, 0.0)
    lt.cyst_losses(rows, lambda depth, f_plain: f_plain >= 0.3 and depth <= limit + 1e-9, proxy_tol, 8,
                   force_ratio=False)


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
