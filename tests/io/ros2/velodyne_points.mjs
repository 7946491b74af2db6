// Decodes Velodyne data packets with Foxglove's decoder (@foxglove/velodyne-cloud, the one Foxglove
// Studio converts velodyne_msgs/VelodyneScan with), for the tests of lidarsurf's own.
//
// Usage: node velodyne_points.mjs PACKETS.bin MODEL CALIBRATION.json OUT.bin
//   PACKETS.bin: 1206-byte packets back to back; MODEL: VLP16, VLP16HiRes, VLP32C, HDL32E or HDL64E;
//   CALIBRATION.json: the calibration YAML's content as JSON.
//   OUT.bin: per point, in the decoder's order, 5 float64: x, y, z (ROS frame), laser id, block azimuth.
import { readFileSync, writeFileSync } from "node:fs";
import velodyne from "@foxglove/velodyne-cloud";

const { Calibration, Model, PointCloud, RawPacket, Transformer } = velodyne;
const [packetsFile, modelName, calibrationFile, output] = process.argv.slice(2);
const bytes = readFileSync(packetsFile);
const model = Model[modelName];
if (model === undefined) throw new Error(`unknown model ${modelName}`);
const transformer = new Transformer(new Calibration(model, JSON.parse(readFileSync(calibrationFile, "utf8"))), { minRange: 0.001, maxRange: 1000 });
const out = [];
for (let at = 0; at + 1206 <= bytes.length; at += 1206) {
  const cloud = new PointCloud({ stamp: 0, maxPoints: RawPacket.MAX_POINTS_PER_PACKET });
  transformer.unpack(new RawPacket(new Uint8Array(bytes.subarray(at, at + 1206))), 0, 0, cloud);
  const view = new DataView(cloud.data.buffer, cloud.data.byteOffset, cloud.data.byteLength);
  for (let i = 0; i < cloud.width; i++) {
    const o = i * cloud.point_step;
    out.push(view.getFloat32(o, true), view.getFloat32(o + 4, true), view.getFloat32(o + 8, true), view.getUint16(o + 20, true), view.getUint16(o + 22, true));
  }
}
writeFileSync(output, Buffer.from(new Float64Array(out).buffer));
