#!/bin/sh
# The session report renders in headless Chromium (Debian's package): a screenshot is taken and
# its pixels checked, and the DOM is dumped and checked (tests/db/check_render.py).
# usage: test_report.sh SIM_SESSION PALP_REVIEW SCENE TMPDIR CHECK_RENDER_PY
set -eu
sim=$1 review=$2 scene=$3 tmp=$4 check=$5
chromium=/usr/bin/chromium
[ -x "$chromium" ] || { echo "FAIL: $chromium not installed (scripts/debian-packages.txt lists chromium)"; exit 1; }
dir=$tmp/report
rm -rf "$dir"
mkdir -p "$dir"
uid=report-run-7c1e-0042
"$sim" "$dir/r.db" "$uid" "$scene" 1.6 >/dev/null
"$review" --db "$dir/r.db" annotate "$uid" --author "Dr. <b>Lee</b>" --note "check <script>alert(1)</script> escaping" --level competent >/dev/null
"$review" --db "$dir/r.db" report "$uid" --out "$dir/report.html"
# Self-contained: nothing fetched from anywhere.
if grep -Eiq '(src|href)=.(https?:)?//|@import|url\(' "$dir/report.html"; then
  echo "FAIL: the report references an external resource"; exit 1
fi
. "$(dirname "$0")/../chromium.sh"
palp_chromium_render "$dir/report.html" "$dir/shot.png" "$dir/dom.html" "$dir/chromium.log" 1100x2200
[ -s "$dir/shot.png" ] || { echo "FAIL: no screenshot"; cat "$dir/chromium.log"; exit 1; }
/usr/bin/python3 "$check" "$dir/shot.png" "$dir/dom.html" "$uid"
