/* dashboard.js - every open session of the class on a grid, each with a live top view, and the
 * server's load and log counters. Sessions appear and disappear as the bridge's session list
 * changes (no reload); a click opens the trainee view of that session. Below the grid, the exercise
 * sessions that ended lately, each with what its trainee's marks found (the server's debrief). */
"use strict";
(function () {
  const st = PALP.state;
  st.dashboard = { cards: [], frames: 0, fpsPerSession: {} };
  const grid = document.getElementById("grid"), cards = new Map();
  let scaleMin = 30, scaleMax = 30; /* the bridge's bounds of each card's own scale (PALP.scaleFor) */
  /* server/validate.h palp_srv_reject_reason, in index order (docs/server.md) */
  const REJECT = ["nonfinite", "unknown_session", "bad_finger", "bad_mode", "bad_distribution", "bad_vertex",
    "out_of_reach", "force_limit", "bad_radius", "model_refused"];
  const SIZE = 150;
  /* The hidden lumps of exercise sessions (an `answers` message: the bridge sends them to this page
   * alone, docs/web.md "The hidden lumps"), by session id; shown unless the instructor hides them
   * (the box in the legend, e.g. before turning the screen to the class). */
  const answersOf = new Map(), showAnswers = document.getElementById("show-answers");
  /* Each session's pressed skin so far (a `cover` message: a hex digit per rest vertex, its bands as
   * bits 1 light, 2 medium, 4 deep), dotted on the top view in the bands' colours (docs/naming.md). */
  const showCover = document.getElementById("show-cover");

  function fmt(x, d) { return x === null || x === undefined ? "n/a" : Number(x).toFixed(d); }

  function makeCard(s) {
    const el = document.createElement("div");
    el.className = "card";
    el.dataset.session = s.id;
    const h = document.createElement("h3");
    const name = document.createElement("span"), band = document.createElement("span");
    h.append(name, band);
    const cv = document.createElement("canvas");
    cv.width = cv.height = SIZE;
    const tb = document.createElement("table");
    const lumps = document.createElement("ul");
    lumps.className = "lumps";
    el.append(h, cv, lumps, tb);
    el.addEventListener("click", function () {
      /* followed as an observer: the instructor's view of a trainee page never marks findings */
      location.href = PALP.withToken("trainee.html?session=" + s.id + "&role=observer"); /* taken out of the address there */
    });
    grid.appendChild(el);
    const c = { el: el, name: name, band: band, canvas: cv, table: tb, lumps: lumps, proj: null, disp: null, phantom: 0, frames: 0, t0: performance.now(), fps: 0,
      scaleMm: scaleMin };
    cards.set(s.id, c);
    return c;
  }

  /* Top view: the dome's triangles seen from above, at rest positions (a press shows as colour). */
  function projection(ph) {
    const R = ph.radius, k = (SIZE / 2 - 4) / R, n = ph.dome_triangles, xy = new Float32Array(ph.rest.length / 3 * 2);
    for (let i = 0; i < xy.length / 2; i++) { xy[2 * i] = SIZE / 2 + k * ph.rest[3 * i]; xy[2 * i + 1] = SIZE / 2 - k * ph.rest[3 * i + 1]; }
    return { xy: xy, tri: ph.triangles.slice(0, 3 * n), n: ph.rest.length / 3, k: k };
  }

  /* The hidden lumps over the top view: each lump a circle of its size around its place on the skin
   * (solid when a standing mark found it, dashed while none has), each standing mark a cross (in
   * the warning red when near no lump), numbered as the lists number them. */
  function drawAnswers(c, g) {
    const a = answersOf.get(Number(c.el.dataset.session));
    if (!a || !showAnswers.checked || !c.proj) return;
    const k = c.proj.k;
    const at = function (p) { return [SIZE / 2 + k * p[0] / 1000, SIZE / 2 - k * p[1] / 1000]; };
    g.save();
    g.lineWidth = 2;
    g.font = "10px sans-serif";
    a.lumps.forEach(function (l, i) {
      const p = at(l.point_mm);
      g.setLineDash(l.found_by ? [] : [4, 3]);
      g.strokeStyle = "#fff";
      g.beginPath();
      g.arc(p[0], p[1], Math.max(3, k * l.across_mm / 2000), 0, 2 * Math.PI);
      g.stroke();
      g.fillStyle = "#fff";
      g.fillText(String(i + 1), p[0] + 2, p[1] - 2);
    });
    g.setLineDash([]);
    for (const m of a.marks_at) {
      const p = at(m.point_mm);
      g.strokeStyle = m.lump > 0 ? "#000" : "#b00020";
      g.beginPath();
      g.moveTo(p[0] - 4, p[1] - 4); g.lineTo(p[0] + 4, p[1] + 4);
      g.moveTo(p[0] + 4, p[1] - 4); g.lineTo(p[0] - 4, p[1] + 4);
      g.stroke();
    }
    g.restore();
  }

  /* The hidden lumps under the top view, in the debrief's words (PALP.debriefLump), live. */
  /* The first line of a session's hidden lumps (an `answers` message), live or ended: what its
   * standing marks found, in warning red while a lump is unfound or a mark near none. */
  function answersHead(li, lead, a) {
    const near = a.marks_at.filter(function (m) { return m.lump === 0; }).length;
    li.textContent = lead + PALP.debriefFound(a) + "; " + PALP.plural(a.marks, "mark", "marks") + " standing, " + near +
      " near no lump" +
      (a.unanswered ? "; " + PALP.plural(a.unanswered, "finding", "findings") + " whose answer the bridge missed" : "");
    li.className = a.found < a.lesions || near ? "warn" : "";
  }
  function listAnswers(c) {
    const a = answersOf.get(Number(c.el.dataset.session));
    c.lumps.textContent = "";
    if (!a) return;
    const head = document.createElement("li");
    if (!showAnswers.checked) {
      head.textContent = "hidden lumps: not shown (the box above)";
      head.className = "muted";
      c.lumps.appendChild(head);
      return;
    }
    answersHead(head, "hidden lumps, the trainee does not see them: ", a);
    c.lumps.appendChild(head);
    a.lumps.forEach(function (l, i) {
      const li = document.createElement("li");
      li.textContent = PALP.debriefLump(l, i, true);
      li.className = l.found_by ? "found" : "";
      c.lumps.appendChild(li);
    });
  }

  function drawCover(c, g) {
    const b = c.cover;
    if (!showCover.checked || !c.proj || !PALP.coverValid(b, c.proj.n)) return;
    const xy = c.proj.xy;
    g.save();
    g.strokeStyle = "#000";
    g.lineWidth = 0.5;
    for (let i = 0; i < b.length; i++) {
      const rgb = PALP.coverColour(b[i]);
      if (!rgb) continue;
      g.fillStyle = PALP.css(rgb);
      g.beginPath();
      g.arc(xy[2 * i], xy[2 * i + 1], 2, 0, 2 * Math.PI);
      g.fill();
      g.stroke();
    }
    g.restore();
  }

  function draw(c, disp) {
    if (!c.proj || (disp && disp.length !== 3 * c.proj.n)) return;
    c.disp = disp;
    const g = c.canvas.getContext("2d"), xy = c.proj.xy, tri = c.proj.tri;
    g.clearRect(0, 0, SIZE, SIZE);
    const mag = new Float32Array(c.proj.n);
    let peak = 0;
    if (disp) for (let i = 0; i < c.proj.n; i++) peak = Math.max(peak, mag[i] = 1000 * Math.hypot(disp[3 * i], disp[3 * i + 1], disp[3 * i + 2]));
    c.scaleMm = PALP.scaleFor(c.scaleMm, peak, scaleMin, scaleMax);
    const scaleMm = c.scaleMm;
    for (let t = 0; t < tri.length; t += 3) {
      const a = tri[t], b = tri[t + 1], d = tri[t + 2];
      g.fillStyle = g.strokeStyle = PALP.css(PALP.viridis((mag[a] + mag[b] + mag[d]) / 3 / scaleMm));
      g.beginPath();
      g.moveTo(xy[2 * a], xy[2 * a + 1]);
      g.lineTo(xy[2 * b], xy[2 * b + 1]);
      g.lineTo(xy[2 * d], xy[2 * d + 1]);
      g.closePath();
      g.fill();
      g.stroke();
    }
    drawCover(c, g);
    drawAnswers(c, g);
  }

  /* LM_* bits (idl/palp_types.idl): now / seen since the session opened, in the station's and the
   * review's words for the valid range's limits (docs/naming.md), and the time outside it. */
  const LM_NAMES = [[1, "force limit"], [2, "skin stretched or bent beyond the model"], [4, "on the base"],
                    [8, "harder than the model can follow"], [16, "contact unsolved"],
                    [64, "deeper than checked against the reference model"],
                    [128, "gel law outside its stable range"]];
  function modelFlags(s) {
    if (s.model_flags_seen === undefined) return "n/a";
    const names = function (v) { return LM_NAMES.filter(function (x) { return v & x[0]; }).map(function (x) { return x[1]; }); };
    if (!s.model_flags_seen) return s.position_finger ? "ok" : "n/a";
    const now = names(s.model_flags);
    const outside = s.outside_s > 0 ? "; outside the valid range " + fmt(s.outside_s, 2) + " s" : "";
    return (now.length ? "now " + now.join(", ") : "ok now") + "; seen " + names(s.model_flags_seen).join(", ") + outside;
  }
  function fill(c, s) {
    c.name.textContent = s.trainee + ", session " + s.id; /* the stations' "session N" (docs/naming.md) */
    /* Held for a lost station, the last force the bridge saw is stale: the server lifted the finger. */
    /* an exercise's band is by the fingertip's depth, as it is graded: 3.5 N can be medium there */
    c.band.textContent = s.status ? "station lost" : fmt(s.force, 2) + " N " + s.band +
      (s.band_rule === "exercise" ? " (by depth)" : "");
    c.band.className = s.status ? "band" : "band " + s.band;
    const rows = [["phantom", s.phantom_name || s.phantom],
      ["trainee station", s.status ? s.status : "connected", !!s.status,
        "the server's word on the trainee's station: a station it lost (a crash, or a machine stalled past its lease) " +
        "keeps its session a few seconds to come back (docs/server.md, station_grace)"],
      ["exercise", s.exercise || "none"],
      s.band_rule === "exercise" ?
        ["coverage l / m / d", fmt(100 * s.coverage[0], 1) + " / " + fmt(100 * s.coverage[1], 1) + " / " +
          fmt(100 * s.coverage[2], 1) + " %", false, /* %, 1 decimal (docs/naming.md) */
          "share of the dome's skin pressed at light, medium and deep pressure, each level itself, as the exercise " +
          "grades thoroughness (by the fingertip's depth), since the bridge began following the session: the skin under " +
          "the fingertip at the physics steps the review samples (a force-driven finger: the footprint disc around each " +
          "sampled contact point, 30 samples/s); the review's figures count every logged step's touched skin"] :
        ["coverage", fmt(100 * s.coverage[0], 1) + " %", false,
          "share of the dome's skin pressed at least lightly, since the bridge began following the session: " +
          "the skin under the fingertip at the physics steps the review samples (a force-driven finger: the footprint " +
          "disc around each sampled contact point, 30 samples/s), marked on the rest mesh"],
      ["findings", s.findings === null ? "n/a" : s.findings, false,
        s.findings === null ? "no findings status from the server (no exercise, or none marked yet)" : "marks standing (the server's count)"],
      ["time left", s.time_left === null || s.time_left === undefined ? (s.findings !== null ? "no limit" : "n/a") : PALP.minutes(s.time_left),
        s.time_left !== null && s.time_left !== undefined && s.time_left < 60,
        "the exercise's time limit less the session's age (the server's figure, twice a second); in its last minute in red"],
      ["peak force", fmt(s.peak_force, 2) + " N"],
      ["late physics steps", s.overruns, s.overruns > 0,
        "its physics steps that ended after the next tick's start, or that its tick thread skipped behind schedule (the server's count)"], ["rejected samples", s.rejected, s.rejected > 0],
      ["position finger", s.position_finger === undefined ? "n/a" : (s.position_finger ? "active" : "none")],
      ["model validity", modelFlags(s), (s.model_flags_seen || 0) !== 0],
      /* from the local models the bridge receives (docs/web.md) */
      ["late haptic updates", s.late_haptic === null ? "n/a" : s.late_haptic + (s.lost_haptic ? " (+" + s.lost_haptic + " lost)" : ""),
        s.late_haptic > 0,
        s.late_haptic === null ? "n/a: no haptic local models in this session (force-driven input has none)"
          : "local models published more than 2 physics periods after the previous frame's (server clock); " +
            "lost: frames the bridge never received"],
      /* session 69: which sessions' reviews will be incomplete, not only that the server's log loses records */
      ["session log", !s.log_lost ? "nothing lost" : s.log_own ? s.log_lost + " of its records lost"
        : PALP.plural(s.log_lost, "record", "records") + " lost by the server while it ran", s.log_lost > 0,
        s.log_own || !s.log_lost ? "this session's own records the server's session log lost while it ran (palp_session_log): " +
          "its review will be incomplete by that many (palp-review show counts the same)"
          : "the records the server's session log lost while this session ran, all sessions' (its server says no " +
            "session's own: older server or permissions)"],
      ["colour scale", "0-" + c.scaleMm + " mm", false, "the top view's full colour scale: grows with the session's deepest displacement, never shrinks"],
      ["frames/s", fmt(c.fps, 1)], ["open", fmt(s.duration, 0) + " s"]];
    c.table.textContent = "";
    for (const r of rows) {
      const tr = c.table.insertRow();
      tr.insertCell().textContent = r[0];
      const v = tr.insertCell();
      v.textContent = String(r[1]);
      if (r[2]) v.className = "warn";
      if (r[3]) tr.title = r[3];
    }
    if (c.phantom !== s.phantom && st.phantoms[s.phantom]) {
      c.phantom = s.phantom;
      c.proj = projection(st.phantoms[s.phantom]);
      draw(c, null);
    }
    listAnswers(c);
  }

  /* The session log in words, from the counters of successive statuses (1 Hz), as the server's own log
   * says it (db/loss_watch.c): losing now (it lost more within the last LOSING_HOLD_MS: a full file's
   * batches fail some 0.4 s apart, and a small one may find room between), writing again (wrote more
   * since, lost no more), or lost earlier and quiet since. The counters alone (red) left an instructor
   * to guess what was wrong and what to do. server id -> {lost, rose (ms), writtenAtRise, state} */
  const LOSING_HOLD_MS = 3000;
  const logSeen = new Map();
  function logWords(s) {
    const written = s.log[0], shed = s.log[1], failed = s.log[2], lost = shed + failed, now = Date.now();
    const prev = logSeen.get(s.id);
    let cur;
    if (prev && lost > prev.lost) cur = {lost: lost, rose: now, writtenAtRise: written, state: "losing"};
    else if (prev && prev.state === "losing" && now - prev.rose < LOSING_HOLD_MS) cur = prev;
    else if (prev) cur = {lost: lost, rose: prev.rose, writtenAtRise: prev.writtenAtRise,
                          state: written > prev.writtenAtRise ? "writing" : "quiet"};
    else cur = {lost: lost, rose: null, writtenAtRise: written, state: "quiet"}; /* lost before this page came */
    logSeen.set(s.id, cur);
    if (!lost) return null;
    const why = "(" + shed + " shed: its queue was full; " + failed + " failed: its file reached its cap " +
      "(session_log_max_mb) or its disk is full, or it cannot write)";
    const todo = "; prune old sessions (palp-review prune), free space or raise the cap; the server's log says which";
    if (cur.state === "losing") return "LOSING records: " + lost + " lost so far " + why + todo;
    if (cur.state === "writing") return "writing again; " + lost + " records lost earlier " + why;
    return lost + " records lost " + why + (cur.rose !== null ? ", the last " + PALP.minutes((now - cur.rose) / 1000) +
      " ago; nothing written since" : ", before this page opened") + todo;
  }

  function serverStatus(m) {
    const box = document.getElementById("server");
    box.textContent = "";
    for (const s of m.servers) {
      const rej = s.rejected.reduce(function (a, b) { return a + b; }, 0);
      const why = s.rejected.map(function (n, i) { return n ? REJECT[i] + " " + n : ""; }).filter(Boolean).join(", ");
      const items = [["server", s.id], ["load", fmt(100 * s.load, 0) + " %", s.load > 0.8],
        ["tick p50/p99/max", fmt(s.tick_us[0], 0) + " / " + fmt(s.tick_us[1], 0) + " / " + fmt(s.tick_us[2], 0) + " us"],
        ["sessions", s.sessions_open + " open, " + s.sessions_total + " total"], ["ticks", s.ticks],
        ["tick passes overrun", s.overruns, s.overruns > 0], ["rejected", rej + (why ? " (" + why + ")" : ""), rej > 0],
        ["log written/shed/failed", s.log[0] + " / " + s.log[1] + " / " + s.log[2], s.log[1] + s.log[2] > 0],
        ["up", fmt(s.uptime, 0) + " s"]];
      const words = logWords(s);
      if (words) items.splice(items.length - 1, 0, ["session log", words, true]);
      for (const it of items) {
        const k = document.createElement("span"), v = document.createElement("span");
        k.className = "k";
        k.textContent = it[0];
        v.className = "v" + (it[2] ? " bad" : "");
        v.textContent = String(it[1]);
        box.append(k, v);
      }
    }
    /* Stations DDS Security refused: they cannot join, and nobody else tells them why. */
    if (m.refused && m.refused.length) {
      const k = document.createElement("span"), v = document.createElement("span");
      k.className = "k";
      k.textContent = "refused by DDS Security";
      v.className = "v bad";
      v.id = "refused";
      v.textContent = m.refused.map(function (r) { return r.who + ": " + r.why + " (" + r.count + "x)"; }).join("; ");
      box.append(k, v);
    }
  }

  /* ---- ended exercise sessions: each one's debrief (docs/web.md, "Debrief") ----
   * The bridge sends a debrief as a session ends and, to a page following every session, the ones it
   * still holds from before the page connected (its last 16, oldest first); so each is put on top.
   * Everything in a row comes from the network: textContent only. */
  const ENDED_MAX = 16; /* the bridge's ring (web/hub.c DEBRIEFS): a long class does not grow the page */
  const ended = document.getElementById("debriefs"), endedRows = new Map(); /* session id -> its row */
  /* session id -> its exercise's name, from the session list while it was open: the debrief names it
   * too (web/hub.c, from the phantom's palp_exercise), this for a bridge that did not see that one.
   * Bounded: the oldest entries go first, an open session's comes back with the next list. */
  const exerciseOf = new Map(), EXERCISES_KEPT = 4 * ENDED_MAX + 64;
  function cell(tr, text, cls, title) {
    const td = tr.insertCell();
    td.textContent = String(text);
    if (cls) td.className = cls;
    if (title) td.title = title;
    return td;
  }
  /* An ended session whose trainee was not told where the lumps were (debrief "count" or "none",
   * an examination): what the marks found, from the bridge's last answers of the session (an
   * `answers` message with "ended"), for the instructor's eyes, under the same box as the live ones. */
  const endedAnswers = new Map(); /* session id -> its last answers; bounded as the rows are */
  function hiddenEnded(tr) {
    const level = tr.dataset.untold, a = endedAnswers.get(Number(tr.dataset.session));
    const cellEl = tr.querySelector("td.lumps");
    cellEl.textContent = "";
    cellEl.className = "lumps muted";
    const told = level === "count" ? "not told where: the exercise tells the count only"
      : "not told: the exercise tells nothing";
    if (!a) { cellEl.textContent = level === "count" ? told : ""; return; }
    if (!showAnswers.checked) {
      cellEl.textContent = (level === "count" ? told + "; " : "") + "hidden lumps: not shown (the box above)";
      return;
    }
    const ul = document.createElement("ul"), head = document.createElement("li");
    answersHead(head, "hidden lumps, the trainee was not told: ", a);
    ul.appendChild(head);
    a.lumps.forEach(function (l, i) {
      const li = document.createElement("li");
      li.textContent = PALP.debriefLump(l, i);
      li.className = l.found_by ? "found" : "bad";
      ul.appendChild(li);
    });
    cellEl.className = "lumps";
    cellEl.appendChild(ul);
  }
  /* The server's score of an ended session (a `score` message: palp_session_score, graded from the
   * server's own log seconds after the session ended; web/hub.c on_score), with the command that shows
   * it in full. It may come before the session's row (a reconnect's replay sends debriefs first, but a
   * bridge may miss one): kept by session, bounded as the rows are. */
  const scores = new Map(); /* session id -> its score message */
  const METRICS = [["sensitivity", "sensitivity"], ["false_positives", "false positives"], ["thoroughness", "thoroughness"],
    ["pattern", "search pattern"], ["time", "time"], ["force", "force"]];
  /* An ended session's message kept by session (its row may come later), newest last, bounded as the
   * rows are: the oldest go first. The tests read the same in palpState.dashboard[name]. */
  function keepEnded(map, name, m) {
    map.delete(m.session);
    map.set(m.session, m);
    st.dashboard[name] = st.dashboard[name] || {};
    st.dashboard[name][m.session] = m;
    for (const id of map.keys()) {
      if (map.size <= 2 * ENDED_MAX) break;
      map.delete(id);
      delete st.dashboard[name][id];
    }
  }
  function scoreCell(tr) {
    const td = tr.querySelector("td.score"), s = scores.get(Number(tr.dataset.session));
    td.textContent = "";
    td.className = "score n";
    if (!s) {
      td.textContent = "n/a";
      td.className += " muted";
      td.title = "no score from the server (yet): it scores an exercise session from its log seconds after the " +
        "session ends, where only instructors can read it (DDS Security on, or its config's session_exercise " +
        "\"always\"); palp-review show gives it from the log";
      return;
    }
    const how = document.createElement("div");
    how.className = "muted";
    how.textContent = "palp-review show " + s.log_uid;
    if (!s.graded) {
      td.append("not scored");
      td.appendChild(how);
      td.className += " muted";
      td.title = "the server could not score this session from its log: " + s.reason;
      return;
    }
    td.append(s.score.toFixed(1) + " " + (s.pass ? "pass" : "fail"));
    if (s.log_complete === false) { /* records lost: the score may be low; the review says the same */
      const warn = document.createElement("div");
      warn.className = "warn";
      warn.textContent = "from a damaged log";
      td.appendChild(warn);
    }
    td.appendChild(how);
    td.className += s.pass ? " pass" : " bad";
    td.title = "the automatic score (0-100) of the exercise's rubric, as palp-review show prints it: " +
      METRICS.map(function (k) {
        return k[1] + " " + Number(s.credit[k[0]]).toFixed(2) + (s.passed[k[0]] ? " (passed)" : " (not passed)");
      }).join(", ") + "; found " + s.found + " of " + s.lesions + ", " + PALP.plural(s.false_marks, "mark", "marks") +
      " near no lump; covered " + s.coverage.join(" / ") + " %; " + s.pattern.replace("_", " ") + " search; " +
      PALP.minutes(s.duration) + " palpating, peak " + s.peak_force + " N; the log: " + s.log_health;
  }
  function debrief(m) {
    if (!Number.isFinite(m.session) || (m.level === "lesions" && !(Array.isArray(m.lumps) && m.lumps.every(PALP.lumpValid))))
      return; /* checked before use (since session 82) */
    const old = endedRows.get(m.session);
    if (old) old.remove(); /* a reconnect's replay: each session once, in the bridge's order */
    const tr = document.createElement("tr"), told = m.level !== "none";
    tr.dataset.session = m.session;
    cell(tr, m.session, "n");
    cell(tr, m.trainee);
    cell(tr, m.exercise || exerciseOf.get(m.session) || "n/a");
    cell(tr, told ? PALP.debriefFound(m) : "not told: the exercise tells nothing", told && m.found < m.lesions ? "warn" : "",
      told ? "lumps the standing marks found (the server matches them as the review does)"
        : "the exercise's debrief is \"none\": the trainee was told nothing of its lumps, not even how many; the review tells");
    cell(tr, m.marks, "n", "marks standing at the session's end (withdrawn marks do not count)");
    cell(tr, told ? m.false_marks : "n/a", "n" + (told && m.false_marks > 0 ? " bad" : ""), "standing marks near no lump");
    cell(tr, told ? m.duplicates : "n/a", "n" + (told && m.duplicates > 0 ? " warn" : ""), "standing marks on a lump another mark found");
    cell(tr, m.reason + (Number.isFinite(m.duration) ? " after " + PALP.minutes(m.duration) : ""), "",
      "why the session ended (the server's word), and after how long (m:ss, the server's figure)");
    const cov = PALP.coveredText(m); /* as the card's "coverage l / m / d" while it ran */
    cell(tr, cov ? m.coverage.map(function (f) { return (100 * f).toFixed(1); }).join(" / ") + " %" : "n/a", "n",
      cov ? "the skin pressed at light, medium and deep pressure, each level itself, as the exercise grades thoroughness " +
        "(the bridge's own figure since it began following the session; the review's within a few points): " + cov
        : "the bridge saw no coverage in the exercise's bands for this session");
    tr.insertCell().className = "score"; /* the server's score, when it comes (scoreCell) */
    const lumps = tr.insertCell();
    lumps.className = "lumps";
    if (m.level === "lesions") {
      const ul = document.createElement("ul");
      m.lumps.forEach(function (l, i) {
        const li = document.createElement("li");
        li.textContent = PALP.debriefLump(l, i); /* the trainee page's words */
        li.className = l.found_by ? "found" : "bad";
        ul.appendChild(li);
      });
      lumps.appendChild(ul);
    } else {
      tr.dataset.untold = m.level; /* the instructor's view of it, when the bridge kept one (hiddenEnded) */
      hiddenEnded(tr);
    }
    scoreCell(tr);
    addEnded(tr, m.session, ended.firstChild);
  }
  function addEnded(tr, session, before) {
    ended.insertBefore(tr, before);
    endedRows.set(session, tr);
    while (ended.rows.length > ENDED_MAX) {
      const last = ended.rows[ended.rows.length - 1];
      endedRows.delete(Number(last.dataset.session));
      last.remove();
    }
    document.getElementById("no-debriefs").hidden = true;
  }
  /* A score whose session has no row: one that ended before this page's bridge began following it (a
   * restarted palp-web gets the server's last 64 scores, kept for late readers, but no debrief: the
   * session's own writer is gone). The row says what the score says and where the rest is; the
   * session's debrief, should it come after all, replaces it (debrief()). In session order, newest on
   * top, among the rows there are (ids grow as sessions open). */
  function scoreRow(m) {
    const tr = document.createElement("tr"), g = m.graded === true && Array.isArray(m.coverage) && Number.isFinite(m.duration);
    const rest = "palp-review show " + m.log_uid + " gives it from the server's log";
    tr.dataset.session = m.session;
    tr.dataset.fromScore = "1";
    cell(tr, m.session, "n");
    cell(tr, m.trainee || "n/a", m.trainee ? "" : "muted", m.trainee ?
      "the session ended before this page's bridge followed it; its trainee as the server named her as it closed" :
      "the session ended before this page's bridge followed it, and no server said its trainee (an older server or " +
      "permissions): " + rest);
    cell(tr, m.exercise || "n/a");
    cell(tr, g ? PALP.debriefFound(m) : "n/a", g && m.found < m.lesions ? "warn" : "",
      "lumps the standing marks found, as the server's score counts them");
    cell(tr, "n/a", "n muted", "not in the server's score: " + rest);
    cell(tr, g ? m.false_marks : "n/a", "n" + (g && m.false_marks > 0 ? " bad" : ""), "standing marks near no lump");
    cell(tr, "n/a", "n muted", "not in the server's score: " + rest);
    cell(tr, "before this page's bridge followed it" + (g ? "; palpated " + PALP.minutes(m.duration) : ""), "muted",
      "the bridge did not see this session end (it was restarted since); the time is the score's, first to last " +
      "finger sample");
    cell(tr, g ? m.coverage.map(function (f) { return Number(f).toFixed(1); }).join(" / ") + " %" : "n/a", "n",
      "the skin pressed at light, medium and deep pressure, as the server's score grades thoroughness");
    tr.insertCell().className = "score";
    cell(tr, "not seen by this bridge: " + rest, "lumps muted");
    scoreCell(tr);
    let before = ended.firstChild;
    while (before && Number(before.dataset.session) > m.session) before = before.nextSibling;
    addEnded(tr, m.session, before);
  }

  showAnswers.addEventListener("change", function () {
    for (const c of cards.values()) { listAnswers(c); draw(c, c.disp); }
    for (const tr of endedRows.values()) if (tr.dataset.untold) hiddenEnded(tr);
  });
  showCover.addEventListener("change", function () {
    for (const c of cards.values()) draw(c, c.disp);
  });

  /* A closed session's entries in the page's state go with its card: kept, they grew with every session
   * of a class (its pressed-skin map a digit per vertex). */
  function forget(id) {
    for (const k of ["cover", "answers", "fpsPerSession"]) if (st.dashboard[k]) delete st.dashboard[k][id];
  }

  PALP.connect({
    open: function (send) { send({ follow: "all" }); },
    hello: function (m) {
      scaleMax = m.scale_mm;
      scaleMin = m.scale_min_mm !== undefined ? m.scale_min_mm : m.scale_mm;
      /* the bounds only: a reconnect keeps each open session's scale, clamped to them (since session 82) */
      for (const c of cards.values()) c.scaleMm = Math.min(scaleMax, Math.max(scaleMin, c.scaleMm));
      PALP.drawColourbar(document.getElementById("colourbar"), 1, " x");
    },
    phantom: function () {
      for (const s of st.sessions) { const c = cards.get(s.id); if (c) fill(c, s); }
    },
    sessions: function (m) {
      const seen = new Set();
      for (const s of m.sessions) {
        seen.add(s.id);
        fill(cards.get(s.id) || makeCard(s), s);
        if (s.exercise) exerciseOf.set(s.id, s.exercise);
      }
      for (const id of exerciseOf.keys()) { if (exerciseOf.size <= EXERCISES_KEPT) break; exerciseOf.delete(id); }
      for (const [id, c] of cards) if (!seen.has(id)) { c.el.remove(); cards.delete(id); answersOf.delete(id); forget(id); }
      st.dashboard.cards = Array.from(cards.keys()).sort(function (a, b) { return a - b; });
      document.getElementById("empty").hidden = cards.size > 0;
      document.getElementById("info").textContent = "class dashboard: " + cards.size + " open session" + (cards.size === 1 ? "" : "s");
    },
    status: serverStatus,
    debrief: debrief,
    score: function (m) {
      keepEnded(scores, "scores", m);
      const tr = endedRows.get(m.session);
      /* a row made from a score alone is made again from the newer (its trainee named since: session 69) */
      if (tr && tr.dataset.fromScore === "1") { tr.remove(); endedRows.delete(m.session); scoreRow(m); }
      else if (tr) scoreCell(tr);
      else if (Number.isFinite(m.session)) scoreRow(m);
    },
    cover: function (m) {
      const c = cards.get(m.session);
      if (!c || typeof m.bands !== "string") return; /* checked against the phantom as drawn (drawCover) */
      c.cover = m.bands;
      st.dashboard.cover = st.dashboard.cover || {};
      st.dashboard.cover[m.session] = m.bands; /* for the tests */
      draw(c, c.disp);
    },
    answers: function (m) {
      if (!Number.isFinite(m.session) || !Array.isArray(m.lumps) || !m.lumps.every(PALP.lumpValid) ||
          !Array.isArray(m.marks_at) || !m.marks_at.every(function (k) {
            return k && Array.isArray(k.point_mm) && k.point_mm.length === 3 && k.point_mm.every(Number.isFinite);
          })) return; /* checked before use (since session 82) */
      if (m.ended) {
        keepEnded(endedAnswers, "endedAnswers", m);
        const tr = endedRows.get(m.session);
        if (tr && tr.dataset.untold) hiddenEnded(tr);
        return;
      }
      answersOf.set(m.session, m);
      st.dashboard.answers = st.dashboard.answers || {};
      st.dashboard.answers[m.session] = m; /* for the tests */
      const c = cards.get(m.session);
      if (c) { listAnswers(c); draw(c, c.disp); }
    },
    deformation: function (f) {
      const c = cards.get(f.session);
      if (!c) return;
      c.frames++;
      st.dashboard.frames++;
      c.latest = f.disp; /* drawn at the next animation frame */
      wake();
    }
  });

  /* A frame only when a deformation arrived (PALP.frameOnDemand) */
  const wake = PALP.frameOnDemand(function () {
    for (const c of cards.values()) if (c.latest) { draw(c, c.latest); c.latest = null; }
  });

  setInterval(function () {
    const now = performance.now();
    for (const [id, c] of cards) {
      c.fps = c.frames * 1000 / (now - c.t0);
      st.dashboard.fpsPerSession[id] = c.fps;
      c.frames = 0;
      c.t0 = now;
    }
  }, 1000);
})();
