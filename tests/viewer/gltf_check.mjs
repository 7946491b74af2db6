// Binary glTF as its users' tools read it (make viewer-check): every .glb passes the Khronos
// glTF validator with no error and no warning, then Debian's Chromium (playwright-core) loads it
// with three.js's own GLTFLoader and DRACOLoader, from the pinned `three` package the viewer
// embeds. The triangles three.js holds must be the PLY's, and the box of the vertices in three's
// world (y up) the PLY's box turned from z up: (x, y, z) -> (x, z, -y), within 1 cm.
// Usage: node gltf_check.mjs THREE_DIR WORK_DIR CASE...
//   CASE = NAME=GLB[,GLB...]=PLY: the GLBs together hold the PLY's triangles.
import { createServer } from "node:http";
import { readFileSync } from "node:fs";
import { extname, join, normalize } from "node:path";
import validator from "gltf-validator";
import { chromium } from "playwright-core";

const [threeDir, work, ...caseArgs] = process.argv.slice(2);
const cases = caseArgs.map((c) => {
  const [name, glbs, ply] = c.split("=");
  return { name, glbs: glbs.split(","), ply };
});

// The PLY's face count and vertex box, read from its header and (binary) vertex records.
function plyFacts(path) {
  const data = readFileSync(path);
  const end = data.indexOf("end_header\n") + "end_header\n".length;
  const header = data.subarray(0, end).toString("latin1").split("\n");
  let element = null, vertices = 0, faces = 0;
  const props = [];
  for (const line of header) {
    const w = line.trim().split(/\s+/);
    if (w[0] === "element") element = w[1], w[1] === "vertex" ? (vertices = Number(w[2])) : w[1] === "face" && (faces = Number(w[2]));
    if (w[0] === "property" && element === "vertex") props.push({ type: w[1], name: w[2] });
    if (w[0] === "format" && w[1] !== "binary_little_endian") throw new Error(`${path}: binary PLY expected`);
  }
  const size = { float: 4, double: 8, uchar: 1, int: 4, uint: 4 };
  const stride = props.reduce((s, p) => s + size[p.type], 0);
  const offset = {};
  props.reduce((o, p) => ((offset[p.name] = { at: o, type: p.type }), o + size[p.type]), 0);
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < vertices; ++i) {
    ["x", "y", "z"].forEach((a, k) => {
      const { at, type } = offset[a];
      const v = type === "double" ? data.readDoubleLE(end + i * stride + at) : data.readFloatLE(end + i * stride + at);
      min[k] = Math.min(min[k], v), max[k] = Math.max(max[k], v);
    });
  }
  return { faces, min, max };
}

let failed = false;
for (const c of cases) {
  let valid = true;
  for (const glb of c.glbs) {
    const report = await validator.validateBytes(new Uint8Array(readFileSync(join(work, glb))), { maxIssues: 50 });
    const { numErrors, numWarnings } = report.issues;
    if (numErrors || numWarnings) {
      console.error(`gltf-check: ${glb}: ${numErrors} errors, ${numWarnings} warnings`, JSON.stringify(report.issues.messages.slice(0, 5)));
      failed = true, valid = false;
    }
  }
  if (valid) console.log(`gltf-check: ${c.name}: ${c.glbs.length} file(s) valid (Khronos glTF validator ${validator.version()})`);
}

// A page served from 127.0.0.1: three from the pinned package, the files from the work directory.
const page = `<!doctype html><html><body><script type="importmap">{"imports": {"three": "/three/build/three.module.js"}}</script>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "/three/examples/jsm/loaders/GLTFLoader.js";
import { DRACOLoader } from "/three/examples/jsm/loaders/DRACOLoader.js";
const draco = new DRACOLoader().setDecoderPath("/three/examples/jsm/libs/draco/gltf/");
const loader = new GLTFLoader().setDRACOLoader(draco);
window.load = async (files) => {
  let triangles = 0, confidence = true;
  const box = new THREE.Box3();
  for (const f of files) {
    const gltf = await loader.loadAsync("/files/" + f);
    gltf.scene.updateMatrixWorld(true);
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      const g = o.geometry;
      triangles += (g.index ? g.index.count : g.attributes.position.count) / 3;
      confidence = confidence && !!g.attributes._confidence && !!g.attributes.normal;
      box.expandByObject(o, true);
    });
  }
  return { triangles, confidence, min: box.min.toArray(), max: box.max.toArray() };
};
document.body.dataset.ready = "1";
</script></body></html>`;
const types = { ".js": "text/javascript", ".mjs": "text/javascript", ".wasm": "application/wasm", ".glb": "model/gltf-binary" };
const server = createServer((req, res) => {
  const url = decodeURIComponent(new URL(req.url, "http://127.0.0.1").pathname);
  const serve = (root, rest) => {
    const path = normalize(join(root, rest));
    if (!path.startsWith(normalize(root))) return res.writeHead(403).end();
    try {
      res.writeHead(200, { "Content-Type": types[extname(path)] || "application/octet-stream" }).end(readFileSync(path));
    } catch {
      res.writeHead(404).end();
    }
  };
  if (url === "/") return res.writeHead(200, { "Content-Type": "text/html" }).end(page);
  if (url.startsWith("/three/")) return serve(threeDir, url.slice("/three/".length));
  if (url.startsWith("/files/")) return serve(work, url.slice("/files/".length));
  res.writeHead(404).end();
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
});
try {
  const tab = await browser.newPage();
  tab.on("pageerror", (e) => console.error("page error:", e.message));
  await tab.goto(`http://127.0.0.1:${server.address().port}/`);
  await tab.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 60000 });
  for (const c of cases) {
    const want = plyFacts(join(work, c.ply));
    const got = await tab.evaluate((files) => window.load(files), c.glbs);
    // three's world is y up: the lidar's (x, y, z) is (x, z, -y) there.
    const wantMin = [want.min[0], want.min[2], -want.max[1]], wantMax = [want.max[0], want.max[2], -want.min[1]];
    const off = Math.max(...[0, 1, 2].map((k) => Math.max(Math.abs(got.min[k] - wantMin[k]), Math.abs(got.max[k] - wantMax[k]))));
    const ok = got.triangles === want.faces && got.confidence && off <= 0.01;
    console.log(`gltf-check: ${c.name}: three.js holds ${got.triangles} triangles, the PLY ${want.faces}; box off by ${(1000 * off).toFixed(2)} mm; ` +
      `normals and confidence ${got.confidence ? "present" : "MISSING"}${ok ? "" : "  <-- FAIL"}`);
    failed ||= !ok;
  }
} finally {
  await browser.close();
  server.close();
}
process.exit(failed ? 1 : 0);
