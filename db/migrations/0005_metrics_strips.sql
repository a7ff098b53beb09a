-- Schema version 5: the strips and their order (docs/assessment.md, "Strips and their order")
-- among a pruned session's stored metrics, so that the class report and the metrics CSV keep
-- them after palp-review prune. NULL in a row stored before version 5: unknown, not none.
ALTER TABLE session_metrics ADD COLUMN strips INTEGER;      -- runs along the axis >= 16 mm
ALTER TABLE session_metrics ADD COLUMN strip_order REAL;    -- palp_pattern_evidence.sweep_monotony [0, 1]
