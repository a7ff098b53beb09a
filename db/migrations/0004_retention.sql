-- Schema version 4: retention (issue 13, docs/db.md "Retention").
-- palp-review prune keeps a session's row, exercise, findings and notes/grades but deletes its
-- bulky data (frames, feedback, contact inputs, meshes, finger samples); before it does, it
-- stores the session's metrics here, so list, show, export --table metrics and the class report
-- still have them. palp-review delete removes a session entirely, this row included.
CREATE TABLE session_metrics (
  session_id      INTEGER PRIMARY KEY REFERENCES session(id),
  computed_unix_s REAL NOT NULL,
  exercise_name   TEXT,                 -- NULL: free practice
  samples         INTEGER NOT NULL,     -- finger samples assessed
  lesions         INTEGER NOT NULL,
  found           INTEGER NOT NULL,
  findings        INTEGER NOT NULL,     -- marks, withdrawn ones included
  withdrawn       INTEGER NOT NULL,
  false_positives INTEGER NOT NULL,
  coverage_light  REAL NOT NULL,        -- share of the dome's area palpated in each band [0, 1]
  coverage_medium REAL NOT NULL,
  coverage_deep   REAL NOT NULL,
  coverage_any    REAL NOT NULL,
  pattern         TEXT NOT NULL,        -- palp_pattern_name
  path_length_m   REAL NOT NULL,
  presses         INTEGER NOT NULL,
  duration_s      REAL NOT NULL,
  peak_force_n    REAL NOT NULL,
  out_of_range    INTEGER NOT NULL,
  score           REAL,                 -- NULL: free practice
  pass            INTEGER               -- NULL: free practice
);

-- When the session's bulky data was pruned (NULL: never): readers say so instead of showing
-- an empty session as if nothing happened.
ALTER TABLE session ADD COLUMN pruned_unix_s REAL;
