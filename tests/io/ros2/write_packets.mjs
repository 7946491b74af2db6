// Writes the Ouster driver's messages of ros1_packets.py as a ROS 2 recording in MCAP, as
// ouster-ros's ROS 2 driver records them: ouster_sensor_msgs/msg/PacketMsg (uint8[] buf) and the
// metadata as std_msgs/msg/String, serialized by @foxglove/cdr, written by @mcap/core (zstd chunks).
//
// Usage: node write_packets.mjs IN.msgs OUT.mcap
import { readFileSync, openSync, writeSync, closeSync } from "node:fs";
import { CdrWriter } from "@foxglove/cdr";
import { McapWriter } from "@mcap/core";
import * as zstd from "@foxglove/wasm-zstd";

const [input, output] = process.argv.slice(2);
const bytes = readFileSync(input);
const messages = [];
for (let at = 0; at < bytes.length;) {
  const n = bytes.readUInt16LE(at);
  const topic = bytes.subarray(at + 2, at + 2 + n).toString();
  at += 2 + n;
  const stamp = bytes.readBigUInt64LE(at), size = bytes.readUInt32LE(at + 8);
  messages.push({ topic, stamp, payload: bytes.subarray(at + 12, at + 12 + size) });
  at += 12 + size;
}

const fd = openSync(output, "w");
let position = 0n;
const writable = { write: async (b) => { writeSync(fd, b); position += BigInt(b.byteLength); }, position: () => position };
await zstd.isLoaded;
const writer = new McapWriter({ writable, compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d) }) });
await writer.start({ profile: "ros2", library: "lidarsurf tests (@mcap/core)" });
const channels = new Map();
for (const m of messages) {
  const metadata = m.topic.endsWith("/metadata");
  if (!channels.has(m.topic)) {
    const name = metadata ? "std_msgs/msg/String" : "ouster_sensor_msgs/msg/PacketMsg";
    const schemaId = await writer.registerSchema({ name, encoding: "ros2msg", data: new TextEncoder().encode(metadata ? "string data" : "uint8[] buf") });
    channels.set(m.topic, await writer.registerChannel({ topic: m.topic, schemaId, messageEncoding: "cdr", metadata: new Map() }));
  }
  const w = new CdrWriter({ size: m.payload.length + 64 });
  if (metadata) w.string(m.payload.toString());
  else w.uint8Array(new Uint8Array(m.payload), true);
  await writer.addMessage({ channelId: channels.get(m.topic), sequence: 0, logTime: m.stamp, publishTime: m.stamp, data: w.data });
}
await writer.end();
closeSync(fd);
