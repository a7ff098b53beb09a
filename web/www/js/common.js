/* common.js - what both palp-web pages share: the WebSocket to the bridge, the deformation frame
 * format, the colour-blind-safe displacement scale (viridis) and how it grows, and the debrief's words. window.palpState is what
 * the pages show, readable by tests (tests/web). */
"use strict";
const PALP = (function () {
  /* viridis (matplotlib's perceptually uniform, colour-blind-safe map), 9 stops, linear between. */
  const VIRIDIS = [[68, 1, 84], [71, 45, 123], [59, 82, 139], [44, 114, 142], [33, 145, 140],
    [40, 174, 128], [94, 201, 98], [173, 220, 48], [253, 231, 37]];
  function viridis(t) {
    t = Math.min(1, Math.max(0, t || 0)) * (VIRIDIS.length - 1);
    const i = Math.min(VIRIDIS.length - 2, Math.floor(t)), f = t - i, a = VIRIDIS[i], b = VIRIDIS[i + 1];
    return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
  }
  function css(rgb) { return "rgb(" + (rgb[0] | 0) + "," + (rgb[1] | 0) + "," + (rgb[2] | 0) + ")"; }

  function params() { return new URLSearchParams(window.location.search); }

  /* The access token: read once from this page's address, kept in this tab's sessionStorage and taken
   * out of the address (history.replaceState), so that the address bar and the history of a projected
   * dashboard do not show the instructors' token to the class (since session 82). A reload, or a page
   * this tab opens, finds it there; the HttpOnly cookie of the first load keeps serving the files. */
  const TOKEN_KEY = "palp_token";
  const token = (function () {
    let u;
    try { u = new URL(window.location.href); } catch (e) { return null; }
    const given = u.searchParams.get("token");
    let kept = null;
    try {
      if (given) window.sessionStorage.setItem(TOKEN_KEY, given);
      kept = window.sessionStorage.getItem(TOKEN_KEY);
    } catch (e) { kept = null; } /* no storage (a locked-down browser): the address's own */
    if (u.searchParams.has("token")) {
      u.searchParams.delete("token");
      try { window.history.replaceState(window.history.state, "", u.pathname + u.search + u.hash); } catch (e) { /* kept */ }
    }
    return given || kept || null;
  })();
  /* the page's token (or null), and a link to another page of this bridge carrying it */
  function getToken() { return token; }
  function withToken(href) {
    return token ? href + (href.indexOf("?") >= 0 ? "&" : "?") + "token=" + encodeURIComponent(token) : href;
  }

  /* Binary frame, little-endian (web/hub.h): u32 magic 'PDEF', u32 session, u32 phantom, u32 n,
   * f64 frame, f64 sim_time [s], then n x 3 f32 displacement from rest [m]. */
  const MAGIC = 0x46454450, HEADER = 32, DISP_MAX_M = 10; /* [m], the visual station's bound */
  function decodeDeformation(buf) {
    if (buf.byteLength < HEADER) return null;
    const v = new DataView(buf);
    if (v.getUint32(0, true) !== MAGIC) return null;
    const n = v.getUint32(12, true);
    if (buf.byteLength !== HEADER + 12 * n) return null;
    /* the values too, as the visual station checks them (palp_cli_deformation_check): a non-finite or
     * absurd displacement (beyond DISP_MAX_M) would pin the session's scale at its top for good and
     * make the mesh vanish (since session 82) */
    const disp = new Float32Array(buf, HEADER, 3 * n);
    for (let i = 0; i < disp.length; i++) if (!(Math.abs(disp[i]) <= DISP_MAX_M)) return null;
    return { session: v.getUint32(4, true), phantom: v.getUint32(8, true), n: n, frame: v.getFloat64(16, true),
      sim_time: v.getFloat64(24, true), disp: disp };
  }

  /* A page's drawing on demand: frameOnDemand(draw) returns wake(), which asks for one animation frame
   * (at most one pending) in which draw() runs. A page calls wake() when something it draws changed;
   * nothing runs while nothing changes. Until 2026-12-07 each page's loop asked for every frame, so a
   * still page drew nothing 60 times a second: ~0.1 s of CPU a second in headless Chromium against
   * ~0.01 s still, and a trainee's laptop paid the same. */
  function frameOnDemand(draw) {
    let asked = false;
    function frame() {
      asked = false;
      draw();
    }
    return function wake() {
      if (!asked) {
        asked = true;
        requestAnimationFrame(frame);
      }
    };
  }

  /* The bridge's finding replies a page keeps (for its messages and the tests): the newest REPLIES_KEPT
   * of them, not every one of a long session's. */
  const REPLIES_KEPT = 32;
  function keepReply(list, m) {
    list.push(m);
    if (list.length > REPLIES_KEPT) list.splice(0, list.length - REPLIES_KEPT);
  }

  const state = { connected: false, hello: null, phantoms: {}, sessions: [], status: null,
    frames: 0, messages: 0, reconnects: 0, findingReplies: [], expired: null };
  window.palpState = state;

  /* Opens the WebSocket (the token this page was opened with, PALP.token()), calls handlers[type](msg) for
   * every message and handlers.deformation(frame) for frames; reconnects, except once the bridge said
   * this page's token expired ({"type": "expired"}): its message stays shown, as no retry with the
   * same token can succeed. A connection the bridge did not answer (refused at the handshake, or closed
   * before its hello) is told apart by the page's own address (probe()): palp-web not reachable at
   * all (stopped, restarting) is retried every second, so the page is back within a second of it;
   * palp-web answering that address but not this page's WebSocket, or closing it with a reason, is a
   * refusal: each doubles the wait, to at most 30 s, and one it answered starts again from a second.
   * (Until 2026-12-06 every unanswered attempt doubled it, so a page came back up to 30 s after a
   * restarted palp-web; before that, a page refused for good (no ?token= in its address, a token
   * palp-web no longer takes, a trainee's fourth page) knocked every second and never said why.) It
   * says the bridge's reason where the bridge closes with one; after 3 refusals without, what its own
   * address's answer tells. */
  const RETRY_MS = 1000, RETRY_MAX_MS = 30000, SAY_AFTER = 3, PROBE_MS = 2000;
  function connect(handlers) {
    const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws" +
      (token ? "?token=" + encodeURIComponent(token) : "");
    const conn = document.getElementById("conn");
    let ws = null, retryMs = RETRY_MS, unanswered = 0, answered = false, attempt = 0;
    state.retryMs = 0;   /* the wait before the next attempt [ms], for tests */
    state.refused = "";  /* why the bridge refuses this page, as shown, or "" */
    function setConn(ok, text) {
      state.connected = ok;
      if (conn) { conn.textContent = text; conn.className = ok ? "conn ok" : "conn"; }
      /* the page's live readouts are marked stale while the socket is down (palp.css greys them): until
       * session 90 the force, band and dent kept their last values as if live (found by review) */
      if (document.body) document.body.classList.toggle("stale", !ok);
    }
    /* A handshake refused tells a page nothing (the browser gives 1006, as for a bridge that is down):
     * the page asks for its own address, as it loaded, to tell them apart. Resolves to why it is
     * refused, or to "" when palp-web does not answer at all (none in PROBE_MS: a hung bridge too). */
    function probe() {
      const ctl = typeof AbortController === "function" ? new AbortController() : null;
      const timer = ctl ? setTimeout(function () { ctl.abort(); }, PROBE_MS) : 0;
      return fetch(location.href, { cache: "no-store", credentials: "same-origin", signal: ctl ? ctl.signal : undefined })
        .then(function (r) {
          return r.status === 401 ? "refused: palp-web does not take this link's token (ask for a new link)" :
            !token ? "refused: this page's address has no ?token= (open the link with its token)" :
            "refused by palp-web: check the link's token";
        }, function () { return ""; })
        .then(function (why) { clearTimeout(timer); return why; });
    }
    function retry(wait) {
      state.retryMs = wait;
      setTimeout(open, wait);
    }
    /* the next attempt after a refusal: the wait, doubled for the one after */
    function backoff() {
      const wait = retryMs;
      retryMs = Math.min(RETRY_MAX_MS, 2 * retryMs);
      retry(wait);
      return ", retrying in " + Math.round(wait / 1000) + " s";
    }
    function open() {
      attempt++;
      ws = new WebSocket(url);
      ws.binaryType = "arraybuffer";
      ws.onopen = function () { setConn(true, "live"); if (handlers.open) handlers.open(send); };
      ws.onclose = function (ev) {
        if (state.expired) { setConn(false, state.expired); return; }
        const was = answered;
        answered = false;
        state.reconnects++;
        if (was) retryMs = RETRY_MS, unanswered = 0;
        if (ev.reason) { /* the bridge's own words (web/serve.c: a page it has no room for) */
          state.refused = "palp-web: " + ev.reason;
          if (was) retry(RETRY_MS), setConn(false, state.refused + ", retrying in 1 s");
          else setConn(false, state.refused + backoff());
          return;
        }
        if (was) {
          setConn(false, "disconnected, retrying");
          retry(RETRY_MS);
          return;
        }
        const at = attempt;
        probe().then(function (why) {
          if (at !== attempt || state.connected || state.expired) return; /* a newer attempt's news */
          if (!why) { /* not refused: not there (yet); back as soon as it is */
            retryMs = RETRY_MS, unanswered = 0;
            state.refused = "";
            setConn(false, "palp-web not reachable, retrying");
            retry(RETRY_MS);
            return;
          }
          const again = backoff();
          if (++unanswered >= SAY_AFTER) {
            state.refused = why;
            setConn(false, why + again);
          } else setConn(false, "disconnected" + again);
        });
      };
      ws.onmessage = function (ev) {
        answered = true;
        state.refused = "";
        state.messages++;
        if (typeof ev.data !== "string") {
          const f = decodeDeformation(ev.data);
          if (f) { state.frames++; if (handlers.deformation) handlers.deformation(f); }
          return;
        }
        let m;
        try { m = JSON.parse(ev.data); } catch (e) { return; }
        /* a message is an object with a string type; anything else (null, a number, an array) is
         * ignored, not read (since session 82: a null threw) */
        if (!m || typeof m !== "object" || Array.isArray(m) || typeof m.type !== "string") return;
        if (m.type === "hello") state.hello = m;
        else if (m.type === "phantom") state.phantoms[m.id] = m;
        else if (m.type === "sessions") { if (!Array.isArray(m.sessions)) return; state.sessions = m.sessions; }
        else if (m.type === "status") state.status = m;
        else if (m.type === "finding_reply") keepReply(state.findingReplies, m);
        else if (m.type === "refused") { /* a control this page's token may not send (a trainee's dashboard) */
          state.refusedControl = String(m.message);
          if (conn) { conn.textContent = "refused: " + state.refusedControl; conn.className = "conn"; }
        }
        else if (m.type === "expired") { state.expired = String(m.message); setConn(false, state.expired); }
        if (handlers[m.type]) handlers[m.type](m);
      };
    }
    /* true if sent: a page says when a request of the trainee's did not go (a mark while disconnected
     * was dropped without a word until session 90) */
    function send(obj) {
      if (!ws || ws.readyState !== 1) return false;
      ws.send(JSON.stringify(obj));
      return true;
    }
    open();
    /* For tests: what a page could send anyway (the bridge, not the page, decides what it may do). */
    window.palpSend = send;
    return send;
  }

  /* The displacement scale of one session: the smallest of 0.5, 1, 2, 5, 10, 20, 30, 50, 100 ...
   * mm that holds the deepest displacement seen so far (peakMm), never below the scale it had
   * (prevMm), kept within the bridge's minMm .. maxMm. It only grows while a page follows one
   * session, so within that session a colour always means the same depth; it starts small so
   * that a stiff phantom's millimetre dent shows (a fixed 30 mm scale left it purple). */
  const LADDER = [0.1, 0.2, 0.25, 0.5, 1, 2, 5, 10, 20, 30, 50, 100, 200, 500, 1000];
  function scaleFor(prevMm, peakMm, minMm, maxMm) {
    let s = maxMm;
    for (const v of LADDER) if (v >= minMm && v >= peakMm) { s = v; break; }
    return Math.min(maxMm, Math.max(minMm, prevMm || 0, s));
  }

  /* The labelled displacement scale: 0 .. scaleMm, about 3-6 ticks; unit " mm" unless given
   * (the dashboard's legend is in fractions of each card's own scale). */
  function drawColourbar(canvas, scaleMm, unit) {
    unit = unit === undefined ? " mm" : unit;
    const g = canvas.getContext("2d"), w = canvas.width, h = canvas.height, bar = 14, top = 8, bottom = h - 8;
    g.clearRect(0, 0, w, h);
    for (let y = top; y <= bottom; y++) {
      g.fillStyle = css(viridis((bottom - y) / (bottom - top)));
      g.fillRect(0, y, bar, 1);
    }
    g.fillStyle = "#1d2330";
    g.font = "11px system-ui, sans-serif";
    g.textBaseline = "middle";
    const step = scaleMm > 20 ? 10 : scaleMm > 8 ? 5 : scaleMm > 3 ? 1 : scaleMm > 1.5 ? 0.5 : scaleMm > 0.6 ? 0.25 : 0.1;
    for (let k = 0; k * step <= scaleMm + 1e-9; k++) {
      const v = Number((k * step).toFixed(2));
      const y = bottom - (v / scaleMm) * (bottom - top);
      g.fillRect(bar, y, 4, 1);
      g.fillText(v + ((k + 1) * step > scaleMm + 1e-9 ? "+" + unit : ""), bar + 6, y);
    }
  }

  /* The debrief's words (a `debrief` message, docs/assessment.md "Debrief"), the station's, for the
   * trainee page ("You " + these) and the dashboard's ended sessions alike. At levels "count" and
   * "lesions" only: at "none" the message holds no lesion, not even how many. */
  function plural(n, one, many) { return n + " " + (n === 1 ? one : many); }
  /* an exercise whose lumps are drawn for each session may hide none (docs/assessment.md) */
  function debriefFound(m) {
    return m.lesions ? "found " + m.found + " of " + plural(m.lesions, "lump", "lumps") : "had no lump to find this time";
  }
  function debriefSummary(m) {
    return debriefFound(m) + " with " + plural(m.marks, "mark", "marks") + " standing; " +
      plural(m.false_marks, "mark was", "marks were") + " near no lump" +
      (m.duplicates ? ", " + m.duplicates + " on a lump already found" : "");
  }
  /* A debrief's coverage (the bridge's own, in the exercise's bands) in the station's words: "light
   * 19.4%, medium 20.1%, deep 0.0%" (client/main.c, findings_ui_coverage); "" without one. */
  function coveredText(m) {
    if (!Array.isArray(m.coverage) || m.band_rule !== "exercise" || m.coverage.length !== 3 ||
        !m.coverage.every(Number.isFinite)) return "";
    return ["light", "medium", "deep"].map(function (b, k) { return b + " " + (100 * m.coverage[k]).toFixed(1) + "%"; }).join(", ");
  }
  /* seconds as m:ss, as the station and the trainee page show an exercise's time left (never below 0:00) */
  function minutes(t) {
    const s = Math.max(0, t);
    return Math.floor(s / 60) + ":" + String(Math.floor(s % 60)).padStart(2, "0");
  }
  /* one lump of a debrief at "lesions" (i from 0), or of the dashboard's hidden lumps, where it is in the words every palp tool uses for a
   * place (docs/naming.md: the clock seen from above, the arc from the pole along the skin) */
  /* A place in the one phrase of every palp tool, palp_place_words (src/place.c) mirrored: "at the pole", or
   * "at H.H o'clock, N mm from the pole" (since session 83; "... mm from the pole along the skin" before,
   * which the review's and the observer's lines did not say). clock_h and arc_mm come rounded as the
   * station prints them (palp_place_clock_shown, palp_place_mm_shown): toFixed only writes them. */
  function placeWords(atPole, clockH, arcMm) {
    return atPole ? "at the pole" : "at " + clockH.toFixed(1) + " o'clock, " + arcMm.toFixed(0) + " mm from the pole";
  }
  /* a lump of a `debrief` or `answers` message with the fields debriefLump and the drawings read (since session 82) */
  function lumpValid(l) {
    return !!l && typeof l === "object" && Number.isFinite(l.found_by) && Number.isFinite(l.clock_h) &&
      Number.isFinite(l.arc_mm) && Number.isFinite(l.across_mm) && Number.isFinite(l.deep_mm) &&
      Array.isArray(l.point_mm) && l.point_mm.length === 3 && l.point_mm.every(Number.isFinite);
  }
  function debriefLump(l, i, live) {
    /* live: the dashboard's hidden lumps while the session runs (an `answers` message): not missed yet */
    /* at_pole: within 1 mm of it (src/palp_place.h), where a clock hour is noise. arc_mm, across_mm and
     * deep_mm come as the whole millimetres the station and palp-review print (the bridge rounds them as
     * "%.0f" does, palp_place_mm_shown): toFixed(0) only writes them (since session 82; rounded twice,
     * 0.1 mm by the bridge and ties up here, one lump in 20 read 1 mm off the station's) */
    return "lump " + (i + 1) + " " + (l.found_by ? "found by mark " + l.found_by : live ? "not found yet" : "MISSED") + ": " +
      placeWords(l.at_pole, l.clock_h, l.arc_mm) + "; " +
      l.across_mm.toFixed(0) + " mm across, its centre " + l.deep_mm.toFixed(0) + " mm deep";
  }

  /* The deepest band pressed at one vertex of a `cover` message's map (a hex digit: bits 1 light,
   * 2 medium, 4 deep), as the colour every palp tool gives that band (docs/naming.md, Okabe-Ito; the
   * stylesheet's .band colours): [r, g, b] 0-255, or null when not pressed. */
  const BAND_RGB = [[4, [0, 158, 115]], [2, [230, 159, 0]], [1, [86, 180, 233]]]; /* deepest first */
  function coverColour(digit) {
    const v = parseInt(digit, 16), b = BAND_RGB.find(function (d) { return v & d[0]; });
    return b ? b[1] : null;
  }
  function coverValid(bands, n) { return typeof bands === "string" && bands.length === n && /^[0-9a-f]*$/.test(bands); }

  return { viridis: viridis, css: css, params: params, token: getToken, withToken: withToken, connect: connect, state: state, coverColour: coverColour,
    coverValid: coverValid,
    decodeDeformation: decodeDeformation, drawColourbar: drawColourbar, scaleFor: scaleFor,
    plural: plural, lumpValid: lumpValid, debriefFound: debriefFound, debriefSummary: debriefSummary, debriefLump: debriefLump, placeWords: placeWords,
    minutes: minutes, coveredText: coveredText, keepReply: keepReply, REPLIES_KEPT: REPLIES_KEPT,
    frameOnDemand: frameOnDemand };
})();
