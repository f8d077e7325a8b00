// protocol_client.mjs URL: an independent Foxglove WebSocket client (npm @foxglove/ws-protocol
// over npm ws) of cenote-server's viewer, for tests/viewer/viewer_e2e_test.py.
// Subscribes to every advertised channel, mirrors /map (entities by id, deletions applied), counts
// messages per topic, keeps the latest camera images, and checks the server's answers to bad
// client messages. Reads one line
// "occupied N" from stdin (the server's occupied voxel count, once ingest is done), then waits
// until its mirror holds N voxels at full detail and no coarse block, and prints a JSON report.
// Exits 1 (with the report) when that does not happen within TIMEOUT_S (default 120).
// AUTH_HEADER: sent as the Authorization header (and a connection without it is tried first).
import wsProtocol from "@foxglove/ws-protocol";
import WebSocket from "ws";
import { createInterface } from "node:readline";

const { FoxgloveClient } = wsProtocol;
const url = process.argv[2];
const timeoutS = Number(process.env.TIMEOUT_S ?? 120);

const report = {
  serverInfo: null,
  channels: [],
  messages: {},
  bytes: 0,
  statuses: [],
  fullVoxels: 0,
  coarseBlocks: 0,
  sawCoarse: false,
  maxEntityVoxels: 0,
  latestStats: null,
  cloudPoints: 0,
  trajectoryPoses: 0,
  frontierEntities: 0,
  cameraTransforms: 0,
  images: {}, // per image topic: the latest {format, data (base64)}
  malformedMessages: 0,
};
const blocks = new Map();
const topicOf = new Map();
let expectedOccupied = null;

// A connection without the token (when the test gives one in AUTH_HEADER) is refused with HTTP 401.
if (process.env.AUTH_HEADER) {
  const refused = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  refused.on("unexpected-response", (request, response) => {
    report.refusedStatus = response.statusCode;
    refused.terminate();
  });
  refused.on("error", () => {});
}
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL], {
  headers: process.env.AUTH_HEADER ? { Authorization: process.env.AUTH_HEADER } : {},
});
const client = new FoxgloveClient({ ws });
client.on("serverInfo", (info) => {
  report.serverInfo = info;
  // Bad messages first: each must come back as an error status, the connection open.
  ws.send("{not json");
  ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 99, channelId: 4242 }] }));
  ws.send(Buffer.from([0x01, 0, 0, 0, 0]));
});
client.on("status", (status) => report.statuses.push(status));
client.on("error", (error) => report.statuses.push({ level: -1, message: String(error) }));
client.on("advertise", (channels) => {
  for (const channel of channels) {
    report.channels.push(channel);
    topicOf.set(client.subscribe(channel.id), channel.topic);
  }
});
client.on("message", ({ subscriptionId, data }) => {
  const topic = topicOf.get(subscriptionId);
  report.messages[topic] = (report.messages[topic] ?? 0) + 1;
  report.bytes += data.byteLength + 13;
  let message;
  try {
    message = JSON.parse(new TextDecoder().decode(data));
  } catch {
    report.malformedMessages += 1;
    return;
  }
  if (topic === "/map") {
    for (const d of message.deletions) blocks.delete(d.id);
    for (const e of message.entities) {
      const meta = Object.fromEntries(e.metadata.map((kv) => [kv.key, kv.value]));
      if (meta.lod === "coarse") report.sawCoarse = true;
      const probabilities = meta.probabilities ? meta.probabilities.split(",").map(Number) : [];
      if (meta.lod === "full" && probabilities.length !== e.cubes.length) report.malformedMessages += 1;
      if (probabilities.some((p) => !(p > 0.5 && p <= 1.0))) report.malformedMessages += 1;
      blocks.set(e.id, { lod: meta.lod, cubes: e.cubes.length, voxels: Number(meta.voxels) });
    }
  } else if (topic === "/stats") {
    report.latestStats = message;
  } else if (topic === "/cloud") {
    report.cloudPoints = Buffer.from(message.data, "base64").length / message.point_stride;
  } else if (topic === "/trajectory") {
    report.trajectoryPoses = message.poses.length;
  } else if (topic === "/frontiers") {
    report.frontierEntities = message.entities.length;
  } else if (topic === "/camera") {
    report.cameraTransforms += 1;
  } else if (topic === "/camera/image" || topic === "/camera/disparity") {
    if (message.frame_id !== "camera") report.malformedMessages += 1;
    report.images[topic] = { format: message.format, data: message.data };
  }
});

function tally() {
  let full = 0;
  let coarse = 0;
  for (const b of blocks.values()) {
    if (b.lod === "coarse") coarse += 1;
    else full += b.cubes;
    report.maxEntityVoxels = Math.max(report.maxEntityVoxels, b.cubes);
  }
  report.fullVoxels = full;
  report.coarseBlocks = coarse;
  report.blocks = blocks.size;
}

function finish(code) {
  tally();
  // Exit once the report is written: a pipe takes a large one (it holds the images) in parts.
  process.stdout.write(JSON.stringify(report) + "\n", () => process.exit(code));
}

createInterface({ input: process.stdin }).on("line", (line) => {
  const match = /^occupied (\d+)$/.exec(line.trim());
  if (match) expectedOccupied = Number(match[1]);
});
const poll = setInterval(() => {
  tally();
  if (expectedOccupied !== null && report.fullVoxels === expectedOccupied && report.coarseBlocks === 0 &&
      report.latestStats && report.latestStats.occupied === expectedOccupied) {
    clearInterval(poll);
    // One more second: the last stats, cloud and trajectory messages arrive.
    setTimeout(() => finish(0), 1500);
  }
}, 100);
setTimeout(() => finish(1), timeoutS * 1000);
