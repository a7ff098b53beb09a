/* trainee.js - one session's phantom in 3D (three.js from Debian's libjs-three), deforming live,
 * shaded by displacement on a viridis scale that grows with the session's deepest dent (PALP.scaleFor); the fingers (and, once the wire carries it, the
 * haptic proxy); the force gauge with its light / medium / deep bands; coverage so far.
 *
 * Which session: ?session=ID, else ?trainee=NAME (that trainee's newest open session), else the
 * newest open session. The page follows a new one when the followed session closes.
 *
 * Role: a trainee page (the default) binds itself to its session ({"trainee": ID}) and, when the
 * session's phantom runs an exercise, shows its instructions, time left, marks standing and the
 * "lump here" / "withdraw last" controls (buttons, keys L and W). ?role=observer (the dashboard's
 * links) and a bare page (no ?session= or ?trainee=) only follow: no controls, and the bridge
 * refuses findings from them. */
"use strict";
(function () {
  const p = PALP.params(), wantSession = Number(p.get("session")) || 0, wantTrainee = p.get("trainee");
  const st = PALP.state;
  st.trainee = { session: 0, phantom: 0, frames: 0, rendered: 0, maxDispMm: 0, scaleMm: 0, fpsReceived: 0, fpsRendered: 0,
    force: 0, band: "none", coverage: [0, 0, 0], arrivals: [] };
  const T = st.trainee;
  /* Bound as the trainee's page only when it names its session or trainee: a bare page (the newest
   * session, whoever's it is) and ?role=observer only watch. */
  const observer = p.get("role") === "observer" || !(wantSession || wantTrainee);
  T.role = observer ? "observer" : "trainee";
  T.exercise = null;      /* the exercise of the followed session's phantom, or null */
  T.marks = null;         /* marks standing, from the server's finding status */
  T.replies = [];         /* the bridge's answers to this page's finding requests, the newest PALP.REPLIES_KEPT */
  T.timeLeft = null;
  T.debrief = null;       /* the server's debrief of her last session, as the bridge sent it */
  T.score = null;         /* its score, where the exercise tells the lesions (a practice exercise) */
  let exercises = [], lastSession = null, findings = null, findingsAt = 0;
  let followedLast = 0; /* the session this page followed before T.session, whose debrief may come late */
  document.getElementById("back").href = PALP.withToken("dashboard.html");

  /* ---- three.js scene, z up as on the wire ---- */
  const view = document.getElementById("view");
  /* No multisampling and one pixel per CSS pixel: a classroom PC may render in software (as the
   * tests do, SwiftShader), where both multiply the cost of a frame. A browser with no WebGL (a
   * blocklisted GPU, a VM, remote desktop: three.js throws) loses the 3D view only: the page says so
   * and everything else (force, gauge, coverage, exercise, findings, debrief) works without it
   * (since session 82; before, the throw stopped the whole script and the page said "connecting"
   * for ever). */
  let renderer = null;
  T.view = "3d";
  try {
    renderer = new THREE.WebGLRenderer({ antialias: false });
    renderer.setPixelRatio(1);
    renderer.setClearColor(0xf4f5f7);
    view.insertBefore(renderer.domElement, view.firstChild);
  } catch (e) {
    renderer = null;
    const why = String((e && e.message) || e || "no WebGL").replace(/[.\s]+$/, "");
    T.view = "3D view unavailable: " + why;
    document.getElementById("waiting").textContent = T.view + " (this browser gives no WebGL; the force, " +
      "coverage, exercise and findings still work)";
  }
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 10);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x555566, 0.75));
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.set(0.5, -0.6, 1.2);
  scene.add(sun);
  const controls = renderer ? new THREE.OrbitControls(camera, renderer.domElement) : null;
  if (controls) {
    controls.enableDamping = false;
    controls.addEventListener("change", redraw);
  }

  let mesh = null, geom = null, rest = null, phantom = null, dirty = true, latest = null;
  /* A frame only when something changed (a deformation, the camera, a finger, the window: PALP.frameOnDemand);
   * redraw() when the scene changed, wake() when only a new deformation waits in `latest`. */
  const wake = PALP.frameOnDemand(loop);
  function redraw() {
    dirty = true;
    wake();
  }
  let scaleMm = 30, scaleMin = 30, scaleMax = 30; /* this session's scale; the bridge's bounds (hello) */
  function setScale(mm) {
    if (mm === scaleMm) return;
    scaleMm = mm;
    T.scaleMm = mm;
    PALP.drawColourbar(document.getElementById("colourbar"), scaleMm);
  }
  const fingerObjs = [];

  function resize() {
    const w = view.clientWidth || 600, h = view.clientHeight || 400;
    if (renderer) renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    redraw();
  }
  window.addEventListener("resize", resize);

  /* The skin pressed so far (a `cover` message, docs/web.md "The pressed skin"): a dot on each
   * pressed vertex in its deepest band's colour (docs/naming.md). The dots share the mesh's positions,
   * so they follow the dent. */
  const showCover = document.getElementById("show-cover");
  let coverPts = null;
  T.coverVertices = 0;
  function clearCover() {
    /* its material too: a new one came with every cover message (GPU memory grew; session 90's review) */
    if (coverPts) { scene.remove(coverPts); coverPts.geometry.dispose(); coverPts.material.dispose(); coverPts = null; }
    T.coverVertices = 0;
  }
  function setCover(bands) {
    if (!geom || !PALP.coverValid(bands, rest.length / 3)) return;
    clearCover();
    const idx = [], col = new Float32Array(rest.length);
    for (let i = 0; i < bands.length; i++) {
      const rgb = PALP.coverColour(bands[i]);
      if (!rgb) continue;
      idx.push(i);
      for (let k = 0; k < 3; k++) col[3 * i + k] = rgb[k] / 255;
    }
    T.coverVertices = idx.length;
    if (!idx.length) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", geom.attributes.position);
    g.setAttribute("color", new THREE.BufferAttribute(col, 3));
    g.setIndex(idx);
    coverPts = new THREE.Points(g, new THREE.PointsMaterial({ size: 5, sizeAttenuation: false, vertexColors: THREE.VertexColors }));
    coverPts.visible = showCover.checked;
    coverPts.renderOrder = 5; /* after the skin, which is offset behind its depth: a dot at a vertex passes the depth test */
    scene.add(coverPts);
    redraw();
  }
  showCover.addEventListener("change", function () { if (coverPts) coverPts.visible = showCover.checked; redraw(); });

  function buildMesh(ph) {
    if (mesh) { scene.remove(mesh); geom.dispose(); mesh.material.dispose(); }
    clearCover();
    phantom = ph;
    rest = new Float32Array(ph.rest);
    geom = new THREE.BufferGeometry();
    geom.setAttribute("position", new THREE.BufferAttribute(new Float32Array(rest), 3));
    const colours = new Float32Array(rest.length);
    geom.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    geom.setIndex(ph.triangles);
    /* The skin drawn a little behind its own depth (polygon offset): the pressed-skin dots sit at its
     * vertices, and half of each square sprite would otherwise fail the depth test where the skin
     * curves towards the eye (the dots read half-hidden, session 61's note). */
    mesh = new THREE.Mesh(geom, new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }));
    scene.add(mesh);
    setDisplacement(null);
    const R = ph.radius;
    camera.position.set(1.6 * R, -2.6 * R, 2.3 * R);
    if (controls) {
      controls.target.set(0, 0, 0.3 * R);
      controls.minDistance = 0.8 * R;
      controls.maxDistance = 12 * R;
      controls.update();
    }
    if (renderer) document.getElementById("waiting").textContent = ""; /* else it keeps saying why there is no view */
    T.phantom = ph.id;
    redraw();
  }

  /* Positions = rest + displacement; colour = |displacement| on the session's scale, grown
   * first to hold this frame's deepest point. */
  function setDisplacement(disp) {
    const pos = geom.attributes.position.array, col = geom.attributes.color.array;
    let max = 0;
    for (let i = 0; disp && i < rest.length; i += 3) max = Math.max(max, 1000 * Math.hypot(disp[i], disp[i + 1], disp[i + 2]));
    setScale(PALP.scaleFor(scaleMm, max, scaleMin, scaleMax));
    for (let i = 0; i < rest.length; i += 3) {
      const dx = disp ? disp[i] : 0, dy = disp ? disp[i + 1] : 0, dz = disp ? disp[i + 2] : 0;
      pos[i] = rest[i] + dx; pos[i + 1] = rest[i + 1] + dy; pos[i + 2] = rest[i + 2] + dz;
      const mm = 1000 * Math.sqrt(dx * dx + dy * dy + dz * dz);
      const c = PALP.viridis(mm / scaleMm);
      col[i] = c[0] / 255; col[i + 1] = c[1] / 255; col[i + 2] = c[2] / 255;
    }
    geom.attributes.position.needsUpdate = true;
    geom.attributes.color.needsUpdate = true;
    geom.computeVertexNormals();
    geom.computeBoundingSphere();
    T.maxDispMm = max;
    document.getElementById("maxdisp").textContent = max.toFixed(2); /* mm, 2 decimals (docs/naming.md) */
    redraw();
  }

  /* Fingers: a position-driven finger is its sphere; a force-driven one a marker at the contact
   * centre and an arrow along the force (10 mm per newton). A position-driven finger with a haptic
   * local model (palp_local_model) is drawn at its proxy, the fingertip held on the surface, with
   * the device point as a small translucent marker beneath it while it presses. */
  const tipMat = new THREE.MeshLambertMaterial({ color: 0xd55e00, transparent: true, opacity: 0.55 });
  const deviceMat = new THREE.MeshBasicMaterial({ color: 0x0072b2, transparent: true, opacity: 0.45 });
  /* The fingers' objects are made once and reused by every live message (up to 30 a second): the
   * spheres share one geometry each (the tip's of radius 1, scaled to the finger's), an arrow is moved
   * and resized. Made anew for each message and never disposed, they grew the renderer's geometries
   * without bound over a class. */
  const tipGeom = new THREE.SphereBufferGeometry(1, 20, 14), deviceGeom = new THREE.SphereBufferGeometry(0.0025, 12, 8);
  const pool = { tip: [], device: [], arrow: [] };
  T.fingerObjects = 0;            /* objects ever made for the fingers, for tests */
  T.memory = renderer ? renderer.info.memory : null; /* the renderer's geometries and textures, for tests */
  function pooled(kind, i, make) {
    if (i < pool[kind].length) return pool[kind][i];
    const o = make();
    /* Drawn over the skin: a finger in its own dent would otherwise be hidden by the dent's rim. */
    o.traverse(function (x) { if (x.material) x.material.depthTest = false; x.renderOrder = 10; });
    scene.add(o);
    pool[kind].push(o);
    T.fingerObjects++;
    return o;
  }
  /* three finite numbers */
  function vec3(v) { return Array.isArray(v) && v.length === 3 && v.every(Number.isFinite); }
  T.proxy = null; /* the newest drawn proxy, for tests: {proxy, device, in_contact, force_limit, out_of_range} */
  function setFingers(list) {
    fingerObjs.length = 0;
    const used = { tip: 0, device: 0, arrow: 0 };
    function take(kind, make) {
      const o = pooled(kind, used[kind]++, make);
      fingerObjs.push(o);
      return o;
    }
    let flagsSeen = 0, drawnProxy = null; /* the drawn fingers' local-model flags, together */
    for (const f of list) {
      if (!f || !vec3(f.center) || !vec3(f.force)) continue; /* checked before use (since session 82) */
      const hasProxy = f.mode === "finger" && vec3(f.proxy) && vec3(f.device);
      const at = hasProxy ? f.proxy : f.center;
      const c = new THREE.Vector3(at[0], at[1], at[2]);
      if (f.mode === "force" && geom) {
        /* The wire gives a force-driven contact's centre on the rest surface: draw it where that
         * skin is now (the nearest vertex's current position), not floating above the dent. */
        const pos = geom.attributes.position.array;
        let best = -1, bd = Infinity;
        for (let i = 0; i < rest.length; i += 3) {
          const d = (rest[i] - c.x) ** 2 + (rest[i + 1] - c.y) ** 2 + (rest[i + 2] - c.z) ** 2;
          if (d < bd) { bd = d; best = i; }
        }
        if (best >= 0) c.set(pos[best], pos[best + 1], pos[best + 2]);
      }
      const r = f.mode === "finger" && f.radius > 0 ? f.radius : 0.003;
      const s = take("tip", function () { return new THREE.Mesh(tipGeom, tipMat); });
      s.scale.setScalar(r);
      s.position.copy(c);
      if (hasProxy) {
        flagsSeen |= f.flags | 0;
        drawnProxy = { proxy: f.proxy, device: f.device, in_contact: !!f.in_contact,
          force_limit: !!f.force_limit, out_of_range: !!f.out_of_range };
        if (f.in_contact) {
          const m = take("device", function () { return new THREE.Mesh(deviceGeom, deviceMat); });
          m.position.set(f.device[0], f.device[1], f.device[2]);
        }
      }
      const F = new THREE.Vector3(f.force[0], f.force[1], f.force[2]), mag = F.length();
      if (f.mode === "force" && mag > 1e-3) {
        /* 10 mm per newton, head included: the head at most half the arrow (a fixed 6 mm head drew every
         * force under 0.6 N as a 6 mm arrow, its cone past the tail; since session 82) */
        const len = 0.01 * mag, dir = F.clone().normalize(), head = Math.min(0.006, 0.5 * len);
        const a = take("arrow", function () { return new THREE.ArrowHelper(dir, c, len, 0xd55e00, head, 0.67 * head); });
        a.position.copy(c).addScaledVector(dir, -len);
        a.setDirection(dir);
        a.setLength(len, head, 0.67 * head);
      }
    }
    T.proxy = drawnProxy;
    const note = document.getElementById("model");
    if (note) {
      note.textContent = modelNote(flagsSeen);
      note.className = note.textContent ? "warn" : "muted";
    }
    for (const k in pool) pool[k].forEach(function (o, i) { o.visible = showFingers && i < used[k]; }); /* the rest wait */
    redraw();
  }
  let showFingers = true;
  /* For tests: hide the fingers so that a screenshot shows the phantom's own change only. */
  window.palpShowFingers = function (on) {
    showFingers = !!on;
    for (const o of fingerObjs) o.visible = showFingers;
    redraw();
  };

  /* ---- force gauge: 0 .. 2x the deep threshold, bands shaded. In an exercise the bridge bands the
   * fingertip by the exercise's bands, as the assessment grades it, and the gauge shows them: by
   * indentation, the indentation against them; by force alone, the force against them (0 .. the deep
   * band's top), not the bridge's --bands, which the band badge and the legend then contradicted
   * (docs/web.md). ---- */
  let bands = { touch_min: 0.2, light_max: 1, medium_max: 3 }, rule = "force";
  /* the exercise's [light, medium, deep] bounds of one measure (key "depth_mm" or "force_N"), where all three give it */
  function exerciseBands(key) {
    const b = T.exercise && T.exercise.bands;
    if (rule !== "exercise" || !b || !b.light[key] || !b.medium[key] || !b.deep[key]) return null;
    return [b.light[key], b.medium[key], b.deep[key]];
  }
  function depthBands() { return exerciseBands("depth_mm"); }
  function drawGauge(force, depthMm) {
    const cv = document.getElementById("gauge"), g = cv.getContext("2d"), w = cv.width, h = cv.height;
    const db = depthBands(), xb = db || exerciseBands("force_N"), unit = db ? " mm" : " N";
    const fmax = xb ? xb[2][1] : 2 * bands.medium_max, top = 6, bottom = h - 6, y = function (f) {
      return bottom - Math.min(1, f / fmax) * (bottom - top);
    };
    g.clearRect(0, 0, w, h);
    const zones = xb ? [[xb[0][0], xb[0][1], "#cce8f8"], [xb[1][0], xb[1][1], "#f8e3b4"], [xb[2][0], xb[2][1], "#b3e2d5"]]
      : [[0, bands.light_max, "#cce8f8"], [bands.light_max, bands.medium_max, "#f8e3b4"], [bands.medium_max, fmax, "#b3e2d5"]];
    if (db) force = depthMm > 0 ? depthMm : 0;
    for (const z of zones) { g.fillStyle = z[2]; g.fillRect(0, y(z[1]), 24, y(z[0]) - y(z[1])); }
    g.fillStyle = "#1d2330";
    g.fillRect(0, y(force) - 1.5, 30, 3);
    g.font = "10px system-ui, sans-serif";
    g.textBaseline = "middle";
    const ticks = xb ? [0, xb[0][1], xb[1][1], fmax] : [0, bands.light_max, bands.medium_max, fmax];
    for (const f of ticks) g.fillText(f + unit, 28, Math.min(bottom - 4, Math.max(top + 4, y(f))));
  }

  function bandLegend() {
    const db = depthBands(), xb = rule === "exercise" && T.exercise && T.exercise.bands;
    document.getElementById("band-legend").textContent = db ?
      "the exercise's bands, as it grades you, by how deep the fingertip presses: light " + db[0][0] + "-" + db[0][1] +
      " mm, medium " + db[1][0] + "-" + db[1][1] + " mm, deep " + db[2][0] + "-" + db[2][1] + " mm" :
      xb ? "the exercise's bands, as it grades you: " + ["light", "medium", "deep"].map(function (n) {
        const x = xb[n];
        return n + (x.depth_mm ? " " + x.depth_mm.join("-") + " mm deep" : "") + (x.force_N ? " " + x.force_N.join("-") + " N" : "");
      }).join(", ") :
      "light < " + bands.light_max + " N, medium " + bands.light_max + "-" + bands.medium_max + " N, deep > " +
      bands.medium_max + " N";
  }

  /* ---- which session ---- */
  let send = null, pendingPhantom = 0;
  function choose(sessions) {
    if (T.session && sessions.some(function (s) { return s.id === T.session; })) return T.session;
    let best = null;
    for (const s of sessions) {
      if (wantSession && s.id !== wantSession) continue;
      if (wantTrainee && s.trainee !== wantTrainee) continue;
      if (!best || s.id > best.id) best = s;
    }
    return best ? best.id : 0;
  }
  /* The server holds a lost trainee station's session a few seconds (the list's `status`): its last force
   * is stale (the server lifted the finger), so the page says "station lost" instead, as the dashboard
   * does (since session 82: it showed the last press frozen as if live). */
  function stationLost() { return !!(lastSession && lastSession.status); }
  /* the force panel with no force on the hand: its figure, the band badge's words and class */
  function showNoForce(force, band, cls) {
    document.getElementById("force").textContent = force;
    const b = document.getElementById("band");
    b.textContent = band;
    b.className = cls;
    document.getElementById("depth").textContent = "";
    drawGauge(0);
  }
  function showLost() { showNoForce("-", "station lost", "band"); }
  function showSession(s) {
    const rows = [["session", s.id], ["trainee", s.trainee], ["phantom", s.phantom_name || s.phantom],
      ["trainee station", s.status ? s.status : "connected"],
      ["tick rate", s.tick_hz + " Hz"], ["late physics steps", s.overruns], ["rejected samples", s.rejected],
      ["findings", s.findings === null ? "n/a" : s.findings]];
    const tb = document.getElementById("session");
    tb.textContent = "";
    for (const r of rows) {
      const tr = tb.insertRow();
      tr.insertCell().textContent = r[0];
      tr.insertCell().textContent = String(r[1]);
    }
    document.getElementById("info").textContent = s.trainee + " on " + (s.phantom_name || "phantom " + s.phantom) +
      " (session " + s.id + ")";
    if (s.status) showLost();
  }

  /* The server's session log losing records while her session runs, in her station's words (the bridge
   * sends them, web/hub.c: palp_dds_log_view_words); as the session ends, the loss in all
   * (palp_dds_log_view_summary), kept so that she still reads why its review will be incomplete, and
   * cleared when a new one starts. */
  function showLog(words, state) {
    const el = document.getElementById("log");
    if (!words) {
      el.hidden = true;
      el.textContent = "";
      return;
    }
    el.textContent = words.charAt(0).toUpperCase() + words.slice(1) + ".";
    el.className = state === "writing" ? "again" : ""; /* the bridge's log_state: "losing", "writing" or "" */
    el.hidden = false;
  }

  /* ---- exercise and findings ---- */
  /* ---- the debrief at the session's end (docs/assessment.md, "Debrief") ----
   * What the trainee's standing marks found, as much as the exercise tells: the lines the station
   * prints, and at "lesions" each lump drawn on the phantom where it is (green found, red missed). */
  const debriefObjs = [];
  const foundMat = new THREE.MeshBasicMaterial({ color: 0x2e9e44, side: THREE.DoubleSide }),
    missedMat = new THREE.MeshBasicMaterial({ color: 0xd0342c, side: THREE.DoubleSide });
  function debriefText(m) {
    let t;
    if (m.level === "none") {
      t = "This exercise keeps its lumps for the instructor's review (" + PALP.plural(m.marks, "mark", "marks") + " standing).";
    } else {
      t = "You " + PALP.debriefSummary(m) + ".";
      if (m.level === "count") t += " This exercise does not say where its lumps are: the instructor's review does.";
    }
    const cov = PALP.coveredText(m); /* not an answer: her station prints it at any level */
    /* "touched": the bridge marked the server's own samples of her touches, as the review counts them */
    if (cov && m.coverage_rule === "touched")
      t += " You covered " + cov + " of the dome (counted as the review counts it, from the triangles you touched).";
    else if (cov) t += " You covered " + cov + " of the dome (as this page saw it; the review counts it from the triangles you touched).";
    return t;
  }
  /* Her score, where the exercise tells her the lesions (a practice exercise; the server tells it on
   * palp_debrief_score, web/hub.c on_debrief_score): the server's automatic score of her session,
   * graded from its log as the review grades it, and what to work on, in her words (work_on: the
   * words her station prints too, palp_metric_to_work_on). */
  function scoreText(m) {
    /* not graded: why, as her station says it (palp_cli_score_text: "no score: REASON"; session 66) */
    if (!m.graded) return typeof m.reason === "string" && m.reason ? "No score: " + m.reason + "." : "";
    const work = Array.isArray(m.work_on) ? m.work_on.filter(function (w) { return typeof w === "string"; }) : [];
    return "Your score: " + m.score.toFixed(1) + " of 100, " + (m.pass ? "passed" : "not passed") +
      " (the automatic score, as the review gives it; your instructor grades you)." +
      (work.length ? " To work on: " + work.join(", ") + "." : "") +
      (m.log_complete === false ? " The session's log is incomplete: the score may be low." : ""); /* as her station says */
  }
  function showScore(m) {
    if (!T.debrief || T.debrief.session !== m.session) return; /* her debrief first (the bridge sends it first) */
    T.score = m;
    const el = document.getElementById("debrief-score");
    el.textContent = scoreText(m);
    el.hidden = el.textContent === "";
  }
  function clearDebrief() {
    for (const o of debriefObjs) { scene.remove(o); o.geometry.dispose(); } /* the materials are shared */
    debriefObjs.length = 0;
    document.getElementById("debrief").hidden = true;
    document.getElementById("debrief-score").hidden = true;
    T.debrief = null;
    T.score = null;
    redraw();
  }
  function showDebrief(m) {
    if (!Array.isArray(m.lumps) || !m.lumps.every(PALP.lumpValid)) return; /* checked before use (since session 82) */
    clearDebrief();
    T.debrief = m;
    document.getElementById("debrief-text").textContent = debriefText(m);
    const ul = document.getElementById("debrief-lumps");
    ul.textContent = "";
    m.lumps.forEach(function (l, i) {
      const li = document.createElement("li");
      li.textContent = PALP.debriefLump(l, i);
      li.className = l.found_by ? "found" : "missed";
      ul.appendChild(li);
      /* a ring of the lump's size on the skin above its centre, facing out along the dome's normal
       * (the point's direction from the base centre), lifted 0.5 mm so the skin does not hide it */
      const r = Math.max(l.across_mm, 2) / 2000;
      const o = new THREE.Mesh(new THREE.RingBufferGeometry(0.7 * r, r, 40), l.found_by ? foundMat : missedMat);
      const n = new THREE.Vector3(l.point_mm[0], l.point_mm[1], l.point_mm[2]).normalize();
      o.position.set(l.point_mm[0] / 1000, l.point_mm[1] / 1000, l.point_mm[2] / 1000).addScaledVector(n, 0.0005);
      o.lookAt(o.position.clone().add(n));
      scene.add(o);
      debriefObjs.push(o);
    });
    document.getElementById("debrief").hidden = false;
    redraw();
  }
  window.palpDebriefText = function (m) { return [debriefText(m)].concat(m.lumps.map(PALP.debriefLump)); };

  function followMsg(id) { return id && !observer ? { trainee: id } : { follow: id || null }; }
  function showExercise() {
    const ex = lastSession ? exercises.find(function (e) { return e.phantom === lastSession.phantom; }) : null;
    T.exercise = ex || null;
    document.getElementById("exercise").hidden = !!ex;
    document.getElementById("ex-panel").hidden = !ex;
    document.getElementById("ex-controls").hidden = !ex || observer;
    if (!ex) return;
    document.getElementById("ex-title").textContent = ex.title || ex.name;
    bandLegend();
    document.getElementById("ex-instructions").textContent = ex.instructions;
    tick();
  }
  /* Time left: the server's newest figure counted down here; before the first, the limit less
   * the session's age. */
  function tick() {
    if (!T.exercise) return;
    let left = null;
    if (findings && findings.time_left >= 0) left = findings.time_left - findings.age - (performance.now() - findingsAt) / 1000;
    else if (findings && findings.time_left < 0) left = null;
    else if (lastSession && T.exercise.time_limit > 0) left = T.exercise.time_limit - lastSession.duration;
    T.timeLeft = left;
    document.getElementById("ex-time").textContent = left === null ? "no limit" : PALP.minutes(left);
    T.marks = findings ? findings.marks : (lastSession && lastSession.findings !== null ? lastSession.findings : 0);
    document.getElementById("ex-marks").textContent = String(T.marks);
  }
  setInterval(tick, 250);
  function message(text, ok) {
    const el = document.getElementById("ex-msg");
    el.textContent = text;
    el.className = ok ? "ok" : "refused";
  }
  function finding(op) {
    if (!send || observer || !T.exercise) return;
    if (!send({ finding: op }))
      message((op === "mark" ? "mark" : "withdrawal") + " not sent: disconnected from palp-web; " +
              (op === "mark" ? "mark" : "withdraw") + " again once it says live", false);
  }
  document.getElementById("lump").addEventListener("click", function () { finding("mark"); });
  document.getElementById("withdraw").addEventListener("click", function () { finding("withdraw"); });
  window.addEventListener("keydown", function (ev) {
    if (ev.repeat || ev.ctrlKey || ev.altKey || ev.metaKey) return;
    if (ev.key === "l" || ev.key === "L") finding("mark");
    else if (ev.key === "w" || ev.key === "W") finding("withdraw");
  });

  let fpsT0 = performance.now(), fpsFrames = 0, fpsRendered = 0;
  send = PALP.connect({
    open: function (snd) { send = snd; if (T.session) send(followMsg(T.session)); },
    exercises: function (m) { exercises = m.exercises; showExercise(); },
    /* Only the followed session's debrief, or, following none, the one followed last (the bridge sends
     * that too: the debrief can reach it after the CLOSED state). A page that moved on to a newer session
     * ignores the old one's: drawn there, its rings would show the new trainee where her lumps are. */
    debrief: function (m) { if (m.session === T.session || (!T.session && m.session === followedLast)) showDebrief(m); },
    score: function (m) { showScore(m); },
    cover: function (m) { if (m.session === T.session && m.phantom === T.phantom) setCover(m.bands); },
    finding_reply: function (m) {
      PALP.keepReply(T.replies, m);
      if (m.ok) message(m.op === "mark" ? "mark " + m.mark_id + " sent" : "mark " + m.mark_id + " withdrawn", true);
      else message(m.reason, false);
    },
    hello: function (m) {
      scaleMax = m.scale_mm;
      scaleMin = m.scale_min_mm !== undefined ? m.scale_min_mm : m.scale_mm; /* an older bridge: fixed */
      /* the bounds only: a reconnect within the followed session keeps its scale (clamped to them), so
       * a colour still means the same depth (since session 82; a new session starts at scaleMin) */
      const keep = T.session && scaleMm > 0 ? Math.min(scaleMax, Math.max(scaleMin, scaleMm)) : scaleMin;
      scaleMm = -1;
      setScale(keep);
      bands = m.bands;
      bandLegend();
      drawGauge(0);
    },
    phantom: function (m) { if (m.id === pendingPhantom) buildMesh(m); },
    sessions: function (m) {
      const id = choose(m.sessions);
      if (id !== T.session) {
        if (T.session) followedLast = T.session;
        T.session = id;
        setScale(scaleMin); /* a new session starts on the smallest scale */
        if (send) send(followMsg(id));
        /* a new session: the last one's debrief and pressed skin go (kept while waiting: the skin she
         * pressed beside the debrief's rings shows where her search passed the lumps) */
        if (id) { clearDebrief(); clearCover(); showLog(""); }
        findings = null;
        setFingers([], null);
        if (!id) {
          document.getElementById("info").textContent = "waiting for a session";
          /* the log's loss while it ran, in all, as her station says it as it ends */
          if (lastSession && lastSession.log_summary) showLog(lastSession.log_summary);
          /* the session is over: the phantom at rest and no force, not its last frame's dent and force
           * (the debrief's rings are drawn on the rest skin) */
          latest = null;
          if (geom) setDisplacement(null);
          showNoForce("0.00", "none", "band none");
        }
      }
      const s = m.sessions.find(function (x) { return x.id === id; });
      lastSession = s || null;
      showExercise();
      if (s) {
        showSession(s);
        showLog(observer ? s.log_observer : s.log, s.log_state); /* an instructor following is told what to do, not to tell one */
        if (s.phantom !== pendingPhantom) {
          pendingPhantom = s.phantom;
          if (PALP.state.phantoms[s.phantom]) buildMesh(PALP.state.phantoms[s.phantom]);
        }
      }
    },
    deformation: function (f) {
      if (f.session !== T.session || !geom || f.n * 3 !== rest.length) return;
      /* Kept, and shaded at the next animation frame: a frame that arrives while the page cannot
       * draw (busy, hidden) costs nothing but its copy. */
      latest = f.disp;
      wake();
      T.frames++;
      /* arrival times [ms] of the newest frames, for the benchmark's inter-frame gaps */
      T.arrivals.push(performance.now());
      if (T.arrivals.length > 4000) T.arrivals.splice(0, 2000);
      fpsFrames++;
    },
    live: function (m) {
      if (m.session !== T.session) return;
      /* the fields checked before use (since session 82) */
      if (!Number.isFinite(m.force) || typeof m.band !== "string" || !Array.isArray(m.coverage) ||
          m.coverage.length !== 3 || !m.coverage.every(Number.isFinite) || !Array.isArray(m.fingers) ||
          (m.depth_mm !== undefined && m.depth_mm !== null && !Number.isFinite(m.depth_mm))) return;
      T.force = m.force;
      T.band = m.band;
      T.bandRule = m.band_rule || "force";
      T.depthMm = m.depth_mm === undefined || m.depth_mm === null ? null : m.depth_mm;
      if (T.bandRule !== rule) {
        rule = T.bandRule;
        bandLegend();
        /* in an exercise, coverage per band as the assessment counts it (a place pressed only deep
         * is not light); else at each band or deeper */
        const names = rule === "exercise" ? ["light", "medium", "deep"] : ["light or deeper", "medium or deeper", "deep"];
        for (let k = 0; k < 3; k++) document.getElementById("covname" + k).textContent = names[k];
        document.getElementById("covnote").textContent = rule === "exercise" ?
          "share of the dome's skin pressed at each level, as the exercise grades thoroughness (approximately: " +
          "the review counts the touched skin of every logged step), since the bridge began following the session" :
          "share of the dome's skin pressed under the finger, since the bridge began following the session";
      }
      document.getElementById("depth").textContent = rule === "exercise" ?
        (T.depthMm === null ? "fingertip not pressing" : "pressed " + T.depthMm.toFixed(1) + " mm deep") : "";
      T.coverage = m.coverage;
      if (stationLost()) showLost();
      else {
        document.getElementById("force").textContent = m.force.toFixed(2);
        const b = document.getElementById("band");
        b.textContent = m.band;
        b.className = "band " + m.band;
        drawGauge(m.force, T.depthMm);
      }
      for (let k = 0; k < 3; k++) {
        const pc = (100 * m.coverage[k]).toFixed(1);
        document.getElementById("cov" + k).textContent = pc;
        document.getElementById("covbar" + k).style.width = pc + "%";
      }
      setFingers(m.fingers);
      if (m.findings) {
        const prev = findings;
        findings = m.findings;
        findingsAt = performance.now();
        /* the server's answer to a mark it refused (the bridge's own refusals come as replies) */
        if (!m.findings.last_accepted && m.findings.reason && (!prev || prev.last_mark_id !== m.findings.last_mark_id))
          message("the server refused mark " + m.findings.last_mark_id + ": " + m.findings.reason, false);
        tick();
      }
    }
  });

  /* frames received and drawn a second, counted by the clock: no frame is asked for while nothing changes */
  setInterval(function () {
    const now = performance.now();
    T.fpsReceived = fpsFrames * 1000 / (now - fpsT0);
    T.fpsRendered = fpsRendered * 1000 / (now - fpsT0);
    fpsFrames = fpsRendered = 0;
    fpsT0 = now;
  }, 1000);

  function loop() {
    if (latest && geom && latest.length === rest.length) {
      setDisplacement(latest);
      latest = null;
    }
    if (dirty && mesh && renderer) {
      renderer.render(scene, camera);
      dirty = false;
      T.rendered++;
      fpsRendered++;
    }
  }
  resize();

  /* The note under the view from the local models' flags (LocalModel.flags, as palp-web
   * passes them: LM_FORCE_LIMIT 1, LM_OUT_OF_RANGE 30, LM_BEYOND_VALIDATED 64,
   * LM_GEL_LAW_RANGE 128), naming the validity limit as the terminal station does: 64 deeper
   * than the FE validation there, LM_LARGE_STRAIN 2 the skin, 28 the base or the step's own
   * limits, 128 the scene's literal gel law outside its stable range. Exported for tests. */
  function modelNote(flags) {
    const f = flags | 0, parts = [];
    if (f & 1) parts.push("force limited");
    if (f & 222) {
      const why = [];
      if (f & 64) why.push("deeper than this place was checked against the reference model");
      if (f & 2) why.push("skin stretched or bent beyond the model's range");
      if (f & 28) why.push("pressed onto the base or harder than the model can follow");
      if (f & 128) why.push("the gel's literal pressure law outside its stable range");
      parts.push("model outside its valid range" + (why.length ? ": " + why.join(", ") : ""));
    }
    return parts.join(" \u00b7 ");
  }
  window.palpModelNote = modelNote;
  /* For tests: where a point of the phantom [m] appears on the page, in CSS pixels. */
  window.palpProject = function (x, y, z) {
    const v = new THREE.Vector3(x, y, z).project(camera), r = (renderer ? renderer.domElement : view).getBoundingClientRect();
    return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
  };
})();
