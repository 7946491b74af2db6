// Writes a KITTI-layout drive (velodyne/NNNNNN.bin, float32 x y z intensity) as ROS 2 recordings
// with the format maintainers' own writers: sensor_msgs/msg/PointCloud2 serialized by
// @foxglove/cdr, in MCAP files written by @mcap/core. One message every 0.1 s from 100 s, as
// kitti_to_ros1_bag.py does, so that every recording of the drive gives the same map.
//
// Usage: node write_ros2.mjs DRIVE_DIR OUT_DIR [TRANSFORMS_JSON]
// Writes in OUT_DIR:
//   zstd.mcap   chunks compressed with zstd (@foxglove/wasm-zstd), with the summary section
//   lz4.mcap    small chunks compressed as LZ4 frames (Debian's lz4), with the summary section
//   plain.mcap  no chunks and no summary, big-endian CDR
//   chunked.mcap  uncompressed chunks, with the summary section
//   messages.cdr  the little-endian CDR messages, each as uint64 stamp_ns, uint32 size, bytes:
//                 write_db3.py puts them in a rosbag2 sqlite3 bag
//   tf.mcap     with TRANSFORMS_JSON (write_tf_bag.py's): the scans with /tf_static, /tf
//               (tf2_msgs/msg/TFMessage), /odom (nav_msgs/msg/Odometry, big-endian CDR) and /pose
//               (geometry_msgs/msg/PoseStamped), the transforms write_tf_bag.py puts in its ROS 1 bag
import { readdirSync, readFileSync, openSync, writeSync, closeSync } from "node:fs";
import { join } from "node:path";
import { spawnSync } from "node:child_process";
import { CdrWriter, EncapsulationKind } from "@foxglove/cdr";
import { McapWriter } from "@mcap/core";
import * as zstd from "@foxglove/wasm-zstd";

const [drive, out, transformsPath] = process.argv.slice(2);
const scans = readdirSync(join(drive, "velodyne")).filter((f) => f.endsWith(".bin")).sort();
const FLOAT32 = 7;
const fields = [["x", 0], ["y", 4], ["z", 8], ["intensity", 12]];

// sensor_msgs/msg/PointCloud2 in CDR (field order of the .msg file).
function pointCloud2(data, sec, nanosec, kind) {
  const n = data.byteLength / 16;
  const w = new CdrWriter({ kind, size: data.byteLength + 512 });
  w.int32(sec).uint32(nanosec).string("velodyne");
  w.uint32(1).uint32(n);
  w.sequenceLength(fields.length);
  for (const [name, offset] of fields) w.string(name).uint32(offset).uint8(FLOAT32).uint32(1);
  const bigEndian = kind === EncapsulationKind.CDR_BE;
  w.uint8(bigEndian ? 1 : 0).uint32(16).uint32(16 * n);
  let bytes = data;
  if (bigEndian) {  // the point data in the byte order the message declares
    bytes = new Uint8Array(data.byteLength);
    const src = new DataView(data.buffer, data.byteOffset, data.byteLength), dst = new DataView(bytes.buffer);
    for (let i = 0; i < data.byteLength; i += 4) dst.setFloat32(i, src.getFloat32(i, true), false);
  }
  w.sequenceLength(bytes.byteLength).uint8Array(bytes, false);
  w.uint8(1);  // is_dense
  return w.data;
}

class FileWritable {
  constructor(path) { this.fd = openSync(path, "w"); this.pos = 0n; }
  async write(buffer) { writeSync(this.fd, buffer); this.pos += BigInt(buffer.byteLength); }
  position() { return this.pos; }
  close() { closeSync(this.fd); }
}

const lz4Frame = (data) => {
  const r = spawnSync("lz4", ["-c", "-q"], { input: data, maxBuffer: 1 << 30 });
  if (r.status !== 0) throw new Error("lz4 failed: " + r.stderr);
  return { compression: "lz4", compressedData: new Uint8Array(r.stdout) };
};

async function writeMcap(path, kind, options) {
  const file = new FileWritable(path);
  const writer = new McapWriter({ writable: file, ...options });
  await writer.start({ profile: "ros2", library: "lidarsurf tests (@mcap/core)" });
  const schema = await writer.registerSchema({ name: "sensor_msgs/msg/PointCloud2", encoding: "ros2msg", data: new TextEncoder().encode("# (definition omitted)") });
  const channel = await writer.registerChannel({ topic: "/velodyne_points", schemaId: schema, messageEncoding: "cdr", metadata: new Map() });
  // A second topic the reader has to pass over.
  const string = await writer.registerSchema({ name: "std_msgs/msg/String", encoding: "ros2msg", data: new TextEncoder().encode("string data") });
  const other = await writer.registerChannel({ topic: "/chatter", schemaId: string, messageEncoding: "cdr", metadata: new Map() });
  for (let k = 0; k < scans.length; ++k) {
    const raw = readFileSync(join(drive, "velodyne", scans[k]));
    const data = new Uint8Array(raw.buffer, raw.byteOffset, raw.byteLength);
    const sec = 100 + Math.floor(k / 10), nanosec = (k % 10) * 100000000;
    const stamp = BigInt(sec) * 1000000000n + BigInt(nanosec);
    await writer.addMessage({ channelId: other, sequence: k, logTime: stamp, publishTime: stamp, data: new Uint8Array([0, 1, 0, 0, 2, 0, 0, 0, 104, 0]) });
    await writer.addMessage({ channelId: channel, sequence: k, logTime: stamp, publishTime: stamp, data: pointCloud2(data, sec, nanosec, kind) });
  }
  await writer.end();
  file.close();
}

// The messages of poses, in the field order of their .msg files.
function header(w, e) {
  w.int32(Number(BigInt(e.stamp_ns) / 1000000000n)).uint32(Number(BigInt(e.stamp_ns) % 1000000000n)).string(e.parent);
}
function pose(w, e) {
  for (const v of e.t) w.float64(v);
  for (const v of e.q) w.float64(v);
}
function tfMessage(entries) {
  const w = new CdrWriter({ kind: EncapsulationKind.CDR_LE });
  w.sequenceLength(entries.length);
  for (const e of entries) {
    header(w, e);
    w.string(e.child);
    pose(w, e);
  }
  return w.data;
}
function odometry(e) {
  const w = new CdrWriter({ kind: EncapsulationKind.CDR_BE });
  header(w, e);
  w.string(e.child);
  pose(w, e);
  for (let i = 0; i < 36; ++i) w.float64(i % 7 === 0 ? 0.01 : 0);  // pose covariance
  for (let i = 0; i < 6; ++i) w.float64(0);                          // twist
  for (let i = 0; i < 36; ++i) w.float64(0);
  return w.data;
}
function poseStamped(e) {
  const w = new CdrWriter({ kind: EncapsulationKind.CDR_LE });
  header(w, e);
  pose(w, e);
  return w.data;
}

async function writeTfMcap(path, transforms) {
  const file = new FileWritable(path);
  const writer = new McapWriter({ writable: file, compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d) }) });
  await writer.start({ profile: "ros2", library: "lidarsurf tests (@mcap/core)" });
  const channel = async (topic, type) => {
    const schema = await writer.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode("# (definition omitted)") });
    return writer.registerChannel({ topic, schemaId: schema, messageEncoding: "cdr", metadata: new Map() });
  };
  const messages = [];
  const tf = await channel("/tf", "tf2_msgs/msg/TFMessage"), tfStatic = await channel("/tf_static", "tf2_msgs/msg/TFMessage");
  const odom = await channel("/odom", "nav_msgs/msg/Odometry"), poses = await channel("/pose", "geometry_msgs/msg/PoseStamped");
  const clouds = await channel("/velodyne_points", "sensor_msgs/msg/PointCloud2");
  messages.push([BigInt(transforms.static[0].stamp_ns), tfStatic, tfMessage(transforms.static)]);
  for (const e of transforms.tf) messages.push([BigInt(e.stamp_ns), tf, tfMessage([e])]);
  for (const e of transforms.odom) messages.push([BigInt(e.stamp_ns), odom, odometry(e)]);
  for (const e of transforms.pose) messages.push([BigInt(e.stamp_ns), poses, poseStamped(e)]);
  for (let k = 0; k < scans.length; ++k) {
    const raw = readFileSync(join(drive, "velodyne", scans[k]));
    const sec = 100 + Math.floor(k / 10), nanosec = (k % 10) * 100000000;
    const data = pointCloud2(new Uint8Array(raw.buffer, raw.byteOffset, raw.byteLength), sec, nanosec, EncapsulationKind.CDR_LE);
    messages.push([BigInt(sec) * 1000000000n + BigInt(nanosec), clouds, data]);
  }
  messages.sort((a, b) => (a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : 0));
  for (const [k, [stamp, channelId, data]] of messages.entries())
    await writer.addMessage({ channelId, sequence: k, logTime: stamp, publishTime: stamp, data });
  await writer.end();
  file.close();
}

await zstd.isLoaded;
if (transformsPath) await writeTfMcap(join(out, "tf.mcap"), JSON.parse(readFileSync(transformsPath, "utf8")));
await writeMcap(join(out, "zstd.mcap"), EncapsulationKind.CDR_LE, { compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d) }) });
await writeMcap(join(out, "lz4.mcap"), EncapsulationKind.CDR_LE, { chunkSize: 256 * 1024, compressChunk: lz4Frame });
await writeMcap(join(out, "plain.mcap"), EncapsulationKind.CDR_BE, {
  useChunks: false, useStatistics: false, useSummaryOffsets: false, repeatSchemas: false, repeatChannels: false,
  useAttachmentIndex: false, useMetadataIndex: false, useMessageIndex: false, useChunkIndex: false,
});
await writeMcap(join(out, "chunked.mcap"), EncapsulationKind.CDR_LE, { chunkSize: 1024 * 1024 });
const blobs = openSync(join(out, "messages.cdr"), "w");
for (let k = 0; k < scans.length; ++k) {
  const raw = readFileSync(join(drive, "velodyne", scans[k]));
  const sec = 100 + Math.floor(k / 10), nanosec = (k % 10) * 100000000;
  const msg = pointCloud2(new Uint8Array(raw.buffer, raw.byteOffset, raw.byteLength), sec, nanosec, EncapsulationKind.CDR_LE);
  const head = Buffer.alloc(12);
  head.writeBigUInt64LE(BigInt(sec) * 1000000000n + BigInt(nanosec), 0);
  head.writeUInt32LE(msg.byteLength, 8);
  writeSync(blobs, head);
  writeSync(blobs, msg);
}
closeSync(blobs);
