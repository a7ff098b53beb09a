-- Schema version 3: assessment (issue 13, docs/assessment.md).
-- An exercise session's exercise, the fingertip's samples, the trainee's findings, and
-- structured grades. Units as in 0001: _m metres, _n newtons, _m2 square metres, _s seconds.

-- The exercise a session ran, as the server loaded it: hidden lesions included. A
-- trainee's station never sees this; the review reveals it.
CREATE TABLE session_exercise (
  session_id    INTEGER PRIMARY KEY REFERENCES session(id),
  exercise_name TEXT NOT NULL,          -- e.g. "easy"
  exercise_json TEXT NOT NULL           -- the exercise file's text (palp_exercise_parse reads it)
);

-- The position-driven fingertip after a physics step, as the assessment needs it
-- (palp_assess_sample), at most every min_interval the server is configured with.
-- frame is the world's frame after the step (as in frame and feedback).
CREATE TABLE finger_sample (
  session_id  INTEGER NOT NULL REFERENCES session(id),
  frame       INTEGER NOT NULL,
  slot        INTEGER NOT NULL,         -- the finger's contact id in the world
  sim_time_s  REAL NOT NULL,
  radius_m    REAL NOT NULL,            -- fingertip radius
  device_x_m  REAL NOT NULL, device_y_m REAL NOT NULL, device_z_m REAL NOT NULL,
  proxy_x_m   REAL NOT NULL, proxy_y_m  REAL NOT NULL, proxy_z_m  REAL NOT NULL,
  force_x_n   REAL NOT NULL, force_y_n  REAL NOT NULL, force_z_n  REAL NOT NULL,  -- phantom on finger
  in_contact  INTEGER NOT NULL CHECK (in_contact = 0 OR in_contact = 1),
  point_x_m   REAL NOT NULL, point_y_m  REAL NOT NULL, point_z_m  REAL NOT NULL,  -- contact point
  area_m2     REAL NOT NULL,            -- contact footprint
  triangles   BLOB,                     -- touched triangles: int32 little-endian mesh indices;
                                        -- NULL: the footprint is the disc of area_m2 around point
  PRIMARY KEY (session_id, frame, slot)
) WITHOUT ROWID;

-- "Lump here" marks and their withdrawals, in the order the server received them.
CREATE TABLE finding (
  id          INTEGER PRIMARY KEY,
  session_id  INTEGER NOT NULL REFERENCES session(id),
  mark_id     INTEGER NOT NULL,         -- the station's number for the mark; a withdrawal names it
  op          TEXT NOT NULL CHECK (op = 'mark' OR op = 'withdraw'),
  frame       INTEGER NOT NULL,         -- world frame when the server received it
  sim_time_s  REAL NOT NULL,            -- world time then
  wall_unix_s REAL NOT NULL,
  point_x_m   REAL, point_y_m REAL, point_z_m REAL  -- marks only
);
CREATE INDEX finding_session ON finding(session_id, id);

-- Structured grades: a note may carry a score 0..100 and/or a rubric level. The old
-- free-text grade column stays for notes written before version 3.
ALTER TABLE note ADD COLUMN score REAL CHECK (score IS NULL OR (score >= 0 AND score <= 100));
ALTER TABLE note ADD COLUMN level TEXT CHECK (level IS NULL OR level = 'insufficient' OR
                                              level = 'developing' OR level = 'competent' OR
                                              level = 'proficient');
