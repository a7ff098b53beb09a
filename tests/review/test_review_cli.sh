#!/bin/sh
# palp-review over a logged class (issue 13), real SQLite file, headless Chromium from Debian:
# show (metrics, free practice), export --table metrics, structured grades (refused forms),
# list (grade, phantom, exercise), the session report and the class report rendered and their
# DOM and pixels asserted (check_review.py), delete and prune (what stays, integrity_check).
# usage: test_review_cli.sh CLASS_DB PALP_REVIEW TMPDIR CHECK_REVIEW_PY
# CLASS_DB: the class review_gen logged (the fixture review_class_log, tests/review/CMakeLists.txt); the
# test works on a copy.
set -u
class_db=$1 review=$2 tmp=$3 check=$4
chromium=/usr/bin/chromium
[ -x "$chromium" ] || { echo "FAIL: $chromium not installed (scripts/debian-packages.txt lists chromium)"; exit 1; }
dir=$tmp/cli
rm -rf "$dir"
mkdir -p "$dir"
db=$dir/class.db
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
expect() { # expect DESCRIPTION PATTERN FILE
  if grep -Eq -- "$2" "$3"; then ok "$1"; else bad "$1: /$2/ not in $3:"; cat "$3"; fi
}
# (its writer closed: an empty WAL, if any, left beside it; the file alone is the whole log)
[ -s "$class_db" ] && [ ! -s "$class_db-wal" ] && cp "$class_db" "$db" ||
  { echo "FAIL no class logged by review_gen at $class_db (the fixture review_class_log)"; exit 1; }
R() { "$review" --db "$db" "$@"; }
# --database, palp-server's name for the same file, is taken too (session 81, docs/naming.md): the same list
"$review" --database "$db" list > "$dir/list-database.txt" 2>&1; rc=$?
R list > "$dir/list-db.txt" 2>&1
if [ $rc -eq 0 ] && cmp -s "$dir/list-database.txt" "$dir/list-db.txt" && grep -q alice "$dir/list-db.txt"; then
  ok "palp-review --database FILE list: exit 0, the same sessions as --db FILE ($(wc -l < "$dir/list-db.txt") lines)"
else bad "palp-review --database FILE list: exit $rc:"; cat "$dir/list-database.txt"; fi

R show class-alice-1 > "$dir/show-alice.txt" 2>&1 || bad "show alice exit status"
expect "show: the expert found 2 of 2" "sensitivity +2 of 2 lesions found \(100%\) +pass" "$dir/show-alice.txt"
expect "show: medium coverage >= 99%" "thoroughness +light 9[0-9]\.[0-9]%, medium (99\.[0-9]|100\.0)%" "$dir/show-alice.txt"
expect "show: vertical strip" "search pattern +vertical_strip" "$dir/show-alice.txt"
# the expert's script strokes 13-15 strips in one pass across the dome (in process: 14, order 1.00, since her deep
# press is 14.5 mm; 15 at 16 mm)
expect "show: the strips and their order" "strips +1[3-5], in order (0\.9[0-9]|1\.00) " "$dir/show-alice.txt"
# the rubric (tests/assess/exercise_expert.json, as the shipped exercises) asks for the strips' order
expect "show: the pattern's pass mark from the rubric" "search pattern +vertical_strip .* \(pass: systematic; strips in order >= 0\.70\) +pass$" "$dir/show-alice.txt"
expect "show: the order's share of the credit" "strips +1[3-5], in order (0\.9[0-9]|1\.00) .*; the rubric rests 50% of the pattern's credit on it: (0\.9[5-9]|1\.00) of 1; pass at 0\.70 +pass$" "$dir/show-alice.txt"
expect "show: score and PASS" "score +9[0-9]\.[0-9] / 100 \(pass at 70\): PASS" "$dir/show-alice.txt"
# a finger's session lists its touches on the phantom's surface, one row each, as many as the metrics' presses
# (the expert's whole search is 1 touch; bob the novice presses 5 times), not the finger slot's device point
R show class-bob-1 > "$dir/show-bob1.txt" 2>&1 || bad "show bob-1 exit status"
if python3 - "$dir/show-alice.txt" "$dir/show-bob1.txt" <<'PY'
import re, sys
for path, want in ((sys.argv[1], 1), (sys.argv[2], 5)):
    text = open(path).read()
    m = re.search(r"^where touched \(the finger's (\d+) touch(es)?, .*\n.*\n((?:    \d+ .*\n)+)", text, re.M)
    assert m and int(m.group(1)) == want and len(m.group(3).splitlines()) == want, (path, m and m.group(0))
    presses = int(re.search(r"search pattern .*?, (\d+) presses", text).group(1))
    assert presses == want, (path, presses)
    assert "where pressed" not in text, path  # no finger row with the device point above the dome
    for row in m.group(3).splitlines():
        f = row.split()
        x, y, z = (float(v) for v in f[4].split(","))
        r = (x * x + y * y + z * z) ** 0.5
        assert 38.0 <= r <= 40.5, (path, row, r)  # on the 40 mm dome's surface (dented by the press), not the device's 50+ mm
PY
then ok "show: the finger's touches, 1 for the expert and 5 for the novice, on the dome's surface"
else bad "show: the finger's touches"; cat "$dir/show-bob1.txt"; fi
# bob's second attempt came after his first had ended, and the exercise (tests/assess/exercise_expert.json)
# debriefs with the lesions' places: the review says this attempt was not blind; his first and
# alice's only attempt were (docs/assessment.md, "Debrief")
R show class-bob-2 > "$dir/show-bob2.txt" 2>&1 || bad "show bob-2 exit status"
# (bob's logs are as a server before session 59 wrote them, without their debriefs: inferred from the
# first attempt's exercise file, and said so)
expect "show: bob's second attempt is not blind, told by his first" \
  "^told +bob had been told where this exercise's lesions are when session class-bob-1 ended \(2026-01-05 [0-9:]+ [-+][0-9]{4}\): this attempt was not blind \(inferred from that session's exercise file: its log does not record what was sent\)$" \
  "$dir/show-bob2.txt"
# what each trainee was told as her session closed: alice's server logged it (review_gen: lump 1
# found by her mark 2, lump 2 by mark 1), placed by tests/assess/exercise_expert.json's angles on the
# 40 mm dome, by hand: polar 30 deg, azimuth 40 deg (from +x towards +y) is 90 - 40 = 50 deg clockwise
# from +y = 1.7 o'clock, 40 mm x 30 deg = 20.9 mm of arc; polar 50, azimuth 215: 90 - 215 + 360 = 235
# deg = 7.8 o'clock, 40 mm x 50 deg = 34.9 mm; bob's logs do not say
expect "show: alice's debrief as her server logged it, the lumps placed as the review places them" \
  "^debrief +told where each lump is: found 2 of 2 lumps; lump 1 found by mark 2 \(at 1\.7 o'clock, 21 mm from the pole\), lump 2 found by mark 1 \(at 7\.8 o'clock, 35 mm from the pole\); 2 marks standing, 0 near no lump$" \
  "$dir/show-alice.txt"
expect "show: bob's log does not say what he was told" \
  "^debrief +not in this log \(its writer logged no debriefs" "$dir/show-bob1.txt"
if grep -q "^told" "$dir/show-bob1.txt" "$dir/show-alice.txt"; then bad "show: a first attempt said to be not blind"
else ok "show: bob's first attempt and alice's say nothing of a debrief before"; fi
R show class-carol-1 > "$dir/show-carol.txt" 2>&1 || bad "show carol exit status"
expect "show: free practice named, no sensitivity" "exercise +none: free practice" "$dir/show-carol.txt"
if grep -q "^debrief" "$dir/show-carol.txt"; then bad "show: free practice with a debrief line"
else ok "show: carol's free practice has no debrief line"; fi
# The model's valid range, from the server's valid_range events (review_gen logs alice's: 355 steps
# of 4 ms, 310 deeper than validated by up to 2.4 mm, 50 with the skin beyond its range, one
# event unreadable); carol's server logged none, bob's log is from a server that did not log them.
expect "show: outside the valid range, summed by limit" \
  "^valid range OUTSIDE for 1\.42 s \(355 steps of 4 ms\): 1\.24 s pressed deeper than this place of the phantom was checked against the reference model \(by up to 2\.4 mm\); 0\.20 s the skin is stretched or bent beyond what the model describes well \(1 of 3 events unreadable: counted in the total only\)$" \
  "$dir/show-alice.txt"
if grep -E "^ +[0-9-]+ [0-9:]+ .* valid_range " "$dir/show-alice.txt" > /dev/null; then bad "show lists the valid_range events one by one"
else ok "show: valid_range events in the summary line and the totals, not listed one by one"; fi
expect "show: the totals count the flagged steps" "totals:.* valid_range 355" "$dir/show-alice.txt"
expect "show: a server that logged none: inside" "^valid range inside at every step" "$dir/show-carol.txt"
R show class-bob-1 > "$dir/show-bob.txt" 2>&1 || bad "show bob exit status"
expect "show: a log without the key does not say, and names replay" "^valid range not in this log .*palp-review replay class-bob-1" "$dir/show-bob.txt"
if grep -Eq "sensitivity +[0-9]" "$dir/show-carol.txt"; then bad "free practice shows a sensitivity"; else ok "free practice: no sensitivity line"; fi

# A SESSION argument that names no session: the number a station showed ("session 2" is the uid's
# tail) is taken when one session has it; otherwise the candidates are listed, newest first.
R show 2 > "$dir/show-2.txt" 2> "$dir/show-2.err" || bad "show 2 (one session numbered 2) exit status"
expect "show N: the one session numbered N is shown" "^session +class-bob-2 " "$dir/show-2.txt"
expect "show N: and the review says which it took" "show: \"session 2\" on the stations is class-bob-2 \(bob, " "$dir/show-2.err"
if R show 1 > "$dir/show-1.txt" 2> "$dir/show-1.err"; then bad "show 1 (three sessions numbered 1) succeeded"
elif [ -s "$dir/show-1.txt" ]; then bad "show 1 printed a session"; cat "$dir/show-1.txt"
else
  expect "show N: several sessions numbered N are listed" "show: session '1' could be any of 3 sessions .*name one by its uid:" "$dir/show-1.err"
  if python3 - "$dir/show-1.err" <<'PY'
import sys
uids = [l.split()[0] for l in open(sys.argv[1]) if l.startswith("  ")]
sys.exit(0 if uids == ["class-carol-1", "class-alice-1", "class-bob-1"] else 1)
PY
  then ok "show N: the candidates are the three sessions numbered 1, newest first"
  else bad "show N: candidates"; cat "$dir/show-1.err"; fi
fi
if R show class- > /dev/null 2> "$dir/show-prefix.err"; then bad "show class- (an ambiguous prefix) succeeded"
else expect "show PREFIX: an ambiguous prefix lists its 4 sessions" "could be any of 4 sessions \(their uids start with it\)" "$dir/show-prefix.err"; fi
if R show 7 > /dev/null 2> "$dir/show-7.err"; then bad "show 7 (no such session) succeeded"
else expect "show N: none numbered N says where to look" "show: session '7': no such session \(palp-review list shows the sessions" "$dir/show-7.err"; fi

R export class-alice-1 --format csv --table metrics --out "$dir/alice.csv" || bad "export metrics"
if python3 - "$dir/alice.csv" <<'PY'

import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 1, rows
r = rows[0]
assert r["session"] == "class-alice-1" and r["trainee"] == "alice" and r["found"] == "2" and r["pass"] == "1", r
assert float(r["coverage_medium"]) >= 0.95 and r["pattern"] == "vertical_strip", r
assert r["outside_valid_range_s"] == "1.42", r  # review_gen's 355 flagged steps of 4 ms
assert 13 <= int(r["strips"]) <= 15 and float(r["strip_order"]) >= 0.9, r  # the columns added 2026-12-04
assert (r["grade_score"], r["grade_level"]) == ("", ""), r  # not graded yet (the grade columns)
assert (r["debrief"], r["not_blind_after"]) == ("lesions", ""), r  # told the lesions at its end; a blind attempt (added last)
PY
then ok "export --table metrics: header and one row, found 2, pass 1, 1.42 s outside the valid range, 13-15 strips in order, no grade, debriefed at level lesions, blind"; else bad "export --table metrics"; fi

# Structured grades: each refused form exits 2 with a message saying what is allowed.
for g in "--score 101" "--score -1" "--score 7/10" "--level B+" "--grade B+" "--grade 7/10" "--level excellent"; do
  # shellcheck disable=SC2086
  if R annotate class-bob-1 --author Lee --note x $g > "$dir/g.txt" 2>&1; then bad "grade '$g' accepted"
  elif grep -Eq "0 to 100|0-100|insufficient, developing, competent, proficient" "$dir/g.txt"; then ok "grade '$g' refused: $(tail -1 "$dir/g.txt" | cut -c1-90)"
  else bad "grade '$g' refused without saying what is allowed: $(cat "$dir/g.txt")"; fi
done
if R annotate class-bob-1 --author Lee --note x --grade "" > "$dir/g.txt" 2>&1; then bad "empty grade accepted"; else ok "empty grade refused"; fi
R annotate class-bob-1 --author Lee --note "missed both lumps" --score 35 > /dev/null || bad "score 35"
R annotate class-alice-1 --author Lee --note "systematic" --level proficient > /dev/null || bad "level proficient"
R list > "$dir/list.txt" 2>&1
expect "list: alice's grade, phantom and exercise" "class-alice-1 +alice +dome_breast_test +test-two-lumps .* proficient" "$dir/list.txt"
expect "list: bob's score" "class-bob-1 +bob .* 35" "$dir/list.txt"
# what is left to grade: the two sessions no note grades (2026-12-05)
R list --ungraded > "$dir/ungraded.txt" 2>&1 || bad "list --ungraded"
if [ "$(awk 'NR > 1 && $1 ~ /^class-/ { print $1 }' "$dir/ungraded.txt" | tr '\n' ' ')" = "class-bob-2 class-carol-1 " ] &&
   grep -q '^2 sessions not graded yet$' "$dir/ungraded.txt" && ! grep -q 'refused by DDS Security' "$dir/ungraded.txt"; then
  ok "list --ungraded: class-bob-2 and class-carol-1, not the graded alice-1 and bob-1"
else bad "list --ungraded:"; cat "$dir/ungraded.txt"; fi

# Reports in headless Chromium, no network.
. "$(dirname "$0")/../chromium.sh"
R report class-alice-1 --out "$dir/alice.html" > /dev/null || bad "report alice"
R report class-bob-1 --out "$dir/bob.html" > /dev/null || bad "report bob"
R report class-bob-2 --out "$dir/bob2.html" > /dev/null || bad "report bob-2"
expect "report: bob's second attempt is not blind" '<p class="warn" id="told-before">bob had been told where this exercise&#39;s lesions are when session class-bob-1 ended' "$dir/bob2.html"
if grep -q 'id="told-before"' "$dir/bob.html" "$dir/alice.html"; then bad "report: a first attempt said to be not blind"
else ok "report: bob's first attempt and alice's say nothing of a debrief before"; fi
expect "report: alice's debrief as logged" \
  '<p id="debrief">Debrief as the session ended: told where each lump is: found 2 of 2 lumps; lump 1 found by mark 2 \(at 1\.7 o&#39;clock, 21 mm from the pole\), lump 2 found by mark 1' "$dir/alice.html"
# the instructor's structured grades (score, level) in the report's notes and the JSON export: both read
# only the free-text grade column until 2026-12-05, so they showed none
expect "report: alice's note with its level" '<tr><td>[^<]*</td><td>Lee</td><td>proficient</td><td>systematic</td></tr>' "$dir/alice.html"
expect "report: bob's note with its score" '<tr><td>[^<]*</td><td>Lee</td><td>35</td><td>missed both lumps</td></tr>' "$dir/bob.html"
R export class-bob-1 --format json --out "$dir/bob.json" || bad "export json"
if python3 -c "import json, sys; n = json.load(open(sys.argv[1]))['notes']; assert [(x['text'], x['grade']) for x in n if x['grade']] == [('missed both lumps', '35')], n" "$dir/bob.json"
then ok "export json: bob's note with its score"; else bad "export json: the notes' grades"; fi
# A log whose feedback table cannot be read (session 90's review): export keeps the whole file already
# there (before: replaced by the cut export, invalid JSON, exit 2), show says where the presses go that
# they are unreadable and exits 2 (before: "0 force contacts, 0 fingers", exit 0); and annotate takes no
# prefix of a uid (before: "annotate class-bob" graded whichever one session its prefix matched).
cp "$db" "$dir/cut.db" && sqlite3 "$dir/cut.db" "DROP TABLE feedback" || bad "a copy without its feedback table"
cp "$dir/bob.json" "$dir/bob-whole.json"
"$review" --db "$dir/cut.db" export class-bob-1 --format json --out "$dir/bob.json" > "$dir/cut-export.txt" 2>&1; rc=$?
if [ $rc -eq 2 ] && cmp -s "$dir/bob.json" "$dir/bob-whole.json" &&
   grep -q "export: the feedback could not be read: .* (not written; the file already there is kept)" "$dir/cut-export.txt"
then ok "export over an unreadable feedback table: exit 2, the whole export already there kept"
else bad "export over an unreadable feedback table: exit $rc: $(cat "$dir/cut-export.txt")"; fi
"$review" --db "$dir/cut.db" show class-bob-1 > "$dir/cut-show.txt" 2>&1; rc=$?
if [ $rc -eq 2 ] && grep -q "^contacts .* inputs; their presses UNREADABLE: the feedback table could not be read" "$dir/cut-show.txt"
then ok "show over an unreadable feedback table: the presses said UNREADABLE, exit 2"
else bad "show over an unreadable feedback table: exit $rc:"; cat "$dir/cut-show.txt"; fi
notes0=$(sqlite3 "$dir/cut.db" "SELECT COUNT(*) FROM note")
"$review" --db "$dir/cut.db" annotate class-bob-2 --author Lee --note "whole uid" > /dev/null 2>&1 || bad "annotate class-bob-2"
"$review" --db "$dir/cut.db" annotate class-alice --author Lee --note x --score 80 > "$dir/cut-annotate.txt" 2>&1; rc=$?
notes1=$(sqlite3 "$dir/cut.db" "SELECT COUNT(*) FROM note")
if [ $rc -eq 2 ] && [ "$notes1" = $((notes0 + 1)) ] && grep -q "never the start of a uid" "$dir/cut-annotate.txt"
then ok "annotate: a whole uid graded, the prefix class-alice refused (exit 2, no note: $notes0 -> $notes1 with the one above)"
else bad "annotate by a prefix: exit $rc, notes $notes0 -> $notes1: $(cat "$dir/cut-annotate.txt")"; fi
expect "report: the strips and their order" '<tr data-metric="strips"><th>Strips and their order</th><td class="value">1[3-5] strips, in order (0\.9[0-9]|1\.00)' "$dir/alice.html"
expect "report: the touches table, the expert's one touch" '<table id="touches">.*' "$dir/alice.html"
if [ "$(sed -n '/<table id="touches">/,/<\/table>/p' "$dir/bob.html" | grep -c '^<tr><td>')" = 5 ]; then
  ok "report: the novice's 5 touches in the touches table"
else bad "report: the novice's touches table"; sed -n '/<table id="touches">/,/<\/table>/p' "$dir/bob.html"; fi
# the top view marks each touch where it came down (not all at the centre: the novice pressed at 5 places)
if python3 - "$dir/bob.html" <<'PY'
import re, sys
c = [(float(x), float(y)) for x, y in re.findall(r'<circle class="touch" cx="([-0-9.]+)" cy="([-0-9.]+)"', open(sys.argv[1]).read())]
assert len(c) == 5, c
assert max(((x - 220) ** 2 + (y - 220) ** 2) ** 0.5 for x, y in c) > 20, c  # 220, 220: the pole; 190 px: the rim
PY
then ok "report: the top view marks the novice's 5 touches where they came down"
else bad "report: the top view's touches"; fi
expect "report: the pattern's pass mark from the rubric" '<tr data-metric="pattern"><th>Search pattern</th><td class="value">vertical_strip [^<]*</td><td>systematic; strips in order &gt;= 0\.70</td><td class="pass">' "$dir/alice.html"
expect "report: what the rubric asks of the order" '<tr data-metric="strips">.*</td><td>&gt;= 0\.70; 50% of the pattern&#39;s credit \((0\.9[5-9]|1\.00) of 1\)</td><td class="pass">pass</td>' "$dir/alice.html"
R class --exercise test-two-lumps --out "$dir/class.html" --csv "$dir/class.csv" > "$dir/class.txt" || bad "class report"
expect "class: the text table has alice's row" "^alice +class-alice-1 +2026-01-06 +2/2 +0 " "$dir/class.txt"
expect "class: bob's second attempt is said not to be blind, under the table" \
  "^not blind: class-bob-2: bob had been told where this exercise's lesions are when session class-bob-1 ended" "$dir/class.txt"
if [ "$(grep -c '^not blind:' "$dir/class.txt")" = 1 ] && [ "$(grep -c 'class="fail told-before"' "$dir/class.html")" = 1 ] &&
  grep -q '<p class="fail told-before">Not blind: class-bob-2: bob had been told' "$dir/class.html"; then
  ok "class: only bob's second attempt is not blind, in the text and the HTML report"
else bad "class: the not-blind attempts"; grep -n "not blind\|told-before" "$dir/class.txt" "$dir/class.html"; fi
pages=
for f in alice bob class; do
  if grep -Eiq '(src|href)=.(https?:)?//|@import|url\(' "$dir/$f.html"; then bad "$f.html references an external resource"; fi
  pages="$pages $dir/$f.html $dir/$f.png $dir/$f.dom.html"
done
# shellcheck disable=SC2086 # the pages' paths, three a page (the build directory's: no spaces)
palp_chromium_render_many 1100x2400 "$dir/chromium.log" $pages > "$dir/render.txt" 2>&1 || {
  echo "FAIL: chromium rendered nothing"; cat "$dir/render.txt" "$dir/chromium.log"; exit 1; }
for f in alice bob class; do
  [ -s "$dir/$f.png" ] && [ -s "$dir/$f.dom.html" ] || { echo "FAIL: chromium rendered nothing of $f.html"; exit 1; }
done
python3 "$check" session-expert "$dir/alice.dom.html" "$dir/alice.png" || fail=1
python3 "$check" session-novice "$dir/bob.dom.html" "$dir/bob.png" || fail=1
python3 "$check" class "$dir/class.dom.html" "$dir/class.png" "$dir/class.csv" || fail=1
# Reports and exports carry trainees' names and grades: a file palp-review creates is its owner's alone.
modes=$(cd "$dir" && stat -c '%n %a' alice.csv alice.html bob.html class.html class.csv | tr '\n' ' ')
if [ "$(cd "$dir" && stat -c '%a' alice.csv alice.html bob.html class.html class.csv | sort -u)" = 600 ]; then
  ok "the export, reports and class files are created mode 0600: $modes"
else
  bad "created files' modes (want 600): $modes"
fi
if R class --exercise no-such-exercise --out "$dir/none.html" > "$dir/none.txt" 2>&1; then bad "class for an unknown exercise succeeded"
else expect "class: unknown exercise named in the error" "no-such-exercise" "$dir/none.txt"; fi

# One trainee's record (session 65): bob's two attempts oldest first, the first blind and the second
# not (as show says), each score and verdict show's, his exercise's scores in order, and what to work
# on: the metrics show marks FAIL for his latest attempt, in the words his station uses (the test's
# own table below, not the code's).
R trainee bob --csv "$dir/bob-record.csv" --out "$dir/bob-record.html" > "$dir/trainee-bob.txt" 2> "$dir/trainee-bob.err" ||
  bad "trainee bob exit status"
R show class-bob-2 > "$dir/show-bob2-again.txt" 2>&1
if python3 - "$dir/trainee-bob.txt" "$dir/show-bob1.txt" "$dir/show-bob2-again.txt" "$dir/bob-record.csv" "$dir/bob-record.html" <<'PY'
import csv, html, re, sys
text = open(sys.argv[1]).read()
shows = [open(p).read() for p in sys.argv[2:4]]
lines = text.splitlines()
assert lines[0] == "trainee bob: 2 sessions assessed, 2026-01-05 to 2026-01-07: 2 of exercises, 0 of free practice", lines[0]
rows = [l.split() for l in lines if l.startswith("class-")]
assert [r[0] for r in rows] == ["class-bob-1", "class-bob-2"], rows
scores = []
for r, show in zip(rows, shows):
    m = re.search(r"score +([0-9.]+) / 100 \(pass at \d+\): (PASS|FAIL)", show)
    found = re.search(r"sensitivity +(\d+) of (\d+) lesions", show)
    assert m and r[3] == "%s/%s" % found.groups() and r[2] == "test-two-lumps", (r, show[:200])
    # SCORE RUBRIC BLIND GRADE are the last four columns
    assert r[-4] == m.group(1) and r[-3] == m.group(2).lower(), (r, m.groups())
    scores.append(m.group(1))
assert [r[-2] for r in rows] == ["yes", "no"], rows  # bob-2 came after bob-1's debrief told the lesions
assert [r[-1] for r in rows] == ["35", "-"], rows  # the grade annotate gave bob-1 above; none for bob-2
assert "  test-two-lumps   scores %s, %s; passed 0 of 2; latest %s fail" % (scores[0], scores[1], scores[1]) in lines, text
words = {"sensitivity": "finding the lumps", "false positives": "marking only lumps",
         "thoroughness": "covering the whole dome at each pressure", "search pattern": "a systematic search pattern",
         "time": "finishing within the time", "force": "pressing within the force limit"}
failed = [w for k, w in words.items() if re.search(r"^  %s .*FAIL$" % k, shows[1], re.M)]
i = lines.index("to work on (what the latest session of each exercise did not pass, the most often first):")
listed = [re.sub(r" \(1 of 1 exercise\)$", "", l.strip()) for l in lines[i + 1:i + 1 + len(failed)]]
assert failed and listed == failed, (failed, lines[i:])
assert "not blind: class-bob-2: bob had been told where this exercise's lesions are" in text, text
got = [r["session"] for r in csv.DictReader(open(sys.argv[4]))]
assert got == ["class-bob-1", "class-bob-2"], got
# the page (--out): the same sessions, scores, blindness, grades and words, self-contained
page = open(sys.argv[5]).read()
cells = lambda cls: [html.unescape(c) for c in re.findall(r'<td class="[^"]*\b%s\b[^"]*">([^<]*)</td>' % cls, page)]
assert cells("session") == ["class-bob-1", "class-bob-2"] and cells("score") == scores, (cells("session"), cells("score"))
assert cells("blind") == ["yes", "no"] and cells("grade") == ["35", "-"], (cells("blind"), cells("grade"))
assert re.findall(r'<li data-metric="[a-z_]+">([^<(]*) \(1 of 1 exercise\)</li>', page) == failed, page
assert '<td class="t scores">%s, %s</td>' % (scores[0], scores[1]) in page and '<svg' in page, page
assert "Not blind: class-bob-2: bob had been told" in html.unescape(page), page
assert not re.search(r"(src|href)=.(https?:)?//|@import|url\(|<script", page, re.I), "external resource or script"
PY
then ok "trainee bob: his two attempts in order, blind then not, the scores and verdicts show gives, what to work on; the page the same"
else bad "trainee bob"; cat "$dir/trainee-bob.txt" "$dir/trainee-bob.err"; fi
if [ "$(stat -c '%a' "$dir/bob-record.html" "$dir/bob-record.csv" | sort -u)" = 600 ]; then
  ok "trainee: the record's page and CSV are created mode 0600"
else bad "trainee: the record's modes: $(stat -c '%n %a' "$dir/bob-record.html" "$dir/bob-record.csv" | tr '\n' ' ')"; fi
# A write that fails (2026-12-06, found by review: exit 2 and nothing said; --csv - mixed the CSV with the
# text table on stdout): /dev/full takes the open and refuses every write. Each file named, with why, exit 2;
# --csv - puts the CSV alone on stdout, the same bytes as the file, and its failure is said as well.
for args in "class --exercise test-two-lumps --out /dev/full" \
            "class --exercise test-two-lumps --out $dir/full.html --csv /dev/full" \
            "trainee bob --out /dev/full" "trainee bob --csv /dev/full"; do
  # shellcheck disable=SC2086
  R $args > /dev/null 2> "$dir/full.err"; rc=$?
  if [ $rc = 2 ] && grep -Eq "(class|trainee): /dev/full: No space left on device" "$dir/full.err"; then ok "$args: exit 2, said: $(tail -1 "$dir/full.err" | sed 's/.*ERROR *//')"
  else bad "$args: exit $rc, stderr:"; cat "$dir/full.err"; fi
done
R class --exercise test-two-lumps --out "$dir/class-pipe.html" --csv - > "$dir/class-stdout.csv" 2> "$dir/class-stdout.err" || bad "class --csv - exit status"
R trainee bob --csv - > "$dir/bob-stdout.csv" 2> "$dir/bob-stdout.err" || bad "trainee --csv - exit status"
if cmp -s "$dir/class-stdout.csv" "$dir/class.csv" && cmp -s "$dir/bob-stdout.csv" "$dir/bob-record.csv" &&
   grep -Eq "^alice +class-alice-1" "$dir/class-stdout.err" && grep -q "^trainee bob: 2 sessions assessed" "$dir/bob-stdout.err"; then
  ok "class and trainee --csv -: stdout the CSV alone (the file's bytes), the text table on stderr"
else bad "--csv -: stdout not the CSV alone"; head -3 "$dir/class-stdout.csv" "$dir/bob-stdout.csv"; fi
for cmd in class trainee; do
  if [ $cmd = class ]; then set -- class --exercise test-two-lumps --out "$dir/class-pipe.html" --csv -; else set -- trainee bob --csv -; fi
  R "$@" > /dev/full 2> "$dir/full.err"; rc=$?
  if [ $rc = 2 ] && grep -q "$cmd: standard output: No space left on device" "$dir/full.err"; then ok "$cmd --csv - > /dev/full: exit 2, said"
  else bad "$cmd --csv - > /dev/full: exit $rc"; cat "$dir/full.err"; fi
done
# A write that fails half way over a report already there (session 82): the report is written beside
# its name and renamed over it only when whole, so the old one is kept, byte for byte, and no
# temporary file is left. RLIMIT_FSIZE (ulimit -f, in 512-byte blocks; SIGXFSZ ignored so that write()
# says EFBIG) stops every write at 64 KiB: above the log's 32 KiB -shm, below both pages (the session's
# 300 KiB, the class's 560 KiB; this log's exports are smaller). export and the CSVs take the same
# review_fopen_out and review_close_out (client/review/out_file.c).
cp "$dir/alice.html" "$dir/kept.html"
for args in "report class-alice-1 --out $dir/kept.html" "class --exercise test-two-lumps --out $dir/kept.html"; do
  # shellcheck disable=SC2086
  (trap '' XFSZ; ulimit -f 128; R $args) > /dev/null 2> "$dir/fsize.err"; rc=$?
  if [ $rc = 2 ] && grep -q ": File too large (not written; a file already there is kept)" "$dir/fsize.err" &&
     cmp -s "$dir/kept.html" "$dir/alice.html" && [ -z "$(find "$dir" -name '*.palp-*')" ]; then
    ok "$args, files limited to 64 KiB: exit 2, said, the file there before kept byte for byte, no temporary left"
  else bad "$args under ulimit -f 128: exit $rc, $(wc -c < "$dir/kept.html") bytes kept of $(wc -c < "$dir/alice.html"):"
    cat "$dir/fsize.err"; find "$dir" -name '*.palp-*'; fi
done
R report class-alice-1 --out "$dir/kept.html" > /dev/null 2>&1 || bad "report over kept.html"
if [ "$(stat -c %a "$dir/kept.html")" = 600 ] && cmp -s "$dir/kept.html" "$dir/alice.html"; then
  ok "report over an existing page: renamed into place, mode 0600, the same bytes as the first"
else bad "report over kept.html: mode $(stat -c %a "$dir/kept.html")"; fi
# what list and show print, on a full disk (2026-12-06, found by review: exit 0, the text lost unsaid)
for args in "list" "show class-alice-1"; do
  # shellcheck disable=SC2086
  R $args > /dev/full 2> "$dir/full.err"; rc=$?
  if [ $rc = 2 ] && grep -q "^palp-review: stdout: No space left on device" "$dir/full.err"; then ok "$args > /dev/full: exit 2, said"
  else bad "$args > /dev/full: exit $rc"; cat "$dir/full.err"; fi
done
R trainee carol > "$dir/trainee-carol.txt" 2>&1 || bad "trainee carol exit status"
expect "trainee carol: one session of free practice, no score" \
  "^class-carol-1 +2026-01-08 +\(practice\) +- +[0-9]+ .* +- +- +- +-$" "$dir/trainee-carol.txt"
# A trainee with nothing to assess (2026-12-06, found by review: --csv and --out were not written, an
# earlier run's files left standing, and a session left out by an error counted as "0 of force contacts
# only"): dan's two sessions in a copy of the log, one of force contacts only (carol's scene, no finger
# samples), one whose logged exercise does not parse. His record is written all the same (the CSV's
# header alone, a page saying why), exit 0, and the line and the page give both reasons, counted.
python3 - "$db" "$dir/dan.db" <<'PY' || bad "making dan's log"
import sqlite3, sys
src, c = sqlite3.connect(sys.argv[1]), sqlite3.connect(sys.argv[2])
src.backup(c)
for uid, day in (("class-dan-1", 3), ("class-dan-2", 4)):
    c.execute("insert into session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, tick_hz, dt_s, "
              "start_unix_s) select ?, 'dan', station, phantom_id, phantom_name, scene_json, '{}', tick_hz, dt_s, "
              "start_unix_s + ? * 86400 from session where uid = 'class-carol-1'", (uid, day))
c.execute("insert into session_exercise(session_id, exercise_name, exercise_json) "
          "select id, 'broken', '{\"name\": \"broken\", \"lesions\": [' from session where uid = 'class-dan-2'")
c.commit()
PY
echo "stale: an earlier run's record" > "$dir/dan.csv"
echo "stale: an earlier run's record" > "$dir/dan.html"
if "$review" --db "$dir/dan.db" trainee dan --csv "$dir/dan.csv" --out "$dir/dan.html" > "$dir/trainee-dan.txt" 2> "$dir/trainee-dan.err"; then
  summary="trainee dan: 2 sessions, none assessed; 1 of force contacts only (nothing to assess); 1 left out, could not be assessed (palp-review show SESSION says why)"
  if [ "$(head -1 "$dir/trainee-dan.txt")" = "$summary" ] && grep -q "class-dan-2 left out" "$dir/trainee-dan.err" &&
     [ "$(cat "$dir/dan.csv")" = "$(head -1 "$dir/bob-record.csv")" ] && ! grep -q stale "$dir/dan.html" &&
     grep -qF "<p id=\"summary\">$summary." "$dir/dan.html" && grep -q '<p id="nothing">' "$dir/dan.html" &&
     ! grep -q '<table' "$dir/dan.html"; then
    ok "trainee dan (nothing to assess): exit 0, the CSV's header alone and a page saying why written over the old files, both reasons counted"
  else bad "trainee dan (nothing to assess)"; cat "$dir/trainee-dan.txt" "$dir/trainee-dan.err" "$dir/dan.csv" "$dir/dan.html"; fi
else bad "trainee dan (nothing to assess) exit status"; cat "$dir/trainee-dan.txt" "$dir/trainee-dan.err"; fi
# --until a date alone takes in that whole day (session 90's review: it was the day's 00:00, so a day's
# own sessions were left out and --since D --until D found none); the sessions start at 11:00 UTC
R list --until 2026-01-05 > "$dir/until.txt" 2>&1
R trainee alice --since 2026-01-06 --until 2026-01-06 > "$dir/trainee-day.txt" 2>&1; rc=$?
if grep -q "^class-bob-1 " "$dir/until.txt" && grep -q "^1 session$" "$dir/until.txt" && [ $rc -eq 0 ] &&
   grep -q "class-alice-1" "$dir/trainee-day.txt"
then ok "--until 2026-01-05 lists that day's class-bob-1 (1 session); trainee alice on 2026-01-06 alone finds hers"
else bad "--until a date alone: exit $rc"; cat "$dir/until.txt" "$dir/trainee-day.txt"; fi
if R trainee alice --since 2026-01-07 > "$dir/trainee-none.txt" 2>&1; then bad "trainee alice since 2026-01-07 (none) succeeded"
else expect "trainee: none in the time asked, said" "no session of trainee 'alice' in that time" "$dir/trainee-none.txt"; fi
if R trainee > "$dir/trainee-noname.txt" 2>&1; then bad "trainee without a name succeeded"
else expect "trainee: the name is asked for" "NAME is required" "$dir/trainee-noname.txt"; fi

# prune --keep-graded over notes that cannot be read keeps every session, saying why (session 90's review:
# an unreadable note table read as "no grade" and graded sessions lost their frames for good)
# (a note table whose grade columns are gone: the sessions list, their grades cannot be read)
cp "$db" "$dir/nonotes.db" && sqlite3 "$dir/nonotes.db" "ALTER TABLE note RENAME TO note_x;
  CREATE VIEW note AS SELECT id, session_id, wall_unix_s, author, text FROM note_x" || bad "a copy whose notes cannot be read"
"$review" --db "$dir/nonotes.db" prune --older-than 1 --keep-graded > "$dir/prune-nonotes.txt" 2>&1
if [ "$(grep -c '^kept   class-[a-z]*-[0-9]: its grade could not be read' "$dir/prune-nonotes.txt")" = 4 ] &&
   ! grep -q '^pruned' "$dir/prune-nonotes.txt"
then ok "prune --keep-graded, the notes unreadable: the 4 sessions kept, none pruned"
else bad "prune --keep-graded, the notes unreadable:"; cat "$dir/prune-nonotes.txt"; fi
# Retention: prune keeps graded sessions; pruned ones keep their metrics; delete removes one.
R prune --older-than 1 --keep-graded > "$dir/prune.txt" 2>&1 || bad "prune exit status"
expect "prune: graded sessions kept" "kept +class-alice-1: graded" "$dir/prune.txt"
expect "prune: bob's second session pruned" "pruned class-bob-2" "$dir/prune.txt"
R show class-bob-2 > "$dir/show-pruned.txt" 2>&1
expect "a pruned session still shows its metrics" "stored when the session was pruned" "$dir/show-pruned.txt"
# the session report's paragraph of stored metrics: bob-2's exercise with its lesions and score, carol's free
# practice with neither (2026-12-06, found by review: "0 of 0 lesions found ... score 0.0 (fail)", its NULL
# score read as 0), its coverage as show gave it before the prune
R report class-bob-2 --out "$dir/bob2-pruned.html" > /dev/null 2>&1 || bad "report of a pruned session"
R report class-carol-1 --out "$dir/carol-pruned.html" > /dev/null 2>&1 || bad "report of a pruned free practice"
if python3 - "$dir/bob2-pruned.html" "$dir/carol-pruned.html" "$dir/show-carol.txt" "$dir/class.csv" <<'PY'
import csv, re, sys
para = lambda p: re.search(r'<p id="assessment-pruned">([^<]*)</p>', open(p).read()).group(1)
b2 = para(sys.argv[1])
score = {r["session"]: r["score"] for r in csv.DictReader(open(sys.argv[4]))}["class-bob-2"]
assert "0 of 2 lesions found" in b2 and ("score %s (fail)" % score) in b2, (b2, score)
c = para(sys.argv[2])
light = re.search(r"thoroughness +light ([0-9.]+)%, medium ([0-9.]+)%, deep ([0-9.]+)%", open(sys.argv[3]).read()).groups()
m = re.search(r"free practice: no hidden lesions, no score\): \d+ marks? \(\d+ withdrawn\), coverage light/medium/deep "
              r"([0-9.]+)% / ([0-9.]+)% / ([0-9.]+)%, pattern [a-z_]+\.$", c)
assert m and m.groups() == light, (c, light)
assert not re.search(r"score [0-9]|lesions found|\((fail|pass)\)", c), c
PY
then ok "report of pruned sessions: bob-2's stored lesions and score, carol's free practice without either"
else bad "report of pruned sessions"; grep -h 'assessment-' "$dir/bob2-pruned.html" "$dir/carol-pruned.html"; fi
# the strips are among the stored metrics since schema 5: the pruned session's CSV fields as before the
# prune; a row stored before schema 5 (NULL) has them unknown (empty), not none (0)
R class --exercise test-two-lumps --out "$dir/class-pruned.html" --csv "$dir/class-pruned.csv" > /dev/null 2>&1 ||
  bad "class report after the prune"
if python3 - "$dir/class.csv" "$dir/class-pruned.csv" <<'PY'
import csv, sys
before = {r["session"]: r for r in csv.DictReader(open(sys.argv[1]))}
rows = {r["session"]: r for r in csv.DictReader(open(sys.argv[2]))}
b2 = rows["class-bob-2"]
assert b2["strips"] != "" and (b2["strips"], b2["strip_order"]) == (before["class-bob-2"]["strips"], before["class-bob-2"]["strip_order"]), (b2, before["class-bob-2"])
a1 = rows["class-alice-1"]  # the expert's strips (13-15, as above), counted again: the same as before the prune
assert 13 <= int(a1["strips"]) <= 15 and a1["strips"] == before["class-alice-1"]["strips"] and rows["class-bob-1"]["strips"] == "0", rows
PY
then ok "class CSV after the prune: the pruned session's strips stored as computed before it, the others' counted"
else bad "class CSV after the prune"; fi
# the overlap and the share never palpated are not among the stored metrics (0004_retention.sql): empty
# fields for the pruned session in every metrics CSV (they said 0.000 and 0.0000, "nothing left
# unpalpated", until 2026-12-06), the columns after them where they were; the sessions still whole keep theirs
R export class-bob-2 --format csv --table metrics --out "$dir/bob2-pruned.csv" > /dev/null 2>&1 || bad "export metrics of a pruned session"
R trainee bob --csv "$dir/bob-record-pruned.csv" > /dev/null 2>&1 || bad "trainee bob after the prune"
if python3 - "$dir/class.csv" "$dir/class-pruned.csv" "$dir/bob2-pruned.csv" "$dir/bob-record-pruned.csv" <<'PY'
import csv, sys
before = {r["session"]: r for r in csv.DictReader(open(sys.argv[1]))}
assert float(before["class-bob-2"]["gap_share"]) > 0.5, before["class-bob-2"]  # the novice left most of the dome
for path in sys.argv[2:]:
    rows = {r["session"]: r for r in csv.DictReader(open(path))}
    b2 = rows["class-bob-2"]
    assert (b2["overlap"], b2["gap_share"]) == ("", ""), (path, b2)
    for k in ("presses", "duration_s", "peak_force_n", "out_of_range", "score", "pass"):
        assert b2[k] == before["class-bob-2"][k], (path, k, b2[k], before["class-bob-2"][k])
    for uid in set(rows) - {"class-bob-2"}:
        assert float(rows[uid]["overlap"]) >= 1.0 and 0.0 <= float(rows[uid]["gap_share"]) <= 1.0, (path, rows[uid])
PY
then ok "class, export and trainee CSVs after the prune: the pruned session's overlap and gap_share empty, its other columns as before"
else bad "the pruned session's overlap and gap_share in the CSVs"; head -3 "$dir/class-pruned.csv" "$dir/bob2-pruned.csv" "$dir/bob-record-pruned.csv"; fi
python3 -c "import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); c.execute('update session_metrics set strips = NULL, strip_order = NULL'); c.commit()" "$db" ||
  bad "clearing the stored strips"
R class --exercise test-two-lumps --out "$dir/class-v4.html" --csv "$dir/class-v4.csv" > /dev/null 2>&1 ||
  bad "class report over metrics stored before schema 5"
if python3 - "$dir/class-v4.csv" <<'PY'
import csv, sys
rows = {r["session"]: r for r in csv.DictReader(open(sys.argv[1]))}
assert (rows["class-bob-2"]["strips"], rows["class-bob-2"]["strip_order"]) == ("", ""), rows["class-bob-2"]
PY
then ok "class CSV: metrics stored before schema 5 have the strips empty (unknown), not 0"
else bad "class CSV over metrics stored before schema 5"; fi
R delete class-carol-1 > /dev/null 2>&1 || bad "delete"
if python3 - "$db" <<'PY'

import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
assert c.execute("pragma integrity_check").fetchone()[0] == "ok"
sid = dict(c.execute("select uid, id from session"))
assert "class-carol-1" not in sid, sid
n = lambda q, *a: c.execute(q, a).fetchone()[0]
assert n("select count(*) from finger_sample where session_id = ?", sid["class-bob-2"]) == 0
assert n("select count(*) from finger_sample where session_id = ?", sid["class-alice-1"]) > 20000  # the expert's exam kept (28,589 samples on the breast-tissue test phantom)
assert n("select count(*) from finding where session_id = ?", sid["class-bob-2"]) >= 1
assert n("select count(*) from session_metrics where session_id = ?", sid["class-bob-2"]) == 1
assert n("select count(*) from note where session_id = ?", sid["class-bob-1"]) == 1
PY
then ok "after prune and delete: integrity ok, samples only for kept sessions, findings/metrics/notes kept"
else bad "after prune and delete"; fi
# A session with no end logged, begun after a writer still open opened the file (a writer_run not
# closed, its process this shell, alive): delete refuses it; one begun before (a dead writer's, cut
# short: a crash logs no end) is deleted beside it (the writer may still be writing it, and a deleted row's id is
# the next session's: its later records would land there) and deletes nothing, and neither delete nor
# prune compacts the file under the writer; once the writer's process is gone (a crash: its row never
# closed) a prune with nothing to prune compacts the pages freed before, and the same delete succeeds.
python3 - "$db" $$ <<'PY' || bad "making a running session"
import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
c.execute("insert into writer_run(app_version, pid, opened_unix_s) values('test', ?, 100)", (int(sys.argv[2]),))
for uid, start in (("live-1", 200), ("old-1", 50)):  # begun after the writer opened the file, and before
    c.execute("insert into session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, tick_hz, "
              "dt_s, start_unix_s) values(?, 'ida', 's', '1', 'p', '{}', '{}', 100, 0.01, ?)", (uid, start))
c.commit()
PY
if R delete class-bob-1 live-1 > "$dir/delete-live.txt" 2>&1; then bad "delete of a session a live writer may be writing succeeded"
else expect "delete: a running session beside a live writer is refused, and why" \
  "delete: session 'live-1' has no end logged and a session log writer \(pid $$\) has had the file open since before it began: .* nothing deleted" \
  "$dir/delete-live.txt"; fi
n_left=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute(\"select count(*) from session where uid in ('class-bob-1', 'live-1')\").fetchone()[0])" "$db")
[ "$n_left" = 2 ] && ok "  nothing deleted, class-bob-1 named before it included (2 of 2 kept)" || bad "  $n_left of 2 sessions kept"
R delete class-bob-1 old-1 > "$dir/delete-beside.txt" 2>&1 || bad "delete of an ended session, and one cut short before the writer opened, beside a live writer"
expect "delete beside a live writer: an ended session and one cut short before it opened go, the file is not compacted under the writer" \
  "^not compacted: a session log writer \(pid $$\) has the file open" "$dir/delete-beside.txt"
free_before=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('pragma freelist_count').fetchone()[0])" "$db")
sh -c 'echo $$' > "$dir/dead.pid" # a process that has exited: the writer that crashed
python3 -c "import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); c.execute('update writer_run set pid = ? where app_version = \"test\"', (int(sys.argv[2]),)); c.commit()" "$db" "$(cat "$dir/dead.pid")"
R prune --older-than 100000 > "$dir/prune-none.txt" 2>&1 || bad "prune with nothing to prune"
free_after=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('pragma freelist_count').fetchone()[0])" "$db")
R delete live-1 > "$dir/delete-dead.txt" 2>&1 || { bad "delete of a session whose writer died"; cat "$dir/delete-dead.txt"; }
gone=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute(\"select count(*) from session where uid = 'live-1'\").fetchone()[0])" "$db")
[ "$gone" = 0 ] && [ "${free_before:-0}" -gt 0 ] && [ "$free_after" = 0 ] &&
  ok "its writer gone, the running session is deleted; the pages freed beside the writer are given back (free pages $free_before -> $free_after)" ||
  bad "after the writer died: live-1 rows $gone, free pages $free_before -> $free_after"
# Session 81 review fixes. mklog FILE UID...: an empty log of this schema (class.db's, its meta rows) with
# ended sessions of those uids, started 1000 s apart in that order, trainee t-UID.
mklog() {
  python3 - "$db" "$@" <<'PY2'
import sqlite3, sys
src, dst, uids = sys.argv[1], sys.argv[2], sys.argv[3:]
s = sqlite3.connect(src)
d = sqlite3.connect(dst)
for (sql,) in s.execute("select sql from sqlite_master where sql is not null and name not like 'sqlite_%' "
                        "order by type = 'table' desc, rowid"):
    d.execute(sql)
d.executemany("insert into meta(key, value) values(?, ?)", s.execute("select key, value from meta"))
d.execute("pragma user_version = %d" % s.execute("pragma user_version").fetchone()[0])
scene = s.execute("select scene_json from session order by id limit 1").fetchone()[0]  # one that parses: prunable
for k, uid in enumerate(uids):
    d.execute("insert into session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, tick_hz, "
              "dt_s, start_unix_s, end_unix_s, end_reason) values(?, ?, 's', '1', 'p', ?, '{}', 100, 0.01, ?, ?, "
              "'normal')", (uid, "t-" + uid, scene, 1.7e9 + 1000 * k, 1.7e9 + 1000 * k + 60))
d.commit()
PY2
}
uids_left() { python3 -c "import sqlite3,sys; print(' '.join(r[0] for r in sqlite3.connect(sys.argv[1]).execute('select uid from session order by uid')))" "$1"; }
# 2. a SESSION argument: delete takes no prefix, and says the uid it deleted; a number is a station's
# session number before it is a prefix (by hand: "3" is the station's number of a41d0b-3 and a prefix of
# 3f9c1e-7; "1" is the station's number of 1795482287-28255-1 and a prefix of all three uids there)
mklog "$dir/names.db" run7-1 run7-10
"$review" --db "$dir/names.db" delete run7-1 > "$dir/names1.txt" 2>&1 || bad "delete run7-1 (an exact uid)"
expect "delete prints the uid it deleted" "^deleted run7-1$" "$dir/names1.txt"
if "$review" --db "$dir/names.db" delete run7-1 > "$dir/names2.txt" 2>&1; then bad "delete run7-1 again succeeded: $(cat "$dir/names2.txt")"
else expect "delete run7-1 again: refused, not run7-10 (a prefix)" "never the start of a uid" "$dir/names2.txt"; fi
[ "$(uids_left "$dir/names.db")" = "run7-10" ] && ok "  run7-10 kept" || bad "  sessions left: $(uids_left "$dir/names.db")"
mklog "$dir/names3.db" 3f9c1e-7 a41d0b-3
"$review" --db "$dir/names3.db" show 3 > "$dir/show3.txt" 2>&1 || bad "show 3"
expect "show 3 is \"session 3\" on the stations (a41d0b-3), not the uid starting with 3" "^session +a41d0b-3 " "$dir/show3.txt"
"$review" --db "$dir/names3.db" delete 3 > "$dir/delete3.txt" 2>&1 || bad "delete 3"
expect "delete 3 deletes a41d0b-3 and says so" "^deleted a41d0b-3$" "$dir/delete3.txt"
[ "$(uids_left "$dir/names3.db")" = "3f9c1e-7" ] && ok "  3f9c1e-7 kept" || bad "  sessions left: $(uids_left "$dir/names3.db")"
mklog "$dir/names4.db" 1795482287-28255-1 1795482287-28255-2 1795482287-28255-12
"$review" --db "$dir/names4.db" show 1 > "$dir/show1.txt" 2>&1 || bad "show 1 over real uids: $(cat "$dir/show1.txt")"
expect "show 1 over real uids (all start with 1) is session 1" "^session +1795482287-28255-1 " "$dir/show1.txt"
"$review" --db "$dir/names4.db" show 1795482287-28255-1 > "$dir/show1x.txt" 2>&1 || bad "show of an exact uid that is a prefix of another"
expect "an exact uid that is also a prefix is that session" "^session +1795482287-28255-1 " "$dir/show1x.txt"
"$review" --db "$dir/names4.db" show 1795482287-28255-2 > /dev/null 2>&1 &&
  "$review" --db "$dir/names4.db" show 1795 > "$dir/show1795.txt" 2>&1 && bad "show 1795: an ambiguous prefix taken" ||
  expect "a prefix of several (and no station number) still lists them" "could be any of 3 sessions" "$dir/show1795.txt"

# 3. a prune's or list's bound that is empty, too large or before 1970 is a bound or refused, never "no
# limit": sessions started 2023-11-14 (1.7e9 s) and 1000 s later; --older-than 30000 days reaches back to
# 1944 (by hand: 30000 x 86400 s = 2.592e9 s before now), so nothing is that old
mklog "$dir/bounds.db" b-1 b-2
pruned_n() { python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('select count(*) from session where pruned_unix_s is not null').fetchone()[0])" "$1"; }
"$review" --db "$dir/bounds.db" prune --older-than "" > "$dir/prune-empty.txt" 2>&1; rc=$?
[ $rc -eq 2 ] && [ "$(pruned_n "$dir/bounds.db")" = 0 ] && ok "prune --older-than '': exit 2, nothing pruned" ||
  bad "prune --older-than '': exit $rc, $(pruned_n "$dir/bounds.db") pruned: $(cat "$dir/prune-empty.txt")"
for v in " 5" 1e3 -1 0x10 100001 5x; do
  "$review" --db "$dir/bounds.db" prune --older-than "$v" > "$dir/prune-bad.txt" 2>&1; rc=$?
  [ $rc -eq 2 ] && [ "$(pruned_n "$dir/bounds.db")" = 0 ] || bad "prune --older-than '$v': exit $rc: $(cat "$dir/prune-bad.txt")"
done
ok "prune --older-than ' 5', 1e3, -1, 0x10, 100001 (over the cap), 5x: each exit 2, nothing pruned"
"$review" --db "$dir/bounds.db" prune --older-than 30000 > "$dir/prune-30000.txt" 2>&1; rc=$?
[ $rc -eq 0 ] && [ "$(pruned_n "$dir/bounds.db")" = 0 ] && grep -q "^0 sessions pruned" "$dir/prune-30000.txt" &&
  ok "prune --older-than 30000: nothing that old, 0 sessions pruned" ||
  bad "prune --older-than 30000: exit $rc, $(pruned_n "$dir/bounds.db") pruned: $(cat "$dir/prune-30000.txt")"
"$review" --db "$dir/bounds.db" list --until 1970-01-01 > "$dir/list-1970.txt" 2>&1 || bad "list --until 1970-01-01 exit status"
expect "list --until 1970-01-01: no session started by the end of 1970-01-01" "^0 sessions$" "$dir/list-1970.txt"
"$review" --db "$dir/bounds.db" list --since 1970-01-01 > "$dir/list-since1970.txt" 2>&1 || bad "list --since 1970-01-01 exit status"
expect "list --since 1970-01-01: both" "^2 sessions$" "$dir/list-since1970.txt"
for v in 2026-02-31 2026-02-29 "2026-03-01Tfoo" "2026-03-01T12:00:00junk" "2026-03-01x"; do
  "$review" --db "$dir/bounds.db" list --since "$v" > "$dir/list-bad.txt" 2>&1 && bad "list --since '$v' accepted: $(cat "$dir/list-bad.txt")"
done
ok "list --since 2026-02-31, 2026-02-29 (not a leap year), and trailing text after a date or time: refused"

# 5. a pruned session says so: show, list, report and replay name it PRUNED, its log is not "complete",
# and a second prune leaves it (and its stamp) alone. class-bob-2 was pruned above.
R show class-bob-2 > "$dir/show-pruned2.txt" 2>&1 || bad "show of a pruned session exit status"
expect "show: PRUNED on its date" "^PRUNED +on [0-9]{4}-[0-9]{2}-[0-9]{2} " "$dir/show-pruned2.txt"
expect "show: the log line says PRUNED, not complete" "^log +PRUNED: " "$dir/show-pruned2.txt"
if grep -Eq "complete: an end was logged|simulated 0\.000 s|replay[^\n]*recomputes it" "$dir/show-pruned2.txt"; then
  bad "show of a pruned session reads as a complete empty one: $(grep -E 'complete|simulated|recomputes' "$dir/show-pruned2.txt")"
else ok "show: no \"complete\", no \"simulated 0.000 s\", no \"replay recomputes it\""; fi
R list > "$dir/list-pruned.txt" 2>&1 || bad "list exit status"
expect "list marks the pruned session, its simulated time unknown" "^class-bob-2 .* - +normal .*\(PRUNED on [0-9]{4}-[0-9]{2}-[0-9]{2}\)" "$dir/list-pruned.txt"
R report class-bob-2 --out "$dir/bob2-pruned2.html" > /dev/null 2>&1 || bad "report of a pruned session"
grep -q '<p class="warn" id="pruned">PRUNED on ' "$dir/bob2-pruned2.html" && ok "report: PRUNED said" || bad "report: PRUNED not said"
R replay class-bob-2 > "$dir/replay-pruned.txt" 2>&1; rc=$?
[ $rc -eq 2 ] && grep -q "was PRUNED on .*nothing to replay" "$dir/replay-pruned.txt" && ok "replay of a pruned session: exit 2, PRUNED said" ||
  bad "replay of a pruned session: exit $rc: $(cat "$dir/replay-pruned.txt")"
stamp() { python3 -c "import sqlite3,sys; print(repr(sqlite3.connect(sys.argv[1]).execute(\"select pruned_unix_s from session where uid = 'class-bob-2'\").fetchone()[0]))" "$db"; }
stamp0=$(stamp)
R prune --older-than 1 --keep-graded > "$dir/prune-again.txt" 2>&1 || bad "prune again exit status"
if ! grep -q "pruned class-bob-2" "$dir/prune-again.txt" && [ "$(stamp)" = "$stamp0" ] &&
   grep -Eq "^0 sessions pruned \([1-9][0-9]* pruned before, left as they were\)" "$dir/prune-again.txt"; then
  ok "prune again: class-bob-2 not pruned again, its stamp $stamp0 kept: $(tail -1 "$dir/prune-again.txt" | cut -c1-80)"
else bad "prune again: stamp $stamp0 -> $(stamp): $(cat "$dir/prune-again.txt")"; fi

# 9. escape sequences from the log never reach the terminal: an exercise name, a free-text grade (a level
# is one of four words, by the schema's CHECK), a DDS Security refusal's detail, an event's kind and detail and a note's author and text, each holding
# ESC ]0;pwned BEL (retitles a terminal) or CSI 2J (clears it, as ESC [ and as the C1 byte pair C2 9B):
# list and show print none of ESC, BEL or C2 9B, and each such character as '?'
mklog "$dir/esc.db" esc-1
python3 - "$dir/esc.db" <<'PY2'
import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
osc, csi, c1 = "\x1b]0;pwned\x07", "\x1b[2J", "\u009b2J"
c.execute("insert into session_exercise(session_id, exercise_name, exercise_json) values(1, ?, '{}')", ("ex" + osc,))
c.execute("update session set trainee = ? where id = 1", ("car" + c1,))  # session 90: a C1 CSI in a name
c.execute("insert into note(session_id, author, wall_unix_s, text, grade) values(1, ?, 1.7e9, ?, ?)", ("Lee" + csi, "t" + c1, "B" + osc))
c.execute("insert into event(session_id, wall_unix_s, frame, kind, detail, count) values(1, 1.7e9, 1, ?, ?, 1)", ("k" + csi, "d" + osc))
c.execute("insert into event(session_id, wall_unix_s, frame, kind, detail, count) values(NULL, 1.7e9, 0, 'security_refused', ?, 3)",
          ("trainee/m" + osc + ": revoked (handshake)",))
c.commit()
PY2
"$review" --db "$dir/esc.db" list > "$dir/esc-list.txt" 2>&1 || bad "list over escape sequences: exit status"
"$review" --db "$dir/esc.db" show esc-1 > "$dir/esc-show.txt" 2>&1  # its scene has no exercise JSON: exit 2 allowed
if ! LC_ALL=C grep -q "$(printf '\033')" "$dir/esc-list.txt" "$dir/esc-show.txt" &&
   ! LC_ALL=C grep -q "$(printf '\007')" "$dir/esc-list.txt" "$dir/esc-show.txt" &&
   ! LC_ALL=C grep -q "$(printf '\302\233')" "$dir/esc-list.txt" "$dir/esc-show.txt" &&
   grep -q "'B?\]0;pwned?' (free text)" "$dir/esc-list.txt" && grep -q 'ex?\]0;pwned?' "$dir/esc-list.txt" &&
   grep -q 'trainee/m?\]0;pwned?: revoked' "$dir/esc-list.txt" &&
   grep -q 'car??2J' "$dir/esc-list.txt" && grep -q 'car??2J' "$dir/esc-show.txt" &&
   grep -q 'k?\[2J' "$dir/esc-show.txt" && grep -q 'Lee?\[2J' "$dir/esc-show.txt" && grep -q 't??2J' "$dir/esc-show.txt"; then
  ok "escape sequences in an exercise name, grades, a refusal, events, notes and (C1) a trainee's name: list and show print '?' for each control character"
else bad "escape sequences reach the terminal:"; od -c "$dir/esc-list.txt" | grep -n '033\|007\|302' | head -5; od -c "$dir/esc-show.txt" | grep -n '033\|007\|302' | head -5; fi

# a log file it cannot open: the reason with it (session 77; it said only "cannot open it")
"$review" --log-file /nonexistent/dir/r.log --db "$db" list > "$dir/logfile.txt" 2>&1
rc=$?
[ $rc -ne 0 ] && grep -q -- "--log-file /nonexistent/dir/r.log: cannot open it: No such file or directory" "$dir/logfile.txt" &&
  ok "a log file it cannot open: exit $rc, the reason said" || bad "a log file it cannot open: exit $rc: $(cat "$dir/logfile.txt")"

# (session 82) an option's value that reads like a common option is the value: --note "--version" printed the
# version and exited 0 without storing the note; --note --log-file 5 opened a log file ./5. On a copy of the log.
cp "$db" "$dir/ver.db"
mkdir -p "$dir/vercwd"
uid=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('select uid from session order by id limit 1').fetchone()[0])" "$dir/ver.db")
last_note() { python3 -c "import sqlite3,sys; r = sqlite3.connect(sys.argv[1]).execute('select note.text from note join session on session.id = note.session_id where session.uid = ? order by note.id desc limit 1', (sys.argv[2],)).fetchone(); print(r[0] if r else '')" "$dir/ver.db" "$uid"; }
(cd "$dir/vercwd" && "$review" --db "$dir/ver.db" annotate "$uid" --author Lee --note "--version" > "$dir/ver.txt" 2>&1)
rc=$?
note=$(last_note)
if [ $rc -eq 0 ] && [ "$note" = "--version" ] && ! grep -q "^palp-review [0-9]" "$dir/ver.txt"; then
  ok "annotate $uid --note \"--version\": exit 0, the note stored as written, no version printed"
else bad "annotate $uid --note \"--version\": exit $rc, last note '$note': $(cat "$dir/ver.txt")"; fi
(cd "$dir/vercwd" && "$review" --db "$dir/ver.db" annotate "$uid" --author Lee --note "--log-file" --score 5 > "$dir/ver.txt" 2>&1)
rc=$?
note=$(last_note)
if [ $rc -eq 0 ] && [ "$note" = "--log-file" ] && [ -z "$(ls "$dir/vercwd")" ]; then
  ok "annotate $uid --note --log-file --score 5: exit 0, the note stored, no log file opened"
else bad "annotate $uid --note --log-file --score 5: exit $rc, last note '$note', files '$(ls "$dir/vercwd")': $(cat "$dir/ver.txt")"; fi
# and --version where it is an option, after the command word too: printed, exit 0
"$review" --db "$dir/ver.db" list --version > "$dir/ver.txt" 2>&1
rc=$?
[ $rc -eq 0 ] && grep -q "^palp-review [0-9]" "$dir/ver.txt" && ok "list --version: the version, exit 0" ||
  bad "list --version: exit $rc: $(cat "$dir/ver.txt")"
# (session 83) an unknown option in last place is called unknown, not "needs a value" (`list --bogus` said
# "--bogus needs a value"); a known one there still needs its value. Each exit 2, one plain line. annotate on
# the copy.
argerr() { # DESCRIPTION EXPECTED-LINE ARGS...: exit 2, exactly that line
  what=$1 want=$2; shift 2
  out=$("$review" "$@" 2>&1); rc=$?
  if [ $rc -eq 2 ] && [ "$out" = "$want" ]; then ok "$what: exit 2, \"$out\""
  else bad "$what: exit $rc (want 2 and exactly \"$want\"): $out"; fi
}
for c in "list" "show class-alice-1" "export class-alice-1" "report class-alice-1" "annotate $uid" "class" "trainee alice"; do
  word=${c%% *}
  # shellcheck disable=SC2086 # the command and its session, two words
  argerr "$c --bogus" "palp-review $word: unknown option --bogus" --db "$dir/ver.db" $c --bogus
done
argerr "list --trainee" "palp-review list: --trainee needs a value" --db "$db" list --trainee
argerr "show class-alice-1 --out" "palp-review show: --out needs a value" --db "$db" show class-alice-1 --out
argerr "annotate $uid --author" "palp-review annotate: --author needs a value" --db "$dir/ver.db" annotate "$uid" --author
argerr "class --exercise" "palp-review class: --exercise needs a value" --db "$db" class --exercise
argerr "trainee alice --since" "palp-review trainee: --since needs a value" --db "$db" trainee alice --since
# --out - for a report or a page is refused, said once (session 90's review: it wrote a file named "-")
mkdir -p "$dir/dashcwd"
(cd "$dir/dashcwd" && "$review" --db "$dir/ver.db" report "$uid" --out - > "$dir/dash.txt" 2>&1); rc=$?
if [ $rc -eq 2 ] && [ ! -e "$dir/dashcwd/-" ] && [ "$(grep -c "'-' is not a file name here" "$dir/dash.txt")" = 1 ] &&
   [ "$(wc -l < "$dir/dash.txt")" = 1 ]
then ok "report --out -: exit 2, no file '-', one line: $(cut -c26- "$dir/dash.txt")"
else bad "report --out -: exit $rc, files: $(ls -A "$dir/dashcwd"):"; cat "$dir/dash.txt"; fi
# --help says what it does: a command-line mistake is a plain line, and the SIGHUP note names palp-web too
"$review" --help > "$dir/help.txt" 2>&1
expect "--help: a command-line mistake is one plain line" "A command-line mistake is one plain line" "$dir/help.txt"
expect "--help: palp-web re-opens its --log-file on SIGHUP too" "and palp-web re-open it on SIGHUP" "$dir/help.txt"
[ $fail -eq 0 ] && echo "passed" || echo "FAILED"
exit $fail
