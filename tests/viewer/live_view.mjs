// The live view in a real browser (make viewer-check): Debian's Chromium, driven by
// playwright-core, opens the page of a running `lidarsurf fuse --serve` mid-drive, takes a
// screenshot, another once the map has grown, and one of the final map; then writes the mesh the
// page holds (window.lidarsurf.mesh(), world coordinates) for the comparison with fuse's output.
// Usage: node live_view.mjs URL WORK_DIR MID_SCANS LATER_SCANS
import { chromium } from "playwright-core";
import { writeFileSync } from "node:fs";

const [url, work, mid, later] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
});
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 600 } });
  page.on("pageerror", (e) => console.error("page error:", e.message));
  await page.goto(url);
  const shown = () => page.evaluate(() => ({ ...document.body.dataset }));
  const waitFor = async (what, test, seconds) => {
    const until = Date.now() + 1000 * seconds;
    for (;;) {
      const s = await shown();
      if (test(s)) return s;
      if (Date.now() > until) throw new Error(`timed out waiting for ${what}: ${JSON.stringify(s)}`);
      await new Promise((r) => setTimeout(r, 100));
    }
  };
  const report = {};
  for (const [name, least] of [["mid", Number(mid)], ["later", Number(later)]]) {
    // The later picture at least 5 scans after the mid one, however late the browser came up.
    const scans = name === "later" ? Math.max(least, report.mid.scans + 5) : least;
    const s = await waitFor(`${scans} scans`, (d) => Number(d.scans) >= scans && d.state === "live", 300);
    await page.waitForTimeout(300); // the frame of that message drawn
    await page.screenshot({ path: `${work}/${name}.png` });
    report[name] = { scans: Number(s.scans), triangles: Number(s.triangles) };
  }
  const f = await waitFor("the final map", (d) => d.state === "final", 600);
  await page.waitForTimeout(300);
  await page.screenshot({ path: `${work}/final.png` });
  report.final = { scans: Number(f.scans), triangles: Number(f.triangles) };
  report.info = await page.evaluate(() => document.getElementById("info").textContent);
  const mesh = await page.evaluate(() => window.lidarsurf.mesh());
  writeFileSync(`${work}/page_mesh.json`, JSON.stringify(mesh));
  writeFileSync(`${work}/live_view.json`, JSON.stringify(report, null, 1));
  console.log(JSON.stringify(report));
} finally {
  await browser.close();
}
