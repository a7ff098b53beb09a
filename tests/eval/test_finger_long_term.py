#!/usr/bin/env python3
"""The long-term default's fingertip against the level-4 FE fingertip (issue 12).

    test_finger_long_term.py PALP_FEM SCENE FINGER_CSV [stored|guard|recompute|fine [--cyst CYST_CSV]
                             [--graded GRADED_CSV [--graded5 GRADED5_CSV]]]

fine: SCENE is the long-term dome on a 1,300-vertex net (config/paper_step_long_term_fine.json), whose
set was fitted against the graded curves: graded() with FINE_BOUNDS, the issue's 15%, and the lesion's
gain floor FINE_GAIN.

The FE curves (a rigid 8 mm sphere pressed by position into the FE dome, level 4,
relaxed long-term reading, 0.25 mm steps until the FE force passes 5 N) are stored
in FINGER_CSV (tests/data/fem_level4_long_term_finger.csv, written by
tests/data/make_long_term_level4.py: each site's FE curve takes 10-20 min at level
4). `palp-fem finger --fe-from` drives the real-time finger of SCENE to the same
depths at the pole, 45 deg, 70 deg and the pole over the 10 mm lesion. Asserted
from the written CSV:
- every real-time force within 15% of the FE's at the depth reached, 0.25 mm to
  the FE's 5 N (the compliance discrimination threshold), except where BOUNDS below
  says otherwise (each exception measured and explained in docs/materials.md,
  "Refitted against the level-4 FEM");
- the real-time proxy reached each FE depth within 5 um (matched positions);
- both curves increase with depth and the FE's reach 5 N (REACH below: the sites
  whose level-4 curves were stopped earlier for time reach less);
- at the pole the real-time force is nearly linear, as the FE's is (the skin bends
  like a plate on the gel): the stiffness over 0.25-1 mm and over 1-2 mm differ by
  less than 30%;
- the lesion's gain (F_lesion / F_pole - 1 at equal depth, each model against itself) is at
  least 0.45 of the FE's at every stored depth: a floor, not the issue's agreement, which this
  set misses (measured 2026-11-28 with the hinges' gel part seeing the lesion: real-time
  +5.1..+5.5% against the FE's +6.2..+10.6%, 0.48-0.88 of it; with the support alone +1.1..+2.4%,
  0.17-0.24, which fails; docs/haptics.md, "The hinges see the lesion").

With --cyst CYST_CSV (tests/data/fem_level4_long_term_cyst.csv): over a 0.2x cyst where the lesion
is, the force within 15% of the FE's and the cyst's loss within 2 points of the FE's (soft() below).

guard: the stored curves were made by today's fingertip FE code: the data file records
PALP_FEM_CODE_VERSION and the sha256 of src/fem/fem_finger.c, which must equal today's
(the displacement guard eval_evaluate_level4_guard recomputes level-4 frames; a level-4
fingertip depth takes 60-75 s, over the budget, so it is the `recompute` mode, by hand:
the pole's first depth recomputed equals the stored one within 1e-4 relative; measured
identical to the 7 stored digits on 2026-11-27).
"""
import csv
import json
import os
import sys

import test_eval_evaluate as common  # its check() and failure count (this folder is on sys.path)

check = common.check
run = common.run  # subprocess.run, output captured, 600 s timeout

# site -> (lowest, highest) real-time / FE ratio allowed at every stored depth: the 15% at
# every site. 70 deg (20 deg above the rim) was held at 1.20 while the rim was clamped (1.07-1.20
# there); with the rim pinned (membrane.rim_hinge_release 1) it is inside 15% (docs/materials.md,
# "The patch map, the support and the rim").
# Measured 2026-11-27: pole 1.012-1.122, 45 deg 1.026-1.131 (to 3 mm), 70 deg 1.008-1.134 (to 2.5 mm),
# lesion 0.937-1.068 (to 3 mm).
BOUNDS = {"pole": (0.85, 1.15), "45deg": (0.85, 1.15), "70deg": (0.85, 1.15), "pole_lesion": (0.85, 1.15)}
# site -> the FE force [N] every stored curve reaches: the 5 N (pole and 45 deg to 3 mm, 5.2 and
# 5.05 N; 70 deg to 2.5 mm, 5.33 N; over the lesion to 3 mm, 5.77 N; 36-87 min a site at level 4 on the
# shared machine, the data file's header)
REACH = {"pole": 5.0, "45deg": 5.0, "70deg": 5.0, "pole_lesion": 5.0}


def columns(rows, site):
    """One site's rows of a `palp-fem finger` CSV: depth [m], FE force [N], real-time force [N],
    real-time depth reached [m]."""
    rs = [x for x in rows if x["site"] == site]
    return ([float(x["depth_m"]) for x in rs], [float(x["fem_N"]) for x in rs], [float(x["realtime_N"]) for x in rs],
            [float(x["realtime_depth_m"]) for x in rs])


def realtime_rows(tool, scene, data, sites, level="4", max_force="3", label=""):
    """`palp-fem finger --fe-from DATA`: the stored FE curves of SITES with the real-time side computed
    now, as rows; None (and a failed check) if the command fails."""
    out = os.path.join(common.scratch("palp_finger_rt_"), "finger.csv")
    r = run([tool, "finger", "--scene", scene, "--level", level, "--site", ",".join(sites), "--fe-from", data,
             "--no-force-table", "--max-force", max_force, "--out", out])
    check(r.returncode == 0, "palp-fem finger%s exited %d: %s" % (label, r.returncode, r.stderr[-500:]))
    return read(out) if r.returncode == 0 else None


def read(path):
    with open(path) as f:
        return list(csv.DictReader(l for l in f if not l.startswith("#")))


def stored(tool, scene, data, rt_rows=None):
    """rt_rows: the real-time side already computed at a superset of the stored depths (graded()'s run:
    the driver walks each site's depths in order from the undeformed dome, so a depth's force does not
    depend on the depths after it), read at the stored depths instead of driving the finger again."""
    if rt_rows is not None:
        rt_at = {(x["site"], round(float(x["depth_m"]), 9)): x for x in rt_rows}
        rows = []
        for x in read(data):
            y = rt_at.get((x["site"], round(float(x["depth_m"]), 9)))
            check(y is not None, "%s %s m: no real-time row at a stored depth" % (x["site"], x["depth_m"]))
            if y is not None:
                rows.append(dict(x, realtime_N=y["realtime_N"], realtime_depth_m=y["realtime_depth_m"]))
    else:
        out = os.path.join(common.scratch("palp_finger_l4_"), "finger.csv")
        # no --site: the default, every site of "all" (60deg, which the stored curves predate, is asked by name)
        r = run([tool, "finger", "--scene", scene, "--level", "4", "--fe-from", data, "--no-force-table", "--out", out])
        check(r.returncode == 0, "palp-fem finger exited %d: %s" % (r.returncode, r.stderr[-500:]))
        if r.returncode:
            return
        rows = read(out)
    for site, (lo, hi) in BOUNDS.items():
        d, fe, rt, dr = columns(rows, site)
        check(len(d) >= 4, "%s: only %d depths" % (site, len(d)))
        for k in range(len(d)):
            ratio = rt[k] / fe[k]
            print("%s %.2f mm: FE %.3f N, real-time %.3f N at %.4f mm, ratio %.3f (bound %.2f-%.2f)"
                  % (site, 1e3 * d[k], fe[k], rt[k], 1e3 * dr[k], ratio, lo, hi))
            check(lo <= ratio <= hi, "%s at %.2f mm: the real-time force is %.3f of the FE's" % (site, 1e3 * d[k], ratio))
            check(abs(dr[k] - d[k]) <= 5e-6, "%s: proxy at %.4f mm for the FE's %.4f mm" % (site, 1e3 * dr[k], 1e3 * d[k]))
        check(all(fe[k + 1] > fe[k] for k in range(len(fe) - 1)), "%s: FE force not increasing: %r" % (site, fe))
        check(all(rt[k + 1] > rt[k] for k in range(len(rt) - 1)), "%s: real-time force not increasing: %r" % (site, rt))
        check(fe[-1] >= REACH[site], "%s: the FE curve stops at %.2f N, before %.1f N" % (site, fe[-1], REACH[site]))
        if site != "pole":
            continue

        def at(xs, ys, x):  # linear interpolation on the written depths
            for k in range(len(xs) - 1):
                if xs[k] <= x <= xs[k + 1]:
                    return ys[k] + (ys[k + 1] - ys[k]) * (x - xs[k]) / (xs[k + 1] - xs[k])
            return float("nan")

        s1 = (at(d, rt, 1e-3) - at(d, rt, 0.25e-3)) / 0.75e-3
        s2 = (at(d, rt, 2e-3) - at(d, rt, 1e-3)) / 1e-3
        print("pole: real-time stiffness 0.25-1 mm %.0f N/m, 1-2 mm %.0f N/m (ratio %.2f, bound 1 +- 0.3)" %
              (s1, s2, s2 / s1))
        check(abs(s2 / s1 - 1.0) < 0.3, "stiffness ratio 1-2 mm / 0.25-1 mm %.2f" % (s2 / s1))
    d0, fe0, rt0, _ = columns(rows, "pole")
    d, fe, rt, _ = columns(rows, "pole_lesion")
    plain = {round(x, 9): k for k, x in enumerate(d0)}
    n = 0
    for k in range(len(d)):
        j = plain.get(round(d[k], 9))
        if j is None:
            continue
        n += 1
        gf, gr = fe[k] / fe0[j] - 1.0, rt[k] / rt0[j] - 1.0
        print("lesion gain %.2f mm: FE %+.1f%%, real-time %+.1f%% (%.2f of it, floor 0.45)" %
              (1e3 * d[k], 100 * gf, 100 * gr, gr / gf))
        check(gr >= 0.45 * gf, "lesion gain at %.2f mm: real-time %+.1f%% below 0.45 of the FE's %+.1f%%" %
              (1e3 * d[k], 100 * gr, 100 * gf))
    check(n >= 4, "lesion gain compared at %d depths" % n)


def guard(tool, scene, data, curves="level-4 fingertip curves",
          rerun="tests/data/make_long_term_level4.py BUILD compute (or this test's `recompute` mode to compare)"):
    """Cheap: the stored curves were made by this FEM's fingertip code (PALP_FEM_CODE_VERSION and
    the sha256 of src/fem/fem_finger.c recorded in the data file's header equal today's)."""
    import hashlib
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    head = [l for l in open(data) if l.startswith("#")]
    sha = hashlib.sha256(open(os.path.join(root, "src/fem/fem_finger.c"), "rb").read()).hexdigest()
    ver = [l for l in open(os.path.join(root, "src/fem/palp_fem.h")) if "define PALP_FEM_CODE_VERSION" in l][0].split()[2]
    print("stored fingertip curves: %s" % "".join(head[:2]).strip())
    print("today: PALP_FEM_CODE_VERSION %s, sha256 of src/fem/fem_finger.c %s" % (ver, sha))
    check(any(("PALP_FEM_CODE_VERSION %s" % ver) in l for l in head),
          "PALP_FEM_CODE_VERSION is %s now: the stored %s may be stale; rerun %s" % (ver, curves, rerun))
    check(any(sha in l for l in head),
          "src/fem/fem_finger.c changed since the stored %s were written; rerun %s" % (curves, rerun))


def recompute(tool, scene, data):
    """By hand (60-75 s, over the test budget): the level-4 FE at the pole recomputed for its first
    depth equals the stored one within 1e-4 relative (measured: identical to the 7 stored digits)."""
    out = os.path.join(common.scratch("palp_finger_guard_"), "finger.csv")
    r = run([tool, "finger", "--scene", scene, "--level", "4", "--site", "pole", "--depths", "1", "--out", out])
    check(r.returncode == 0, "palp-fem finger exited %d: %s" % (r.returncode, r.stderr[-500:]))
    if r.returncode:
        return
    now = [x for x in read(out) if x["site"] == "pole"]
    ref = [x for x in read(data) if x["site"] == "pole"]
    check(len(now) == 1 and len(ref) >= 1, "%d recomputed rows, %d stored" % (len(now), len(ref)))
    if not now or not ref:
        return
    a, b = float(now[0]["fem_N"]), float(ref[0]["fem_N"])
    print("level-4 FE, pole, %.2f mm: %.6g N now, %.6g N stored (relative difference %.2g, bound 1e-4)" %
          (1e3 * float(now[0]["depth_m"]), a, b, abs(a / b - 1.0)))
    check(now[0]["depth_m"] == ref[0]["depth_m"], "depths differ: %s / %s" % (now[0]["depth_m"], ref[0]["depth_m"]))
    check(abs(a / b - 1.0) <= 1e-4, "the level-4 FE no longer gives the stored fingertip force: rerun "
          "tests/data/make_long_term_level4.py")


def soft(tool, scene, data, rt_rows=None):
    """A 0.2x cyst where the lesion is (CYST_CSV, level 4): both models lose force over it, the real-time
    force within 15% of the FE's and its loss (F_cyst / F_pole - 1, each model against itself) within 2
    points of the FE's at every stored depth (measured 2026-11-29: FE -2.3..-3.7%, real-time -2.2..-2.4%,
    within 1.5 points, with the hinges' gel part seeing the cyst; without that -0.4..-0.9%, up to 2.8
    points short, which fails; docs/haptics.md, "A soft cyst strains as Eshelby's sphere").
    rt_rows: graded()'s real-time run, whose plain pole (no lesion in its world, so the cyst's ratio does
    not enter it) walked the same depth sequence at least as deep: its real-time pole is read from there
    and only the cyst is driven here (the pole had been driven again, 8 of the test's 53 depths)."""
    rows = cyst_rows(tool, scene, data, "4", "5", rt_rows)
    if rows:
        cyst_losses(rows, lambda depth, f_plain: True, lambda depth: 5e-6, 6)


def cyst_rows(tool, scene, data, level, max_force, rt_rows=None):
    """The real-time side at the stored FE depths of the pole and a 0.2x cyst (--fe-from data); None
    if palp-fem failed. rt_rows: a real-time run of the same scene whose plain pole reached the stored
    pole's depths (the driver presses each site through one fixed depth sequence from the undeformed
    dome, so a depth's force depends only on the depths before it): the pole is read from it, and only
    the cyst is driven here."""
    out = os.path.join(common.scratch("palp_finger_cyst_"), "finger.csv")
    sites = "pole,pole_lesion" if rt_rows is None else "pole_lesion"
    r = run([tool, "finger", "--scene", scene, "--level", level, "--site", sites, "--lesion-ratio", "0.2",
             "--fe-from", data, "--no-force-table", "--max-force", max_force, "--out", out])
    check(r.returncode == 0, "palp-fem finger (cyst) exited %d: %s" % (r.returncode, r.stderr[-500:]))
    if r.returncode:
        return None
    if rt_rows is None:
        return read(out)
    rt_at = {round(float(x["depth_m"]), 9): x for x in rt_rows if x["site"] == "pole"}
    pole = []
    for x in read(data):
        if x["site"] != "pole":
            continue
        y = rt_at.get(round(float(x["depth_m"]), 9))
        check(y is not None, "cyst: the plain pole at %s m has no real-time row" % x["depth_m"])
        if y is not None:
            pole.append(dict(x, realtime_N=y["realtime_N"], realtime_depth_m=y["realtime_depth_m"]))
    return pole + read(out)


def cyst_losses(rows, keep, proxy_tol, least, force_ratio=True, loss_tol=0.02):
    """The pole over a 0.2x cyst (site pole_lesion) against the plain pole, both models at the depths
    keep(depth [m], plain FE force [N]) admits: both lose force over it, the real-time force within 15%
    of the FE's (unless force_ratio is False: a reference known to be stiff, whose ratio is printed),
    its loss within loss_tol (2 points; None: printed, where a finer reference is checked); at least
    `least` depths; the proxy within proxy_tol(depth) [m]
    of each FE depth (matched positions)."""
    d0, fe0, rt0, _ = columns(rows, "pole")
    d, fe, rt, dr = columns(rows, "pole_lesion")
    plain = {round(x, 9): k for k, x in enumerate(d0)}
    n, worst = 0, 0.0
    for k in range(len(d)):
        j = plain.get(round(d[k], 9))
        if j is None or not keep(d[k], fe0[j]):
            continue
        n += 1
        q, gf, gr = rt[k] / fe[k], fe[k] / fe0[j] - 1.0, rt[k] / rt0[j] - 1.0
        worst = max(worst, abs(gr - gf))
        print("cyst %.2f mm: FE %.3f N (%+.1f%%), real-time %.3f N (%+.1f%%), ratio %.3f" %
              (1e3 * d[k], fe[k], 100 * gf, rt[k], 100 * gr, q))
        check(abs(dr[k] - d[k]) <= proxy_tol(d[k]), "cyst: proxy at %.4f mm for the FE's %.4f mm" %
              (1e3 * dr[k], 1e3 * d[k]))
        check(gf < 0 and gr < 0, "cyst at %.2f mm: both models softer over it (FE %+.1f%%, real-time %+.1f%%)" %
              (1e3 * d[k], 100 * gf, 100 * gr))
        check(not force_ratio or 0.85 <= q <= 1.15, "cyst at %.2f mm: real-time / FE %.3f (15%%)" % (1e3 * d[k], q))
        check(loss_tol is None or abs(gr - gf) <= loss_tol, "cyst at %.2f mm: loss %+.1f%% against the FE's %+.1f%% "
              "(%.0f points)" % (1e3 * d[k], 100 * gr, 100 * gf, 100 * (loss_tol or 0.0)))
    check(n >= least, "cyst: compared at %d depths (want %d)" % (n, least))
    print("cyst: %d depths, loss within %.1f points of the FE's" % (n, 100 * worst))


# The graded reference (--graded GRADED_CSV, tests/data/fem_graded4_long_term_finger.csv: level 4 with
# the mesh graded 0.5 at each site, ~2 mm cells there against uniform level 4's 3.9 mm, which are longer
# than the skin's bending length; --graded5 GRADED5_CSV, fem_graded5_long_term_finger.csv: level 5
# graded at the pole and at 45 deg, to 4 mm). docs/materials.md, "The long-term set against the graded fingertip".
GRADED_SITES = ("pole", "45deg", "70deg")
SITE_DEG = {"pole": 0.0, "45deg": 45.0, "70deg": 70.0}
# site -> (lowest, highest) real-time / graded FE from the FE's 0.3 N: a REGRESSION BOUND, not the issue's
# 15%, which this set misses against these curves (measured 2026-12-02: pole 1.192-1.357 to 4 mm, 45 deg
# 1.158-1.284 to 4 mm, 70 deg 1.126-1.245 to 2.5 mm); a refit into 15% (bending x0.46) made the 338-vertex
# net's point stiffness vary by 11.5% between a vertex and a face as a fingertip slid
# (model_finger_surface's bound is the hand's 7%) and was not shipped
GRADED_BOUNDS = {"pole": (1.10, 1.42), "45deg": (1.05, 1.33), "70deg": (1.05, 1.31)}
# The same set fitted for a 1,300-vertex net (config/paper_step_long_term_fine.json): the 15%.
FINE_BOUNDS = {"pole": (0.85, 1.15), "45deg": (0.85, 1.15), "70deg": (0.85, 1.15)}
# Its lesion gain from 1 mm is at least this share of the graded FE's: a floor, not the agreement
# within 15%, which it misses (measured 2026-12-02: 0.57-0.72, +6.3..+9.3% against +11.0..+13.7%).
FINE_GAIN = 0.50


def validated_table(scene):
    """The scene's parameter file's validated fingertip table: {polar_deg: depth_m}."""
    sc = json.load(open(scene))
    params = os.path.join(os.path.dirname(os.path.abspath(scene)), sc["parameters"])
    return {round(e["polar_deg"], 6): e["depth_m"] for e in json.load(open(params))["validated"]["finger"]}


def by_depth(rows, site):
    return {round(float(x["depth_m"]), 9): float(x["fem_N"]) for x in rows if x["site"] == site}


def graded(tool, scene, data, graded_csv, graded5_csv=None, bounds=None, gain_floor=None):
    """The references' convergence, and the set against the graded curves. At each depth the reference
    is the least force of level 5 graded, level 4 graded and uniform level 4 (these bricks converge from
    the stiff side). Asserted: level 5 graded within 0.93-1.00 of level 4 graded (measured 0.936-0.990,
    0.25-4 mm, pole and 45 deg) and level 4 graded no stiffer than uniform level 4 (1%; measured 0.849-0.969) where both
    reach; the lesion's gain (F_lesion / F_pole - 1 on one mesh) no smaller on the graded mesh than on
    the uniform one less 1 point, and at least 8% from 1 mm (measured +11.0..+13.7% against +8.2..+10.6%:
    refining the mesh under the finger raises it, as for breast tissue); the real-time set's ratio from
    the FE's 0.3 N to the validated depth or the curve's end inside GRADED_BOUNDS, the proxy at the FE's
    depth. Printed: the lesion's real-time gain against the graded FE's; with gain_floor, asserted to be at
    least that share of it. bounds: GRADED_BOUNDS, or FINE_BOUNDS for the 1,300-vertex set."""
    bounds = bounds or GRADED_BOUNDS
    what = "the issue's 15%" if bounds is FINE_BOUNDS else "the regression bound"
    g4, u4 = read(graded_csv), read(data)
    g5 = read(graded5_csv) if graded5_csv else []
    keys = list(g4[0].keys())
    joined = os.path.join(common.scratch("palp_finger_graded_"), "graded_joined.csv")
    sites = GRADED_SITES + ("pole_lesion",)
    claimed = validated_table(scene)
    # The real-time run goes at each off-pole site only as deep as something reads it: the check below
    # (to the validated depth) and stored() (to the uniform level-4 curve's end). The driver presses
    # through one depth sequence, so the depths kept give the same forces (70 deg's 3-5 mm, read by
    # nothing for the 338-vertex set, whose table stops at 2.5 mm, had cost 3 of the test's 53 depths;
    # 5 mm, 1 of the 1,300-vertex set's 37). The pole and the lesion run to the end (the lesion's gain).
    reach = {site: max([claimed.get(SITE_DEG[site], 0.0)] + list(by_depth(u4, site))) for site in GRADED_SITES
             if site != "pole"}
    with open(joined, "w") as f:
        f.write(",".join(keys) + "\n")
        for site in sites:
            u, f5 = by_depth(u4, site), by_depth(g5, site)
            for x in g4:
                if x["site"] != site:
                    continue
                depth = round(float(x["depth_m"]), 9)
                force = g4f = float(x["fem_N"])
                if depth in f5:
                    q5 = f5[depth] / g4f
                    print("%s %.2f mm: level 5 graded / level 4 graded %.3f" % (site, 1e3 * depth, q5))
                    check(0.93 <= q5 <= 1.0, "%s %.2f mm: level 5 graded / level 4 graded %.3f outside 0.93-1.00"
                          % (site, 1e3 * depth, q5))
                    force = min(force, f5[depth])
                if depth in u:
                    print("%s %.2f mm: level 4 graded / uniform level 4 %.3f" % (site, 1e3 * depth, g4f / u[depth]))
                    check(g4f <= 1.01 * u[depth], "%s %.2f mm: level 4 graded %.3f N stiffer than uniform level 4 "
                          "%.3f N" % (site, 1e3 * depth, g4f, u[depth]))
                    force = min(force, u[depth])
                if depth > reach.get(site, float("inf")) + 1e-9:
                    continue  # the FE side's checks above still ran
                row = dict(x, fem_N="%.9e" % force)
                f.write(",".join(row[k] or "" for k in keys) + "\n")
    rows = realtime_rows(tool, scene, joined, sites, max_force="20", label=" (graded, joined)")
    if rows is None:
        return None
    for site in GRADED_SITES:
        d, fe, rt, dr = columns(rows, site)
        lo_b, hi_b = bounds[site]
        limit = min(claimed.get(SITE_DEG[site], 0.0), d[-1] if d else 0.0)
        n, lo, hi = 0, 9.0, 0.0
        for k in range(len(d)):
            if fe[k] < 0.3 or d[k] > limit + 1e-9:
                continue
            check(abs(dr[k] - d[k]) <= max(5e-6, 0.005 * d[k]), "%s: proxy at %.4f mm for %.4f mm" %
                  (site, 1e3 * dr[k], 1e3 * d[k]))
            q = rt[k] / fe[k]
            n, lo, hi = n + 1, min(lo, q), max(hi, q)
            check(lo_b <= q <= hi_b, "graded, %s at %.2f mm: real-time / graded FE %.3f outside %s "
                  "%.2f-%.2f" % (site, 1e3 * d[k], q, what, lo_b, hi_b))
        check(n >= 4, "graded, %s: %d depths from 0.3 N to %.1f mm (want 4)" % (site, n, 1e3 * limit))
        print("graded, %s: real-time / graded FE %.3f-%.3f over %d depths to %.1f mm (the issue's 15%%: %s)" %
              (site, lo, hi, n, 1e3 * limit, "met" if 0.85 <= lo and hi <= 1.15 else "NOT met"))
    d0, _, rt0, _ = columns(rows, "pole")
    d, _, rt, _ = columns(rows, "pole_lesion")
    fe0, fe = by_depth(g4, "pole"), by_depth(g4, "pole_lesion")
    ue0, ue = by_depth(u4, "pole"), by_depth(u4, "pole_lesion")
    plain = {round(x, 9): k for k, x in enumerate(d0)}
    n = 0
    for k in range(len(d)):
        j, key = plain.get(round(d[k], 9)), round(d[k], 9)
        if j is None or d[k] < 1e-3 - 1e-12 or key not in fe0 or key not in fe:
            continue
        n += 1
        gf, gr = fe[key] / fe0[key] - 1.0, rt[k] / rt0[j] - 1.0
        gu = ue[key] / ue0[key] - 1.0 if key in ue and key in ue0 else float("nan")
        print("lesion gain %.2f mm: graded FE %+.1f%% (uniform level 4 %+.1f%%), real-time %+.1f%% (%.2f of the graded)"
              % (1e3 * d[k], 100 * gf, 100 * gu, 100 * gr, gr / gf))
        check(gf >= 0.08 and not gf < gu - 0.01, "lesion gain at %.2f mm: graded FE %+.1f%%, uniform level 4 %+.1f%%"
              % (1e3 * d[k], 100 * gf, 100 * gu))
        check(gain_floor is None or gr >= gain_floor * gf, "lesion gain at %.2f mm: real-time %+.1f%%, %.2f of the "
              "graded FE's %+.1f%%, below the floor %.2f" % (1e3 * d[k], 100 * gr, gr / gf, 100 * gf, gain_floor or 0.0))
    check(n >= 4, "graded lesion gain compared at %d depths" % n)
    return rows


def mesh_guard(path, rerun):
    """The curves in path were made by today's fingertip FE code and mesher: the sha256 of
    src/fem/fem_finger.c and src/fem/fem_mesh.c in its header equal today's (else: rerun, how)."""
    import hashlib
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    head = [l for l in open(path) if l.startswith("#")]
    for src in ("src/fem/fem_finger.c", "src/fem/fem_mesh.c"):
        sha = hashlib.sha256(open(os.path.join(root, src), "rb").read()).hexdigest()
        check(any(sha in l for l in head), "%s changed since %s was written: %s" % (src, os.path.basename(path), rerun))
    print("%s: %s" % (os.path.basename(path), "".join(head[:2]).strip()))


def main():
    tool, scene, data = sys.argv[1], sys.argv[2], sys.argv[3]
    mode = sys.argv[4] if len(sys.argv) > 4 else "stored"
    opts = dict(zip(sys.argv[5::2], sys.argv[6::2]))  # --cyst FILE, as test_finger_breast_tissue.py
    cyst, graded_csv, graded5_csv = opts.get("--cyst"), opts.get("--graded"), opts.get("--graded5")
    if mode == "fine":
        # the 1,300-vertex set: the graded curves only (the uniform level-4 ones are stiff under a fingertip)
        graded(tool, scene, data, graded_csv, graded5_csv, FINE_BOUNDS, FINE_GAIN)
        return 1 if common.failures else 0
    rt_rows = None
    if mode == "stored":
        # the graded curves' depths include the stored ones: one real-time run serves both (and the cyst's
        # plain pole, soft())
        rt_rows = graded(tool, scene, data, graded_csv, graded5_csv) if graded_csv else None
        stored(tool, scene, data, rt_rows)
    else:
        {"guard": guard, "recompute": recompute}[mode](tool, scene, data)
    if graded_csv and mode == "guard":
        for path in (graded_csv, graded5_csv):
            if path:
                mesh_guard(path, "rerun tests/data/make_refined_refs.sh BUILD tests/data long_term")
    if cyst and mode == "stored":
        soft(tool, scene, cyst, rt_rows)
    elif cyst and mode == "guard":
        guard(tool, scene, cyst, "level-4 cyst curves", "tests/data/make_long_term_level4.py BUILD --cyst compute")
    return 1 if common.failures else 0


if __name__ == "__main__":
    sys.exit(main())
