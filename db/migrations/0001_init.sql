-- palp session log, schema version 1.
-- Units are SI and named in the column: _m metres, _n newtons, _pa pascals, _m3 cubic metres,
-- _s seconds, _hz hertz, _unix_s wall-clock seconds since 1970-01-01 UTC.

-- Key/value facts about the file itself: app_version, created_unix_s, upgraded_unix_s.
CREATE TABLE meta (
  key   TEXT PRIMARY KEY,
  value TEXT NOT NULL
);

-- One trainee session on one phantom.
CREATE TABLE session (
  id             INTEGER PRIMARY KEY,
  uid            TEXT NOT NULL UNIQUE,  -- chosen by the server, unique across server runs
  trainee        TEXT NOT NULL,
  station        TEXT NOT NULL,
  phantom_id     TEXT NOT NULL,
  phantom_name   TEXT NOT NULL,
  scene_json     TEXT NOT NULL,         -- the scene the world was built from (palp_scene_parse)
  params_json    TEXT NOT NULL,         -- server-side parameters of the phantom, informational
  tick_hz        REAL NOT NULL,
  dt_s           REAL NOT NULL,         -- fixed step the world was stepped with
  start_unix_s   REAL NOT NULL,
  end_unix_s     REAL,                  -- NULL while running or if the end was never logged
  end_reason     TEXT CHECK (end_reason IN ('normal', 'station_vanished', 'server_shutdown', 'error')),
  end_detail     TEXT
);
CREATE INDEX session_trainee ON session(trainee);
CREATE INDEX session_phantom ON session(phantom_id);
CREATE INDEX session_start ON session(start_unix_s);

-- Every contact input as the server applied it to the world, in order (id is the order).
-- Applied at `frame`, i.e. before the step from frame to frame + 1.
-- The CHECKs use OR, not IN (...): SQLite evaluates a CHECK's IN list through a temporary
-- table built on every statement execution, which tripled the cost of this 1 kHz insert.
CREATE TABLE contact_input (
  id              INTEGER PRIMARY KEY,
  session_id      INTEGER NOT NULL REFERENCES session(id),
  frame           INTEGER NOT NULL,
  sim_time_s      REAL NOT NULL,
  slot            INTEGER NOT NULL,     -- contact id in the server's world
  op              TEXT NOT NULL CHECK (op = 'add' OR op = 'update' OR op = 'remove'),
  kind            TEXT NOT NULL CHECK (kind = 'force' OR kind = 'finger'),
  distribution    INTEGER,              -- palp_distribution 1..4 (force contacts)
  center_x_m      REAL, center_y_m REAL, center_z_m REAL,
  force_x_n       REAL, force_y_n  REAL, force_z_n  REAL,  -- force contacts
  radius_m        REAL,                 -- fingers
  patch_area_m2   REAL,
  sigma_fraction  REAL,
  offset_fraction REAL,
  offset_dir_x    REAL, offset_dir_y REAL, offset_dir_z REAL
);
CREATE INDEX contact_input_session ON contact_input(session_id, frame);

-- Force feedback sent to the station: the force the phantom exerts on the contact [N].
CREATE TABLE feedback (
  session_id INTEGER NOT NULL REFERENCES session(id),
  frame      INTEGER NOT NULL,
  slot       INTEGER NOT NULL,
  force_x_n  REAL NOT NULL, force_y_n REAL NOT NULL, force_z_n REAL NOT NULL,
  PRIMARY KEY (session_id, frame, slot)
) WITHOUT ROWID;

-- Summary after each step; frame is the world's frame after the step.
CREATE TABLE frame (
  session_id      INTEGER NOT NULL REFERENCES session(id),
  frame           INTEGER NOT NULL,
  sim_time_s      REAL NOT NULL,
  top_disp_m      REAL NOT NULL,        -- |x - X| of the top (pole) vertex
  max_disp_m      REAL NOT NULL,        -- max over vertices of |x - X|
  volume_m3       REAL NOT NULL,
  pressure_pa     REAL NOT NULL,        -- gauge gel pressure
  contact_force_n REAL NOT NULL,        -- |sum of the contacts' feedback|
  state_hash      INTEGER NOT NULL,     -- palp_world_hash, the uint64 bits stored as int64
  PRIMARY KEY (session_id, frame)
) WITHOUT ROWID;

-- Full deformed surface at a reduced rate: vertex_count * 3 little-endian IEEE-754 doubles [m].
CREATE TABLE mesh (
  session_id   INTEGER NOT NULL REFERENCES session(id),
  frame        INTEGER NOT NULL,
  vertex_count INTEGER NOT NULL,
  positions_m  BLOB NOT NULL,
  PRIMARY KEY (session_id, frame)
);

-- join, leave, reject, clamp, overrun, shed, disk_error, info.
CREATE TABLE event (
  id          INTEGER PRIMARY KEY,
  session_id  INTEGER REFERENCES session(id),  -- NULL for server-wide events
  wall_unix_s REAL NOT NULL,
  frame       INTEGER,
  kind        TEXT NOT NULL,
  detail      TEXT NOT NULL DEFAULT '',
  count       INTEGER NOT NULL DEFAULT 1        -- how many occurrences this row stands for
);
CREATE INDEX event_session ON event(session_id, id);

-- Instructor notes and grades.
CREATE TABLE note (
  id          INTEGER PRIMARY KEY,
  session_id  INTEGER NOT NULL REFERENCES session(id),
  author      TEXT NOT NULL,
  wall_unix_s REAL NOT NULL,
  text        TEXT NOT NULL,
  grade       TEXT
);
CREATE INDEX note_session ON note(session_id);
