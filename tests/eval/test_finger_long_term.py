#!/usr/bin/env python3
"""The long-term candidate's fingertip against the FE fingertip (issue 12).

`palp-fem finger --site pole` on config/paper_step_long_term.json: a rigid 8 mm
sphere pressed by position into the FE dome (level 2, relaxed long-term reading,
augmented-Lagrangian contact) and the real-time finger driven to the same depths,
0.25 mm until the FE force passes 5 N (2.5 mm). Asserted from the written CSV:
- every real-time force within 15% of the FE's at the depth reached (the
  compliance discrimination threshold; measured 0.99-1.03 on 2026-11-26, 0.962-1.005
  after the peak refit of 2026-11-27);
- the real-time proxy reached each FE depth within 5 um (the comparison is at
  matched positions);
- both curves increase with depth and reach 5 N (the issue's 0.3-5 N range);
- the real-time force is nearly linear, as the FE's is (the skin bends like a plate
  on the gel): the stiffness from 0.25-1 mm and from 1-2 mm differ by less than 30%
  (measured 4%; the membrane without bending gave 2.4x, 0.70 -> 2.95 N at 1 -> 2 mm).
"""
import csv
import os
import subprocess
import sys
import tempfile

import test_eval_evaluate as common  # its check() and failure count (this folder is on sys.path)

check = common.check


def main():
    tool, scene = sys.argv[1], sys.argv[2]
    tmp = tempfile.mkdtemp(prefix="palp_finger_lt_")
    out = os.path.join(tmp, "finger.csv")
    r = subprocess.run([tool, "finger", "--scene", scene, "--level", "2", "--reading", "long_term",
                        "--site", "pole", "--out", out], capture_output=True, text=True, timeout=600)
    check(r.returncode == 0, "palp-fem finger exited %d: %s" % (r.returncode, r.stderr[-500:]))
    if r.returncode:
        return 1
    rows = list(csv.DictReader(open(out)))
    check(len(rows) >= 5, "only %d depths" % len(rows))
    d = [float(x["depth_m"]) for x in rows]
    fe = [float(x["fem_N"]) for x in rows]
    rt = [float(x["realtime_N"]) for x in rows]
    dr = [float(x["realtime_depth_m"]) for x in rows]
    for k in range(len(rows)):
        ratio = rt[k] / fe[k]
        print("pole %.2f mm: FE %.3f N, real-time %.3f N at %.4f mm, ratio %.3f (bound 0.85-1.15)"
              % (1e3 * d[k], fe[k], rt[k], 1e3 * dr[k], ratio))
        check(0.85 <= ratio <= 1.15, "at %.2f mm the real-time force is %.3f of the FE's" % (1e3 * d[k], ratio))
        check(abs(dr[k] - d[k]) <= 5e-6, "proxy at %.4f mm for the FE's %.4f mm" % (1e3 * dr[k], 1e3 * d[k]))
    check(all(fe[k + 1] > fe[k] for k in range(len(fe) - 1)), "FE force not increasing: %r" % fe)
    check(all(rt[k + 1] > rt[k] for k in range(len(rt) - 1)), "real-time force not increasing: %r" % rt)
    check(fe[-1] >= 5.0, "the FE curve stops at %.2f N, before 5 N" % fe[-1])

    def at(xs, ys, x):  # linear interpolation on the written depths
        for k in range(len(xs) - 1):
            if xs[k] <= x <= xs[k + 1]:
                return ys[k] + (ys[k + 1] - ys[k]) * (x - xs[k]) / (xs[k + 1] - xs[k])
        return float("nan")

    s1 = (at(d, rt, 1e-3) - at(d, rt, 0.25e-3)) / 0.75e-3
    s2 = (at(d, rt, 2e-3) - at(d, rt, 1e-3)) / 1e-3
    print("real-time stiffness 0.25-1 mm %.0f N/m, 1-2 mm %.0f N/m (ratio %.2f, bound 1 +- 0.3)" % (s1, s2, s2 / s1))
    check(abs(s2 / s1 - 1.0) < 0.3, "stiffness ratio 1-2 mm / 0.25-1 mm %.2f" % (s2 / s1))
    return 1 if common.failures else 0


if __name__ == "__main__":
    sys.exit(main())
