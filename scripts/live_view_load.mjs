// Clients for the live view's load measure (scripts/live_view_load.sh): READERS WebSocket clients
// that read every message of ws://HOST:PORT/live (header decoded: scans, flags; bytes counted) and
// STALLED ones that complete the handshake and then never read (a frozen browser tab: the kernel's
// buffers fill, then nothing moves). Ends when every reader has the final map or is gone, and writes
// per client: messages, MB, the last scan seen and the final message (the server reports the drops).
// Usage: node --experimental-websocket live_view_load.mjs URL READERS STALLED OUT.json
import net from "node:net";
import { randomBytes } from "node:crypto";
import { writeFileSync } from "node:fs";

const [url, readers, stalled, out] = process.argv.slice(2);
const { hostname, port } = new URL(url);
const start = Date.now();
const seconds = () => (Date.now() - start) / 1000;
const results = [];

function reader(i) {
  return new Promise((done) => {
    const r = { kind: "reader", id: i, messages: 0, mb: 0, scans: 0, final: false, closed_s: null };
    results.push(r);
    const ws = new WebSocket(`ws://${hostname}:${port}/live`);
    ws.binaryType = "arraybuffer";
    ws.onmessage = (e) => {
      const dv = new DataView(e.data);
      r.messages++;
      r.mb += e.data.byteLength / 1e6;
      r.scans = dv.getUint32(12, true);
      if (dv.getUint32(8, true) & 2) {
        r.final = true;
        r.final_s = seconds();
        ws.close();
        done();
      }
    };
    ws.onclose = () => {
      r.closed_s = seconds();
      done();
    };
  });
}

function stall(i) {
  const r = { kind: "stalled", id: i, handshake: false };
  results.push(r);
  const s = net.connect({ host: hostname, port: Number(port) }, () => {
    s.write(`GET /live HTTP/1.1\r\nHost: ${hostname}:${port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n` +
            `Sec-WebSocket-Key: ${randomBytes(16).toString("base64")}\r\nSec-WebSocket-Version: 13\r\n\r\n`);
  });
  s.once("data", (d) => {
    r.handshake = d.toString().startsWith("HTTP/1.1 101");
    s.pause(); // never read again
  });
  s.on("error", () => {});
  return s;
}

const sockets = [];
for (let i = 0; i < Number(stalled); i++) sockets.push(stall(i));
await Promise.all(Array.from({ length: Number(readers) }, (_, i) => reader(i)));
for (const r of results) if (r.mb !== undefined) r.mb = Math.round(r.mb * 10) / 10;
writeFileSync(out, JSON.stringify(results, null, 1));
console.log(JSON.stringify(results));
for (const s of sockets) s.destroy();
