#!/usr/bin/env python3
"""Asserts what headless Chromium rendered of palp-review's reports (issue 13), from the DOM
Chromium dumped and from its screenshot's pixels. Standard library only.
usage: check_review.py session-expert|session-novice DOM.html SHOT.png
       check_review.py class DOM.html SHOT.png CLASS.csv"""
import csv
import os
import re
import sys
from collections import Counter
from html.parser import HTMLParser

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "db"))
from check_render import read_png  # noqa: E402  (the same PNG decoder as the session-report test)

BAND = {"light": (0x56, 0xB4, 0xE9), "medium": (0xE6, 0x9F, 0x00), "deep": (0x00, 0x9E, 0x73)}
failures = 0


def check(cond, msg):
    global failures
    print(("ok   " if cond else "FAIL ") + msg)
    if not cond:
        failures += 1


class Dom(HTMLParser):
    """Elements as (tag, attrs, text) with the ids and classes of their ancestors."""

    def __init__(self):
        super().__init__()
        self.stack, self.els = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        el = {"tag": tag, "a": a, "text": "", "anc": [(e["tag"], e["a"]) for e in self.stack]}
        self.els.append(el)
        if tag not in ("polygon", "circle", "path", "rect", "polyline", "br", "meta", "line"):
            self.stack.append(el)

    def handle_endtag(self, tag):
        for i in range(len(self.stack) - 1, -1, -1):
            if self.stack[i]["tag"] == tag:
                del self.stack[i:]
                break

    def handle_data(self, data):
        for e in self.stack:
            e["text"] += data

    def within(self, el, key, val):
        return any(a.get(key) == val or (key == "class" and val in (a.get("class") or "").split())
                   for _, a in el["anc"])

    def by(self, key, val):
        return [e for e in self.els
                if e["a"].get(key) == val or (key == "class" and val in (e["a"].get("class") or "").split())]


def pixels(shot):
    """Pixels within 12 per channel of each band's colour. The distinct colours are counted first
    (Counter over zipped channel slices runs in C) and only those are compared with the bands: a
    1100x2400 report has a few thousand colours, and the per-pixel loop took ~4 s an image."""
    w, h, bpp, rows = read_png(shot)
    seen = Counter()
    for row in rows:
        seen.update(zip(row[0::bpp], row[1::bpp], row[2::bpp]))
    count = {k: 0 for k in BAND}
    for px, n in seen.items():
        for k, c in BAND.items():
            if all(abs(px[i] - c[i]) <= 12 for i in range(3)):
                count[k] += n
    return count


def fills(dom, svg_id):
    svg = dom.by("id", svg_id)
    if not svg:
        return None
    polys = [e for e in dom.els if e["tag"] == "polygon" and dom.within(e, "id", svg_id)]
    return polys


def metric(dom, key):
    rows = [e for e in dom.els if e["tag"] == "tr" and e["a"].get("data-metric") == key]
    return " ".join(rows[0]["text"].split()) if rows else None


def session(kind, dom_path, shot):
    dom = Dom()
    dom.feed(open(dom_path, encoding="utf-8").read())
    expert = kind == "session-expert"
    sens = metric(dom, "sensitivity")
    check(sens is not None and (("2 of 2 lesions found" in sens and "pass" in sens) if expert else
                                ("0 of 2 lesions found" in sens and "FAIL" in sens)),
          "%s: the sensitivity row reads %r" % (kind, sens))
    score = metric(dom, "score")
    check(score is not None and (score.endswith("pass") if expert else score.endswith("FAIL")),
          "%s: the score row reads %r" % (kind, score))
    for b, col in BAND.items():
        polys = fills(dom, "coverage-" + b)
        check(polys is not None and len(polys) > 300, "%s: coverage map %s drawn (%s triangles)" %
              (kind, b, None if polys is None else len(polys)))
        if polys:
            hexcol = "#%02x%02x%02x" % col
            share = sum(1 for p in polys if p["a"].get("fill") == hexcol) / len(polys)
            cov = metric(dom, "coverage_" + b) or ""
            if expert:
                check(share >= 0.85, "%s: %s map %.0f%% of triangles in the band colour (metric: %s)" %
                      (kind, b, 100 * share, cov))
            else:
                check(share <= 0.2, "%s: %s map %.0f%% in the band colour, a novice's (metric: %s)" %
                      (kind, b, 100 * share, cov))
    path = [e for e in dom.els if e["tag"] == "polyline" and "finger-path" in (e["a"].get("class") or "")]
    npts = len(path[0]["a"].get("points", "").split()) if path else 0
    check(npts > (500 if expert else 20), "%s: the finger's path has %d points" % (kind, npts))
    lesions = [e for e in dom.els if e["tag"] == "circle" and "lesion" in (e["a"].get("class") or "").split()]
    check(len(lesions) == 2, "%s: both lesions revealed on the path map (%d)" % (kind, len(lesions)))
    rows = [e for e in dom.els if e["tag"] == "tr" and dom.within(e, "id", "findings")
            and "finding" in (e["a"].get("class") or "").split()]
    classes = sorted(e["a"]["class"].split()[1] for e in rows)
    if expert:
        check(classes == ["found", "found"], "expert: findings table %s (2 found, none false)" % classes)
    else:
        check("false" in classes and "withdrawn" in classes, "novice: findings table %s (a false mark and a "
              "withdrawn one)" % classes)
    marks = [e for e in dom.els if "finding" in (e["a"].get("class") or "").split() and e["tag"] in ("path", "rect", "circle")]
    check(len(marks) == len(rows), "%s: %d marks drawn for %d findings" % (kind, len(marks), len(rows)))
    # the model's valid range, next to the assessment (review_gen logs alice's valid_range events;
    # bob's log is from a server that did not log them)
    found = dom.by("id", "valid-range")
    vr = found[0] if found else None
    text = " ".join(vr["text"].split()) if vr else ""
    if expert:
        check(vr is not None and "warn" in (vr["a"].get("class") or "").split() and
              text.startswith("OUTSIDE for 1.42 s (355 steps of 4 ms): ") and "1.24 s pressed deeper than this place" in text and
              "by up to 2.4 mm" in text and "weigh the pressure levels" in text,
              "expert: the valid-range paragraph warns, summed by limit: %r" % text[:160])
    else:
        check(vr is not None and "warn" not in (vr["a"].get("class") or "") and text.startswith("not in this log"),
              "novice: the valid-range paragraph says the log does not say: %r" % text[:120])
    px = pixels(shot)
    if expert:
        for b in BAND:
            check(px[b] >= 2000, "%s: screenshot has %d pixels of the %s colour" % (kind, px[b], b))
    else:  # the legend's swatches are in every band's colour; only light was palpated
        check(px["light"] > px["medium"] + 50, "%s: screenshot has more light-band pixels (%d) than medium (%d, the "
              "legend's)" % (kind, px["light"], px["medium"]))


def klass(dom_path, shot, csv_path):
    dom = Dom()
    dom.feed(open(dom_path, encoding="utf-8").read())
    rows = [e for e in dom.els if e["tag"] == "tr" and "trainee-row" in (e["a"].get("class") or "").split()]
    tds = []
    for r in rows:
        cells = [e for e in dom.els if e["tag"] == "td" and any(a is r["a"] for _, a in e["anc"])]
        tds.append([" ".join(c["text"].split()) for c in cells])
    # cells by their column's heading, not their place (the columns follow the terminal table's order)
    heads = [" ".join(e["text"].split()) for e in dom.els if e["tag"] == "th"
             and any(a.get("id") == "class-table" for _, a in e["anc"])]
    want = ["trainee", "session", "started", "lesions found", "false positives", "coverage light", "medium", "deep",
            "search pattern", "strips, in order", "time [s]", "peak force [N]", "score", "rubric",
            "outside the model's valid range [s]", "grade"]
    check(heads == want, "class: the columns in the terminal table's order: %s" % heads)
    col = {h: i for i, h in enumerate(heads)}
    tds = [{h: t[i] if i < len(t) else None for h, i in col.items()} for t in tds]
    names = [t["trainee"] for t in tds]
    check(names == ["bob", "alice", "bob"], "class: one row per session, oldest first: %s" % names)
    data = list(csv.DictReader(open(csv_path)))
    check([d["trainee"] for d in data] == names, "class: the CSV has the same rows (%s)" % [d["trainee"] for d in data])
    for t, d in zip(tds, data):
        check(t["session"] == d["session"] and t["lesions found"] == "%s of %s" % (d["found"], d["lesions"]) and
              abs(float(t["score"]) - float(d["score"])) < 0.051,
              "class: %s row matches the CSV (found %s, score %s vs %s)" % (t["session"], t["lesions found"], t["score"], d["score"]))
    alice = [t for t in tds if t["trainee"] == "alice"][0]
    check(alice["lesions found"] == "2 of 2" and alice["search pattern"] == "vertical_strip" and alice["rubric"] == "pass",
          "class: alice's row %s" % alice)
    # seconds outside the model's valid range: alice's 355 logged steps of 4 ms; bob's logs do not say
    out = "outside the model's valid range [s]"
    check(alice[out] == "1.42" and all(t[out] == "-" for t in tds if t["trainee"] == "bob"),
          "class: outside the valid range, alice %r, bob %r" % (alice[out], [t[out] for t in tds if t["trainee"] == "bob"]))
    # the strips and their order, beside the pattern: alice's expert strokes one pass of 15 strips
    ok = re.fullmatch(r"1[3-5], (0\.9[0-9]|1\.00)", alice["strips, in order"]) is not None
    check(ok and [t["strips, in order"] for t in tds] == ["%s, %.2f" % (d["strips"], float(d["strip_order"]))
                                          if d["pattern"] == "vertical_strip" and int(d["strips"]) >= 3
                                          else "-" for d in data],
          "class: the strips and their order, alice %r, and every row as in the CSV %r" %
          (alice["strips, in order"], [(d["strips"], d["strip_order"]) for d in data]))
    # the instructor's latest grade, added as the last columns (2026-12-05): bob's first session
    # scored 35, alice's proficient, bob's second ungraded; the page's grade column says the same
    grades = [(d["session"], d["grade_score"], d["grade_level"]) for d in data]
    check(sorted(grades) == [("class-alice-1", "", "proficient"), ("class-bob-1", "35", ""), ("class-bob-2", "", "")],
          "class CSV: grade_score and grade_level of the latest grade %r" % grades)
    page = [t["grade"] for t in tds]
    want_page = [" ".join(x for x in (d["grade_score"], d["grade_level"]) if x) or "-" for d in data]
    check(page == want_page, "class: the page's grades %r are the CSV's %r" % (page, want_page))
    # what each was told as the session closed, and after which debrief an attempt was not blind
    # (the last columns, since session 59): alice's server logged her debrief, bob's did not, and
    # bob's second attempt came after his first's debrief (inferred: his logs do not record it)
    told = sorted((d["session"], d["debrief"], d["not_blind_after"]) for d in data)
    check(told == [("class-alice-1", "lesions", ""), ("class-bob-1", "", ""), ("class-bob-2", "", "class-bob-1")],
          "class CSV: debrief and not_blind_after %r" % told)
    csv_out = {d["trainee"]: d["outside_valid_range_s"] for d in data}
    check(csv_out == {"alice": "1.42", "bob": ""}, "class CSV: outside_valid_range_s %r (bob's logs do not say)" % csv_out)
    maps = [e for e in dom.els if e["tag"] == "svg" and "coverage" in (e["a"].get("class") or "").split()]
    check(len(maps) == 9, "class: small multiples, 3 bands x 3 sessions (%d maps)" % len(maps))
    prog = {e["a"].get("data-trainee"): e for e in dom.els if e["tag"] == "tr" and e["a"].get("data-trainee")}
    for who, n in (("bob", 2), ("alice", 1)):
        pts = [e for e in dom.els if e["tag"] == "circle" and "point" in (e["a"].get("class") or "").split()
               and who in prog and any(a is prog[who]["a"] for _, a in e["anc"])]
        check(len(pts) == n, "class: %s's progress chart has %d point(s) (%d)" % (who, n, len(pts)))
    px = pixels(shot)
    check(all(px[b] > 300 for b in BAND), "class: screenshot shows every band colour %s" % px)


def main():
    if sys.argv[1] == "class":
        klass(*sys.argv[2:5])
    else:
        session(sys.argv[1], sys.argv[2], sys.argv[3])
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
