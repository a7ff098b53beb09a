#!/bin/sh
# palp-recorder's log at its cap (session 66, docs/db.md "palp-recorder"): its file padded to ~0.97 MB
# and the recorder run with --max-mb 1 while a real palp-server (no log of its own) serves trainee
# rita for 3 s on domain 136. Checked: the recorder says at start that the log is nearly full; as the
# session fills it, it says the loss while it runs, with the cap and what to do, and records on; its
# stop line counts the failed records and it exits 1 (records were lost); the file is sound
# (integrity_check ok) and still a palp log (palp-review list reads it).
# usage: recorder_full.sh SERVER CLIENT RECORDER REVIEW CONFIG_DIR
set -u
server=$1 client=$2 recorder=$3 review=$4 config_dir=$5
export CYCLONEDDS_URI=${CYCLONEDDS_URI:-file://$config_dir/cyclonedds-loopback.xml}
tmp=$(mktemp -d)
spid= rpid=
trap '[ -n "$spid" ] && kill $spid 2>/dev/null; [ -n "$rpid" ] && kill $rpid 2>/dev/null; rm -rf "$tmp"' EXIT
fail=0
ok() { echo "ok   $1"; }
bad() { echo "FAIL $1"; fail=1; }
# the log made by the recorder itself, then padded by a table of the test's own
"$recorder" --domain 136 --db "$tmp/rec.db" --duration 0.2 > "$tmp/make.log" 2>&1 || { cat "$tmp/make.log"; exit 1; }
python3 - "$tmp/rec.db" <<'PY' || exit 1
import sqlite3, sys
h = sqlite3.connect(sys.argv[1])
h.execute("CREATE TABLE pad(x BLOB)")
h.execute("INSERT INTO pad VALUES(zeroblob(850000))")
h.commit()
n, size = h.execute("SELECT page_count, page_count * page_size FROM pragma_page_count, pragma_page_size").fetchone()
h.close()
print("padded log: %d pages, %d bytes" % (n, size))
sys.exit(0 if 900000 <= size < 1000000 else 1)
PY
cat > "$tmp/server.json" <<JSON
{ "domain_id": 136, "tick_rate_hz": 100, "tick_threads": 1,
  "dds_config": "$config_dir/cyclonedds-loopback.xml",
  "phantoms": [ { "id": 1, "name": "dome", "scene": "$config_dir/paper_step_long_term.json" } ] }
JSON
"$recorder" --domain 136 --db "$tmp/rec.db" --max-mb 1 > "$tmp/recorder.log" 2>&1 &
rpid=$!
"$server" --config "$tmp/server.json" --no-db > "$tmp/server.log" 2>&1 &
spid=$!
"$client" --role trainee --domain 136 --phantom 1 --name rita --timeout 10 --duration 3 --profile sine --t-on 0 \
  --t-off 60 --quiet > "$tmp/rita.log" 2>&1 || { echo "FAIL rita's station:"; cat "$tmp/rita.log"; fail=1; }
sleep 2.5 # the recorder's next look at its writer (every second) after the losses
kill $spid; wait $spid; spid=
kill $rpid; wait $rpid; rrc=$?; rpid=
log=$(cat "$tmp/recorder.log")
if grep -q "WARN  palp-recorder: session log: 0\.9[0-9] MB of its cap of 1\.00 MB (--max-mb): nearly full; prune old sessions (palp-review prune), move the log away or raise the cap" "$tmp/recorder.log"
then ok "the recorder says at start that its log is nearly full"; else bad "no 'nearly full' line:
$log"; fi
if grep -q "WARN  palp-recorder: session log: [0-9]* records lost so far (0 shed: the queue was full; [0-9]* failed: .*database or disk is full); the file reached its cap of 1\.00 MB (--max-mb) or its disk is full: prune old sessions (palp-review prune), move the log away or raise the cap; recording goes on" "$tmp/recorder.log"
then ok "and the loss while it runs, with the cap and what to do"; else bad "no loss line while it ran:
$log"; fi
# said before the stop: the loss line comes before the stop line
if awk '/records lost so far/ { l = NR } /INFO  palp-recorder: stopped;/ { s = NR } END { exit !(l && s && l < s) }' "$tmp/recorder.log"
then ok "  before its stop"; else bad "the loss was not said before the stop"; fi
if grep -q "stopped; [0-9]* records written, 0 shed, [1-9][0-9]* failed" "$tmp/recorder.log" && [ "$rrc" -eq 1 ]
then ok "its stop line counts the failed records, exit 1"; else bad "stop line or exit ($rrc):
$log"; fi
# The writer's own stderr lines for dropped batches (session 67): the first at once, then at most one per
# 10 s, the rest as it closes: at most 2 over this ~6 s run (a line per batch before: one each ~0.4 s),
# and together they count every failed record the stop line counts.
failed=$(sed -n 's/.*stopped; [0-9]* records written, 0 shed, \([0-9]*\) failed.*/\1/p' "$tmp/recorder.log" | head -1)
lines=$(grep -c "palp_db: .*: dropped [0-9]* records" "$tmp/recorder.log")
said=$(sed -n 's/.*palp_db: .*: dropped \([0-9]*\) records.*/\1/p' "$tmp/recorder.log" | awk '{ n += $1 } END { print n + 0 }')
if [ -n "$failed" ] && [ "$lines" -ge 1 ] && [ "$lines" -le 2 ] && [ "$said" -eq "$failed" ]
then ok "the writer's stderr says the dropped batches in $lines line(s), $said records = the $failed failed"
else bad "dropped-batch lines: $lines (want 1-2), $said records said, $failed failed:
$log"; fi
ic=$(python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute('PRAGMA integrity_check').fetchone()[0])" "$tmp/rec.db")
if [ "$ic" = ok ] && "$review" --db "$tmp/rec.db" list > "$tmp/list.txt" 2>&1
then ok "the file is sound (integrity_check $ic) and palp-review reads it"; else bad "integrity_check $ic, or list failed:
$(cat "$tmp/list.txt")"; fi
exit $fail
