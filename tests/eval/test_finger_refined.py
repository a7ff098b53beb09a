#!/usr/bin/env python3
"""The exercise phantom's fingertip against FE curves on a mesh refined where the finger presses
(issue 12; docs/fem.md, "The fingertip's mesh").

    test_finger_refined.py PALP_FEM SCENE REFINED_CSV ALPHA03_CSV LEVEL4_CSV LEVEL3_CSV DEEP_CSV [stored|guard]

REFINED_CSV (tests/data/fem_refined_breast_tissue_finger.csv) holds the FE curves of the
breast-tissue dome at level 5 with the mesh graded at each site (`"mesh": {"level": 5,
"grading": 0.5, "grading_polar_deg": SITE}`: cells at the site half the uniform size, ~1.6 mm
on the surface, against 3.9 mm at uniform level 4, which the set was validated against until
2026-11-30).
ALPHA03_CSV is the pole again with grading 0.3 (~0.9 mm cells). Asserted:

- hand calculation: the refined pole's secant stiffness at 0.25 mm (where the contact's radius,
  sqrt(R d) = 1.4 mm, is under the skin's bending length) is within 10% of a Kirchhoff plate on an
  elastic half-space under a point load, k = 3 sqrt(3) D / l^2, l = (2 D / E*)^(1/3) [N/m], with the
  profile's skin (E 334 kPa, 2 mm, nu 0.499: D = E t^3 / (12 (1 - nu^2))) and fat (E 15 kPa, E* =
  E / (1 - nu^2)): 160.7 N/m. (Measured: 156.5 N/m, -2.6%; uniform level 4 185 N/m, +15.4%, level 3
  +32%: they fail it.) The estimate leaves out the dome's curvature and the sphere's finite contact
  (both stiffen) and the skin's shear (softens), hence 10%;
- convergence at the pole: grading 0.3 against 0.5, within 3% from 2 mm (measured at most 1.7%,
  at 3 mm; shallower the contact spans few cells and they differ more: 5.6% at 1 mm, 3.9% at 1.5); CalculiX's quadratic bricks on the same graded mesh, a cap of 0.5 cm^2 at 0.3 N
  (bench/fem/ccx_crosscheck --cap-area 0.5e-4 --grading 0.5), put this mesh ~4% stiff (docs/fem.md);
- the refined curves are no stiffer than uniform level 4 at equal depth from 1 mm (1%: these
  elements converge from the stiff side; measured 0.82-0.92 at the pole);
- the real-time set against the refined curves, from the FE's 0.3 N: within the issue's 15%
  (since the set was refitted against them, 2026-11-30: pole 1.084-1.132 at 2-6 mm, 45 deg
  1.024-1.123 at 2-5 mm, 60 deg 0.932-1.033 at 1.5-4 mm, 70 deg 0.896-1.117 at 1.5-5 mm; the set
  before stood at 1.24-1.36, 1.25-1.29, 1.16-1.17 and 1.02-1.34; docs/materials.md, "Refitted
  against the refined fingertip");
- over the 10 mm lesion (5x, centre 10 mm deep): the refined FE's gain (F_lesion / F_pole - 1 at
  equal depth) is at least the issue's 20% from 2.5 to 4 mm (measured +20.2..+20.8%; uniform level 4
  +17.8..+18.0%, level 3 +14.2..+15.2%: the gain rises as the mesh under the finger is refined),
  gradings 0.3 and 0.5 within 1.5 points from 1.5 mm, and the real-time gain at least 0.80 of the
  FE's there, a REGRESSION BOUND (measured 0.83-0.84 since the refit, +16.9..+17.2%; 0.72-0.73
  before; the issue's 15% is missed by 1-2 points). --gain-floor G sets that bound: 0.78 for the
  1,300-vertex exercise set (config/phantoms/dome_fine.json; measured 0.79-0.80, +16.1..+16.4%; run
  by hand, tests/eval/CMakeLists.txt says why).

With DEEP_CSV (tests/data/fem_graded4_breast_tissue_finger.csv: level 4 graded 0.5 at each site, to
12-14 mm, ~15-40 min of one core a site), the set's validated table (config/params/breast_tissue.json)
rests on the refined curves: at each depth the least force of level 5 graded, level 4 graded and
uniform level 4 (these elements converge from the stiff side), which is level 5 graded to its end
(4-6 mm), then level 4 graded, and uniform level 4 at 70 deg from 6 mm and at 60 deg at 14 mm.
Asserted: level 4 graded within 0.97-1.09 of level 5 graded from 2 mm (measured 1.00-1.06 at the pole,
1.02-1.03 at 45 deg, 1.01-1.04 at 60 deg, 1.04-1.08 at 70 deg); for each site, from the FE's 0.3 N to the
table's depth, real-time / FE within 15%, at least 8 depths, the proxy at the FE's depth, the table no
deeper than the curves reach nor than the first depth where the ratio leaves 15% (measured 2026-11-30:
pole to 12 mm 1.084-1.139, 14 mm 1.155 out; 45 deg to 12 mm 1.024-1.127, 14 mm 1.156 out; 60 deg to
14 mm 0.932-1.072; 70 deg to 12 mm 0.868-1.117, 14 mm 0.844 out). Printed: level 4 graded against
uniform level 4 from 8 mm (0.96-0.98 at the pole and 45 deg, 0.99-1.00 at 60 deg, 1.09-1.15 at 70 deg,
where the graded mesh's cells near the base, grown up to 2x, stiffen it).

guard: the stored curves were made by today's fingertip FE code and mesher (the sha256 of
src/fem/fem_finger.c and src/fem/fem_mesh.c in the file's header equal today's).
"""
import math
import os
import sys

import test_eval_evaluate as common  # check() and the failure count (this folder is on sys.path)
import test_finger_long_term as lt  # read(), columns(), guard()

check = common.check

SITES = ["pole", "45deg", "60deg", "70deg"]
SITE_DEG = {"pole": 0.0, "45deg": 45.0, "60deg": 60.0, "70deg": 70.0}
DEEP_VS_L5 = 1.09  # the level-4 graded curve at most this much stiffer than level 5 graded from 2 mm (measured 1.00-1.06 at the pole, 1.04-1.08 at 70 deg)
FROM = 1e-3  # [m] the stiff-side check starts here: shallower, the faceted surface's offset is a fair part of the depth
CONVERGED_FROM = 2e-3  # [m] gradings 0.3 and 0.5 compared from here: the contact's radius sqrt(R d) = 4 mm spans 2-4 cells


def plate_on_half_space():
    """[N/m] A Kirchhoff plate (the skin) bonded to an elastic half-space (the fat) under a point
    load: the surface's Fourier stiffness is (E*/2) |xi|, so w(0) = P / (2 pi) int_0^inf dxi /
    (D xi^3 + E*/2) = P l^2 / (3 sqrt(3) D), l = (2 D / E*)^(1/3) (Hetenyi 1946)."""
    e_skin, t, nu = 334e3, 2e-3, 0.499  # breast skin (src/fem/fem_config.c, breast_tissue; Sutradhar & Miller 2013)
    e_fat = 15e3  # fat's secant modulus (ibid.; Samani 2007)
    d = e_skin * t ** 3 / (12.0 * (1.0 - nu * nu))  # [N m]
    e_star = e_fat / (1.0 - nu * nu)  # [Pa]
    l = (2.0 * d / e_star) ** (1.0 / 3.0)  # [m]
    return 3.0 * math.sqrt(3.0) * d / (l * l)


def by_depth(rows, site):
    d, fe, _, _ = lt.columns(rows, site)
    return {round(x, 9): f for x, f in zip(d, fe)}


def stored(data, alpha03, level4, level3, rt, gain_floor=0.80):
    ref, fine, l4, l3 = lt.read(data), lt.read(alpha03), lt.read(level4), lt.read(level3)
    sites = [s for s in SITES if any(x["site"] == s for x in ref)]
    check(sites[:1] == ["pole"], "refined sites: %r (want the pole first)" % sites)
    asked = sites + (["pole_lesion"] if any(x["site"] == "pole_lesion" for x in ref) else [])

    # the hand calculation at the pole's first depth
    k_hand = plate_on_half_space()
    for name, rows in (("refined", ref), ("uniform level 4", l4), ("uniform level 3", l3)):
        p = by_depth(rows, "pole").get(2.5e-4)
        if p is None:
            continue
        k = p / 2.5e-4
        print("pole 0.25 mm, %s: %.1f N/m against the plate on a half-space's %.1f N/m (%+.1f%%)" %
              (name, k, k_hand, 100 * (k / k_hand - 1)))
        if name == "refined":
            check(abs(k / k_hand - 1) <= 0.10, "refined pole at 0.25 mm: %.1f N/m, hand %.1f N/m (10%%)" % (k, k_hand))
    check(2.5e-4 in by_depth(ref, "pole"), "the refined pole has no 0.25 mm row")

    # grading 0.3 against 0.5 at the pole
    a5, a3 = by_depth(ref, "pole"), by_depth(fine, "pole")
    n, worst = 0, 0.0
    for x in sorted(a3):
        if x >= CONVERGED_FROM - 1e-12 and x in a5:
            n, worst = n + 1, max(worst, abs(a3[x] / a5[x] - 1))
            print("pole %.2f mm: grading 0.3 %.4f N, 0.5 %.4f N (%+.2f%%)" % (1e3 * x, a3[x], a5[x], 100 * (a3[x] / a5[x] - 1)))
    check(n >= 3, "grading 0.3 and 0.5 share %d depths from 2 mm (want 3)" % n)
    check(worst <= 0.03, "grading 0.3 against 0.5 at the pole: %.1f%% apart (3%%)" % (100 * worst))

    # no stiffer than uniform level 4
    for site in asked:
        r, u = by_depth(ref, site), by_depth(l4, site)
        common_d = [x for x in sorted(r) if x in u and x >= FROM - 1e-12]
        check(len(common_d) >= 4, "%s: %d depths shared with level 4 from 1 mm" % (site, len(common_d)))
        q = [r[x] / u[x] for x in common_d]
        for x, v in zip(common_d, q):
            check(v <= 1.01, "%s at %.2f mm: refined %.4f N stiffer than uniform level 4 %.4f N" % (site, 1e3 * x, r[x], u[x]))
        if q:
            print("%s: refined / uniform level 4 %.3f-%.3f over %d depths from 1 mm" % (site, min(q), max(q), len(q)))

    # the real-time set against the refined curves
    rows = with_realtime(ref, rt, asked, "refined")
    for site in sites:
        d, fe, rt, dr = lt.columns(rows, site)
        lo, hi, n = 9.0, 0.0, 0
        for k in range(len(d)):
            if fe[k] < 0.3:
                continue
            check(abs(dr[k] - d[k]) <= max(5e-6, 0.005 * d[k]), "%s: proxy at %.4f mm for %.4f mm" % (site, 1e3 * dr[k], 1e3 * d[k]))
            q = rt[k] / fe[k]
            lo, hi, n = min(lo, q), max(hi, q), n + 1
            print("refined, %s %.2f mm: FE %.3f N, real-time %.3f N, ratio %.3f" % (site, 1e3 * d[k], fe[k], rt[k], q))
            check(0.85 <= q <= 1.15, "refined, %s at %.2f mm: real-time / FE %.3f outside 15%%" % (site, 1e3 * d[k], q))
        check(n >= 3, "refined, %s: %d depths from 0.3 N" % (site, n))
        print("refined, %s: real-time / FE %.3f-%.3f over %d depths from 0.3 N (the issue's 15%%: %s)" %
              (site, lo, hi, n, "met" if 0.85 <= lo and hi <= 1.15 else "missed"))
    if "pole_lesion" in asked:
        # the lesion's gain, F_lesion / F_pole - 1 at equal depth, each curve against its own plain pole
        def gains(rs):
            p, l = by_depth(rs, "pole"), by_depth(rs, "pole_lesion")
            return {x: l[x] / p[x] - 1 for x in l if x in p}
        g5, g3, g4 = gains(ref), gains(fine), gains(l4)
        d, fe, rt, _ = lt.columns(rows, "pole_lesion")
        d0, fe0, rt0, _ = lt.columns(rows, "pole")
        plain = {round(x, 9): k for k, x in enumerate(d0)}
        n3, worst3, target, rt_lo = 0, 0.0, 0, 9.0
        for k in range(len(d)):
            j = plain.get(round(d[k], 9))
            x = round(d[k], 9)
            if j is None or d[k] < 1.5e-3 - 1e-12:
                continue
            gf, gr = fe[k] / fe0[j] - 1, rt[k] / rt0[j] - 1
            print("refined, pole_lesion %.2f mm: FE gain %+.1f%% (grading 0.3: %s; uniform level 4: %s), real-time %+.1f%% "
                  "(%.2f of the FE's)" % (1e3 * d[k], 100 * gf, "%+.1f%%" % (100 * g3[x]) if x in g3 else "-",
                                         "%+.1f%%" % (100 * g4[x]) if x in g4 else "-", 100 * gr, gr / gf))
            if x in g3:
                n3, worst3 = n3 + 1, max(worst3, abs(g3[x] - gf))
            if 2.5e-3 - 1e-12 <= d[k] <= 4e-3 + 1e-12:
                target += 1
                check(gf >= 0.20, "pole_lesion at %.2f mm: the refined FE's gain %+.1f%%, below the issue's 20%%" % (1e3 * d[k], 100 * gf))
                rt_lo = min(rt_lo, gr / gf)
                check(gr / gf >= gain_floor, "pole_lesion at %.2f mm: real-time gain %.2f of the refined FE's, outside the "
                      "regression bound %.2f" % (1e3 * d[k], gr / gf, gain_floor))
        check(target >= 3, "pole_lesion: %d refined depths in 2.5-4 mm" % target)
        check(n3 >= 3 and worst3 <= 0.015, "pole_lesion: gradings 0.3 and 0.5 give gains %.1f points apart over %d depths "
              "from 1.5 mm (1.5 points)" % (100 * worst3, n3))
        print("pole_lesion: the refined FE's gain at 20%% or more from 2.5 to 4 mm (%d depths), gradings 0.3 / 0.5 within %.1f "
              "points; real-time gain at least %.2f of it there (the issue's 15%%: %s)" %
              (target, 100 * worst3, rt_lo, "met" if rt_lo >= 0.85 else "missed"))


def composite(ref, deep, l4, path):
    """The curves the validated table rests on, written to path: at each depth of each site's uniform
    level-4 curve, the least force of the meshes that reach it (level 5 graded, level 4 graded, uniform
    level 4). These bricks converge from the stiff side (a displacement-based FE's force at a
    prescribed depth is too high; every check above and the level sequence agree), so the least is
    the tightest of them: level 5 graded where it reaches (to 4-6 mm), then level 4 graded, and
    uniform level 4 at 70 deg from 6 mm, where the graded mesh's cells near the base, grown by
    up to 2x, make it the stiffer. Returns {site: [mesh of each row]}."""
    names = (("level 5 graded", ref), ("level 4 graded", deep), ("uniform level 4", l4))
    by = {name: {site: by_depth(rows, site) for site in SITES} for name, rows in names}
    keys = list(l4[0].keys())
    which = {}
    with open(path, "w") as f:
        f.write(",".join(keys) + "\n")
        for site in SITES:
            which[site] = []
            for x in l4:
                if x["site"] != site:
                    continue
                depth = round(float(x["depth_m"]), 9)
                force, name = min((by[n][site][depth], n) for n, _ in names if depth in by[n][site])
                row = dict(x, fem_N="%.9e" % force)
                f.write(",".join(row[k] or "" for k in keys) + "\n")
                which[site].append(name)
    return which


def table(data, deep, level4, rt, claimed, joined, which):
    """The set's validated table against the refined curves (REFINED_CSV, extended by DEEP_CSV): joined,
    the composite's path, and which, its mesh at each row (realtime_once wrote them)."""
    ref, dp, l4 = lt.read(data), lt.read(deep), lt.read(level4)
    # the deep extension's own convergence: the level-4 graded mesh against level 5 graded where both
    # reach (from 2 mm), and against uniform level 4 from 8 mm, where the contact spans many cells
    for site in SITES:
        g4, g5, u4 = by_depth(dp, site), by_depth(ref, site), by_depth(l4, site)
        both = [x for x in sorted(g4) if x in g5 and x >= CONVERGED_FROM - 1e-12]
        q = [g4[x] / g5[x] for x in both]
        if not g4:
            print("%s: no level-4 graded curve; the table rests on level 5 graded and uniform level 4 there" % site)
            continue
        check(len(both) >= 3, "%s: the level-4 graded curve shares %d depths with level 5 from 2 mm" % (site, len(both)))
        check(all(0.97 <= v <= DEEP_VS_L5 for v in q), "%s: level-4 graded / level-5 graded %s outside 0.97-%.2f" %
              (site, " ".join("%.3f" % v for v in q), DEEP_VS_L5))
        deep_d = [x for x in sorted(g4) if x in u4 and x >= 8e-3 - 1e-12]
        qu = [g4[x] / u4[x] for x in deep_d]
        print("%s: level-4 graded / level-5 graded %s from 2 mm; / uniform level 4 %s from 8 mm" %
              (site, "%.3f-%.3f" % (min(q), max(q)) if q else "-", "%.3f-%.3f" % (min(qu), max(qu)) if qu else "-"))
    rows = with_realtime(lt.read(joined), rt, SITES, "the table's curves")
    for site in SITES:
        d, fe, rt, dr = lt.columns(rows, site)
        limit = claimed.get(SITE_DEG[site])
        check(limit is not None, "the validated table has no %s entry" % site)
        if limit is None:
            continue
        check(limit <= d[-1] + 1e-9, "%s: the table claims %.1f mm, deeper than the refined curves reach (%.1f mm)" %
              (site, 1e3 * limit, 1e3 * d[-1]))
        first_out = next((d[k] for k in range(len(d)) if fe[k] >= 0.3 and not 0.85 <= rt[k] / fe[k] <= 1.15), None)
        check(first_out is None or limit < first_out, "%s: the table claims %.1f mm, the ratio leaves 15%% at %.1f mm" %
              (site, 1e3 * limit, 1e3 * (first_out or 0.0)))
        n, lo, hi = 0, 9.0, 0.0
        for k in range(len(d)):
            if fe[k] < 0.3 or d[k] > limit + 1e-9:
                continue
            check(abs(dr[k] - d[k]) <= max(5e-6, 0.005 * d[k]), "%s: proxy at %.4f mm for %.4f mm" % (site, 1e3 * dr[k], 1e3 * d[k]))
            q = rt[k] / fe[k]
            n, lo, hi = n + 1, min(lo, q), max(hi, q)
            src = which[site][k]
            print("table, %s %.2f mm (%s): FE %.3f N, real-time %.3f N, ratio %.3f" % (site, 1e3 * d[k], src, fe[k], rt[k], q))
            check(0.85 <= q <= 1.15, "table, %s at %.2f mm: real-time / refined FE %.3f (15%%)" % (site, 1e3 * d[k], q))
        check(n >= 8, "table, %s: %d depths from 0.3 N to %.1f mm (want 8)" % (site, n, 1e3 * limit))
        print("table, %s: validated to %.1f mm, real-time / refined FE %.3f-%.3f over %d depths; first depth outside 15%%: %s" %
              (site, 1e3 * limit, lo, hi, n, "none (the curve's end, %.1f mm)" % (1e3 * d[-1]) if first_out is None
               else "%.1f mm" % (1e3 * first_out)))


def with_realtime(fe_rows, rt, sites, what):
    """fe_rows (site, depth_m, fem_N) of sites joined with the real-time run's columns at the same depths
    (rt: {(site, depth): row of the one real-time run}); a depth the run did not reach fails."""
    rows = []
    for x in fe_rows:
        if x["site"] not in sites:
            continue
        y = rt.get((x["site"], round(float(x["depth_m"]), 9)))
        check(y is not None, "%s: %s at %s m has no real-time row" % (what, x["site"], x["depth_m"]))
        if y is not None:
            rows.append(dict(x, realtime_N=y["realtime_N"], realtime_depth_m=y["realtime_depth_m"]))
    return rows


def realtime_once(tool, scene, data, deep, level4):
    """One real-time run serves both checks: `palp-fem finger --fe-from` presses each site through the
    command's fixed depth sequence, its real-time side at a depth depending only on the depths before
    it, so each site is run to the deepest curve that asks for it (the table's joined curves, or the
    refined one; the lesion from the refined one) and the other is read from the same rows (two runs
    took 15 + 20 s). Returns ({(site, depth): row}, the joined curves' path, composite()'s mesh of each of
    their rows); the first None if the run failed."""
    ref, dp, l4 = lt.read(data), lt.read(deep), lt.read(level4)
    tmp = common.scratch("palp_finger_refined_")
    joined = os.path.join(tmp, "refined_joined.csv")
    which = composite(ref, dp, l4, joined)
    jr = lt.read(joined)
    asked = SITES + (["pole_lesion"] if any(x["site"] == "pole_lesion" for x in ref) else [])
    union = os.path.join(tmp, "realtime_depths.csv")
    keys = list(jr[0].keys())
    with open(union, "w") as f:
        f.write(",".join(keys) + "\n")
        for site in asked:
            a, b = [x for x in jr if x["site"] == site], [x for x in ref if x["site"] == site]
            for x in a if len(a) >= len(b) else b:
                f.write(",".join(x.get(k) or "" for k in keys) + "\n")
    rows = lt.realtime_rows(tool, scene, union, asked, max_force="20", label=" (refined and joined)")
    if rows is None:
        return None, joined, which
    # the real-time force rises with depth along each site's whole run (to 14 mm; over the lesion to the
    # refined curve's end), as the level-3 run of test_finger_breast_tissue.py asserted before 2026-12-02
    for site in asked:
        _, _, rt, _ = lt.columns(rows, site)
        check(len(rt) >= 8 and all(rt[k + 1] > rt[k] for k in range(len(rt) - 1)),
              "%s: the real-time force does not rise with depth over %d depths: %r" % (site, len(rt), rt))
    return {(x["site"], round(float(x["depth_m"]), 9)): x for x in rows}, joined, which


def guard(data, alpha03, deep):
    for path in (data, alpha03, deep):
        lt.mesh_guard(path, "recompute it (its header says how)")


def main():
    tool, scene, data, alpha03, level4, level3, deep = sys.argv[1:8]
    mode = sys.argv[8] if len(sys.argv) > 8 else "stored"
    # --gain-floor G: the lesion gain's regression bound (0.80; the 1,300-vertex exercise set's 0.78)
    opts = dict(zip(sys.argv[9::2], sys.argv[10::2]))
    gain_floor = float(opts.get("--gain-floor", 0.80))
    if mode == "guard":
        guard(data, alpha03, deep)
    else:
        rt, joined, which = realtime_once(tool, scene, data, deep, level4)
        if rt is not None:
            stored(data, alpha03, level4, level3, rt, gain_floor)
            table(data, deep, level4, rt, lt.validated_table(scene), joined, which)
    return 1 if common.failures else 0


if __name__ == "__main__":
    sys.exit(main())
