// The viewer of `lidarsurf view` and `lidarsurf fuse --serve`, drawn with three.js (the global
// THREE of build/three.min.js, inlined above). Two sources, one viewer:
//  - a mesh in the page (`view`): the data block holds its arrays;
//  - a live map (`fuse --serve`, data.live): the page reads the stream at /live of the server
//    that served it (io/live_stream.hpp has the format): the map so far, then each scan's
//    changed blocks, the sensor's pose and trajectory; the last message holds the final mesh.
// Orbit with the left button, pan with the right one (or shift), zoom with the wheel. The panel
// switches the colouring (height, neighbourhood level k', Gaussian confidence, intensity, normal,
// grey), the
// wireframe, the points and, live, whether the camera follows the sensor; the URL's hash sets
// them too: #colour=level&wireframe=1&points=0&follow=0. The surface is lit by its normals.
(function () {
  "use strict";
  const data = JSON.parse(document.getElementById("lidarsurf-data").textContent);
  const live = data.live === true;

  function decode(b64, Type) {
    if (!b64) return new Type(0);
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer);
  }

  // ---- Colourings: height over the 2nd-98th percentile, k' over 1..k_max, confidence over
  // [tau, 1] and, below tau (the mesh's Eq. (3) threshold), magenta: surface inferred between scan
  // rings (bridges), not measured; intensity as a grey ramp over its 2nd-98th percentile (pale
  // blue: a vertex no return reached).
  function ramp(t, c) {
    t = Math.min(1, Math.max(0, t));
    return c.setHSL(0.66 * (1 - t), 0.75, 0.5);
  }
  const grey = new THREE.Color(0.7, 0.7, 0.7), none = new THREE.Color(0.6, 0.6, 0.6), inferred = new THREE.Color(0.85, 0.25, 0.85);
  const unread = new THREE.Color(0.55, 0.65, 0.8);
  const tau = typeof data.tau === "number" && data.tau > 0 ? data.tau : 0.2;
  const range = { zlo: 0, zhi: 1, kmax: 1, ilo: 0, ihi: 1 };
  const modes = {
    height: (p, i, c) => ramp((p.positions[3 * i + 2] - range.zlo) / (range.zhi - range.zlo), c),
    level: (p, i, c) => (p.levels.length ? ramp((p.levels[i] - 1) / Math.max(1, range.kmax - 1), c) : c.copy(none)),
    confidence: (p, i, c) => {
      if (!p.confidence.length) return c.copy(none);
      const v = p.confidence[i];
      return v < tau ? c.copy(inferred) : ramp((v - tau) / Math.max(1 - tau, tau), c);
    },
    intensity: (p, i, c) => {
      if (!p.intensity.length) return c.copy(none);
      const v = p.intensity[i];
      if (!(v === v)) return c.copy(unread);
      const g = 0.08 + 0.9 * Math.min(1, Math.max(0, (v - range.ilo) / (range.ihi - range.ilo)));
      return c.setRGB(g, g, g);
    },
    normal: (p, i, c) => {
      const n = p.geometry.attributes.normal.array;
      return c.setRGB(0.5 + 0.5 * n[3 * i], 0.5 + 0.5 * n[3 * i + 1], 0.5 + 0.5 * n[3 * i + 2]);
    },
    grey: (p, i, c) => c.copy(grey),
  };
  const settings = { colour: data.colour in modes ? data.colour : "height", wireframe: false, points: false, follow: true };
  for (const part of window.location.hash.replace(/^#/, "").split("&")) {
    const [key, value] = part.split("=");
    if (key === "colour" && value in modes) settings.colour = value;
    if (key === "wireframe") settings.wireframe = value === "1";
    if (key === "points") settings.points = value === "1";
    if (key === "follow") settings.follow = value !== "0";
  }

  // ---- The scene: the surface as pieces (the whole mesh, or the live map's blocks), lit by
  // their normals: a soft sky and ground light, and a light from behind the camera's shoulder.
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f4f7);
  const surface = new THREE.Group();
  scene.add(surface);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x707070, 0.55));
  const key = new THREE.DirectionalLight(0xffffff, 0.75);
  scene.add(key, key.target);
  const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
  const pieces = new Map(); // name -> piece
  let triangles = 0;

  function colour(p) {
    const f = modes[settings.colour], c = new THREE.Color(), out = p.geometry.attributes.color.array;
    for (let i = 0, n = p.positions.length / 3; i < n; i++) {
      f(p, i, c);
      out[3 * i] = c.r;
      out[3 * i + 1] = c.g;
      out[3 * i + 2] = c.b;
    }
    p.geometry.attributes.color.needsUpdate = true;
  }
  // The intensity ramp's range: the 2nd and 98th percentiles of the finite values shown (of at
  // most 200,000 of them, evenly taken).
  function intensityRange() {
    let n = 0;
    for (const p of pieces.values()) n += p.intensity.length;
    if (!n) return;
    const step = Math.max(1, Math.floor(n / 200000)), values = [];
    for (const p of pieces.values())
      for (let i = 0; i < p.intensity.length; i += step) if (p.intensity[i] === p.intensity[i]) values.push(p.intensity[i]);
    if (!values.length) return;
    values.sort((a, b) => a - b);
    range.ilo = values[Math.floor(0.02 * (values.length - 1))];
    range.ihi = Math.max(range.ilo + 1e-6, values[Math.floor(0.98 * (values.length - 1))]);
  }
  function addPiece(name, positions, indices, levels, confidence, intensity) {
    removePiece(name);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(indices, 1));
    geometry.computeVertexNormals();
    geometry.setAttribute("color", new THREE.BufferAttribute(new Float32Array(positions.length), 3));
    const p = { positions, indices, levels, confidence, intensity, geometry, object: new THREE.Mesh(geometry, material) };
    for (let i = 0; i < levels.length; i++) if (levels[i] > range.kmax) range.kmax = levels[i];
    colour(p);
    surface.add(p.object);
    pieces.set(name, p);
    triangles += indices.length / 3;
    heights.add(positions, 1);
  }
  function removePiece(name) {
    const p = pieces.get(name);
    if (!p) return;
    surface.remove(p.object);
    p.geometry.dispose();
    pieces.delete(name);
    triangles -= p.indices.length / 3;
    heights.add(p.positions, -1);
  }

  // Heights of every vertex shown, in 0.25 m bins: the height colouring's range follows the map.
  const heights = {
    bins: new Map(),
    total: 0,
    add(positions, sign) {
      for (let i = 2; i < positions.length; i += 3) {
        const b = Math.floor(positions[i] * 4);
        this.bins.set(b, (this.bins.get(b) || 0) + sign);
      }
      this.total += (sign * positions.length) / 3;
    },
    // Sets range.zlo/zhi to the 2nd and 98th percentiles when they moved by over 0.5 m (or at
    // once when `force`); true when they were set.
    update(force) {
      if (this.total <= 0) return false;
      const keys = [...this.bins.keys()].filter((b) => this.bins.get(b) > 0).sort((a, b) => a - b);
      let seen = 0, lo = keys[0], hi = keys[keys.length - 1];
      for (const b of keys) {
        const before = seen;
        seen += this.bins.get(b);
        if (before < 0.02 * this.total && seen >= 0.02 * this.total) lo = b;
        if (before < 0.98 * this.total && seen >= 0.98 * this.total) hi = b;
      }
      const zlo = lo / 4, zhi = Math.max(zlo + 0.5, (hi + 1) / 4);
      const moved = Math.abs(zlo - range.zlo) > 0.5 || Math.abs(zhi - range.zhi) > 0.5;
      if (moved || force) (range.zlo = zlo), (range.zhi = zhi);
      return moved || force;
    },
  };

  // ---- The camera: orbit controls, spherical coordinates around a target.
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  document.body.appendChild(renderer.domElement);
  const camera = new THREE.PerspectiveCamera(55, 1, 0.05, 5000);
  camera.up.set(0, 0, 1);
  const target = new THREE.Vector3();
  const view = { azimuth: -2.3, elevation: 0.6, distance: 60, size: 60 };
  function place() {
    const ce = Math.cos(view.elevation);
    camera.position.set(
      target.x + view.distance * ce * Math.cos(view.azimuth),
      target.y + view.distance * ce * Math.sin(view.azimuth),
      target.z + view.distance * Math.sin(view.elevation)
    );
    camera.lookAt(target);
    // The key light comes from above the camera's left shoulder: faces turned away are darker.
    const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
    key.position.copy(camera.position).addScaledVector(right, -0.5 * view.distance).add(new THREE.Vector3(0, 0, 0.7 * view.distance));
    key.target.position.copy(target);
  }
  let drag = null;
  renderer.domElement.addEventListener("contextmenu", (e) => e.preventDefault());
  renderer.domElement.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
  });
  window.addEventListener("pointerup", () => (drag = null));
  window.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) {
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 0);
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 1);
      const scale = view.distance / renderer.domElement.clientHeight;
      target.addScaledVector(right, -dx * scale).addScaledVector(up, dy * scale);
      if (live) settings.follow = false, (follow.checked = false);
    } else {
      view.azimuth -= 0.005 * dx;
      view.elevation = Math.min(1.55, Math.max(-1.55, view.elevation + 0.005 * dy));
    }
    draw();
  });
  renderer.domElement.addEventListener(
    "wheel",
    (e) => {
      e.preventDefault();
      view.distance = Math.min(10 * view.size + 10, Math.max(0.1, view.distance * Math.exp(0.001 * e.deltaY)));
      draw();
    },
    { passive: false }
  );

  // ---- The panel.
  const select = document.getElementById("colour");
  const wire = document.getElementById("wireframe");
  const pts = document.getElementById("points");
  const follow = document.getElementById("follow");
  const info = document.getElementById("info");
  let cloud = null;
  function apply() {
    if (settings.colour === "intensity") intensityRange();
    for (const p of pieces.values()) colour(p);
    material.wireframe = settings.wireframe;
    if (cloud) cloud.visible = settings.points;
    select.value = settings.colour;
    wire.checked = settings.wireframe;
    pts.checked = !!cloud && settings.points;
    pts.disabled = !cloud;
    follow.checked = settings.follow;
    document.body.dataset.colour = settings.colour; // what is shown, for tests
    draw();
  }
  select.addEventListener("change", () => ((settings.colour = select.value), apply()));
  wire.addEventListener("change", () => ((settings.wireframe = wire.checked), apply()));
  pts.addEventListener("change", () => ((settings.points = pts.checked), apply()));
  follow.addEventListener("change", () => ((settings.follow = follow.checked), sensor && settings.follow && target.copy(sensor.position), draw()));
  document.getElementById("follow-label").hidden = !live;

  let frame = 0;
  function draw() {
    if (frame) return;
    frame = requestAnimationFrame(() => {
      frame = 0;
      const w = window.innerWidth, h = window.innerHeight;
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      place();
      renderer.render(scene, camera);
    });
  }
  window.addEventListener("resize", draw);

  // The mesh the page holds, in world coordinates (for tests and the console).
  let origin = [0, 0, 0];
  window.lidarsurf = {
    mesh() {
      const positions = [], indices = [];
      for (const p of pieces.values()) {
        const base = positions.length / 3;
        for (let i = 0; i < p.positions.length; i += 3)
          positions.push(p.positions[i] + origin[0], p.positions[i + 1] + origin[1], p.positions[i + 2] + origin[2]);
        for (let i = 0; i < p.indices.length; i++) indices.push(p.indices[i] + base);
      }
      return { positions, indices };
    },
  };

  function describe(state) {
    const n = (x) => x.toLocaleString();
    info.textContent = data.title + ": " + (live ? n(scans) + " scans, " : "") + n(triangles) + " triangles" + (state ? " (" + state + ")" : "");
    document.body.dataset.triangles = String(triangles);
    document.body.dataset.scans = String(scans);
    document.body.dataset.state = state || "static";
  }

  // ---- Source 1: a mesh in the page. The first view frames the bulk of the surface (the
  // median vertex, the 70th percentile of the horizontal spread), not its outliers.
  let scans = 0, sensor = null;
  if (!live) {
    origin = data.centre || [0, 0, 0];
    const positions = decode(data.vertices, Float32Array);
    addPiece("mesh", positions, decode(data.indices || data.triangles, Uint32Array), decode(data.levels, Uint8Array), decode(data.confidence, Float32Array),
             decode(data.intensity, Float32Array));
    heights.update(true);
    intensityRange();
    for (const p of pieces.values()) colour(p);
    const nv = positions.length / 3;
    const median = (axis) => {
      const v = [];
      for (let i = 0; i < nv; i++) v.push(positions[3 * i + axis]);
      v.sort((a, b) => a - b);
      return v.length ? v[Math.floor(v.length / 2)] : 0;
    };
    target.set(median(0), median(1), median(2));
    const spread = [];
    for (let i = 0; i < nv; i++) spread.push(Math.hypot(positions[3 * i] - target.x, positions[3 * i + 1] - target.y));
    spread.sort((a, b) => a - b);
    view.size = Math.max(1, spread.length ? 2 * spread[Math.floor(0.7 * (spread.length - 1))] : 10);
    view.distance = 1.1 * view.size;
    const points = decode(data.points, Float32Array);
    if (points.length) {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(points, 3));
      cloud = new THREE.Points(g, new THREE.PointsMaterial({ color: 0x202020, size: 2, sizeAttenuation: false }));
      scene.add(cloud);
    }
    describe("");
    apply();
    document.body.dataset.ready = "1";
    return;
  }

  // ---- Source 2: the live map. The trajectory as a line, the sensor as an arrow along its x axis.
  let track = new Float32Array(3 * 1024), trackLength = 0;
  const trackGeometry = new THREE.BufferGeometry();
  trackGeometry.setAttribute("position", new THREE.BufferAttribute(track, 3));
  trackGeometry.setDrawRange(0, 0);
  scene.add(new THREE.Line(trackGeometry, new THREE.LineBasicMaterial({ color: 0xd62728 })));
  sensor = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 4, 0xd62728, 1.5, 1);
  sensor.visible = false;
  scene.add(sensor);
  function extendTrack(points) {
    if (3 * trackLength + points.length > track.length) {
      const grown = new Float32Array(2 * (track.length + points.length));
      grown.set(track.subarray(0, 3 * trackLength));
      track = grown;
      trackGeometry.setAttribute("position", new THREE.BufferAttribute(track, 3));
    }
    track.set(points, 3 * trackLength);
    trackLength += points.length / 3;
    trackGeometry.attributes.position.needsUpdate = true;
    trackGeometry.setDrawRange(0, trackLength);
    trackGeometry.computeBoundingSphere();
  }

  // One message of the stream (io/live_stream.hpp): header, trajectory, removed keys, blocks.
  const kReset = 1, kFinal = 2, kMore = 4;
  let state = "connecting";
  function receive(buffer) {
    const dv = new DataView(buffer);
    const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1), dv.getUint8(2), dv.getUint8(3));
    if (magic !== "LSLV" || dv.getUint32(4, true) !== 3) throw new Error("not a lidarsurf live stream (version 3)");
    const flags = dv.getUint32(8, true);
    scans = dv.getUint32(12, true);
    origin = [dv.getFloat64(16, true), dv.getFloat64(24, true), dv.getFloat64(32, true)];
    const pose = new Float32Array(buffer, 40, 12);
    const nTrajectory = dv.getUint32(88, true), nRemoved = dv.getUint32(92, true), nChanged = dv.getUint32(96, true);
    let at = 112;
    if (flags & kReset) {
      for (const name of [...pieces.keys()]) removePiece(name);
      trackLength = 0;
    }
    extendTrack(new Float32Array(buffer, at, 3 * nTrajectory));
    at += 12 * nTrajectory;
    const removed = new Int32Array(buffer, at, 3 * nRemoved);
    at += 12 * nRemoved;
    for (let i = 0; i < nRemoved; i++) removePiece(removed[3 * i] + "," + removed[3 * i + 1] + "," + removed[3 * i + 2]);
    // A block: its vertex records and triangles in meshoptimizer's codecs; positions in 16-bit
    // steps from the block's lowest corner, confidence in 16-bit steps from 0, intensity in 16-bit
    // steps from its base (65535: none; a step below 0: the block has no intensity).
    for (let b = 0; b < nChanged; b++) {
      const k = new Int32Array(buffer, at, 3);
      const nv = dv.getUint32(at + 12, true), nt = dv.getUint32(at + 16, true);
      const base = [dv.getFloat32(at + 20, true), dv.getFloat32(at + 24, true), dv.getFloat32(at + 28, true)];
      const step = dv.getFloat32(at + 32, true), cstep = dv.getFloat32(at + 36, true);
      const ibase = dv.getFloat32(at + 40, true), istep = dv.getFloat32(at + 44, true);
      const vertexBytes = dv.getUint32(at + 48, true), indexBytes = dv.getUint32(at + 52, true);
      at += 56;
      const records = new Uint8Array(12 * nv);
      MeshoptDecoder.decodeVertexBuffer(records, nv, 12, new Uint8Array(buffer, at, vertexBytes));
      at += (vertexBytes + 3) & ~3;
      const indices = new Uint32Array(3 * nt);
      MeshoptDecoder.decodeIndexBuffer(new Uint8Array(indices.buffer), 3 * nt, 4, new Uint8Array(buffer, at, indexBytes));
      at += (indexBytes + 3) & ~3;
      const q = new Uint16Array(records.buffer);
      const positions = new Float32Array(3 * nv), confidence = new Float32Array(nv), levels = new Uint8Array(nv);
      const intensity = new Float32Array(istep >= 0 ? nv : 0);
      for (let i = 0; i < nv; i++) {
        for (let a = 0; a < 3; a++) positions[3 * i + a] = base[a] + q[6 * i + a] * step;
        confidence[i] = q[6 * i + 3] * cstep;
        levels[i] = records[12 * i + 8];
        if (istep >= 0) intensity[i] = q[6 * i + 5] === 65535 ? NaN : ibase + q[6 * i + 5] * istep;
      }
      for (let i = 0; i < indices.length; i++) if (indices[i] >= nv) throw new Error("a triangle index out of its block");
      addPiece(k[0] + "," + k[1] + "," + k[2], positions, indices, levels, confidence, intensity);
    }
    // The sensor: position and heading (the pose's x axis); the camera follows it when asked.
    const position = new THREE.Vector3(pose[3], pose[7], pose[11]);
    sensor.position.copy(position);
    sensor.setDirection(new THREE.Vector3(pose[0], pose[4], pose[8]).normalize());
    sensor.visible = true;
    if (settings.follow) target.copy(position);
    // The intensity ramp follows the map: its range is taken again every tenth scan (and at a reset
    // or the end), the blocks recoloured when it moved by over 5 %.
    let recolour = heights.update() || flags & kReset;
    if (settings.colour === "intensity" && (flags & (kReset | kFinal) || scans % 10 === 0)) {
      const [lo, hi] = [range.ilo, range.ihi];
      intensityRange();
      recolour = recolour || Math.abs(range.ilo - lo) + Math.abs(range.ihi - hi) > 0.05 * (hi - lo);
    }
    if (recolour) for (const p of pieces.values()) colour(p);
    state = flags & kFinal ? "final" : flags & kMore ? "catching up" : "live";
    describe(state);
    draw();
  }

  function connect() {
    const socket = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/live");
    socket.binaryType = "arraybuffer";
    socket.onmessage = (e) => {
      try {
        receive(e.data);
      } catch (err) {
        describe("stream error: " + err.message);
        socket.close();
      }
    };
    socket.onclose = () => {
      if (state !== "final") describe(state === "connecting" ? "no server" : "disconnected");
    };
  }
  describe(state);
  apply();
  document.body.dataset.ready = "1";
  MeshoptDecoder.ready.then(connect);  // the stream's decoder (WebAssembly) first
})();
