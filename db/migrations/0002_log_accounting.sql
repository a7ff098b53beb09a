-- Schema version 2: make incomplete logs visible.
-- A session records how many of its records the writer shed (queue full) or lost (disk error),
-- so a reviewer never mistakes a gap for a quiet trainee.
ALTER TABLE session ADD COLUMN records_shed INTEGER NOT NULL DEFAULT 0;
ALTER TABLE session ADD COLUMN records_failed INTEGER NOT NULL DEFAULT 0;

-- One row per writer that opened the file (a server run or a recorder), with its final counts.
CREATE TABLE writer_run (
  id             INTEGER PRIMARY KEY,
  app_version    TEXT NOT NULL,
  pid            INTEGER NOT NULL,
  opened_unix_s  REAL NOT NULL,
  closed_unix_s  REAL,                  -- NULL if the writer died without closing
  records_written INTEGER NOT NULL DEFAULT 0,
  records_shed   INTEGER NOT NULL DEFAULT 0,
  records_failed INTEGER NOT NULL DEFAULT 0,
  last_error     TEXT
);
