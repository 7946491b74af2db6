// The viewer of `lidarsurf view`: the mesh (and the input points) from the data block of this
// file, drawn with three.js (the global THREE of build/three.min.js, inlined above). Orbit with
// the left button, pan with the right one (or shift), zoom with the wheel. The panel switches the
// colouring (height, neighbourhood level k', Gaussian confidence), the wireframe and the points;
// the same settings can be given in the URL's hash: #colour=level&wireframe=1&points=0.
(function () {
  "use strict";
  const data = JSON.parse(document.getElementById("lidarsurf-data").textContent);

  function decode(b64, Type) {
    if (!b64) return new Type(0);
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer);
  }
  const positions = decode(data.vertices, Float32Array); // metres, relative to data.centre
  const indices = decode(data.triangles, Uint32Array);
  const levels = decode(data.levels, Uint8Array);
  const confidence = decode(data.confidence, Float32Array);
  const points = decode(data.points, Float32Array);
  const nv = positions.length / 3;

  // Colour ramps: height over the 2nd-98th percentile, k' over 1..k_max, confidence over [0, 1].
  function ramp(t) {
    t = Math.min(1, Math.max(0, t));
    const c = new THREE.Color();
    c.setHSL(0.66 * (1 - t), 0.75, 0.5);
    return c;
  }
  const zs = [];
  for (let i = 0; i < nv; i++) zs.push(positions[3 * i + 2]);
  zs.sort((a, b) => a - b);
  const zlo = zs.length ? zs[Math.floor(0.02 * (zs.length - 1))] : 0;
  const zhi = zs.length ? Math.max(zlo + 1e-6, zs[Math.floor(0.98 * (zs.length - 1))]) : 1;
  let kmax = 1;
  for (let i = 0; i < levels.length; i++) kmax = Math.max(kmax, levels[i]);
  const modes = {
    height: (i) => ramp((positions[3 * i + 2] - zlo) / (zhi - zlo)),
    level: (i) => (levels.length ? ramp((levels[i] - 1) / Math.max(1, kmax - 1)) : new THREE.Color(0.6, 0.6, 0.6)),
    confidence: (i) => (confidence.length ? ramp(confidence[i]) : new THREE.Color(0.6, 0.6, 0.6)),
    grey: () => new THREE.Color(0.7, 0.7, 0.7),
  };

  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(indices, 1));
  geometry.computeVertexNormals();
  const colours = new Float32Array(3 * nv);
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
  const mesh = new THREE.Mesh(geometry, material);

  const cloud = new THREE.Points(
    (() => {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(points, 3));
      return g;
    })(),
    new THREE.PointsMaterial({ color: 0x202020, size: 2, sizeAttenuation: false })
  );

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f4f7);
  scene.add(mesh, cloud);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const sun = new THREE.DirectionalLight(0xffffff, 0.9);
  sun.position.set(0.4, 0.5, 1.0);
  scene.add(sun);

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  document.body.appendChild(renderer.domElement);
  const camera = new THREE.PerspectiveCamera(55, 1, 0.05, 5000);
  camera.up.set(0, 0, 1);

  // Orbit controls: spherical coordinates around a target. The first view frames the bulk of the
  // surface (the median vertex, the 70th percentile of the horizontal spread), not its outliers.
  function median(axis) {
    const v = [];
    for (let i = 0; i < nv; i++) v.push(positions[3 * i + axis]);
    v.sort((a, b) => a - b);
    return v.length ? v[Math.floor(v.length / 2)] : 0;
  }
  const target = new THREE.Vector3(median(0), median(1), median(2));
  const spread = [];
  for (let i = 0; i < nv; i++) spread.push(Math.hypot(positions[3 * i] - target.x, positions[3 * i + 1] - target.y));
  spread.sort((a, b) => a - b);
  const size = Math.max(1, spread.length ? 2 * spread[Math.floor(0.7 * (spread.length - 1))] : 10);
  const view = { azimuth: -2.3, elevation: 0.6, distance: 1.1 * size };
  function place() {
    const ce = Math.cos(view.elevation);
    camera.position.set(
      target.x + view.distance * ce * Math.cos(view.azimuth),
      target.y + view.distance * ce * Math.sin(view.azimuth),
      target.z + view.distance * Math.sin(view.elevation)
    );
    camera.lookAt(target);
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
      view.distance = Math.min(10 * size + 10, Math.max(0.1, view.distance * Math.exp(0.001 * e.deltaY)));
      draw();
    },
    { passive: false }
  );

  // Settings: the panel and the URL's hash.
  const settings = { colour: data.colour in modes ? data.colour : "height", wireframe: false, points: false };
  for (const part of window.location.hash.replace(/^#/, "").split("&")) {
    const [key, value] = part.split("=");
    if (key === "colour" && value in modes) settings.colour = value;
    if (key === "wireframe") settings.wireframe = value === "1";
    if (key === "points") settings.points = value === "1";
  }
  const select = document.getElementById("colour");
  const wire = document.getElementById("wireframe");
  const pts = document.getElementById("points");
  function apply() {
    const f = modes[settings.colour];
    for (let i = 0; i < nv; i++) {
      const c = f(i);
      colours[3 * i] = c.r;
      colours[3 * i + 1] = c.g;
      colours[3 * i + 2] = c.b;
    }
    geometry.attributes.color.needsUpdate = true;
    material.wireframe = settings.wireframe;
    cloud.visible = settings.points && points.length > 0;
    select.value = settings.colour;
    wire.checked = settings.wireframe;
    pts.checked = cloud.visible;
    pts.disabled = points.length === 0;
    document.body.dataset.colour = settings.colour; // what is shown, for tests
    draw();
  }
  select.addEventListener("change", () => ((settings.colour = select.value), apply()));
  wire.addEventListener("change", () => ((settings.wireframe = wire.checked), apply()));
  pts.addEventListener("change", () => ((settings.points = pts.checked), apply()));

  function draw() {
    const w = window.innerWidth, h = window.innerHeight;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    place();
    renderer.render(scene, camera);
  }
  window.addEventListener("resize", draw);
  document.getElementById("info").textContent =
    data.title + ": " + nv.toLocaleString() + " vertices, " + (indices.length / 3).toLocaleString() + " triangles" +
    (points.length ? ", " + (points.length / 3).toLocaleString() + " points" : "");
  apply();
  document.body.dataset.ready = "1";
})();
