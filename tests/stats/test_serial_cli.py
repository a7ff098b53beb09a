#!/usr/bin/env python3
"""test_serial_cli - palp-stats neff | bootstrap | tost | ba-rm against textbook values.

    test_serial_cli.py PALP_STATS WORKDIR

Expected values come from the literature or closed forms, never from the code:
- ba-rm: Bland & Altman (2007, Sec. 3) on the cardiac output data of Bland &
  Altman (1999, Table 4; 12 subjects, 60 pairs RV - IC): bias 0.6021667, SD of a
  single difference 0.99062408, limits [-1.3394565, 2.5437899]; and a 2 x 2
  design worked by hand (MS_w = 2, MS_b = 16, m0 = 2, SD 3).
- neff: a cosine of 3 full periods over n = 24 values has mean 0 and lag-1
  autocorrelation r1 = (n - 2)/n cos(2 pi 3/24) exactly (sum of cos(2wt + w) over
  t = 0..n-2 is -cos w), so n_eff = n (1 - r1)/(1 + r1) = 5.12301; an AR(1) series
  x_t = 0.8 x_{t-1} + e_t (n = 20000, this file's own Gaussian generator) has
  r1 -> 0.8 (SE ~ 0.004, asserted within 0.015) and n_eff -> n (1 - 0.8)/(1 + 0.8)
  = 2222 (asserted within 8%).
- bootstrap: 1..6 with blocks of 2 has the exact bootstrap SE sqrt(2/3) (the five
  block means 1.5..5.5 have variance 2, three blocks per resample), with blocks of
  1 the i.i.d. value sqrt((35/12)/6); asserted within 2% at 40,000 resamples
  (Monte Carlo error ~0.35%). On the AR(1) series the SE must match the
  theoretical SE of the mean, sqrt(sigma^2/n (1 + phi)/(1 - phi)) with sigma^2 =
  1/(1 - phi^2), within 15% (one realisation: ~5% sampling error, ~5% block bias).
  The same seed gives the same output; another seed another interval.
- tost: 1, 2, 3 (mean 2, SE 1/sqrt 3, 2 df) with the closed-form tail of t with
  2 df, Q(t) = 1/2 - t/(2 sqrt(2 + t^2)), and t_{0.95,2} = 2.919986 (tables):
  margins -+3 give p = 0.112702, not equivalent; -+4 give p = 0.037088,
  equivalent; the same by units (three units of two rows with means 1, 2, 3);
  --serial on the cosine: SE = SD/sqrt(n_eff), df = n_eff - 1.
- errors: a subject with one pair, a constant series, no margin, --serial with
  --unit, --a and --b (or --subject and --a) naming one column, an option of another
  command, a --seed that is not 0..2^64-1: exit status 1 or 2 with a message naming
  the problem.
"""
import json
import math
import os
import random
import shutil
import subprocess
import sys

failures = 0


def check(cond, msg):
    global failures
    if not cond:
        failures += 1
        print("FAIL: " + msg, file=sys.stderr)


def close(a, b, rel, absol=0.0):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), absol)


CO = """1,7.83,6.57 1,7.42,5.62 1,7.89,6.9 1,7.12,6.57 1,7.88,6.35 2,6.16,4.06 2,7.26,4.29 2,6.71,4.26
2,6.54,4.09 3,4.75,4.71 3,5.24,5.5 3,4.86,5.08 3,4.78,5.02 3,6.05,6.01 3,5.42,5.67 4,4.21,4.14
4,3.61,4.2 4,3.72,4.61 4,3.87,4.68 4,3.92,5.04 5,3.13,3.03 5,2.98,2.86 5,2.85,2.77 5,3.17,2.46
5,3.09,2.32 5,3.12,2.43 6,5.92,5.9 6,6.42,5.81 6,5.92,5.7 6,6.27,5.76 7,7.13,5.09 7,6.62,4.63
7,6.58,4.61 7,6.93,5.09 8,4.54,4.72 8,4.81,4.61 8,5.11,4.36 8,5.29,4.2 8,5.39,4.36 8,5.57,4.2
9,4.48,3.17 9,4.92,3.12 9,3.97,2.96 10,4.22,4.35 10,4.65,4.62 10,4.74,3.16 10,4.44,3.53
10,4.5,3.53 11,6.78,7.2 11,6.07,6.09 11,6.52,7.0 11,6.42,7.1 11,6.41,7.4 11,5.76,6.8 12,5.06,4.5
12,4.72,4.2 12,4.9,3.8 12,4.8,3.8 12,4.9,4.2 12,5.1,4.5"""


def main():
    tool, work = sys.argv[1:3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)

    def write(name, text):
        with open(os.path.join(work, name), "w") as f:
            f.write(text)

    def stats(*args):
        r = subprocess.run([tool] + list(args), cwd=work, capture_output=True, text=True, timeout=60)
        return r

    def js(*args):
        r = stats(*(list(args) + ["--json"]))
        check(r.returncode == 0, "%s: exit %d %s" % (" ".join(args), r.returncode, r.stderr[-500:]))
        return json.loads(r.stdout) if r.returncode == 0 else {}

    # ---- ba-rm: Bland & Altman 2007 ----
    write("co.csv", "subject,rv,ic\n" + "\n".join(CO.split()) + "\n")
    j = js("ba-rm", "co.csv", "--subject", "subject", "--a", "rv", "--b", "ic")
    if j:
        check(j["subjects"] == 12 and j["n"] == 60, "CO: 12 subjects, 60 pairs")
        check(close(j["bias"], 0.6021667, 1e-6), "CO bias %r vs 0.6021667" % j["bias"])
        check(close(j["sd_total"], 0.99062408, 1e-7), "CO SD %r vs 0.99062408" % j["sd_total"])
        check(close(j["loa_lower"], -1.3394565, 1e-6) and close(j["loa_upper"], 2.5437899, 1e-6),
              "CO limits [%r, %r] vs [-1.3394565, 2.5437899]" % (j["loa_lower"], j["loa_upper"]))
    # differences given directly, by hand: subjects {1, 3} and {5, 7}
    write("rm.csv", "s,d\nA,1\nB,5\nA,3\nB,7\n")
    j = js("ba-rm", "rm.csv", "--subject", "s", "--value", "d")
    if j:
        check(close(j["ms_within"], 2.0, 1e-12) and close(j["ms_between"], 16.0, 1e-12) and
              close(j["divisor"], 2.0, 1e-12), "hand 2x2: MS_w 2, MS_b 16, m0 2")
        check(close(j["bias"], 4.0, 1e-12) and close(j["sd_total"], 3.0, 1e-12), "hand 2x2: bias 4, SD 3")
        check(close(j["loa_lower"], 4 - 5.88, 1e-12) and close(j["loa_upper"], 4 + 5.88, 1e-12),
              "hand 2x2: limits 4 -+ 5.88")

    # ---- neff: closed-form cosine ----
    n = 24
    w = 2 * math.pi * 3 / n
    write("cos.csv", "x\n" + "".join("%.17g\n" % math.cos(w * t) for t in range(n)))
    r1 = (n - 2) / n * math.cos(w)
    neff = n * (1 - r1) / (1 + r1)
    sd = math.sqrt((n / 2) / (n - 1))
    j = js("neff", "cos.csv", "--value", "x")
    if j:
        check(close(j["r1"], r1, 1e-12), "cosine r1 %r vs %r" % (j["r1"], r1))
        check(close(j["n_eff"], neff, 1e-12), "cosine n_eff %r vs %r" % (j["n_eff"], neff))
        check(close(j["mean"], 0.0, 0, 1e-15) and close(j["sd"], sd, 1e-12), "cosine mean 0, SD sqrt(12/23)")
        check(close(j["se_ar1"], sd / math.sqrt(neff), 1e-12), "cosine SE = SD/sqrt(n_eff)")

    # ---- AR(1), phi = 0.8 ----
    rng = random.Random(12345)
    phi, N = 0.8, 20000
    x, xs = rng.gauss(0, 1) / math.sqrt(1 - phi * phi), []
    for _ in range(N):
        xs.append(x)
        x = phi * x + rng.gauss(0, 1)
    write("ar1.csv", "x\n" + "".join("%.17g\n" % v for v in xs))
    j = js("neff", "ar1.csv", "--value", "x")
    if j:
        check(abs(j["r1"] - phi) < 0.015, "AR(1) r1 %r vs 0.8" % j["r1"])
        want = N * (1 - phi) / (1 + phi)
        check(close(j["n_eff"], want, 0.08), "AR(1) n_eff %r vs %r" % (j["n_eff"], want))
    se_true = math.sqrt(1 / (1 - phi * phi) / N * (1 + phi) / (1 - phi))
    j = js("bootstrap", "ar1.csv", "--value", "x", "--resamples", "4000", "--seed", "7")
    if j:
        check(close(j["se"], se_true, 0.15), "AR(1) bootstrap SE %r vs theory %r" % (j["se"], se_true))
        check(j["blocks"] >= 4, "AR(1): the rule's block leaves >= 4 blocks")

    # ---- bootstrap: exact values ----
    write("six.csv", "x\n1\n2\n3\n4\n5\n6\n")
    j = js("bootstrap", "six.csv", "--value", "x", "--block", "2", "--resamples", "40000", "--seed", "3")
    if j:
        check(close(j["se"], math.sqrt(2 / 3), 0.02), "1..6, b = 2: SE %r vs sqrt(2/3)" % j["se"])
        check(j["mean"] == 3.5 and j["blocks"] == 3, "1..6: mean 3.5, 3 blocks")
        check(j["ci_lower"] < 3.5 < j["ci_upper"] and j["level"] == 0.9, "1..6: 90% interval around the mean")
    j = js("bootstrap", "six.csv", "--value", "x", "--block", "1", "--resamples", "40000", "--seed", "3")
    if j:
        check(close(j["se"], math.sqrt(35 / 12 / 6), 0.02), "1..6, b = 1: SE %r vs iid" % j["se"])
    a1 = stats("bootstrap", "six.csv", "--value", "x", "--seed", "9")
    a2 = stats("bootstrap", "six.csv", "--value", "x", "--seed", "9")
    a3 = stats("bootstrap", "six.csv", "--value", "x", "--seed", "10", "--block", "1")
    a4 = stats("bootstrap", "six.csv", "--value", "x", "--seed", "11", "--block", "1")
    check(a1.returncode == 0 and a1.stdout == a2.stdout, "bootstrap: same seed, same output")
    check(a3.returncode == 0 and a3.stdout != a4.stdout, "bootstrap: another seed, another output")

    # ---- tost: closed-form 2 df ----
    def q2(t):
        return 0.5 - t / (2 * math.sqrt(2 + t * t))

    t95 = 2.919986  # t_{0.95, 2}, statistical tables
    write("three.csv", "x\n1\n2\n3\n")
    write("units.csv", "run,x\nA,0.5\nB,2\nC,2.5\nA,1.5\nB,2\nC,3.5\n")
    for margin, eq in ((3, False), (4, True)):
        se = 1 / math.sqrt(3)
        p = max(q2((2 + margin) / se), q2((margin - 2) / se))
        for args in (("three.csv", "--value", "x"), ("units.csv", "--value", "x", "--unit", "run")):
            j = js("tost", *args, "--margin", str(margin))
            if not j:
                continue
            tag = "tost %s margin %d" % (args[0], margin)
            check(close(j["estimate"], 2, 1e-12) and close(j["se"], se, 1e-12) and j["df"] == 2, tag + ": 2, SE, df")
            check(close(j["p"], p, 1e-9), tag + ": p %r vs %r" % (j["p"], p))
            check(close(j["ci_lower"], 2 - t95 * se, 1e-6) and close(j["ci_upper"], 2 + t95 * se, 1e-6),
                  tag + ": interval 2 -+ t95 SE")
            check(j["equivalent"] == eq, tag + ": equivalent %s" % eq)
            check(j["observations"] == 3, tag + ": 3 observations")
    check(close(q2(math.sqrt(3)), 0.112702, 1e-5) and close(q2(2 * math.sqrt(3)), 0.037088, 1e-4),
          "the closed form itself reproduces the tabulated tails")
    j = js("tost", "cos.csv", "--value", "x", "--margin", "1", "--serial")
    if j:
        check(close(j["n_eff"], neff, 1e-12) and close(j["df"], neff - 1, 1e-12), "tost --serial: df = n_eff - 1")
        check(close(j["se"], sd / math.sqrt(neff), 1e-12), "tost --serial: SE = SD/sqrt(n_eff)")
    j = js("tost", "co.csv", "--a", "rv", "--b", "ic", "--lower", "-1", "--upper", "2")
    if j:
        check(close(j["estimate"], 0.6021667, 1e-6) and j["lower"] == -1 and j["upper"] == 2, "tost on a - b")

    # ---- errors ----
    write("one.csv", "s,d\nA,1\nA,2\nB,3\n")
    r = stats("ba-rm", "one.csv", "--subject", "s", "--value", "d")
    check(r.returncode == 1 and r.stdout == "" and "one.csv:4" in r.stderr and '"B"' in r.stderr,
          "ba-rm: a subject with one pair named with its line (%r)" % r.stderr[-300:])
    write("const.csv", "x\n2\n2\n2\n2\n")
    r = stats("neff", "const.csv", "--value", "x")
    check(r.returncode == 1 and "same" in r.stderr, "neff: a constant series is refused")
    r = stats("tost", "three.csv", "--value", "x")
    check(r.returncode == 2 and "--margin" in r.stderr, "tost without margins: usage error")
    r = stats("tost", "units.csv", "--value", "x", "--margin", "1", "--serial", "--unit", "run")
    check(r.returncode == 2, "tost --serial with --unit: usage error")
    r = stats("tost", "cos.csv", "--value", "x", "--margin", "1", "--alpha", "0.7")
    check(r.returncode == 2 and "--alpha" in r.stderr, "tost --alpha 0.7: usage error")
    # --a and --b naming one column: a - b = 0 would be EQUIVALENT; a label column that is measured
    for args, tag in ((("tost", "co.csv", "--a", "rv", "--b", "RV", "--margin", "1"), "tost --a rv --b RV"),
                      (("neff", "co.csv", "--a", "rv", "--b", "rv"), "neff --a rv --b rv"),
                      (("ba-rm", "co.csv", "--subject", "rv", "--a", "rv", "--b", "ic"), "ba-rm --subject rv --a rv")):
        r = stats(*args)
        check(r.returncode == 2 and r.stdout == "" and "name the same column" in r.stderr,
              tag + ": usage error (%r)" % r.stderr[-300:])
    # an option of another command: refused naming the command it belongs to (it was dropped unread:
    # bland-altman --subject gave plain Bland-Altman where the repeated-measures one was meant)
    for args, opt, owner in ((("bland-altman", "co.csv", "--a", "rv", "--b", "ic", "--subject", "subject"), "--subject", "ba-rm"),
                             (("rmse", "co.csv", "--a", "rv", "--b", "ic", "--margin", "1"), "--margin", "tost"),
                             (("anova", "co.csv", "--group", "subject", "--value", "rv", "--alpha", "0.1"), "--alpha", "tost"),
                             (("bland-altman", "co.csv", "--a", "rv", "--b", "ic", "--level", "0.9"), "--level", "bootstrap"),
                             (("tost", "co.csv", "--a", "rv", "--b", "ic", "--margin", "1", "--seed", "3"), "--seed", "bootstrap")):
        r = stats(*args)
        check(r.returncode == 2 and r.stdout == "" and "%s does not take %s; it belongs to %s" % (args[0], opt, owner) in r.stderr,
              "%s %s: usage error naming %s (%r)" % (args[0], opt, owner, r.stderr[-300:]))
    # --seed: digits only, up to 2^64 - 1 (" -5" was 2^64 - 5, a larger one saturated)
    for seed in (" -5", "-5", "18446744073709551616", "1e3", "0x10"):
        r = stats("bootstrap", "six.csv", "--value", "x", "--seed", seed)
        check(r.returncode == 2 and "--seed expects a whole number" in r.stderr, "bootstrap --seed %r: usage error" % seed)
    r = stats("bootstrap", "six.csv", "--value", "x", "--seed", "18446744073709551615", "--resamples", "100")
    check(r.returncode == 0, "bootstrap --seed 18446744073709551615 (2^64 - 1) taken (rc %d)" % r.returncode)
    r = stats("bootstrap", "six.csv", "--value", "x", "--block", "7")
    check(r.returncode == 1 and "longer" in r.stderr, "bootstrap: block longer than the series")

    # ---- many distinct labels (session 81 review): each new label was compared with every
    # earlier one, O(n^2): 100,000 labels took 34 s, 200,000 took 95 s. Now a hash table.
    # 100,000 labels, each with the rows "L{i},1" and "L{i},3" (anova groups, ba-rm subjects)
    # or one row "U{i},2" (tost units). By hand: anova, every group mean 2 and SS_within 2:
    # SS_between = 0, so F = 0 and p = 1, df (99999, 100000); tost --unit: 100,000
    # observations all equal to 2. Bound: 5 s of the child's CPU time (user + sys, so
    # a loaded machine does not count); measured 0.05-0.2 s each, the old code 34 s.
    nl = 100000
    write("many.csv", "g,v\n" + "".join("L%d,1\nL%d,3\n" % (i, i) for i in range(nl)))
    write("many_units.csv", "u,v\n" + "".join("U%d,2\n" % i for i in range(nl)))
    for args, tag in ((("anova", "many.csv", "--group", "g", "--value", "v"), "anova 100,000 groups"),
                      (("tost", "many_units.csv", "--unit", "u", "--value", "v", "--margin", "1"), "tost 100,000 units"),
                      (("ba-rm", "many.csv", "--subject", "g", "--value", "v"), "ba-rm 100,000 subjects")):
        before = os.times()
        try:
            r = subprocess.run([tool] + list(args) + ["--json"], cwd=work, capture_output=True, text=True,
                               timeout=30)
        except subprocess.TimeoutExpired:
            check(False, "%s: still running after 30 s, bound 5 s of CPU (quadratic label look-up?)" % tag)
            continue
        after = os.times()
        cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
        check(cpu < 5.0, "%s: %.2f s of CPU, bound 5 s (quadratic label look-up?)" % (tag, cpu))
        check(r.returncode == 0, "%s: exit %d %s" % (tag, r.returncode, r.stderr[-500:]))
        if r.returncode != 0:
            continue
        j = json.loads(r.stdout)
        if args[0] == "anova":
            a = j["anova"]
            check(len(j["groups"]) == nl and a["between"]["df"] == nl - 1 and a["within"]["df"] == nl,
                  "%s: %d groups, df (%r, %r)" % (tag, len(j["groups"]), a["between"]["df"], a["within"]["df"]))
            check(a["between"]["ss"] == 0 and close(a["within"]["ss"], 2.0 * nl, 1e-12) and a["p"] == 1,
                  "%s: SS_b 0, SS_w 2 nl, p 1 (%r, %r, %r)" % (tag, a["between"]["ss"], a["within"]["ss"], a["p"]))
        elif args[0] == "tost":
            check(j["observations"] == nl and close(j["estimate"], 2.0, 1e-12),
                  "%s: %r observations, estimate %r" % (tag, j["observations"], j["estimate"]))
        else:
            check(j["subjects"] == nl and j["n"] == 2 * nl, "%s: %r subjects, %r pairs" % (tag, j["subjects"], j["n"]))


main()
print("test_serial_cli: %s" % ("ok" if failures == 0 else "%d failure(s)" % failures))
sys.exit(1 if failures else 0)
