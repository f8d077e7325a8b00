// gen_mcap.js OUT_DIR: writes the MCAP recordings the ROS 2 bag tests read, with the MCAP team's own
// writer (@mcap/core) and Foxglove's ROS 2 CDR serialiser, and OUT_DIR/expected.json with what a
// reader must find in them (topics, counts, time spans, every message's bytes, chunk offsets).
//
//   dive_none.mcap, dive_zstd.mcap, dive_lz4.mcap  chunked (small chunks), summary with statistics
//   dive_unchunked.mcap                            messages in the data section, no chunk indexes
//   dive_nosummary.mcap                            chunked, no summary section at all
//   dive_bz2.mcap                                  a chunk that declares compression "bz2"
//   cdr/<type>.cdr                                 one message of each type the message layer reads
"use strict";

const fs = require("fs");
const path = require("path");
const { McapWriter, McapIndexedReader } = require("@mcap/core");
const { MessageWriter } = require("@foxglove/rosmsg2-serialization");
const { stringify } = require("@foxglove/rosmsg");
const { ros2humble } = require("@foxglove/rosmsg-msgs-common");
const zstd = require("@foxglove/wasm-zstd");
const lz4 = require("lz4js");

const out = process.argv[2];
if (!out) throw new Error("usage: node gen_mcap.js OUT_DIR");
fs.mkdirSync(path.join(out, "cdr"), { recursive: true });

// The definitions a type needs, itself first (the form MessageWriter and a ros2msg schema take).
function definitionsOf(type) {
  const seen = new Map();
  const visit = (name) => {
    if (seen.has(name)) return;
    const def = ros2humble[name];
    if (!def) throw new Error(`no definition of ${name}`);
    seen.set(name, def);
    for (const field of def.definitions) if (field.isComplex) visit(field.type);
  };
  visit(type);
  return [...seen.values()];
}
const writers = new Map();
function serialise(type, message) {
  if (!writers.has(type)) writers.set(type, new MessageWriter(definitionsOf(type)));
  return writers.get(type).writeMessage(message);
}
function schemaText(type) {
  return stringify(definitionsOf(type));
}

const T0 = 1700000000000000000n;  // ns
const stamp = (ns) => ({ sec: Number(ns / 1000000000n), nanosec: Number(ns % 1000000000n) });
const header = (ns, frame) => ({ stamp: stamp(ns), frame_id: frame });
const pose = (i) => ({
  position: { x: 0.5 * i, y: -0.25 * i, z: 1.0 + 0.125 * i },
  orientation: { x: 0, y: 0, z: Math.sin(0.05 * i), w: Math.cos(0.05 * i) },
});
const cov = (base) => Array.from({ length: 36 }, (_, k) => base + k);

function image(ns, frame, seed) {
  const width = 4;
  const height = 3;
  const data = new Uint8Array(width * height);
  for (let k = 0; k < data.length; ++k) data[k] = (seed * 31 + k * 7) & 0xff;
  return { header: header(ns, frame), height, width, encoding: "mono8", is_bigendian: 0, step: width, data };
}
function cameraInfo(ns) {
  return {
    header: header(ns, "cam0"), height: 3, width: 4, distortion_model: "plumb_bob",
    d: [-0.28, 0.07, 0.0002, 0.00002, 0],
    k: [458.654, 0, 367.215, 0, 457.296, 248.375, 0, 0, 1],
    r: [1, 0, 0, 0, 1, 0, 0, 0, 1],
    p: [435.2, 0, 367.4, 0, 0, 435.2, 252.2, 0, 0, 0, 1, 0],
    binning_x: 0, binning_y: 0, roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false },
  };
}
function transform(ns, parent, child, i) {
  const p = pose(i);
  return {
    header: header(ns, parent), child_frame_id: child,
    transform: { translation: p.position, rotation: p.orientation },
  };
}

// The dive: every message with its topic, type, log time and content, in log-time order. Header stamps
// are 5 ms before the log times, so that a reader that confuses the two is caught.
const TOPICS = [
  { name: "/cam0/image_raw", type: "sensor_msgs/Image" },
  { name: "/cam1/image_raw", type: "sensor_msgs/Image" },
  { name: "/cam0/image_raw/compressed", type: "sensor_msgs/CompressedImage" },
  { name: "/cam0/camera_info", type: "sensor_msgs/CameraInfo" },
  { name: "/odom", type: "nav_msgs/Odometry" },
  { name: "/pose", type: "geometry_msgs/PoseStamped" },
  { name: "/transform", type: "geometry_msgs/TransformStamped" },
  { name: "/tf", type: "tf2_msgs/TFMessage" },
];
const dive = [];
function add(topic, logNs, message) {
  const t = TOPICS.find((x) => x.name === topic);
  dive.push({ topic, type: t.type, logNs, data: serialise(t.type, message) });
}
for (let i = 0; i < 12; ++i) {
  const ns = T0 + BigInt(i) * 50000000n;  // 20 Hz
  const st = ns - 5000000n;
  if (i % 2 === 0) {
    add("/cam0/image_raw", ns, image(st, "cam0", i));
    add("/cam1/image_raw", ns + 1000n, image(st, "cam1", i + 100));
  }
  add("/odom", ns + 2000n, {
    header: header(st, "odom"), child_frame_id: "base_link",
    pose: { pose: pose(i), covariance: cov(i) },
    twist: { twist: { linear: { x: 0.1, y: 0, z: -0.1 }, angular: { x: 0, y: 0, z: 0.01 * i } }, covariance: cov(100) },
  });
  if (i % 4 === 1) add("/pose", ns + 3000n, { header: header(st, "map"), pose: pose(i) });
  if (i === 3 || i === 9) {
    add("/cam0/image_raw/compressed", ns + 4000n, {
      header: header(st, "cam0"), format: "mono8; png compressed ",
      data: Uint8Array.from([0x89, 0x50, 0x4e, 0x47, i, 1, 2, 3]),
    });
  }
  if (i === 0) add("/cam0/camera_info", ns + 5000n, cameraInfo(st));
  if (i % 5 === 2) add("/transform", ns + 6000n, transform(st, "world", "cam0", i));
  if (i % 6 === 4) {
    add("/tf", ns + 7000n, { transforms: [transform(st, "world", "imu", i), transform(st, "imu", "cam0", i + 1)] });
  }
}

// A writable that remembers the file offset after each message, to tell which chunk holds it.
class FileSink {
  constructor() {
    this.parts = [];
    this.size = 0n;
  }
  async write(buffer) {
    this.parts.push(Buffer.from(buffer));
    this.size += BigInt(buffer.byteLength);
  }
  position() {
    return this.size;
  }
}

async function writeMcap(name, options) {
  const sink = new FileSink();
  const writer = new McapWriter({ writable: sink, chunkSize: 700, ...options });
  await writer.start({ profile: "ros2", library: "cenote tests/io/bag/gen" });
  const channels = new Map();
  for (const t of TOPICS) {
    const ros2type = t.type.replace("/", "/msg/");
    const schemaId = await writer.registerSchema({
      name: ros2type, encoding: "ros2msg", data: new TextEncoder().encode(schemaText(t.type)),
    });
    channels.set(t.name, await writer.registerChannel({ topic: t.name, schemaId, messageEncoding: "cdr", metadata: new Map() }));
  }
  // A channel of another encoding: not a topic for cenote, its messages stepped over.
  const jsonChannel = await writer.registerChannel({
    topic: "/diagnostics", schemaId: 0, messageEncoding: "json", metadata: new Map(),
  });
  const flushes = [];  // per message: how many chunk flushes had happened once it was added
  let last = sink.position();
  let flushCount = 0;
  let seq = 0;
  for (const m of dive) {
    await writer.addMessage({ channelId: channels.get(m.topic), sequence: seq++, logTime: m.logNs, publishTime: m.logNs, data: m.data });
    if (seq % 7 === 0) {
      await writer.addMessage({ channelId: jsonChannel, sequence: seq, logTime: m.logNs, publishTime: m.logNs,
                                data: new TextEncoder().encode('{"level":0}') });
    }
    if (sink.position() !== last) ++flushCount;
    last = sink.position();
    flushes.push(flushCount);
  }
  await writer.end();
  const bytes = Buffer.concat(sink.parts);
  fs.writeFileSync(path.join(out, name), bytes);

  // Chunk offsets from the MCAP team's own indexed reader (files with a summary).
  let chunks = [];
  if (options.useChunks !== false && options.useChunkIndex !== false) {
    const reader = await McapIndexedReader.Initialize({
      readable: {
        size: async () => BigInt(bytes.length),
        read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
      },
      decompressHandlers: { zstd: (data, size) => zstd.decompress(data, Number(size)), lz4: (data, size) => lz4.decompress(data, Number(size)) },
    });
    chunks = reader.chunkIndexes.map((c) => ({ start: c.chunkStartOffset.toString(), length: c.chunkLength.toString(), compression: c.compression }));
    // A message added before the k-th flush lies in chunk k (the flush it triggered or the next one).
    return { size: bytes.length, chunks, chunk_of_message: flushes.map((f, i) => (f > (i === 0 ? 0 : flushes[i - 1]) ? f - 1 : f)) };
  }
  return { size: bytes.length, chunks, chunk_of_message: [] };
}

async function main() {
  await zstd.isLoaded;
  const compressors = {
    zstd: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) }),
    lz4: (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(data)) }),
    bz2: (data) => ({ compression: "bz2", compressedData: data }),
  };
  const files = {};
  files.dive_none = await writeMcap("dive_none.mcap", {});
  files.dive_zstd = await writeMcap("dive_zstd.mcap", { compressChunk: compressors.zstd });
  files.dive_lz4 = await writeMcap("dive_lz4.mcap", { compressChunk: compressors.lz4 });
  files.dive_unchunked = await writeMcap("dive_unchunked.mcap", { useChunks: false });
  files.dive_nosummary = await writeMcap("dive_nosummary.mcap", {
    useStatistics: false, useSummaryOffsets: false, useChunkIndex: false, useMessageIndex: false,
    repeatSchemas: false, repeatChannels: false, useAttachmentIndex: false, useMetadataIndex: false,
  });
  files.dive_bz2 = await writeMcap("dive_bz2.mcap", { compressChunk: compressors.bz2 });

  const topics = TOPICS.map((t) => {
    const ms = dive.filter((m) => m.topic === t.name);
    return { name: t.name, type: t.type, count: ms.length, first_ns: ms[0].logNs.toString(), last_ns: ms[ms.length - 1].logNs.toString() };
  });
  const messages = dive.map((m) => ({ topic: m.topic, log_time_ns: m.logNs.toString(), data: Buffer.from(m.data).toString("hex") }));

  // One message of each type, with the values a decoder must find (CDR bytes in cdr/<name>.cdr).
  const samples = {
    image: ["sensor_msgs/Image", image(T0 + 123456789n, "cam0", 7)],
    compressed_image: ["sensor_msgs/CompressedImage", { header: header(T0 + 5n, "cam1"), format: "jpeg", data: Uint8Array.from([0xff, 0xd8, 0xff, 0xe0, 9]) }],
    camera_info: ["sensor_msgs/CameraInfo", cameraInfo(T0 + 77n)],
    odometry: ["nav_msgs/Odometry", {
      header: header(T0 + 1000n, "odom"), child_frame_id: "cam0", pose: { pose: pose(3), covariance: cov(0.5) },
      twist: { twist: { linear: { x: 1, y: 2, z: 3 }, angular: { x: 4, y: 5, z: 6 } }, covariance: cov(7) },
    }],
    pose_stamped: ["geometry_msgs/PoseStamped", { header: header(T0 + 2000n, "map"), pose: pose(5) }],
    transform_stamped: ["geometry_msgs/TransformStamped", transform(T0 + 3000n, "world", "cam0", 7)],
    tf_message: ["tf2_msgs/TFMessage", { transforms: [transform(T0 + 4000n, "world", "imu", 2), transform(T0 + 4001n, "imu", "cam0", 9)] }],
  };
  const cdr = {};
  for (const [name, [type, message]] of Object.entries(samples)) {
    fs.writeFileSync(path.join(out, "cdr", `${name}.cdr`), serialise(type, message));
    cdr[name] = { type, message };
  }
  const json = JSON.stringify({ topics, messages, files, cdr },
    (key, value) => (typeof value === "bigint" ? value.toString() : value instanceof Uint8Array ? Array.from(value) : value), 1);
  fs.writeFileSync(path.join(out, "expected.json"), json);
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
