// euroc_to_mcap.js DIVE OUT.mcap IMAGES COMPRESSION [PIXELS_DIR]: a simulated dive (`cenote sim`, EuRoC
// layout) as a ROS 2 MCAP recording, written by the MCAP team's own writer (@mcap/core) with CDR from
// Foxglove's ROS 2 serialiser, in the order a recorder would log it (by time; poses before images).
//   IMAGES png: sensor_msgs/CompressedImage, the PNG files' bytes, on /cam0/image_raw/compressed and
//              /cam1/image_raw/compressed;
//          jpeg: the same topics, format "bgr8; jpeg compressed bgr8", the bytes of PIXELS_DIR/<cam>/<name>.jpg
//              (OpenCV's JPEG at quality 95, dump_pixels.py);
//          raw: sensor_msgs/Image (mono8 or bgr8) on /cam0/image_raw and /cam1/image_raw, the pixels from
//              PIXELS_DIR/<cam>/<name>.raw with PIXELS_DIR/pixels.json ({width, height, channels}),
//              which OpenCV dumped (dump_pixels.py).
//   COMPRESSION none, zstd or lz4 chunks.
//   The ground-truth body poses (state_groundtruth_estimate0) as nav_msgs/Odometry on /odom (frame world,
//   child body), stamped with their own timestamps.
"use strict";

const fs = require("fs");
const path = require("path");
const { McapWriter } = require("@mcap/core");
const { MessageWriter } = require("@foxglove/rosmsg2-serialization");
const { stringify } = require("@foxglove/rosmsg");
const { ros2humble } = require("@foxglove/rosmsg-msgs-common");
const zstd = require("@foxglove/wasm-zstd");
const lz4 = require("lz4js");

const [dive, out, images, compression, pixelsDir] = process.argv.slice(2);
if (!compression) throw new Error("usage: node euroc_to_mcap.js DIVE OUT.mcap png|jpeg|raw none|zstd|lz4 [PIXELS_DIR]");
const mav0 = path.join(dive, "mav0");

function definitionsOf(type) {
  const seen = new Map();
  const visit = (name) => {
    if (seen.has(name)) return;
    seen.set(name, ros2humble[name]);
    for (const f of ros2humble[name].definitions) if (f.isComplex) visit(f.type);
  };
  visit(type);
  return [...seen.values()];
}
const stampOf = (ns) => ({ sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) });

function csvRows(file) {
  return fs.readFileSync(file, "utf8").split("\n").map((l) => l.trim()).filter((l) => l && !l.startsWith("#"))
    .map((l) => l.split(",").map((c) => c.trim()));
}

async function main() {
  await zstd.isLoaded;
  const compressChunk = {
    none: undefined,
    zstd: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) }),
    lz4: (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(data)) }),
  }[compression];
  const imageType = images === "raw" ? "sensor_msgs/Image" : "sensor_msgs/CompressedImage";
  const suffix = images === "raw" ? "image_raw" : "image_raw/compressed";
  const pixels = images === "raw" ? JSON.parse(fs.readFileSync(path.join(pixelsDir, "pixels.json"), "utf8")) : null;

  const events = [];  // [stamp ns, order, topic, make message]
  for (const row of csvRows(path.join(mav0, "state_groundtruth_estimate0", "data.csv"))) {
    const ns = BigInt(row[0]);
    const [px, py, pz, qw, qx, qy, qz] = row.slice(1, 8).map(Number);
    events.push([ns, 0, "/odom", () => ({
      header: { stamp: stampOf(ns), frame_id: "world" }, child_frame_id: "body",
      pose: { pose: { position: { x: px, y: py, z: pz }, orientation: { x: qx, y: qy, z: qz, w: qw } }, covariance: new Array(36).fill(0) },
      twist: { twist: { linear: { x: 0, y: 0, z: 0 }, angular: { x: 0, y: 0, z: 0 } }, covariance: new Array(36).fill(0) },
    })]);
  }
  ["cam0", "cam1"].forEach((cam, side) => {
    for (const [stamp, file] of csvRows(path.join(mav0, cam, "data.csv"))) {
      const ns = BigInt(stamp);
      const header = { stamp: stampOf(ns), frame_id: cam };
      events.push([ns, 1 + side, `/${cam}/${suffix}`, () => {
        const stem = path.parse(file).name;
        if (images === "png") return { header, format: "png", data: fs.readFileSync(path.join(mav0, cam, "data", file)) };
        if (images === "jpeg") {
          return { header, format: "bgr8; jpeg compressed bgr8", data: fs.readFileSync(path.join(pixelsDir, cam, `${stem}.jpg`)) };
        }
        const data = fs.readFileSync(path.join(pixelsDir, cam, `${stem}.raw`));
        return { header, height: pixels.height, width: pixels.width, encoding: pixels.channels === 3 ? "bgr8" : "mono8",
                 is_bigendian: 0, step: pixels.width * pixels.channels, data };
      }]);
    }
  });
  events.sort((a, b) => (a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : a[1] - b[1]));

  const parts = [];
  let size = 0n;
  const writer = new McapWriter({
    writable: { write: async (b) => { parts.push(Buffer.from(b)); size += BigInt(b.byteLength); }, position: () => size },
    chunkSize: 256 * 1024, compressChunk,
  });
  await writer.start({ profile: "ros2", library: "cenote tests/io/bag/gen/euroc_to_mcap.js" });
  const channels = new Map();
  const serialisers = new Map();
  for (const [topic, type] of [["/odom", "nav_msgs/Odometry"], [`/cam0/${suffix}`, imageType], [`/cam1/${suffix}`, imageType]]) {
    const schemaId = await writer.registerSchema({
      name: type.replace("/", "/msg/"), encoding: "ros2msg", data: new TextEncoder().encode(stringify(definitionsOf(type))),
    });
    channels.set(topic, await writer.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() }));
    serialisers.set(topic, new MessageWriter(definitionsOf(type)));
  }
  let sequence = 0;
  for (const [ns, , topic, make] of events) {
    const data = serialisers.get(topic).writeMessage(make());
    await writer.addMessage({ channelId: channels.get(topic), sequence: sequence++, logTime: ns, publishTime: ns, data });
  }
  await writer.end();
  fs.writeFileSync(out, Buffer.concat(parts));
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
