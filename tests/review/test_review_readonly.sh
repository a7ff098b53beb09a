#!/bin/sh
# palp-review's reading commands never change the log they read (found by review, 2026-12-06: they
# opened it read-write and upgraded an older palp's schema in place, so an instructor reviewing a
# copy of an old log, or a log on read-only media, changed it or failed):
#  - logs of schema 1 and 4 (an older palp's, WAL mode as palp leaves them): list, show, export,
#    report, replay, class and trainee leave the file byte-identical (sha256), its mtime (ns) and
#    user_version as they were, and list/show/export print the old rows through the upgraded copy;
#  - PALP_REVIEW_COPY_MB=0 (a log too large to copy): refused, exit 2, naming `palp-review migrate`,
#    the file byte-identical;
#  - a directory this user cannot write, the files 0444 (as root, palp-review runs as nobody
#    through setpriv, as root ignores the permissions): the old log and a current one are read, and
#    no -wal, -shm or -journal is made beside them; a rollback-mode copy with a hot journal is refused
#    rather than read without its journal (immutable is for WAL files without a -wal, or with an empty
#    one, only: a copy with a zero-length -wal is read as the others); such a
#    file (no -wal, no locks) is read from a copy in memory made at open, said in the log, and refused
#    beyond PALP_REVIEW_COPY_MB (0 here) naming it;
#  - a log shared through a group, read by another member: nothing left beside it (a read-only SQLite
#    connection leaves its -wal and -shm, and the log's owner could not write them), and the owner
#    writes after; the file not the reviewer's to write: read from a copy, nothing left either;
#  - migrate upgrades the file itself (user_version 1 -> current; the rows as the copy showed them),
#    and says there is nothing to do the second time;
#  - a write command (annotate) still writes and upgrades.
# usage: test_review_readonly.sh PALP_REVIEW MIGRATIONS_DIR TMPDIR
set -u
review=$1 migrations=$2 tmp=$3
dir=$tmp/readonly
rm -rf "$dir"
mkdir -p "$dir"
fail=0
ok() { echo "ok   $*"; }
bad() { echo "FAIL $*"; fail=1; }
current=$(ls "$migrations"/*.sql | wc -l)

# A log as palp with schema VERSION left it: the migrations up to VERSION, a session (ended, with two
# frames, an event and a graded note), WAL mode, cleanly closed (no -wal).
old_log() { # FILE VERSION
  {
    for m in "$migrations"/*.sql; do
      n=$(basename "$m" | cut -c1-4)
      [ "$(expr "$n" + 0)" -le "$2" ] && cat "$m"
    done
    echo "PRAGMA user_version = $2;
      INSERT INTO meta(key, value) VALUES('app_version', '0.0.9');
      INSERT INTO session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, tick_hz, dt_s,
        start_unix_s, end_unix_s, end_reason, end_detail)
        VALUES('old-run-1', 'carol', 'station-3', 'p1', 'dome old', '{}', '{}', 100, 0.01, 1.6e9, 1.6e9 + 2, 'normal', '');
      INSERT INTO frame(session_id, frame, sim_time_s, top_disp_m, max_disp_m, volume_m3, pressure_pa, contact_force_n,
        state_hash) VALUES(1, 1, 0.01, 1e-3, 2e-3, 1e-4, 5.0, 3.0, -42), (1, 2, 0.02, 1.5e-3, 2.5e-3, 1e-4, 5.5, 3.25, 7);
      INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count) VALUES(1, 1.6e9 + 1, 1, 'info', 'old event', 1);
      INSERT INTO note(session_id, author, wall_unix_s, text, grade) VALUES(1, 'Lee', 1.6e9 + 3, 'old note', 'B');
      PRAGMA journal_mode = WAL;"
  } | sqlite3 "$1" > /dev/null || bad "making $1"
}
state() { # FILE: what reading must not change; user_version from the header's bytes 60-63 (big-endian), as
  # sqlite3 itself, run as root, would make a -wal beside the file in the read-only directory below
  printf '%s %s %s' "$(sha256sum < "$1" | cut -c1-64)" "$(stat -c %.9Y "$1")" \
    "$(od -A n -t u1 -j 60 -N 4 "$1" | awk '{ print (($1 * 256 + $2) * 256 + $3) * 256 + $4 }')"
}

for v in 1 4; do
  db=$dir/v$v.db
  old_log "$db" "$v"
  before=$(state "$db")
  R() { "$review" --db "$db" "$@"; }
  R list > "$dir/list-$v.txt" 2> "$dir/list-$v.err" || bad "v$v: list exit status: $(cat "$dir/list-$v.err")"
  R show old-run-1 > "$dir/show-$v.txt" 2>&1 || bad "v$v: show exit status"
  R export old-run-1 --format csv > "$dir/export-$v.csv" 2>&1 || bad "v$v: export exit status"
  R export old-run-1 --format json --table notes --out "$dir/notes-$v.json" > /dev/null 2>&1 || bad "v$v: export notes"
  R report old-run-1 --out "$dir/report-$v.html" > /dev/null 2>&1 || bad "v$v: report exit status"
  R replay old-run-1 > /dev/null 2>&1; rc=$? # an empty scene: replay may refuse it, but must not crash
  [ $rc -lt 128 ] || bad "v$v: replay crashed ($rc)"
  R class --exercise none --out "$dir/class-$v.html" > /dev/null 2>&1 # no exercise sessions: exit 2, said
  R trainee carol > "$dir/trainee-$v.txt" 2>&1 || bad "v$v: trainee exit status"
  # a dry run only reads (session 81: prune --dry-run opened the file read-write and upgraded it in place)
  R prune --older-than 0 --dry-run > "$dir/dry-$v.txt" 2>&1 || bad "v$v: prune --dry-run exit status: $(cat "$dir/dry-$v.txt")"
  after=$(state "$db")
  if [ "$before" = "$after" ] && [ ! -e "$db-wal" ] && [ ! -e "$db-shm" ]; then
    ok "v$v: list, show, export, report, replay, class, trainee and prune --dry-run leave the file as it was (sha256 mtime user_version: $after), no -wal or -shm beside it"
  else bad "v$v: the file changed by reading it: $before -> $after; beside it: $(ls "$db"-* 2>&1)"; fi
  # its scene '{}' gives no metrics: the dry run says it would keep it (a real prune would too)
  grep -Eq "^(would prune|kept) +old-run-1" "$dir/dry-$v.txt" && ok "v$v: prune --dry-run read the session: $(grep old-run-1 "$dir/dry-$v.txt" | cut -c1-90)" ||
    bad "v$v: prune --dry-run: $(cat "$dir/dry-$v.txt")"
  if grep -Eq "^old-run-1 +carol +dome old +- +2020-09-13 .* +0\.02 normal +1 +'B' \(free text\)$" "$dir/list-$v.txt" &&
     grep -q '^1 session$' "$dir/list-$v.txt" &&
     grep -q "a log of schema version $v (an older palp's), read through a copy upgraded to version $current in memory; the file is left as it is" "$dir/list-$v.err"; then
    ok "v$v: list shows the old session (trainee, phantom, end, note, grade) and says it read a copy"
  else bad "v$v: list:"; cat "$dir/list-$v.txt" "$dir/list-$v.err"; fi
  if grep -q '^trainee    carol   station station-3$' "$dir/show-$v.txt" && grep -q '^events     1$' "$dir/show-$v.txt" &&
     grep -q "Lee \\[grade 'B' (free text)\\]: old note" "$dir/show-$v.txt" &&
     grep -q '^peak force           3.25 N at t = 0.02 s' "$dir/show-$v.txt"; then
    ok "v$v: show reads the old session's trainee, frames, event and note"
  else bad "v$v: show:"; cat "$dir/show-$v.txt"; fi
  if [ "$(grep -c '^[12],0.0[12],' "$dir/export-$v.csv")" = 2 ] && grep -Eq '^2,0\.02,0\.0015,0\.0025[0-9]*,0\.0001,5\.5,3\.25,0x0+7$' "$dir/export-$v.csv"; then
    ok "v$v: export csv gives both old frames"
  else bad "v$v: export:"; cat "$dir/export-$v.csv"; fi
done

# Too large to copy (PALP_REVIEW_COPY_MB=0: copy nothing): refused with the command that upgrades.
db=$dir/v1.db
before=$(state "$db")
if PALP_REVIEW_COPY_MB=0 "$review" --db "$db" list > "$dir/big.txt" 2>&1; then bad "a log too large to copy was read"
else
  rc=$?
  if [ $rc -eq 2 ] && grep -q "its schema version 1 is older than this palp's ($current), and reading it unchanged needs a copy in memory .*upgrade the file itself with \`palp-review --db $db migrate\`" "$dir/big.txt" &&
     [ "$(state "$db")" = "$before" ]; then
    ok "too large to copy: refused (exit 2), naming palp-review migrate, the file as it was"
  else bad "too large to copy: exit $rc, $(cat "$dir/big.txt")"; fi
fi

# A read-only directory, read-only files: copies of the old log and of a current one, read as a user
# who may not write there (root may write anywhere: palp-review then runs as nobody).
ro=$dir/ro
mkdir -p "$ro"
old_log "$ro/old.db" 1
old_log "$ro/current.db" 1
"$review" --db "$ro/current.db" migrate > /dev/null 2>&1 || bad "migrating the current copy"
# ... and one in rollback-journal mode left with a hot journal (its writer killed mid-transaction, as
# palp never leaves a log, but a copy made elsewhere may be): the journal holds the committed pages
# the transaction overwrote, so reading the file without it (immutable) would not be reading the log
python3 - "$ro/current.db" "$dir/hot.db" <<'PY' || bad "making a log with a hot journal"
import shutil, sqlite3, sys
c = sqlite3.connect(sys.argv[1], isolation_level=None)
c.execute("PRAGMA journal_mode = DELETE")
c.execute("PRAGMA cache_size = 5")  # dirty pages spill into the file before the commit
c.execute("BEGIN")
c.execute("UPDATE session SET trainee = 'uncommitted'")
for i in range(2000):
    c.execute("INSERT INTO event(session_id, wall_unix_s, frame, kind, detail) VALUES(1, 1.6e9, ?, 'info', ?)", (i, "x" * 200))
shutil.copy(sys.argv[1], sys.argv[2])
shutil.copy(sys.argv[1] + "-journal", sys.argv[2] + "-journal")
c.execute("ROLLBACK")
c.execute("PRAGMA journal_mode = WAL")
PY
mv "$dir/hot.db" "$dir/hot.db-journal" "$ro/"
# ... and a copy of the current log with an empty -wal beside it (a reader's, or one a checkpoint reset):
# it holds no commit, so the file is read as one without a -wal (2026-12-06; it was refused)
cp "$ro/current.db" "$ro/wal0.db"
: > "$ro/wal0.db-wal"
chmod 0444 "$ro"/*.db "$ro"/*.db-journal "$ro"/*.db-wal
chmod 0555 "$ro"
as_reader() {
  if [ "$(id -u)" = 0 ]; then setpriv --reuid=65534 --regid=65534 --clear-groups "$@"
  else "$@"; fi
}
if [ "$(id -u)" = 0 ] && as_reader sh -c ": > '$ro/probe'" 2>/dev/null; then bad "the read-only directory is writable for the reader"; fi
for f in old current wal0; do
  before=$(state "$ro/$f.db")
  as_reader "$review" --db "$ro/$f.db" list > "$dir/ro-$f.txt" 2>&1 || bad "read-only $f: list exit status: $(cat "$dir/ro-$f.txt")"
  as_reader "$review" --db "$ro/$f.db" show old-run-1 >> "$dir/ro-$f.txt" 2>&1 || bad "read-only $f: show exit status"
  if grep -Eq "^old-run-1 +carol " "$dir/ro-$f.txt" && grep -q '^trainee    carol ' "$dir/ro-$f.txt" &&
     [ "$(state "$ro/$f.db")" = "$before" ] && [ "$(ls -A "$ro" | tr '\n' ' ')" = "current.db hot.db hot.db-journal old.db wal0.db wal0.db-wal " ]; then
    ok "read-only directory and file ($f log, as $(as_reader id -un)): list and show read it, nothing made beside it"
  else bad "read-only directory ($f log): $(ls -A "$ro" | tr '\n' ' '): $(cat "$dir/ro-$f.txt")"; fi
  # ... from a copy taken at once (2026-12-06, found by review: read in place without locks for the whole
  # command, a writer opening the file meanwhile could checkpoint into it under the reads): said, and
  # bounded by PALP_REVIEW_COPY_MB as every copy is. What this shows is that the reads go to a copy made
  # when the file was opened, not that a change during the copy is caught (no test makes that race).
  if [ "$(grep -c "$ro/$f.db: no -wal beside it, and this user cannot write the file or its directory: read from a copy in memory taken at once" "$dir/ro-$f.txt")" = 2 ]; then
    ok "read-only directory ($f log): list and show each read from a copy in memory taken at open"
  else bad "read-only directory ($f log): no copy said: $(cat "$dir/ro-$f.txt")"; fi
  if PALP_REVIEW_COPY_MB=0 as_reader "$review" --db "$ro/$f.db" list > "$dir/ro-big-$f.txt" 2>&1; then
    bad "read-only directory ($f log): read without locks beyond PALP_REVIEW_COPY_MB=0: $(cat "$dir/ro-big-$f.txt")"
  elif grep -q "there is no -wal beside it and this user cannot write the file or its directory, .* more than the 0.0 MB allowed (PALP_REVIEW_COPY_MB)" "$dir/ro-big-$f.txt" &&
       [ "$(state "$ro/$f.db")" = "$before" ]; then
    ok "read-only directory ($f log), PALP_REVIEW_COPY_MB=0: refused naming PALP_REVIEW_COPY_MB, the file as it was"
  else bad "read-only directory ($f log), PALP_REVIEW_COPY_MB=0: $(cat "$dir/ro-big-$f.txt")"; fi
done
before=$(state "$ro/hot.db") jbefore=$(sha256sum < "$ro/hot.db-journal")
if as_reader "$review" --db "$ro/hot.db" list > "$dir/ro-hot.txt" 2>&1; then
  bad "read-only directory: a log with a hot journal was read past its journal: $(cat "$dir/ro-hot.txt")"
elif grep -q "hot.db: cannot read it: " "$dir/ro-hot.txt" && [ "$(state "$ro/hot.db")" = "$before" ] &&
     [ "$(sha256sum < "$ro/hot.db-journal")" = "$jbefore" ]; then
  ok "read-only directory: a rollback-mode log with a hot journal is refused (not read without its journal), both files as they were"
else bad "read-only directory, hot journal: $(cat "$dir/ro-hot.txt")"; fi
chmod 0755 "$ro"

# A log shared through a group (found by review, 2026-12-06): its owner (uid 65533) and a reviewer
# (uid 65534), both in group 4242, which may write the directory and the 0664 file. A read-only SQLite
# connection makes a -wal and -shm beside a cleanly closed WAL log and never removes them: they were
# left owned by the reviewer, 65534:65534 0664, and the owner's next write failed ("attempt to write a
# readonly database"). Now the reviewer's list and show leave nothing beside the file, its bytes and
# mtime as they were, and the owner writes. Then the file 0644 (the reviewer may write the directory,
# not the file, so SQLite could not remove what it made): read from a copy, nothing beside it, the
# owner writes again. Needs root to act as the two users: not root is a failure, not a skip (a run as a
# user would otherwise pass without the case, as the suite's other missing prerequisites fail).
if [ "$(id -u)" != 0 ]; then
  bad "the shared-directory case needs root (setpriv as two users); run the test as root"
else
  sh=$dir/shared
  mkdir -p "$sh"
  old_log "$sh/log.db" 1
  "$review" --db "$sh/log.db" migrate > /dev/null 2>&1 || bad "migrating the shared log"
  chown 65533:4242 "$sh/log.db" && chmod 0664 "$sh/log.db" && chown 0:4242 "$sh" && chmod 0775 "$sh" ||
    bad "setting the shared directory's owners"
  reviewer() { setpriv --reuid=65534 --regid=65534 --groups=4242 "$@"; }
  owner() { setpriv --reuid=65533 --regid=65533 --groups=4242 "$@"; }
  for mode in 0664 0644; do
    chmod "$mode" "$sh/log.db"
    # counted before the review: root's sqlite3, closing last, would remove what the reviewer left
    notes=$(sqlite3 "$sh/log.db" "SELECT count(*) FROM note")
    before=$(state "$sh/log.db")
    reviewer "$review" --db "$sh/log.db" list > "$dir/shared-$mode.txt" 2>&1 || bad "shared $mode: list exit status"
    reviewer "$review" --db "$sh/log.db" show old-run-1 >> "$dir/shared-$mode.txt" 2>&1 || bad "shared $mode: show exit status"
    left=$(ls -A "$sh" | tr '\n' ' ')
    if grep -Eq "^old-run-1 +carol " "$dir/shared-$mode.txt" && grep -q '^trainee    carol ' "$dir/shared-$mode.txt" &&
       [ "$left" = "log.db " ] && [ "$(state "$sh/log.db")" = "$before" ]; then
      ok "shared directory, the file $mode: the reviewer's list and show read it and leave nothing beside it, the file as it was"
    else bad "shared directory, the file $mode: beside it: $left; $(ls -ln "$sh"); $(cat "$dir/shared-$mode.txt")"; fi
    if owner "$review" --db "$sh/log.db" annotate old-run-1 --author Lee --note "after the review" > "$dir/shared-w-$mode.txt" 2>&1 &&
       [ "$(sqlite3 "$sh/log.db" "SELECT count(*) FROM note")" = $((notes + 1)) ]; then
      ok "shared directory, the file $mode: the owner writes the log after the review"
    else bad "shared directory, the file $mode: the owner's write: $(cat "$dir/shared-w-$mode.txt")"; fi
    rm -f "$sh/log.db-wal" "$sh/log.db-shm" # root's sqlite3 count above may leave them for the next round
  done
  if grep -q "no -wal beside it, and this user cannot write the file or its directory: read from a copy" "$dir/shared-0644.txt" &&
     ! grep -q "read from a copy" "$dir/shared-0664.txt"; then
    ok "shared directory: the 0664 file read in place, the 0644 one (not the reviewer's to tidy after) from a copy"
  else bad "shared directory: how each was read: $(cat "$dir/shared-0664.txt" "$dir/shared-0644.txt")"; fi
  chown -R 0:0 "$sh"
fi

# migrate: the file itself upgraded, its rows as the copy showed them; then nothing to do.
"$review" --db "$db" migrate > "$dir/migrate.txt" 2>&1 || bad "migrate exit status"
"$review" --db "$db" migrate >> "$dir/migrate.txt" 2>&1 || bad "migrate again exit status"
"$review" --db "$db" list > "$dir/list-migrated.txt" 2>/dev/null
if grep -q "^$db: upgraded from schema version 1 to $current$" "$dir/migrate.txt" &&
   grep -q "^$db: schema version $current, this palp's: nothing to upgrade$" "$dir/migrate.txt" &&
   [ "$(sqlite3 "$db" 'PRAGMA user_version')" = "$current" ] && cmp -s "$dir/list-1.txt" "$dir/list-migrated.txt"; then
  ok "migrate: upgraded 1 -> $current in the file, list the same as through the copy; again: nothing to upgrade"
else bad "migrate: $(cat "$dir/migrate.txt")"; diff "$dir/list-1.txt" "$dir/list-migrated.txt"; fi

# annotate writes, so it opens the file read-write and upgrades it
db=$dir/v4.db
"$review" --db "$db" annotate old-run-1 --author Lee --note "again" --score 60 > /dev/null 2>&1 || bad "annotate exit status"
if [ "$(sqlite3 "$db" 'PRAGMA user_version')" = "$current" ] && [ "$(sqlite3 "$db" "SELECT count(*) FROM note")" = 2 ]; then
  ok "annotate on a v4 log: the note written, the file upgraded to $current"
else bad "annotate on a v4 log"; fi

# --out never names the log being read (session 81, found by review: report --out the --db truncated it),
# nor its -wal or -shm (through another name: a symlink); an existing output is made 0600 as it is rewritten
# (it kept its 0644). The log's sha256 unchanged; then report, export, class --csv and trainee over 0644 files.
db=$dir/out.db
old_log "$db" "$current"
sqlite3 "$db" "PRAGMA journal_mode = DELETE" > /dev/null  # no -wal left to compare against
before=$(sha256sum < "$db")
cp "$db" "$dir/out2.db"  # for the modes below, whatever becomes of this one
ln -sf "$db" "$dir/out-link.db"
refused=""
for out in "$db" "$dir/out-link.db"; do
  "$review" --db "$db" report old-run-1 --out "$out" > "$dir/out-self.txt" 2>&1 && refused="$refused accepted:$out"
  grep -q "is the session log being read" "$dir/out-self.txt" || refused="$refused unsaid:$out"
  "$review" --db "$db" export old-run-1 --format csv --out "$out" > /dev/null 2>&1 && refused="$refused export:$out"
  "$review" --db "$db" trainee carol --out "$out" > /dev/null 2>&1 && refused="$refused trainee:$out"
done
[ -z "$refused" ] && [ "$(sha256sum < "$db")" = "$before" ] &&
  ok "--out the log itself (and through a symlink): report, export and trainee refuse, said; the log's sha256 unchanged" ||
  bad "--out the log itself:$refused; sha256 $before -> $(sha256sum < "$db"): $(cat "$dir/out-self.txt")"
modes=""
for f in report.html export.csv list.csv record.html; do
  echo old > "$dir/$f"
  chmod 0644 "$dir/$f"
done
db=$dir/out2.db
"$review" --db "$db" report old-run-1 --out "$dir/report.html" > /dev/null 2>&1 || bad "report over a 0644 file"
"$review" --db "$db" export old-run-1 --format csv --out "$dir/export.csv" > /dev/null 2>&1 || bad "export over a 0644 file"
"$review" --db "$db" trainee carol --csv "$dir/list.csv" --out "$dir/record.html" > /dev/null 2>&1 || bad "trainee over 0644 files"
for f in report.html export.csv list.csv record.html; do
  modes="$modes $f:$(stat -c %a "$dir/$f")"
  grep -q "^old$" "$dir/$f" && modes="$modes(not rewritten)"
done
[ "$modes" = " report.html:600 export.csv:600 list.csv:600 record.html:600" ] &&
  ok "outputs that were 0644 rewritten 0600:$modes" || bad "outputs over 0644 files:$modes"

[ $fail -eq 0 ] && rm -rf "$dir" && echo "passed" || echo "FAILED"
exit $fail
