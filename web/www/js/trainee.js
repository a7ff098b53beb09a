/* trainee.js - one session's phantom in 3D (three.js from Debian's libjs-three), deforming live,
 * shaded by displacement on a fixed viridis scale; the fingers (and, once the wire carries it, the
 * haptic proxy); the force gauge with its light / medium / deep bands; coverage so far.
 *
 * Which session: ?session=ID, else ?trainee=NAME (that trainee's newest open session), else the
 * newest open session. The page follows a new one when the followed session closes. */
"use strict";
(function () {
  const p = PALP.params(), wantSession = Number(p.get("session")) || 0, wantTrainee = p.get("trainee");
  const st = PALP.state;
  st.trainee = { session: 0, phantom: 0, frames: 0, rendered: 0, maxDispMm: 0, fpsReceived: 0, fpsRendered: 0,
    force: 0, band: "none", coverage: [0, 0, 0], arrivals: [] };
  const T = st.trainee;
  const token = p.get("token");
  if (token) document.getElementById("back").href = "dashboard.html?token=" + encodeURIComponent(token);

  /* ---- three.js scene, z up as on the wire ---- */
  const view = document.getElementById("view");
  /* No multisampling and one pixel per CSS pixel: a classroom PC may render in software (as the
   * tests do, SwiftShader), where both multiply the cost of a frame. */
  const renderer = new THREE.WebGLRenderer({ antialias: false });
  renderer.setPixelRatio(1);
  renderer.setClearColor(0xf4f5f7);
  view.insertBefore(renderer.domElement, view.firstChild);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 10);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x555566, 0.75));
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.set(0.5, -0.6, 1.2);
  scene.add(sun);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableDamping = false;
  controls.addEventListener("change", function () { dirty = true; });

  let mesh = null, geom = null, rest = null, phantom = null, scaleMm = 30, dirty = true, latest = null;
  const fingerObjs = [];

  function resize() {
    const w = view.clientWidth || 600, h = view.clientHeight || 400;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    dirty = true;
  }
  window.addEventListener("resize", resize);

  function buildMesh(ph) {
    if (mesh) { scene.remove(mesh); geom.dispose(); }
    phantom = ph;
    rest = new Float32Array(ph.rest);
    geom = new THREE.BufferGeometry();
    geom.setAttribute("position", new THREE.BufferAttribute(new Float32Array(rest), 3));
    const colours = new Float32Array(rest.length);
    geom.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    geom.setIndex(ph.triangles);
    mesh = new THREE.Mesh(geom, new THREE.MeshLambertMaterial({ vertexColors: THREE.VertexColors, side: THREE.DoubleSide }));
    scene.add(mesh);
    setDisplacement(null);
    const R = ph.radius;
    camera.position.set(1.6 * R, -2.6 * R, 2.3 * R);
    controls.target.set(0, 0, 0.3 * R);
    controls.minDistance = 0.8 * R;
    controls.maxDistance = 12 * R;
    controls.update();
    document.getElementById("waiting").textContent = "";
    T.phantom = ph.id;
    dirty = true;
  }

  /* Positions = rest + displacement; colour = |displacement| on the fixed scale. */
  function setDisplacement(disp) {
    const pos = geom.attributes.position.array, col = geom.attributes.color.array;
    let max = 0;
    for (let i = 0; i < rest.length; i += 3) {
      const dx = disp ? disp[i] : 0, dy = disp ? disp[i + 1] : 0, dz = disp ? disp[i + 2] : 0;
      pos[i] = rest[i] + dx; pos[i + 1] = rest[i + 1] + dy; pos[i + 2] = rest[i + 2] + dz;
      const mm = 1000 * Math.sqrt(dx * dx + dy * dy + dz * dz);
      if (mm > max) max = mm;
      const c = PALP.viridis(mm / scaleMm);
      col[i] = c[0] / 255; col[i + 1] = c[1] / 255; col[i + 2] = c[2] / 255;
    }
    geom.attributes.position.needsUpdate = true;
    geom.attributes.color.needsUpdate = true;
    geom.computeVertexNormals();
    geom.computeBoundingSphere();
    T.maxDispMm = max;
    document.getElementById("maxdisp").textContent = max.toFixed(1);
    dirty = true;
  }

  /* Fingers: a position-driven finger is its sphere; a force-driven one a marker at the contact
   * centre and an arrow along the force (10 mm per newton). A position-driven finger with a haptic
   * local model (palp_local_model) is drawn at its proxy, the fingertip held on the surface, with
   * the device point as a small translucent marker beneath it while it presses. */
  const tipMat = new THREE.MeshLambertMaterial({ color: 0xd55e00, transparent: true, opacity: 0.55 });
  const deviceMat = new THREE.MeshBasicMaterial({ color: 0x0072b2, transparent: true, opacity: 0.45 });
  T.proxy = null; /* the newest drawn proxy, for tests: {proxy, device, in_contact, force_limit, out_of_range} */
  function setFingers(list) {
    for (const o of fingerObjs) scene.remove(o);
    fingerObjs.length = 0;
    let limited = false, outOfRange = false, drawnProxy = null;
    for (const f of list) {
      const hasProxy = f.mode === "finger" && Array.isArray(f.proxy) && Array.isArray(f.device);
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
      const s = new THREE.Mesh(new THREE.SphereBufferGeometry(r, 20, 14), tipMat);
      s.position.copy(c);
      fingerObjs.push(s);
      if (hasProxy) {
        limited = limited || !!f.force_limit;
        outOfRange = outOfRange || !!f.out_of_range;
        drawnProxy = { proxy: f.proxy, device: f.device, in_contact: !!f.in_contact,
          force_limit: !!f.force_limit, out_of_range: !!f.out_of_range };
        if (f.in_contact) {
          const m = new THREE.Mesh(new THREE.SphereBufferGeometry(0.0025, 12, 8), deviceMat);
          m.position.set(f.device[0], f.device[1], f.device[2]);
          fingerObjs.push(m);
        }
      }
      const F = new THREE.Vector3(f.force[0], f.force[1], f.force[2]), mag = F.length();
      if (f.mode === "force" && mag > 1e-3) {
        const len = 0.01 * mag, dir = F.clone().normalize();
        fingerObjs.push(new THREE.ArrowHelper(dir, c.clone().addScaledVector(dir, -len), len, 0xd55e00, 0.006, 0.004));
      }
    }
    T.proxy = drawnProxy;
    const note = document.getElementById("model");
    if (note) {
      const parts = [];
      if (limited) parts.push("force limited");
      if (outOfRange) parts.push("model outside its valid range");
      note.textContent = parts.join(" \u00b7 ");
      note.className = parts.length ? "warn" : "muted";
    }
    /* Drawn over the skin: a finger in its own dent would otherwise be hidden by the dent's rim. */
    for (const o of fingerObjs) {
      o.traverse(function (x) { if (x.material) x.material.depthTest = false; x.renderOrder = 10; });
      o.visible = showFingers;
      scene.add(o);
    }
    dirty = true;
  }
  let showFingers = true;
  /* For tests: hide the fingers so that a screenshot shows the phantom's own change only. */
  window.palpShowFingers = function (on) {
    showFingers = !!on;
    for (const o of fingerObjs) o.visible = showFingers;
    dirty = true;
  };

  /* ---- force gauge: 0 .. 2x the deep threshold, bands shaded ---- */
  let bands = { touch_min: 0.2, light_max: 1, medium_max: 3 };
  function drawGauge(force) {
    const cv = document.getElementById("gauge"), g = cv.getContext("2d"), w = cv.width, h = cv.height;
    const top = 6, bottom = h - 6, fmax = 2 * bands.medium_max, y = function (f) {
      return bottom - Math.min(1, f / fmax) * (bottom - top);
    };
    g.clearRect(0, 0, w, h);
    const zones = [[0, bands.light_max, "#cfe3f3"], [bands.light_max, bands.medium_max, "#f8e3b4"],
      [bands.medium_max, fmax, "#f5cdb0"]];
    for (const z of zones) { g.fillStyle = z[2]; g.fillRect(0, y(z[1]), 24, y(z[0]) - y(z[1])); }
    g.fillStyle = "#1d2330";
    g.fillRect(0, y(force) - 1.5, 30, 3);
    g.font = "10px system-ui, sans-serif";
    g.textBaseline = "middle";
    for (const f of [0, bands.light_max, bands.medium_max, fmax]) g.fillText(f + " N", 28, Math.min(bottom - 4, Math.max(top + 4, y(f))));
  }

  function bandLegend() {
    document.getElementById("band-legend").textContent = "light < " + bands.light_max + " N, medium " +
      bands.light_max + "-" + bands.medium_max + " N, deep > " + bands.medium_max + " N";
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
  function showSession(s) {
    const rows = [["session", s.id], ["trainee", s.trainee], ["phantom", s.phantom_name || s.phantom],
      ["tick rate", s.tick_hz + " Hz"], ["overruns", s.overruns], ["rejected samples", s.rejected],
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
  }

  let fpsT0 = performance.now(), fpsFrames = 0, fpsRendered = 0;
  send = PALP.connect({
    open: function (snd) { send = snd; if (T.session) send({ follow: T.session }); },
    hello: function (m) {
      scaleMm = m.scale_mm;
      bands = m.bands;
      bandLegend();
      PALP.drawColourbar(document.getElementById("colourbar"), scaleMm);
      drawGauge(0);
    },
    phantom: function (m) { if (m.id === pendingPhantom) buildMesh(m); },
    sessions: function (m) {
      const id = choose(m.sessions);
      if (id !== T.session) {
        T.session = id;
        if (send) send({ follow: id || null });
        setFingers([], null);
        if (!id) document.getElementById("info").textContent = "waiting for a session";
      }
      const s = m.sessions.find(function (x) { return x.id === id; });
      if (s) {
        showSession(s);
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
      T.frames++;
      /* arrival times [ms] of the newest frames, for the benchmark's inter-frame gaps */
      T.arrivals.push(performance.now());
      if (T.arrivals.length > 4000) T.arrivals.splice(0, 2000);
      fpsFrames++;
    },
    live: function (m) {
      if (m.session !== T.session) return;
      T.force = m.force;
      T.band = m.band;
      T.coverage = m.coverage;
      document.getElementById("force").textContent = m.force.toFixed(2);
      const b = document.getElementById("band");
      b.textContent = m.band;
      b.className = "band " + m.band;
      drawGauge(m.force);
      for (let k = 0; k < 3; k++) {
        const pc = (100 * m.coverage[k]).toFixed(1);
        document.getElementById("cov" + k).textContent = pc;
        document.getElementById("covbar" + k).style.width = pc + "%";
      }
      setFingers(m.fingers);
    }
  });

  function loop(now) {
    if (latest && geom && latest.length === rest.length) {
      setDisplacement(latest);
      latest = null;
    }
    if (dirty && mesh) {
      renderer.render(scene, camera);
      dirty = false;
      T.rendered++;
      fpsRendered++;
    }
    if (now - fpsT0 >= 1000) {
      T.fpsReceived = fpsFrames * 1000 / (now - fpsT0);
      T.fpsRendered = fpsRendered * 1000 / (now - fpsT0);
      fpsFrames = fpsRendered = 0;
      fpsT0 = now;
    }
    requestAnimationFrame(loop);
  }
  resize();
  requestAnimationFrame(loop);

  /* For tests: where a point of the phantom [m] appears on the page, in CSS pixels. */
  window.palpProject = function (x, y, z) {
    const v = new THREE.Vector3(x, y, z).project(camera), r = renderer.domElement.getBoundingClientRect();
    return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
  };
})();
