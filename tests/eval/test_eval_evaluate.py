#!/usr/bin/env python3
"""test_eval_evaluate - palp-eval evaluate, checked from the outside.

    test_eval_evaluate.py PALP_EVAL SCENE tables|errors|shipped|clock|...

tables: runs `evaluate` on the paper's scene with the coarsest FEM level and a
few frames, then recomputes every statistic of Tables V and VI from the written
pair files (displacement_dN.csv, force_dN.csv) with an independent
implementation in this file (math.fsum sums, its own regularised incomplete
beta function for the F distribution's p-value) and compares with tables.csv
and tables.json. Tolerances: 1e-9 relative for RMSE, bias, SD, F, sums of
squares (the CSVs carry 17 significant digits, so only summation order
differs); 1e-7 relative (or 1e-12 absolute) for p; agreement counts exactly.
The paper's columns must be the published numbers. A second run must take the
FEM reference from the cache and give byte-identical tables.

shipped: the shipped (calibrated) parameters against the full FEM level-1
reference of distribution II beat the paper's RMSE; the hand-set ones do not.

long_term: the default parameters, for the long-term reading
(config/params/paper_long_term.json, scene paper_step_long_term.json) against
the level-4 long-term FEM of distribution II stored in
tests/data/fem_level4_long_term_d2.csv (written by tests/data/make_long_term_level4.py;
every vertex at 32 of the 400 frames, the FEM's most displaced vertex at all 400),
the model's side from an evaluate run here: RMSE over the stored frames at
most 3% of the level-4 FEM's peak and the model's peak within 10% of it (the
issue's target; measured 2.18% over the stored frames, 2.4% over all 400 in evaluate, and
1.064); figures in docs/materials.md, "The patch map and the support". Recovery to 5% of
the peak after the release, at the FEM's most displaced vertex (vertex 35, stored at every
frame): within 0.15 s of the level-4 FEM's (measured 0.744 s against 0.687 s). The FEM side is the
patch load map (docs/fem.md, "Surface map"), the default.
The level-2 FEM peak (a level-2 run of the hold's 200 frames, where the peak is) must equal the one
recorded in the data file (relative 1e-6): the stored level-4 field was written by the FEM the tests build
(eval_level4_guard recomputes its first 12 frames). The level-2-fitted set
(config/params/paper_long_term_level2.json) fails the peak bound (-11.9% against the
patch-mapped level-4 FEM; -16.9% against the point-mapped one).

level4_guard: `evaluate --level 4 --frames 12 --distributions 2` (~8 s): the
FEM's first 12 frames equal the stored ones within 1e-4 of the stored peak (the
Newton tolerance; measured 0: bit-identical on this machine), so that the stored
reference cannot go stale silently when the FEM changes.

breast_tissue: the same for config/params/breast_tissue.json (scene
paper_step_breast_tissue.json) against the level-4 breast-tissue FEM of distribution II
(HHT-alpha -0.05, patch load map) stored in tests/data/fem_level4_breast_tissue_d2.csv
(written by tests/data/make_breast_tissue_refs.py): RMSE over the stored frames at most 7% of
the level-4 peak and the model's peak within 10% of it (measured 2026-11-30, the set refitted against
the fingertip FE refined where the finger presses: 6.82% over the stored frames, 0.32 mm, the issue's
1 mm met; peak +8.3%, and +4.7% against level 4 graded at the load, whose peak is 3.2% deeper than
uniform level 4's, docs/materials.md "Refitted against the refined fingertip"; recovery 1.080 s. The
bound was 6% until then: measured 2026-11-28 with the support's
relaxing branch: 5.50% over the stored frames, 0.26 mm, and +7.3%; the issue's 5% (or
1 mm) is met over the whole field, 3.8% in evaluate's 400 frames: the stored frames weigh the
first 120 ms, 12 of their 32, where the field moves fastest). Recovery at vertex 35: within
0.25 s of the level-4 FEM's and inside the issue's 1.0 +- 0.2 s (measured 1.114 s against the
FEM's 0.929 s; the set before the relaxing branch recovered in 0.758 s and fails the band; under
III and IV, not stored, the model is 0.19-0.22 s quicker than the FEM instead: docs/materials.md,
"The recovery"). Until
then this compared with the level-2 FEM (6% / 16%), whose peak is 15% below level 4's: the
set's +13.9% there was mostly the reference's (docs/materials.md, "The fingertip references
at level 3").

material: the tables name the FEM material profile (see test_material).

clock: the real-time model's step force switches at the FEM's time, not at the
world's summed clock (see test_clock).

errors: bad inputs end with a clear message on stderr, nothing on stdout and a
non-zero exit status (1 for unusable inputs, 2 for command-line errors).
"""
import atexit
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

failures = 0
_scratch = []


def check(cond, msg):
    global failures
    if not cond:
        failures += 1
        print("FAIL: " + msg, file=sys.stderr)


def scratch(prefix):
    """A temporary directory of this script's, removed when it ends with every check passed (one run
    of the test command left ~45 MB in /tmp before, 2026-12-05); kept and named when one failed."""
    d = tempfile.mkdtemp(prefix=prefix)
    _scratch.append(d)
    return d


@atexit.register
def _remove_scratch():
    for d in _scratch:
        if failures:
            print("kept for inspection: " + d, file=sys.stderr)
        else:
            shutil.rmtree(d, ignore_errors=True)


def close(a, b, rel, absol=0.0):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), absol)


# ---- an independent F-distribution tail -------------------------------------------
def betacf(a, b, x):
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 200000):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        de = d * c
        h *= de
        if abs(de - 1.0) < 1e-16:
            return h
    raise RuntimeError("betacf did not converge")


def betainc(a, b, x):
    """Regularised incomplete beta I_x(a, b)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    lbt = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(lbt) * betacf(a, b, x) / a
    return 1.0 - math.exp(lbt) * betacf(b, a, 1.0 - x) / b


def f_tail(f, d1, d2):
    """P(F(d1, d2) > f) = I_{d2 / (d2 + d1 f)}(d2 / 2, d1 / 2)."""
    if math.isinf(f):
        return 0.0
    return betainc(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))


def stats(a, b):
    """The paper's statistics of paired values, computed from the definitions."""
    n = len(a)
    d = [x - y for x, y in zip(a, b)]
    rmse = math.sqrt(math.fsum(x * x for x in d) / n)
    bias = math.fsum(d) / n
    sd = math.sqrt(math.fsum((x - bias) ** 2 for x in d) / (n - 1))
    lo, hi = bias - 2 * sd, bias + 2 * sd
    within = sum(1 for x in d if lo <= x <= hi)
    ma, mb = math.fsum(a) / n, math.fsum(b) / n
    g = (ma + mb) / 2
    ss_b = n * (ma - g) ** 2 + n * (mb - g) ** 2
    ss_w = math.fsum((x - ma) ** 2 for x in a) + math.fsum((y - mb) ** 2 for y in b)
    df_w = 2 * n - 2
    f = (ss_b / 1) / (ss_w / df_w)
    p = f_tail(f, 1, df_w)
    return dict(n=n, rmse=rmse, bias=bias, sd=sd, within=within, agreement_percent=100.0 * within / n,
                mean_rt=ma, mean_ref=mb, ss_between=ss_b, ss_within=ss_w, f=f, p=p, df_within=df_w,
                meets=int(p > 0.05 and within / n > 0.95))


def t_tail(t, df):
    """P(T_df > t) = I_{df / (df + t^2)}(df / 2, 1 / 2) / 2 for t >= 0."""
    if math.isinf(t):
        return 0.0 if t > 0 else 1.0
    q = 0.5 * betainc(df / 2.0, 0.5, df / (df + t * t))
    return q if t >= 0 else 1.0 - q


def sound(a, b, frames, margin):
    """The second table from its definitions: per-frame mean difference, lag-1
    autocorrelation, AR(1) effective size, TOST with SE = SD / sqrt(n_eff)."""
    per = len(a) // frames
    dbar = [math.fsum(a[f * per + i] - b[f * per + i] for i in range(per)) / per for f in range(frames)]
    m = math.fsum(dbar) / frames
    ss = math.fsum((x - m) ** 2 for x in dbar)
    r1 = math.fsum((dbar[t] - m) * (dbar[t + 1] - m) for t in range(frames - 1)) / ss if ss > 0 else 0.0
    neff = min(frames, max(1.0, frames * (1 - r1) / (1 + r1)))
    out = dict(bias=m, r1=r1, n_eff=neff, frame_sd=math.sqrt(ss / (frames - 1)), dbar=dbar)
    if neff >= 2:
        se = out["frame_sd"] / math.sqrt(neff)
        out["tost_p"] = max(t_tail((m + margin) / se, neff - 1), t_tail((margin - m) / se, neff - 1)) if se > 0 \
            else (0.0 if -margin < m < margin else 1.0)
    return out


def rm_limits(diffs):
    """Bland & Altman (2007) limits from a list of per-run difference lists."""
    n = sum(len(d) for d in diffs)
    k = len(diffs)
    means = [math.fsum(d) / len(d) for d in diffs]
    bias = math.fsum(math.fsum(d) for d in diffs) / n
    ms_w = math.fsum(math.fsum((x - mu) ** 2 for x in d) for d, mu in zip(diffs, means)) / (n - k)
    ms_b = math.fsum(len(d) * (mu - bias) ** 2 for d, mu in zip(diffs, means)) / (k - 1)
    m0 = (n * n - sum(len(d) ** 2 for d in diffs)) / ((k - 1) * n)
    sd = math.sqrt(max(0.0, (ms_b - ms_w) / m0) + ms_w)
    return bias, bias - 1.96 * sd, bias + 1.96 * sd


PAPER = {  # Widmer & Hu 2011, Tables V (cm) and VI (N): RMSE, F, p, SD, agree %
    "V": {"I": (0.17, 2.37, 0.12, 0.27, 95.2), "II": (0.21, 1.52, 0.36, 0.29, 95.0),
          "III": (0.26, 1.69, 0.32, 0.32, 95.3), "IV": (0.32, 0.96, 0.48, 0.33, 96.5)},
    "VI": {"I": (0.05, 0.12, 0.86, 0.01, 98.6), "II": (0.12, 12.0, 0.31, 0.12, 96.1),
           "III": (0.15, 1.93, 0.29, 0.21, 95.2), "IV": (0.16, 2.02, 0.21, 0.25, 95.1)},
}
ROMAN = ["I", "II", "III", "IV"]
FRAMES = 4


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=600, **kw)


def test_tables(tool, scene):
    tmp = scratch("palp_eval_test_")
    out, cache = os.path.join(tmp, "out"), os.path.join(tmp, "cache")
    cmd = [tool, "evaluate", "--scene", scene, "--level", "1", "--frames", str(FRAMES), "--out", out,
           "--cache-dir", cache, "--quiet"]
    r = run(cmd)
    check(r.returncode == 0, "evaluate exited %d: %s" % (r.returncode, r.stderr))
    if r.returncode:
        return
    check("Table V" in r.stdout and "Table VI" in r.stdout, "tables not printed:\n" + r.stdout)
    rows = list(csv.DictReader(open(os.path.join(out, "tables.csv"))))
    check(len(rows) == 8, "tables.csv has %d rows, 8 expected (2 tables x 4 distributions)" % len(rows))
    js = json.load(open(os.path.join(out, "tables.json")))
    md = open(os.path.join(out, "tables.md")).read()
    pooled_diffs = {}
    for row in rows:
        t, dist = row["table"], row["distribution"]
        k = ROMAN.index(dist) + 1
        fname = ("displacement_d%d.csv" if t == "V" else "force_d%d.csv") % k
        pairs = list(csv.DictReader(open(os.path.join(out, fname))))
        col = ("rt_cm", "fem_cm") if t == "V" else ("rt_N", "fem_N")
        a = [float(p[col[0]]) for p in pairs]
        b = [float(p[col[1]]) for p in pairs]
        frames = sorted({int(p["frame"]) for p in pairs})
        check(frames == list(range(FRAMES)), "%s: frames %s, expected 0..%d" % (fname, frames, FRAMES - 1))
        for p in pairs[:50]:
            check(close(float(p["time_s"]), 0.01 * (int(p["frame"]) + 1), 1e-9),
                  "%s: frame %s at t = %s s, expected (frame + 1) x 0.01 s" % (fname, p["frame"], p["time_s"]))
        verts = {int(p["vertex"]) for p in pairs}
        check(len(pairs) == len(verts) * FRAMES, "%s: %d pairs for %d vertices x %d frames" %
              (fname, len(pairs), len(verts), FRAMES))
        if t == "V":
            # 338 vertices minus the fixed rim: the rim is one ring, so at least
            # 250 and at most 337 free vertices carry data
            check(250 <= len(verts) <= 337, "%s: %d vertices with displacement data" % (fname, len(verts)))
        else:
            check(len(verts) >= 1 and (len(verts) == 1) == (dist == "I"),
                  "%s: %d contact vertices (distribution I has one, the others a patch)" % (fname, len(verts)))
        s = stats(a, b)
        where = "Table %s, Distr. %s" % (t, dist)
        check(int(row["pairs"]) == s["n"], "%s: pairs %s vs %d in the pair file" % (where, row["pairs"], s["n"]))
        for key in ("rmse", "bias", "sd", "mean_rt", "mean_ref", "ss_between", "ss_within"):
            check(close(float(row[key]), s[key], 1e-9, 1e-15),
                  "%s: %s = %s, recomputed %.17g" % (where, key, row[key], s[key]))
        check(close(float(row["anova_f"]), s["f"], 1e-8, 1e-12),
              "%s: F = %s, recomputed %.17g" % (where, row["anova_f"], s["f"]))
        check(close(float(row["anova_p"]), s["p"], 1e-7, 1e-12),
              "%s: p = %s, recomputed %.17g" % (where, row["anova_p"], s["p"]))
        check(int(row["df_within"]) == s["df_within"] and int(row["df_between"]) == 1,
              "%s: degrees of freedom %s, %s" % (where, row["df_between"], row["df_within"]))
        check(close(float(row["agreement_percent"]), s["agreement_percent"], 1e-12),
              "%s: agreement %s%%, recomputed %.6f%% (%d of %d)" % (where, row["agreement_percent"],
                                                                    s["agreement_percent"], s["within"], s["n"]))
        check(int(row["meets"]) == s["meets"], "%s: verdict %s, recomputed %d" % (where, row["meets"], s["meets"]))
        paper = PAPER[t][dist]
        got = tuple(float(row[c]) for c in ("paper_rmse", "paper_f", "paper_p", "paper_sd", "paper_agreement_percent"))
        check(got == paper, "%s: paper columns %s, published %s" % (where, got, paper))
        jt = [x for x in js["tables"] if x["table"] == t][0]
        jr = [x for x in jt["rows"] if x["distribution"] == dist][0]
        check(close(jr["rmse"], s["rmse"], 1e-9) and close(jr["anova"]["p"], s["p"], 1e-7, 1e-12) and
              jr["meets_paper_criteria"] == bool(s["meets"]), "%s: tables.json disagrees" % where)
        check(("| Distr. %s |" % dist) in md, "tables.md lacks the row of Distr. %s" % dist)
        # the second table, recomputed from the pair file
        js_s = jr.get("sound")
        check(js_s is not None, "%s: tables.json lacks the second table" % where)
        if js_s:
            peak = max(b)
            # displacement: max(5% of the peak, min(1 mm, 15% of the peak)) (docs/statistics.md)
            margin = max(0.05 * peak, min(0.1, 0.15 * peak)) if t == "V" else 0.15 * peak
            q = sound(a, b, FRAMES, margin)
            check(close(js_s["margin"], margin, 1e-12), "%s: margin %s, expected %.17g" % (where, js_s["margin"], margin))
            for key in ("bias", "r1", "n_eff", "frame_sd"):
                check(close(js_s[key], q[key], 1e-9, 1e-15), "%s: %s = %s, recomputed %.17g" % (where, key, js_s[key], q[key]))
            check(js_s["tost_valid"] == ("tost_p" in q), "%s: tost_valid %s" % (where, js_s["tost_valid"]))
            if "tost_p" in q and js_s["tost_valid"]:
                check(close(js_s["tost_p"], q["tost_p"], 1e-7, 1e-12),
                      "%s: TOST p = %s, recomputed %.17g" % (where, js_s["tost_p"], q["tost_p"]))
            # bootstrap: means of frame values lie within their range; seeded, so the rerun repeats it
            check(min(q["dbar"]) - 1e-12 <= js_s["boot_ci_lower"] <= js_s["boot_ci_upper"] <= max(q["dbar"]) + 1e-12,
                  "%s: bootstrap interval outside the range of the per-frame means" % where)
            pooled_diffs.setdefault(t, []).append(([x - y for x, y in zip(a, b)], margin))
        check("Second table" in md, "tables.md lacks the second table")
    # pooled over the four runs: repeated-measures limits from the definitions
    for t, runs in pooled_diffs.items():
        jp = [x for x in js["tables"] if x["table"] == t][0].get("pooled")
        check(jp is not None and jp["runs"] == 4, "Table %s: pooled row missing" % t)
        if not jp:
            continue
        bias, lo, hi = rm_limits([d for d, _ in runs])
        check(close(jp["bias"], bias, 1e-9, 1e-15) and close(jp["rm_loa_lower"], lo, 1e-9, 1e-15) and
              close(jp["rm_loa_upper"], hi, 1e-9, 1e-15),
              "Table %s pooled: LoA [%s, %s], recomputed [%.17g, %.17g]" % (t, jp["rm_loa_lower"], jp["rm_loa_upper"], lo, hi))
        check(close(jp["margin"], min(mg for _, mg in runs), 1e-12), "Table %s pooled: margin not the strictest" % t)
        rb = [math.fsum(d) / len(d) for d, _ in runs]
        mb = math.fsum(rb) / 4
        se = math.sqrt(math.fsum((x - mb) ** 2 for x in rb) / 3) / 2
        mg = jp["margin"]
        p = max(t_tail((mb + mg) / se, 3), t_tail((mg - mb) / se, 3))
        check(close(jp["tost_p"], p, 1e-7, 1e-12), "Table %s pooled: TOST p %s, recomputed %.17g" % (t, jp["tost_p"], p))
    # the caveat under each paper table (session 82 review, defect 9): "up to N pairs" is the
    # largest row's pair count, and the claim that the ANOVA's p "measures the sample size" is
    # made only when every distribution's lag-1 autocorrelation (tables.json sound.r1) is at
    # least 0.5 (force's is near -0.24 in a 400-frame run, where the frames are nearly independent)
    caveats = [l for l in r.stdout.splitlines() if l.startswith("caveat: the ANOVA pools")]
    check(len(caveats) == 2, "one caveat under each paper table, got %d" % len(caveats))
    for t, line in zip(("V", "VI"), caveats):
        jt = [x for x in js["tables"] if x["table"] == t][0]
        nmax = max(x["pairs"] for x in jt["rows"])
        r1 = [x["sound"]["r1"] for x in jt["rows"] if "sound" in x]
        check(("up to %d " % nmax) in line, "Table %s caveat %r: expected up to %d pairs" % (t, line, nmax))
        claims = "so its p measures the sample size" in line
        check(claims == (min(r1) >= 0.5), "Table %s caveat %r with r1 %s: the sample-size claim %s" %
              (t, line, r1, "made" if claims else "missing"))
        check(("from %.3f to %.3f" % (min(r1), max(r1))) in line, "Table %s caveat %r: r1 range %s" % (t, line, r1))
    # plots: well-formed SVG for every distribution
    for k in range(1, 5):
        for name in ("top_vertex_d%d.svg", "peak_vertex_d%d.svg", "bland_altman_displacement_d%d.svg",
                     "bland_altman_force_d%d.svg"):
            path = os.path.join(out, name % k)
            try:
                root = ET.parse(path).getroot()
                check(root.tag.endswith("svg"), "%s is not an SVG document" % path)
            except Exception as e:  # noqa: BLE001 - any parse failure is the finding
                check(False, "%s: %s" % (path, e))
    # a rerun takes the reference from the cache and reproduces the tables exactly
    first = open(os.path.join(out, "tables.csv")).read()
    r2 = run(cmd)
    check(r2.returncode == 0, "second evaluate exited %d: %s" % (r2.returncode, r2.stderr))
    check(open(os.path.join(out, "tables.csv")).read() == first, "rerun (FEM from cache) changed tables.csv")
    js2 = json.load(open(os.path.join(out, "tables.json")))
    check(all(r["ref_from_cache"] for t in js2["tables"] for r in t["rows"]),
          "rerun did not take the FEM reference from the cache")


def test_errors(tool, scene):
    tmp = scratch("palp_eval_err_")
    bad_json = os.path.join(tmp, "bad.json")
    open(bad_json, "w").write("{ \"name\": \"x\", \"mesh\": { \"radius_m\": 0.04, ")
    bad_material_scene = os.path.join(tmp, "badmaterial.json")
    sc = json.load(open(scene))
    sc["material"] = "no_such_profile"
    sc["parameters"] = os.path.join(os.path.dirname(os.path.abspath(scene)), sc["parameters"])
    json.dump(sc, open(bad_material_scene, "w"))
    no_contact = os.path.join(tmp, "nocontact.json")
    open(no_contact, "w").write(
        '{"name": "n", "mesh": {"radius_m": 0.04, "vertex_count": 100},'
        ' "membrane": {"thickness_m": 0.002, "density_kg_m3": 950, "E1_Pa": 4.2e6, "eta1_Pa_s": 2e8,'
        ' "E2_Pa": 8e6, "eta2_Pa_s": 8e5},'
        ' "gel": {"law": "polytropic", "pressure_Pa": 101325, "a1": 10, "a2_Pa_s_m3": 5e6,'
        ' "support_modulus_Pa_m": 1.5e6, "support_viscosity_Pa_s_m": 6e5},'
        ' "time": {"dt_s": 0.01, "frames": 10, "frame_period_s": 0.01},'
        ' "effects": ["membrane_elasticity"], "contacts": []}')
    out = os.path.join(tmp, "out")
    cases = [
        # (arguments, exit status, words the message must contain)
        (["evaluate", "--scene", os.path.join(tmp, "missing.json")], 1, ["missing.json", "not found"]),
        (["evaluate", "--scene", bad_json], 1, ["bad.json"]),
        (["evaluate", "--scene", no_contact], 1, ["no contact"]),
        (["evaluate", "--scene", scene, "--level", "0"], 2, ["--level", "\"0\""]),
        (["evaluate", "--scene", scene, "--level", "two"], 2, ["--level", "two"]),
        (["evaluate", "--scene", scene, "--level"], 2, ["--level"]),
        (["evaluate", "--scene", scene, "--fem-config", os.path.join(tmp, "nofem.json")], 1, ["nofem.json"]),
        (["evaluate", "--scene", scene, "--params", os.path.join(tmp, "noparams.json")], 1, ["noparams.json",
                                                                                           "not found"]),
        (["evaluate", "--scene", scene, "--frames", "-3"], 2, ["--frames"]),
        (["evaluate", "--scene", scene, "--distributions", "1,5"], 2, ["--distributions"]),
        (["evaluate", "--bogus"], 2, ["--bogus"]),
        (["judge"], 2, ["judge"]),
        (["calibrate", "--scene", scene, "--fit", "E1,E9"], 2, ["E9"]),
        (["calibrate", "--scene", os.path.join(tmp, "missing.json")], 1, ["not found"]),
        (["calibrate", "--scene", scene, "--recovery-target", "0"], 2, ["--recovery-target", ">= 0.01"]),
        # a scene whose parameter file names a profile the FEM does not know: refused, named
        (["evaluate", "--scene", bad_material_scene], 1, ["material", "no_such_profile"]),
        # session 82: the FEM's own level bound is the command line's (17 was an input error, exit 1)
        (["evaluate", "--scene", scene, "--level", "17"], 2, ["--level", "1 to 16", "\"17\""]),
        # a repeated entry is no second run (it was pooled as one: an SD of 0, "equivalent")
        (["evaluate", "--scene", scene, "--distributions", "2,2"], 2, ["--distributions", "2 given twice"]),
        (["evaluate", "--scene", scene, "--sites", "2", "--forces", "3,1,3"], 2, ["--forces", "3 N given twice"]),
        (["calibrate", "--scene", scene, "--finger", "pole,45deg,pole"], 2, ["--finger", "\"pole\" given twice"]),
        (["calibrate", "--scene", scene, "--finger", "pole,elbow"], 2, ["--finger", "elbow"]),
        # an empty selection ran nothing and exited 0 with empty tables (calibrate: exit 1)
        (["evaluate", "--scene", scene, "--distributions", ""], 2, ["--distributions"]),
        (["evaluate", "--scene", scene, "--distributions", ",,,"], 2, ["--distributions", ",,,"]),
        (["calibrate", "--scene", scene, "--distributions", ""], 2, ["--distributions"]),
        (["evaluate", "--scene", scene, "--distributions", "1,"], 2, ["--distributions", "1,"]),
        # --finger-depths as the last argument read *NULL: a segmentation fault, exit 139
        (["calibrate", "--scene", scene, "--out", out, "--finger-depths"], 2,
         ["palp-eval: --finger-depths needs a value"]),
        (["evaluate", "--scene", scene, "--out", out, "--finger-depths"], 2,
         ["palp-eval: --finger-depths needs a value"]),
        (["calibrate", "--scene", scene, "--finger-depths", "2,1"], 2, ["palp-eval: --finger-depths", "\"2,1\""]),
        # an option of another command, refused and the command it belongs to named (session 82:
        # `evaluate --forces 1` ran the scene's 3 N without a word, `--fit E9x` passed under evaluate)
        (["evaluate", "--scene", scene, "--forces", "1"], 2, ["--forces belongs to evaluate --sites"]),
        (["evaluate", "--scene", scene, "--fit", "E9x"], 2, ["--fit belongs to calibrate"]),
        (["evaluate", "--scene", scene, "--sites", "2", "--peak-weight", "3"], 2, ["--peak-weight belongs to calibrate"]),
        (["calibrate", "--scene", scene, "--sites", "2"], 2, ["--sites belongs to evaluate --sites"]),
        (["calibrate", "--scene", scene, "--no-plots"], 2, ["--no-plots belongs to evaluate"]),
    ]
    for args, status, words in cases:
        r = run([tool] + args + ["--out", out] if args[0] in ("evaluate", "calibrate") and "--out" not in args
                else [tool] + args)
        what = "palp-eval " + " ".join(args)
        check(r.returncode == status, "%s: exit %d, expected %d (stderr: %s)" % (what, r.returncode, status,
                                                                                  r.stderr.strip()))
        check(r.stdout == "", "%s: wrote to stdout on error: %r" % (what, r.stdout[:200]))
        for w in words:
            check(w in r.stderr, "%s: message lacks %r: %s" % (what, w, r.stderr.strip()))
        check("Segmentation" not in r.stderr and r.returncode > 0, "%s: crashed" % what)


def test_shipped(tool, scene):
    """The shipped parameters are calibrated: under distribution II, the full
    400 frames against FEM level 1 (computed cold here, ~50 s), the displacement
    RMSE is below the paper's 0.21 cm and within 8% of the 0.139 cm measured when
    they were fitted (bound 0.15 cm), while the hand-set parameters on the same
    reference (from the cache) stay above 0.5 cm (measured 0.604); force meets the
    paper's criteria."""
    tmp = scratch("palp_eval_shipped_")
    cache = os.path.join(tmp, "cache")
    handset = os.path.join(os.path.dirname(scene), "params", "handset.json")
    rmse = {}
    for name, extra in (("shipped", []), ("handset", ["--params", handset])):
        out = os.path.join(tmp, name)
        r = run([tool, "evaluate", "--scene", scene, "--level", "1", "--distributions", "2", "--no-plots",
                 "--out", out, "--cache-dir", cache, "--quiet"] + extra)
        check(r.returncode == 0, "%s: evaluate exited %d: %s" % (name, r.returncode, r.stderr))
        if r.returncode:
            return
        t = json.load(open(os.path.join(out, "tables.json")))["tables"]
        disp = [row for row in t[0]["rows"] if row["distribution"] == "II"][0]
        force = [row for row in t[1]["rows"] if row["distribution"] == "II"][0]
        rmse[name] = disp["rmse"]
        print("%s: Table V II RMSE %.4f cm, Table VI II RMSE %.4f N, force verdict %s" %
              (name, disp["rmse"], force["rmse"], force["meets_paper_criteria"]))
        if name == "shipped":
            check(force["meets_paper_criteria"], "shipped: force under II does not meet the paper's criteria")
    check(rmse["shipped"] < 0.15, "shipped: displacement RMSE %.4f cm (bound 0.15; paper 0.21)" % rmse["shipped"])
    check(rmse["handset"] > 0.5, "hand-set: displacement RMSE %.4f cm, expected > 0.5" % rmse["handset"])



def test_clock(tool, scene):
    """Both models on one clock (session 82 review, defect 1). With 10 ms steps a step force
    released at t_off = 0.1 s is on for exactly the steps starting at 0, 10, ..., 90 ms: ten
    steps, as with t_off = 0.095 s. The world's clock sums 0.01 ten times to
    0.09999999999999999 < 0.1, so before the fix the real-time model saw an eleventh loaded
    step with t_off 0.1 (frame 10 moved by 0.219 cm) while the FEM, on f x period + q x dt,
    did not. Asserted: the real-time |u| of every free vertex at every one of 15 frames
    (distribution II, FEM level 1) is the same for t_off 0.1 and 0.095 s (within 1e-12 cm:
    the same forces in the same order give the same numbers), and so is the FEM's (the
    control). And the test can see a step: t_off 0.105 s (eleven loaded steps on both
    clocks) moves the real-time frame 10 by more than 0.01 cm against t_off 0.1 s."""
    tmp = scratch("palp_eval_clock_")
    cache = os.path.join(tmp, "cache")
    sc = json.load(open(scene))
    sc["parameters"] = os.path.join(os.path.dirname(os.path.abspath(scene)), sc["parameters"])
    cols = {}
    for t_off in ("0.1", "0.095", "0.105"):
        sc["contacts"][0]["profile"]["t_off_s"] = float(t_off)
        path = os.path.join(tmp, "step_%s.json" % t_off)
        json.dump(sc, open(path, "w"))
        out = os.path.join(tmp, "out_" + t_off)
        r = run([tool, "evaluate", "--scene", path, "--level", "1", "--frames", "15", "--distributions", "2",
                 "--no-plots", "--out", out, "--cache-dir", cache, "--quiet"])
        check(r.returncode == 0, "t_off %s: evaluate exited %d: %s" % (t_off, r.returncode, r.stderr))
        if r.returncode:
            return
        pairs = list(csv.DictReader(open(os.path.join(out, "displacement_d2.csv"))))
        cols[t_off] = {(int(p["frame"]), int(p["vertex"])): (float(p["rt_cm"]), float(p["fem_cm"])) for p in pairs}
    a, b, c = cols["0.1"], cols["0.095"], cols["0.105"]
    check(set(a) == set(b) and len({f for f, _ in a}) == 15, "t_off 0.1 / 0.095: the same 15 frames and vertices")
    for side, name in ((0, "real-time"), (1, "FEM")):
        worst = max((abs(a[k][side] - b[k][side]), k) for k in a if k in b)
        check(worst[0] <= 1e-12, "%s |u| differs between t_off 0.1 and 0.095 s by %.3g cm at (frame, vertex) %s: "
              "the two clocks disagree at the step's edge" % (name, worst[0], worst[1]))
    d10 = max(abs(a[k][0] - c[k][0]) for k in a if k[0] == 10 and k in c)
    check(d10 > 0.01, "t_off 0.105 s (11 loaded steps) moved the real-time frame 10 by only %.3g cm against "
          "0.1 s (10 steps): the test cannot see one step of load" % d10)
    print("t_off 0.1 vs 0.105 s at frame 10: %.3f cm" % d10)



def test_material(tool, scene):
    """The tables name the FEM material profile they were measured against (session 82 review,
    defect 5: stdout, tables.json and tables.md named the level only, so tables from --material X
    read like the default). Expected names from the inputs, not from palp-eval: the scene's
    parameter file's "material" key (read here) and the --material given; the load map
    documented per profile in docs/materials.md (paper_instantaneous reads the loads
    literally, "point"; breast_tissue "patch"). 4 frames, distribution II, FEM level 1."""
    tmp = scratch("palp_eval_material_")
    sc = json.load(open(scene))
    params = os.path.join(os.path.dirname(os.path.abspath(scene)), sc["parameters"])
    own = json.load(open(params))["material"]
    for name, extra, material, load_map in ((own, [], own, "point"),
                                             ("breast_tissue", ["--material", "breast_tissue"], "breast_tissue",
                                              "patch")):
        out = os.path.join(tmp, name)
        r = run([tool, "evaluate", "--scene", scene, "--level", "1", "--frames", "4", "--distributions", "2",
                 "--no-plots", "--out", out, "--cache-dir", os.path.join(tmp, "cache"), "--quiet"] + extra)
        check(r.returncode == 0, "%s: evaluate exited %d: %s" % (name, r.returncode, r.stderr))
        if r.returncode:
            continue
        ref = json.load(open(os.path.join(out, "tables.json")))["reference"]
        check(ref.get("material") == material and ref.get("load_map") == load_map,
              "%s: tables.json reference %s, expected material %s, load map %s" % (name, ref, material, load_map))
        line = [l for l in r.stdout.splitlines() if l.startswith("reference: FEM level 1")]
        check(len(line) == 1 and ("material profile %s, %s load map" % (material, load_map)) in line[0],
              "%s: stdout's reference line %r lacks the profile %s" % (name, line, material))
        md = open(os.path.join(out, "tables.md")).read().splitlines()[0]
        check(("material profile `%s`" % material) in md, "%s: tables.md header %r lacks the profile" % (name, md))


DATA_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")
LEVEL4_D2 = os.path.join(DATA_DIR, "fem_level4_long_term_d2.csv")


def read_level4_d2(path=None):
    """The stored level-4 field: {(frame, vertex): cm} and the '#' header's numbers."""
    head, ref = {}, {}
    with open(path or LEVEL4_D2) as f:
        lines = [l for l in f]
    for l in lines:
        if l.startswith("# level-2 FEM peak "):
            head["peak2"] = float(l.split()[4])
        if l.startswith("# level-4 FEM peak ") and " at vertex " in l:
            head["peak_vertex"] = int(l.split(" at vertex ")[1].split(",")[0])
    for row in csv.DictReader(l for l in lines if not l.startswith("#")):
        ref[(int(row["frame"]), int(row["vertex"]))] = float(row["fem_cm"])
    return head, ref


def test_long_term(tool, scene):
    """See the module's docstring (long_term)."""
    check_stored_level4(tool, scene, "paper_step_long_term.json", LEVEL4_D2, 0.03, 0.10, "long-term default",
                        "make_long_term_level4.py", 0.15)


def recovery_s(trace, t_release=2.0):
    """Seconds after t_release until |u| first falls to 5% of its peak while loaded (linear
    between frames); None if it does not within the trace. trace: [(t [s], |u|)], in order."""
    peak = max(u for t, u in trace if t <= t_release + 1e-9)
    level, prev = 0.05 * peak, None
    for t, u in trace:
        if t > t_release + 1e-9 and prev is not None and prev[1] > level >= u:
            return prev[0] + (t - prev[0]) * (prev[1] - level) / (prev[1] - u) - t_release
        prev = (t, u)
    return None


HOLD_FRAMES = 200  # the scenes' step load is on for 2 s: frames 0-199 at 10 ms


def check_stored_level4(tool, scene, scene_name, data, rmse_bound, peak_bound, label, maker, rec_tol, rec_band=None):
    """Distribution II of a set (its model side from an evaluate run here) against the
    level-4 FEM field stored in data: RMSE over the stored full frames at most rmse_bound of the
    level-4 peak, the model's peak within peak_bound of it; the level-2 FEM peak (over the hold,
    where it lies) equal to the one recorded with the stored field (the FEM did not change since). Recovery: at the
    FEM's most displaced vertex (stored at every frame), the model's time to 5% of its peak
    after the 2 s release within rec_tol seconds of the FEM's, and inside rec_band (lo, hi)
    when one is given."""
    lt_scene = os.path.join(os.path.dirname(scene), scene_name)
    tmp = scratch("palp_eval_level4_ref_")
    # Two runs, each only as long as what it is read for (until 2026-12-07 one level-2 run of all 400
    # frames, whose FEM was ~95% of the test: 11.2 s CPU long-term, 14.4 s breast tissue):
    # - the model's side, all 400 frames, from a level-1 run (the real-time record does not depend on
    #   the FEM level: measured bit-identical to the level-2 run's; level 1's FEM is the cheapest, ~1.5 s);
    # - the level-2 FEM for the guard, its first HOLD_FRAMES (the 2 s hold): the FEM steps forward in
    #   time only, so they equal the 400-frame run's first 200 bit for bit (measured, long-term), and the
    #   peak recorded with the stored field lies in them (frame 199 long-term, 198 breast tissue: the
    #   data files' level-2 peak is the whole run's; frames 200-399 reach at most 96% of it long-term,
    #   45% breast tissue, measured). What the guard no longer sees is an FEM change confined to the
    #   release that lifts a frame there above the hold's peak (the old guard saw only that there too).
    outs = {}
    for name, extra in (("rt", ["--level", "1"]), ("fem2", ["--level", "2", "--frames", str(HOLD_FRAMES)])):
        outs[name] = os.path.join(tmp, name)
        r = run([tool, "evaluate", "--scene", lt_scene, "--distributions", "2", "--no-plots", "--out", outs[name],
                 "--cache-dir", os.path.join(tmp, "cache"), "--quiet"] + extra)
        check(r.returncode == 0, "evaluate (%s) exited %d: %s" % (" ".join(extra), r.returncode, r.stderr))
        if r.returncode:
            return
    rt, fem2, time_of = {}, {}, {}
    with open(os.path.join(outs["rt"], "displacement_d2.csv")) as f:
        for row in csv.DictReader(f):
            key = (int(row["frame"]), int(row["vertex"]))
            rt[key] = float(row["rt_cm"])
            time_of[key[0]] = float(row["time_s"])
    with open(os.path.join(outs["fem2"], "displacement_d2.csv")) as f:
        for row in csv.DictReader(f):
            fem2[(int(row["frame"]), int(row["vertex"]))] = float(row["fem_cm"])
    check(len(rt) == 400 * 296, "pairs: %d, expected 400 frames x 296 free vertices" % len(rt))
    check(len(fem2) == HOLD_FRAMES * 296 and all(k in rt for k in fem2),
          "level-2 pairs: %d, expected the model's first %d frames x 296 vertices" % (len(fem2), HOLD_FRAMES))
    head, ref = read_level4_d2(data)
    frames = {}
    for fr, _ in ref:
        frames[fr] = frames.get(fr, 0) + 1
    full = sorted(fr for fr, n in frames.items() if n == 296)
    check(len(full) == 32 and len(frames) == 400, "stored reference: %d full frames of %d" % (len(full), len(frames)))
    check(all(k in rt for k in ref), "stored reference names vertex-frames the model does not have")
    sq = [(rt[(fr, v)] - ref[(fr, v)]) ** 2 for fr, v in ref if fr in full]
    rmse = math.sqrt(math.fsum(sq) / len(sq))
    peak4, peak_rt, peak2 = max(ref.values()), max(rt.values()), max(fem2.values())
    sq2 = [(rt[k] - fem2[k]) ** 2 for k in fem2]
    rmse2 = math.sqrt(math.fsum(sq2) / len(sq2))
    print("%s, distribution II, FEM level 4 (stored): RMSE %.4f mm = %.2f%% of the FEM peak %.4f mm "
          "(bound %.0f%%); model peak %.4f mm, ratio %.3f (bound 1 +- %.2f)" %
          (label, 10 * rmse, 100 * rmse / peak4, 10 * peak4, 100 * rmse_bound, 10 * peak_rt, peak_rt / peak4,
           peak_bound))
    print("  level 2 (for reference, the hold's %d frames): FEM peak %.4f mm (stored %.4f mm), model / level 2 %.3f, "
          "RMSE %.2f%% of it" % (HOLD_FRAMES, 10 * peak2, 10 * head.get("peak2", float("nan")), peak_rt / peak2,
                                 100 * rmse2 / peak2))
    check(close(peak2, head.get("peak2", float("nan")), 1e-6),
          "the level-2 FEM peak %.9g cm is not the %r cm recorded with the stored level-4 field: the FEM changed, "
          "rerun tests/data/%s" % (peak2, head.get("peak2"), maker))
    check(rmse <= rmse_bound * peak4, "RMSE %.4f mm above %.0f%% of the level-4 FEM peak %.4f mm" %
          (10 * rmse, 100 * rmse_bound, 10 * peak4))
    check(abs(peak_rt / peak4 - 1.0) <= peak_bound, "model peak %.4f mm vs level-4 FEM %.4f mm" %
          (10 * peak_rt, 10 * peak4))
    v = head.get("peak_vertex")
    traced = v is not None and all((fr, v) in ref for fr in range(400))
    check(traced, "stored reference: no vertex stored at every frame (its '# level-4 FEM peak ... at vertex N' line)")
    if not traced:
        return
    rec_rt = recovery_s([(time_of[fr], rt[(fr, v)]) for fr in range(400)])
    rec_fem = recovery_s([(time_of[fr], ref[(fr, v)]) for fr in range(400)])
    print("  recovery to 5%% at vertex %d (the level-4 FEM's most displaced): model %s s, level-4 FEM %s s "
          "(bound: within %.2f s of it%s)" %
          (v, "%.3f" % rec_rt if rec_rt is not None else "not within 2 s", "%.3f" % rec_fem if rec_fem is not None
           else "not within 2 s", rec_tol, ", and in %.2f-%.2f s" % rec_band if rec_band else ""))
    check(rec_rt is not None and rec_fem is not None and abs(rec_rt - rec_fem) <= rec_tol,
          "recovery: model %s s against the level-4 FEM's %s s (tolerance %.2f s)" % (rec_rt, rec_fem, rec_tol))
    if rec_band:
        check(rec_rt is not None and rec_band[0] <= rec_rt <= rec_band[1],
              "recovery: model %s s outside %.2f-%.2f s" % (rec_rt, rec_band[0], rec_band[1]))


def test_level4_guard(tool, scene):
    """See the module's docstring (level4_guard)."""
    lt_scene = os.path.join(os.path.dirname(scene), "paper_step_long_term.json")
    tmp = scratch("palp_eval_level4_")
    out = os.path.join(tmp, "out")
    r = run([tool, "evaluate", "--scene", lt_scene, "--level", "4", "--frames", "12", "--distributions", "2",
             "--no-plots", "--out", out, "--cache-dir", os.path.join(tmp, "cache"), "--quiet"])
    check(r.returncode == 0, "evaluate exited %d: %s" % (r.returncode, r.stderr))
    if r.returncode:
        return
    _, ref = read_level4_d2()
    peak = max(ref.values())
    worst, n = 0.0, 0
    with open(os.path.join(out, "displacement_d2.csv")) as f:
        for row in csv.DictReader(f):
            key = (int(row["frame"]), int(row["vertex"]))
            check(key in ref, "frame %d vertex %d is not in the stored reference" % key)
            if key in ref:
                worst, n = max(worst, abs(float(row["fem_cm"]) - ref[key])), n + 1
    print("level-4 FEM, frames 0-11 of distribution II: %d values, largest difference from the stored reference "
          "%.3g cm = %.2g of its peak (bound 1e-4)" % (n, worst, worst / peak))
    check(n == 12 * 296, "%d recomputed values, expected 12 frames x 296 vertices" % n)
    check(worst <= 1e-4 * peak, "the level-4 FEM no longer gives the stored reference (%.3g cm off): rerun "
          "tests/data/make_long_term_level4.py" % worst)


def test_breast_tissue(tool, scene):
    """See the module's docstring (breast_tissue)."""
    check_stored_level4(tool, scene, "paper_step_breast_tissue.json", os.path.join(DATA_DIR, "fem_level4_breast_tissue_d2.csv"),
                        0.07, 0.10, "breast-tissue set", "make_breast_tissue_refs.py", 0.25, (0.8, 1.2))


def main():
    tool, scene, which = sys.argv[1], sys.argv[2], sys.argv[3]
    {"tables": test_tables, "errors": test_errors, "shipped": test_shipped, "clock": test_clock,
     "material": test_material,
     "long_term": test_long_term, "level4_guard": test_level4_guard, "breast_tissue": test_breast_tissue}[which](tool, scene)
    if failures:
        print("%d check(s) failed" % failures, file=sys.stderr)
        return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
