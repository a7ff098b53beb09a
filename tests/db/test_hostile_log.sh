#!/bin/sh
# palp-review tells the truth about a log, and survives a damaged one (issue 15):
#  - a whole log: "complete";
#  - 87% of its frames deleted: "DAMAGED: ... N of M frames missing", N and M counted here with sqlite3;
#  - no end logged (the server was SIGKILLed): "CUT SHORT ... the data ends at frame F", F = max(frame);
#  - a mesh row claiming 178,956,971 vertices (x 24 B wraps to 8 in 32 bits): report and show run, exit 0;
#  - a frame number of 10^12: replay stops at once with "DAMAGED LOG", exit 2, within 10 s;
#  - an empty file and a foreign SQLite file: list refuses them (exit 2) and leaves them byte-identical;
#  - a damaged page under the note, event or session_metrics table: show, report and export exit 2 naming it.
# usage: test_hostile_log.sh SIM_SESSION PALP_REVIEW SCENE TMPDIR
set -eu
sim=$1 review=$2 scene=$3 tmp=$4
dir=$tmp/hostile_log
rm -rf "$dir"
mkdir -p "$dir"
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
uid=hostile-0001
"$sim" "$dir/base.db" "$uid" "$scene" 1.0 >/dev/null
sqlite3 "$dir/base.db" "PRAGMA wal_checkpoint(TRUNCATE);" >/dev/null
copy() { cp "$dir/base.db" "$dir/$1.db"; }

out=$("$review" --db "$dir/base.db" show "$uid")
echo "$out" | grep -q "^log        complete: an end was logged" && ok "whole log: complete" || { bad "whole log not called complete"; echo "$out" | tail -3; }

copy holes
total=$(sqlite3 "$dir/holes.db" "SELECT count(*) FROM frame")
sqlite3 "$dir/holes.db" "DELETE FROM frame WHERE frame IN (SELECT frame FROM frame ORDER BY frame LIMIT (SELECT count(*) * 87 / 100 FROM frame) OFFSET 5)"
left=$(sqlite3 "$dir/holes.db" "SELECT count(*) FROM frame")
missing=$((total - left))
out=$("$review" --db "$dir/holes.db" show "$uid")
echo "$out" | grep -q "^log        DAMAGED: 0 records shed (queue full), 0 lost to disk errors, $missing of $total frames missing" \
  && ok "87% of frames deleted ($missing of $total): DAMAGED, counted" || { bad "holes not reported ($missing of $total)"; echo "$out" | tail -3; }
"$review" --db "$dir/holes.db" list | grep -q "(log damaged)" && ok "list marks the damaged log" || bad "list does not mark the damaged log"

copy killed
sqlite3 "$dir/killed.db" "UPDATE session SET end_unix_s = NULL, end_reason = NULL, end_detail = NULL"
last=$(sqlite3 "$dir/killed.db" "SELECT max(frame) FROM frame")
out=$("$review" --db "$dir/killed.db" show "$uid")
echo "$out" | grep -q "^log        CUT SHORT: no end was logged .*the data ends at frame $last," \
  && ok "no end logged: CUT SHORT at frame $last" || { bad "cut short not reported"; echo "$out" | tail -3; }

copy mesh
sqlite3 "$dir/mesh.db" "UPDATE mesh SET vertex_count = 178956971, positions_m = zeroblob(8) WHERE rowid = (SELECT min(rowid) FROM mesh)"
if "$review" --db "$dir/mesh.db" report "$uid" --out "$dir/mesh.html" >/dev/null 2>"$dir/mesh.err" && [ -s "$dir/mesh.html" ]; then
  ok "mesh row of 178,956,971 vertices: report written, no crash"
else
  bad "report on a bad mesh row failed: $(cat "$dir/mesh.err")"
fi

# Frame times no axis can step through (session 81, found by review): times of 1e17 s, 16 s apart (beyond
# 2^53 a tick step of 1 or 2 s leaves the value as it was), and every frame at +Inf (SQLite reads 9e999
# as Inf: an axis from Inf to Inf stepped for ever), and the first frame at -Inf and the last at +Inf. Before, report wrote <line> elements for ever (1 GB in 10 s). Now: exit 0 within 10 s, the page
# under 2 MB (the whole session's page is ~0.1 MB), and the infinite point said to be left out.
copy bigtime
sqlite3 "$dir/bigtime.db" "UPDATE frame SET sim_time_s = 1e17 + (frame % 2) * 16"
copy inftime
sqlite3 "$dir/inftime.db" "UPDATE frame SET sim_time_s = 9e999"
copy pminf
sqlite3 "$dir/pminf.db" "UPDATE frame SET sim_time_s = 9e999 WHERE frame = (SELECT max(frame) FROM frame);
  UPDATE frame SET sim_time_s = -9e999 WHERE frame = (SELECT min(frame) FROM frame)"
nframes=$(sqlite3 "$dir/base.db" "SELECT count(*) FROM frame")
for case in bigtime inftime pminf; do
  set +e
  start=$(date +%s)
  timeout 10 "$review" --db "$dir/$case.db" report "$uid" --out "$dir/$case.html" > "$dir/$case.out" 2>&1; rc=$?
  took=$(( $(date +%s) - start ))
  set -e
  size=$(stat -c %s "$dir/$case.html" 2>/dev/null || echo 0)
  rm -f "$dir/$case.db"  # a failing run may leave a 1 GB page: not kept beside it
  if [ $rc -eq 0 ] && [ "$size" -gt 0 ] && [ "$size" -lt 2000000 ]; then
    ok "$case: report exits 0 in ${took} s, the page $size bytes"
  else bad "$case: report exit $rc after ${took} s, the page $size bytes: $(tail -c 300 "$dir/$case.out")"; fi
  # the points left out, by hand: the force plot has 1 series, the displacement plot 2 (top and largest);
  # at 1,000 frames each bucket of the 1,500-point plots is one frame
  case $case in
  inftime) want="$nframes points of|$((2 * nframes)) points of" ;;
  pminf) want="2 points of|4 points of" ;;
  *) want="" ;;
  esac
  [ -z "$want" ] || { [ "$(grep -Ec "class=\"warn nonfinite\">($want) this plot not drawn" "$dir/$case.html")" = 2 ] &&
    ok "  the infinite times said under both plots: $(grep -o 'nonfinite">[0-9]* points' "$dir/$case.html" | tr '\n' ' ')" ||
    bad "  the infinite times not said: $(grep -o 'nonfinite">[^<]*' "$dir/$case.html")"; }
  rm -f "$dir/$case.html"
done

copy frame
sqlite3 "$dir/frame.db" "UPDATE frame SET frame = 1000000000000 WHERE frame = (SELECT max(frame) FROM frame)"
set +e
start=$(date +%s)
out=$(timeout 20 "$review" --db "$dir/frame.db" replay "$uid" 2>&1)
rc=$?
took=$(( $(date +%s) - start ))
set -e
if [ $rc -eq 2 ] && [ $took -le 10 ] && echo "$out" | grep -q "DAMAGED LOG: logged frame 1000000000000"; then
  ok "frame 10^12: replay stops in ${took} s with a clear message, exit 2"
else
  bad "frame 10^12: exit $rc after ${took} s: $out"
fi

# A step of 1e-7 s (and a tick rate to match) with its one frame numbered 5e8 (session 81, found by review): the
# gap guard allowed 60 s / dt_s = 6e8 steps, hours of stepping. Now a step no server steps at (1e-4 ..
# 0.1 s) is refused at once: exit 2 within 10 s, said.
copy tinydt
# (the only frame left: else a frame before it, mismatching at the new step, would stop the replay first)
sqlite3 "$dir/tinydt.db" "UPDATE session SET dt_s = 1e-7, tick_hz = 1e7; DELETE FROM frame WHERE frame < (SELECT max(frame) FROM frame);
  UPDATE frame SET frame = 500000000"
set +e
start=$(date +%s)
out=$(timeout 20 "$review" --db "$dir/tinydt.db" replay "$uid" 2>&1)
rc=$?
took=$(( $(date +%s) - start ))
set -e
if [ $rc -eq 2 ] && [ $took -le 10 ] && echo "$out" | grep -q "DAMAGED LOG: session $uid logged a step of 1e-07 s"; then
  ok "dt_s 1e-7, a frame at 5e8: replay refuses in ${took} s, exit 2: $(echo "$out" | sed 's/.*replay: //' | cut -c1-110)"
else
  bad "dt_s 1e-7, a frame at 5e8: exit $rc after ${took} s: $(echo "$out" | tail -c 300)"
fi

: > "$dir/empty.db"
set +e
msg=$("$review" --db "$dir/empty.db" list 2>&1); rc=$?
set -e
size=$(stat -c %s "$dir/empty.db")
[ $rc -eq 2 ] && [ "$size" -eq 0 ] && echo "$msg" | grep -q "not a palp session log" \
  && ok "empty file refused, still 0 bytes: $msg" || bad "empty file: exit $rc, size $size: $msg"

sqlite3 "$dir/foreign.db" "CREATE TABLE recipes(name TEXT); INSERT INTO recipes VALUES('bread')"
sum0=$(md5sum < "$dir/foreign.db")
set +e
msg=$("$review" --db "$dir/foreign.db" list 2>&1); rc=$?
set -e
sum1=$(md5sum < "$dir/foreign.db")
[ $rc -eq 2 ] && [ "$sum0" = "$sum1" ] && [ ! -e "$dir/foreign.db-wal" ] && echo "$msg" | grep -q "not a palp session log" \
  && ok "foreign SQLite file refused, byte-identical: $msg" || bad "foreign file: exit $rc: $msg"

# Hostile text and numbers in a log made elsewhere (session 75, found by review):
#  - NULL op and kind in contact_input and NULL kind in event (tables without NOT NULL): show,
#    replay and the exports run to an exit status of their own (< 128: no crash);
#  - an event kind holding a quote and a line break: the CSV export still parses to one row per
#    event, the kind read back whole; a detail starting '=' goes out with an apostrophe first (a
#    spreadsheet would run it as a formula);
#  - scene_json of a value followed by more text: the JSON export is one valid document whose keys
#    are the export's own, the scene kept as a string;
#  - a start 1e300 s after 1970 and frames at -9e18 and 9e18: show runs (no crash), the start shown "-".
copy nulls
sqlite3 "$dir/nulls.db" "CREATE TABLE ci AS SELECT * FROM contact_input; DROP TABLE contact_input; ALTER TABLE ci RENAME TO contact_input;
  UPDATE contact_input SET op = NULL, kind = NULL WHERE rowid = (SELECT min(rowid) FROM contact_input);
  CREATE TABLE ev AS SELECT * FROM event; DROP TABLE event; ALTER TABLE ev RENAME TO event;
  INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count) SELECT id, 1.0, 1, NULL, 'x', 1 FROM session;"
crashed=""
for cmd in show replay "export --format csv --table contacts" "export --format json --table events"; do
  set +e
  # shellcheck disable=SC2086
  "$review" --db "$dir/nulls.db" $cmd "$uid" > "$dir/nulls.out" 2>&1; rc=$?
  set -e
  [ $rc -lt 128 ] || crashed="$crashed $cmd:$rc"
done
[ -z "$crashed" ] && ok "NULL op, kind and event kind: show, replay, exports exit on their own (no crash)" || bad "NULL columns crash:$crashed"

copy text
sqlite3 "$dir/text.db" "DELETE FROM event; INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count)
  SELECT id, 1.0, 1, 'x\",1' || char(10) || '1,2,forged,1,\"', 'plain', 1 FROM session;
  INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count) SELECT id, 2.0, 2, 'info', '=1+1', 1 FROM session;"
"$review" --db "$dir/text.db" export "$uid" --format csv --table events --out "$dir/events.csv" >/dev/null 2>&1 || bad "events CSV export"
if python3 - "$dir/events.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline="")))
body = rows[1:]
assert len(body) == 2, rows
assert body[0][2] == 'x",1\n1,2,forged,1,"' and body[0][4] == "plain", body[0]
assert body[1][4] == "'=1+1", body[1]
PY
then ok "events CSV: a kind with a quote and a line break stays one field of one row; '=1+1' goes out as \"'=1+1\""
else bad "events CSV with hostile text: $(head -c 400 "$dir/events.csv")"; fi
sqlite3 "$dir/text.db" "UPDATE session SET scene_json = '{}, \"frames\": [{\"frame\": 1}], \"x\": {}'"
"$review" --db "$dir/text.db" export "$uid" --format json --table events --out "$dir/text.json" >/dev/null 2>&1 || bad "JSON export"
if python3 - "$dir/text.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s = d["session"]
assert "x" not in d and "x" not in s and isinstance(d.get("frames", []), list), (sorted(d), sorted(s))
assert isinstance(s["scene"], str) and s["scene"].startswith("{}, "), type(s["scene"]).__name__
PY
then ok "JSON export: a scene of a value and more text goes in as a string; no key of its own added"
else bad "JSON export with a trailing-text scene: $(head -c 400 "$dir/text.json")"; fi

# Stored JSON that cJSON takes and JSON does not, and text that is not UTF-8 (session 81, found by review:
# the export wrote the stored scene as it was, and strings' bad bytes raw): "01", "1.", a raw line break
# and \x01 inside a string, a \xff byte; a trainee "eve\xff\x01", a note by "Lee\n" reading "x\xc0\xafy"
# (an overlong '/'). Each export is read by Python's json, strict (no control character inside a string,
# no NaN or Infinity), from strict UTF-8; by hand: the scene's b is 1, its string "a\nb\x01c" whole, a bad
# byte U+FFFD (the scene with one kept as a string), the trainee "eve\ufffd?" (a control character in a
# name reads '?'), the note "x\ufffd\ufffdy" by "Lee\n".
for k in 0 1 2 3; do
  copy json
  python3 - "$dir/json.db" $k <<'PY2'
import sqlite3, sys
scenes = [b'{"b": 01}', b'{"b": 1.}', b'{"b": 1, "s": "a\nb\x01c"}', b'{"b": 1, "s": "\xff"}']
c = sqlite3.connect(sys.argv[1])
c.execute("UPDATE session SET scene_json = CAST(? AS TEXT), trainee = CAST(? AS TEXT)", (scenes[int(sys.argv[2])], b"eve\xff\x01"))
c.execute("INSERT INTO note(session_id, author, wall_unix_s, text) SELECT id, 'Lee' || char(10), 1.0, CAST(? AS TEXT) FROM session",
          (b"x\xc0\xafy",))
c.commit()
PY2
  "$review" --db "$dir/json.db" export "$uid" --format json --out "$dir/json.json" > "$dir/json.out" 2>&1 || bad "JSON export $k: $(cat "$dir/json.out")"
  if python3 - "$dir/json.json" $k <<'PY2'
import json, sys
def no_constant(name):
    raise ValueError("non-standard constant " + name)
d = json.loads(open(sys.argv[1], "rb").read().decode("utf-8"), parse_constant=no_constant)
k = int(sys.argv[2])
s = d["session"]
scene = s["scene"]
if k < 3:
    assert scene["b"] == 1 and scene.get("s", "a\nb\x01c") == "a\nb\x01c", scene
else:
    assert scene == '{"b": 1, "s": "\ufffd"}', scene
assert s["trainee"] == "eve\ufffd?", s["trainee"]
assert [(n["author"], n["text"]) for n in d["notes"]] == [("Lee\n", "x\ufffd\ufffdy")], d["notes"]
PY2
  then ok "JSON export $k: strict JSON in strict UTF-8, the values as stored"
  else bad "JSON export $k: $(grep -a '"scene"\|"trainee"' "$dir/json.json" | cut -c1-120 | od -c | head -6)"; fi
done
# ... and a frame's pressure +Inf and top displacement -Inf (a damaged log; SQLite reads 9e999 as Inf):
# the JSON export writes null for each (it wrote "inf", which no JSON reader takes; session 81)
copy jinf
sqlite3 "$dir/jinf.db" "UPDATE frame SET pressure_pa = 9e999, top_disp_m = -9e999 WHERE frame = (SELECT min(frame) FROM frame)"
"$review" --db "$dir/jinf.db" export "$uid" --format json --out "$dir/jinf.json" > "$dir/jinf.out" 2>&1 || bad "JSON export of infinite values: $(cat "$dir/jinf.out")"
if python3 - "$dir/jinf.json" <<'PY2'
import json, sys
def no_constant(name):
    raise ValueError("non-standard constant " + name)
d = json.loads(open(sys.argv[1], "rb").read().decode("utf-8"), parse_constant=no_constant)
f = d["frames"][0]
assert f["pressure_pa"] is None and f["top_disp_m"] is None, f
assert all(isinstance(g["pressure_pa"], (int, float)) for g in d["frames"][1:]), "the other frames values as numbers"
PY2
then ok "JSON export: a frame's infinite values written null, the document strict JSON"
else bad "JSON export of infinite values: $(grep -a -m1 'pressure_pa' "$dir/jinf.json" | cut -c1-200)"; fi

# Smaller ones (session 81, found by review): the finger samples unreadable (their table gone: SQLite
# says "no such table"): show and report exit 2 as export, trainee and class do (they exited 0); a JSON
# export of a table that is none: exit 2 (0); a header's schema version of -3: "not a palp session log"
# with the version said (it read "not an SQLite database: not an error").
copy nosamples
sqlite3 "$dir/nosamples.db" "DROP TABLE finger_sample"
set +e
"$review" --db "$dir/nosamples.db" show "$uid" > "$dir/nosamples.out" 2>&1; rc_show=$?
"$review" --db "$dir/nosamples.db" report "$uid" --out "$dir/nosamples.html" >> "$dir/nosamples.out" 2>&1; rc_report=$?
"$review" --db "$dir/base.db" export "$uid" --format json --table bogus --out "$dir/bogus.json" > "$dir/bogus.out" 2>&1; rc_bogus=$?
cp "$dir/base.db" "$dir/minus3.db"
sqlite3 "$dir/minus3.db" "PRAGMA user_version = -3"
msg=$("$review" --db "$dir/minus3.db" list 2>&1); rc_minus3=$?
set -e
[ $rc_show -eq 2 ] && [ $rc_report -eq 2 ] && [ "$(grep -c "could not be computed: .*no such table: finger_sample" "$dir/nosamples.out")" -ge 2 ] &&
  ok "finger samples unreadable: show and report exit 2, said" || bad "finger samples unreadable: show $rc_show, report $rc_report: $(tail -3 "$dir/nosamples.out")"
[ $rc_bogus -eq 2 ] && ok "export --format json --table bogus: exit 2: $(cat "$dir/bogus.out")" || bad "export --table bogus: exit $rc_bogus"
[ $rc_minus3 -eq 2 ] && echo "$msg" | grep -q "not a palp session log (an SQLite database whose schema version is -3" &&
  ok "user_version -3: $msg" | sed 's/ok   user_version -3: .*palp-review: /ok   user_version -3: /' || bad "user_version -3: exit $rc_minus3: $msg"

# 100,000 marks, all with id 7, then 100,000 withdrawals of id 8 (which names none, so each looked through
# every mark): show took 10 s to read them (each withdrawal scanned the marks back; session 81); now the
# withdrawals are matched by binary search: show within 5 s (by estimate 0.3 s here, most of it reading).
copy marks
sqlite3 "$dir/marks.db" "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 100000)
  INSERT INTO finding(session_id, mark_id, op, frame, sim_time_s, wall_unix_s, point_x_m, point_y_m, point_z_m)
  SELECT (SELECT id FROM session), 7, 'mark', i, i * 1e-3, 1.0, 0, 0, 0.04 FROM n;
  WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 100000)
  INSERT INTO finding(session_id, mark_id, op, frame, sim_time_s, wall_unix_s) SELECT (SELECT id FROM session), 8,
  'withdraw', 100000 + i, 100 + i * 1e-3, 1.0 FROM n;"
set +e
start=$(date +%s)
timeout 60 "$review" --db "$dir/marks.db" show "$uid" > "$dir/marks.out" 2>&1; rc=$?
took=$(( $(date +%s) - start ))
set -e
rm -f "$dir/marks.db"
[ $rc -lt 124 ] && [ $took -le 5 ] && ok "100,000 marks and 100,000 withdrawals: show in ${took} s (exit $rc)" ||
  bad "100,000 marks and 100,000 withdrawals: show exit $rc after ${took} s"

# an escape sequence in a trainee's name (OSC: retitle the terminal, then BEL) and a line break in the
# station's: list and show print neither byte, the name read with '?' for each control character
copy escape
sqlite3 "$dir/escape.db" "UPDATE session SET trainee = char(27) || ']0;pwned' || char(7) || 'eve', station = 'a' || char(10) || 'b'"
"$review" --db "$dir/escape.db" list > "$dir/escape.out" 2>&1 || bad "list with an escape in a name"
"$review" --db "$dir/escape.db" show "$uid" >> "$dir/escape.out" 2>&1 || bad "show with an escape in a name"
if ! LC_ALL=C grep -q "$(printf '\033')" "$dir/escape.out" && ! LC_ALL=C grep -q "$(printf '\007')" "$dir/escape.out" &&
  grep -q '?\]0;pwned?eve' "$dir/escape.out" && grep -q 'station a?b' "$dir/escape.out"; then
  ok "control characters in names: list and show print '?' for each, no escape or bell byte"
else bad "control characters reach the terminal: $(od -c "$dir/escape.out" | head -5)"; fi

copy huge
sqlite3 "$dir/huge.db" "UPDATE session SET start_unix_s = 1e300; UPDATE frame SET frame = -9000000000000000000 WHERE frame = (SELECT min(frame) FROM frame);
  UPDATE frame SET frame = 9000000000000000000 WHERE frame = (SELECT max(frame) FROM frame)"
set +e
out=$("$review" --db "$dir/huge.db" show "$uid" 2>&1); rc=$?
set -e
[ $rc -lt 128 ] && echo "$out" | grep -Eq "^started +-$" && ok "start 1e300 s and frames at +-9e18: show exits $rc, the start shown '-'" ||
  bad "huge numbers: exit $rc: $(echo "$out" | head -8)"

# A damaged page under a table that show, report and export read to its end (2026-12-06, found by review:
# the notes and the events ended where the damage began, exit 0, as if there were no more; stored
# metrics that could not be read were "none"). damage TABLE DB overwrites the header of TABLE's
# highest-numbered leaf page (its page type 0xff): a scan in id order reads the rows before it, then
# SQLite says the file is malformed. Each command says which table and why, and exits 2.
damage() {
  python3 - "$2" "$1" <<'PY'
import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
ps = c.execute("pragma page_size").fetchone()[0]
pages = [r[0] for r in c.execute("select pageno from dbstat where name = ? and pagetype = 'leaf' order by pageno", (sys.argv[2],))]
c.close()
assert pages, sys.argv[2]
with open(sys.argv[1], "r+b") as f:
    f.seek((pages[-1] - 1) * ps)
    f.write(b"\xff" * 16)
PY
}
damaged() { # damaged DB VERB REST... : exit 2 and stderr naming the table, "malformed"
  db=$1 verb=$2
  shift 2
  set +e
  "$review" --db "$db" "$verb" "$uid" "$@" > "$dir/damaged.out" 2> "$dir/damaged.err"; rc=$?
  set -e
  if [ $rc -eq 2 ] && grep -Eq "the ($want) could not be read: database disk image is malformed" "$dir/damaged.err"; then
    ok "$(basename "$db"): $verb $*: exit 2, said: $(sed 's/.*ERROR *palp-review: //' "$dir/damaged.err" | tail -1 | cut -c1-150)"
  else bad "$(basename "$db"): $verb $*: exit $rc:"; tail -n 3 "$dir/damaged.out" "$dir/damaged.err" || true; fi
}
copy notes
sqlite3 "$dir/notes.db" "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 300)
  INSERT INTO note(session_id, author, wall_unix_s, text) SELECT (SELECT id FROM session), 'Lee', 1000 + i,
  'note ' || i || ' ' || hex(zeroblob(100)) FROM n; PRAGMA wal_checkpoint(TRUNCATE);" >/dev/null
damage note "$dir/notes.db"
want="note table|notes"
damaged "$dir/notes.db" show
damaged "$dir/notes.db" report --out "$dir/notes.html"
damaged "$dir/notes.db" export --format csv --table notes --out "$dir/notes.csv"
damaged "$dir/notes.db" export --format json --out "$dir/notes.json"
# the damage is mid-way: the notes before it were read (and written), not all 300
rows=$(python3 -c "import csv, sys; print(len(list(csv.reader(open(sys.argv[1])))) - 1)" "$dir/notes.csv")
[ "$rows" -gt 0 ] && [ "$rows" -lt 300 ] && grep -q 'class="warn db-error"' "$dir/notes.html" &&
  ok "  the damage mid-way: $rows of 300 notes read before it; the report's page says where it stops" ||
  bad "  the notes before the damage: $rows read; the page: $(grep -c 'db-error' "$dir/notes.html")"
copy events
sqlite3 "$dir/events.db" "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 300)
  INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count) SELECT (SELECT id FROM session), 1000 + i, i,
  'info', 'event ' || i || ' ' || hex(zeroblob(100)), 1 FROM n; PRAGMA wal_checkpoint(TRUNCATE);" >/dev/null
damage event "$dir/events.db"
want="event table|events"
damaged "$dir/events.db" show
damaged "$dir/events.db" report --out "$dir/events.html"
damaged "$dir/events.db" export --format csv --table events --out "$dir/events-damaged.csv"
# the log's health reads the event table too (its last event's time): unknown, not "complete: 0 of 0
# frames" (2026-12-06, session 77: palp_db_log_health_get took a failed read for an empty session)
"$review" --db "$dir/events.db" show "$uid" 2>/dev/null | grep -Eq "^log +UNKNOWN: .*malformed" &&
  ok "events damaged: show's log line says UNKNOWN and why" ||
  bad "events damaged: show's log line: $("$review" --db "$dir/events.db" show "$uid" 2>/dev/null | grep '^log')"
# stored metrics as a prune leaves them (the samples gone, a session_metrics row), their page damaged
copy metrics
sqlite3 "$dir/metrics.db" "DELETE FROM finger_sample; UPDATE session SET pruned_unix_s = 2000;
  INSERT INTO session_metrics(session_id, computed_unix_s, exercise_name, samples, lesions, found, findings, withdrawn,
  false_positives, coverage_light, coverage_medium, coverage_deep, coverage_any, pattern, path_length_m, presses,
  duration_s, peak_force_n, out_of_range, score, pass) SELECT id, 2000, NULL, 500, 0, 0, 0, 0, 0, 0.25, 0.1, 0, 0.3,
  'unsystematic', 0.2, 3, 1.0, 4.5, 0, NULL, NULL FROM session; PRAGMA wal_checkpoint(TRUNCATE);" >/dev/null
"$review" --db "$dir/metrics.db" show "$uid" | grep -q "stored when the session was pruned" &&
  ok "stored metrics, undamaged: show gives them" || bad "stored metrics, undamaged: show does not give them"
# the same with an exercise logged, for class (its sessions are those of one exercise)
cp "$dir/metrics.db" "$dir/metricsx.db"
python3 - "$dir/metricsx.db" "$(dirname "$scene")/../assess/exercise_expert.json" <<'PY'
import sqlite3, sys
c = sqlite3.connect(sys.argv[1])
c.execute("INSERT INTO session_exercise(session_id, exercise_name, exercise_json) SELECT id, 'test-two-lumps', ? FROM session",
          (open(sys.argv[2]).read(),))
c.commit()
c.execute("PRAGMA wal_checkpoint(TRUNCATE)")
c.close()
PY
damage session_metrics "$dir/metrics.db"
damage session_metrics "$dir/metricsx.db"
want="session_metrics table"
damaged "$dir/metrics.db" show
damaged "$dir/metrics.db" report --out "$dir/metrics.html"
damaged "$dir/metrics.db" export --format csv --table metrics --out "$dir/metrics.csv"
trainee=$(sqlite3 "$dir/base.db" "SELECT trainee FROM session")
# trainee and class over a log they cannot read: exit 2, the sessions left out counted and named, not
# "exit 0" (trainee) or "no session of exercise 'X' ... (exercises logged: X)" (class) (2026-12-06, found by review)
set +e
"$review" --db "$dir/metrics.db" trainee "$trainee" > "$dir/metrics-trainee.out" 2>&1; rc=$?
set -e
[ $rc -eq 2 ] && grep -q "none assessed; 1 left out, could not be assessed" "$dir/metrics-trainee.out" &&
  ok "trainee: the session whose stored metrics cannot be read is left out as not assessed, not as force contacts only; exit 2" ||
  bad "trainee over damaged stored metrics: exit $rc: $(cat "$dir/metrics-trainee.out")"
set +e
"$review" --db "$dir/metricsx.db" class --exercise test-two-lumps --out "$dir/metricsx.html" > "$dir/metricsx-class.out" 2> "$dir/metricsx-class.err"; rc=$?
set -e
if [ $rc -eq 2 ] && grep -q "session_metrics table could not be read" "$dir/metricsx-class.err" &&
   grep -q "no session could be assessed: 1 left out because the log could not be read ($uid;" "$dir/metricsx-class.err" &&
   ! grep -q "no session of exercise" "$dir/metricsx-class.err"; then
  ok "class: the session whose log cannot be read counted and named, exit 2: $(tail -1 "$dir/metricsx-class.err" | cut -c1-150)"
else bad "class over damaged stored metrics: exit $rc:"; cat "$dir/metricsx-class.out" "$dir/metricsx-class.err"; fi

exit $fail
