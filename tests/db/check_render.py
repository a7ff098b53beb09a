#!/usr/bin/env python3
"""Asserts that headless Chromium rendered the session report: the screenshot is a real,
non-blank PNG showing the plots, and the DOM holds the session id, the three SVG plots with
their data, and the escaped instructor note. Standard library only (zlib, struct).
usage: check_render.py SHOT.png DOM.html SESSION_UID"""
import struct
import sys
import zlib
from itertools import accumulate


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG file"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), "unexpected PNG format %d/%d" % (depth, ctype)
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytes(stride)
    lo, hi = int.from_bytes(b"\x7f" * stride, "big"), int.from_bytes(b"\x80" * stride, "big")
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)]
        if f == 2:  # Up, the commonest: bytewise (x + b) mod 256 on whole rows as integers (no carry
            # crosses a byte: the low 7 bits are added apart and the top bit is an exclusive or)
            x, b = int.from_bytes(line, "big"), int.from_bytes(prev, "big")
            line = (((x & lo) + (b & lo)) ^ ((x ^ b) & hi)).to_bytes(stride, "big")
        elif f == 1:  # Sub: a running sum per channel
            out = bytearray(stride)
            for c in range(bpp):
                out[c::bpp] = bytes(map((255).__and__, accumulate(line[c::bpp])))
            line = bytes(out)
        elif f in (3, 4):  # Average, Paeth: byte by byte
            line = bytearray(line)
            for i in range(stride):
                a = line[i - bpp] if i >= bpp else 0
                b = prev[i]
                if f == 3:
                    line[i] = (line[i] + (a + b) // 2) & 255
                else:
                    c = prev[i - bpp] if i >= bpp else 0
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
            line = bytes(line)
        rows.append(line)
        prev = line
    return w, h, bpp, rows


def main():
    shot, dom_path, uid = sys.argv[1:4]
    w, h, bpp, rows = read_png(shot)
    colours, nonwhite, red, shaded = set(), 0, 0, 0
    for row in rows[::2]:
        for x in range(0, w * bpp, bpp * 2):
            r, g, b = row[x], row[x + 1], row[x + 2]
            colours.add((r >> 3, g >> 3, b >> 3))
            if r < 245 or g < 245 or b < 245:
                nonwhite += 1
            # the force curve's stroke, #c0392b = (192, 57, 43), within 40 per channel (antialiasing)
            if abs(r - 192) < 40 and abs(g - 57) < 40 and abs(b - 43) < 40:
                red += 1
            # the phantom's skin-tone rest shading, rgb(246, 226, 212), within 12 per channel
            if abs(r - 246) < 12 and abs(g - 226) < 12 and abs(b - 212) < 12:
                shaded += 1
    samples = len(rows[::2]) * len(range(0, w * bpp, bpp * 2))
    frac = nonwhite / samples
    print("screenshot %dx%d: %d colour buckets, %.1f%% non-white, %d force-curve samples, %d phantom samples"
          % (w, h, len(colours), 100 * frac, red, shaded))
    fails = []
    if len(colours) < 40:
        fails.append("too few colours (%d < 40): blank or unstyled page" % len(colours))
    if not 0.03 < frac < 0.9:
        fails.append("non-white fraction %.3f outside (0.03, 0.9)" % frac)
    if red < 30:
        fails.append("the force curve is not visible (%d < 30 samples)" % red)
    if shaded < 500:
        fails.append("the phantom top view is not visible (%d < 500 samples)" % shaded)

    dom = open(dom_path, encoding="utf-8", errors="replace").read()
    for needle in [uid, 'id="plot-force"', 'id="plot-displacement"', 'id="plot-topview"', "<polyline",
                   'class="press"', "Dr. &lt;b&gt;Lee&lt;/b&gt;", "check &lt;script&gt;"]:
        if needle not in dom:
            fails.append("DOM lacks %r" % needle)
    if "<script" in dom.lower():
        fails.append("the report must carry no script (note text must be escaped)")
    if dom.count("<polygon") < 100:
        fails.append("top view has %d mesh triangles (< 100)" % dom.count("<polygon"))
    for f in fails:
        print("FAIL:", f)
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
