// main.js: cenote's browser viewer. Connects to the server that served the page (or ?ws=URL),
// with its token (?token=), over the Foxglove WebSocket protocol, and draws what it receives:
// voxels (/map), the latest fused points (/cloud), the trajectory and camera (/trajectory,
// /camera), frontier clusters (/frontiers), statistics (/stats), the latest left image and
// disparity preview (/camera/image, /camera/disparity). What the page has received is on
// window.cenoteViewer (the browser test reads it there).
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { FoxgloveConnection } from "./protocol.js";
import { VoxelLayer, heightColor } from "./voxels.js";

const params = new URLSearchParams(window.location.search);
const token = params.get("token");
const wsUrl =
  params.get("ws") ??
  `${window.location.protocol === "https:" ? "wss" : "ws"}://${window.location.host}/` +
    (token ? `?token=${encodeURIComponent(token)}` : "");

// --- scene -----------------------------------------------------------------------------------
const container = document.getElementById("view");
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x0b1d2a);
const camera = new THREE.PerspectiveCamera(60, 1, 0.01, 1000);
camera.up.set(0, 0, 1); // the map's world frame: z up
camera.position.set(-3, -3, 3);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, 0);
scene.add(new THREE.AmbientLight(0xffffff, 0.6));
const sun = new THREE.DirectionalLight(0xffffff, 0.9);
sun.position.set(1, 2, 4);
scene.add(sun);
scene.add(new THREE.AxesHelper(0.5));

const voxels = new VoxelLayer(scene);
const points = new THREE.Points(
  new THREE.BufferGeometry(),
  new THREE.PointsMaterial({ size: 0.02, vertexColors: true }),
);
scene.add(points);
const trajectory = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xffcc33 }));
scene.add(trajectory);
const cameraMarker = new THREE.AxesHelper(0.3);
cameraMarker.visible = false;
scene.add(cameraMarker);
const frontiers = new THREE.Group();
frontiers.visible = document.getElementById("show-frontiers").checked;
scene.add(frontiers);
const measureGroup = new THREE.Group();
scene.add(measureGroup);

function resize() {
  const { clientWidth: w, clientHeight: h } = container;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", resize);
resize();

// --- what the page reports ------------------------------------------------------------------
const state = {
  connected: false,
  framesReceived: 0, // message data frames, all channels
  messages: {}, // per topic
  bytesReceived: 0,
  voxels: 0, // occupied voxels held at full detail
  coarseBlocks: 0,
  blocks: 0,
  stats: null, // the latest /stats message
  statuses: [],
  cloudPoints: 0,
  trajectoryPoses: 0,
  frontierClusters: 0,
  images: {}, // per image element: its size once shown
  flownMetres: 0, // how far the fly keys moved the camera
};
window.cenoteViewer = state;

// --- channels ---------------------------------------------------------------------------------
function decodeBase64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// A foxglove.CompressedImage into the <img> of that id.
function showImage(id, message) {
  const img = document.getElementById(id);
  const url = URL.createObjectURL(new Blob([decodeBase64(message.data)], { type: `image/${message.format}` }));
  img.onload = () => {
    URL.revokeObjectURL(url);
    state.images[id] = { width: img.naturalWidth, height: img.naturalHeight };
  };
  img.src = url;
}

function showCloud(message) {
  const bytes = decodeBase64(message.data);
  const view = new DataView(bytes.buffer);
  const stride = message.point_stride;
  const n = Math.floor(bytes.length / stride);
  const offset = Object.fromEntries(message.fields.map((f) => [f.name, f.offset]));
  const positions = new Float32Array(n * 3);
  const colors = new Float32Array(n * 3);
  const color = new THREE.Color();
  for (let i = 0; i < n; i++) {
    const base = i * stride;
    const x = view.getFloat32(base + offset.x, true);
    const y = view.getFloat32(base + offset.y, true);
    const z = view.getFloat32(base + offset.z, true);
    positions.set([x, y, z], i * 3);
    if (voxels.colorBy === "height") heightColor(z, color);
    else color.setRGB(bytes[base + offset.red] / 255, bytes[base + offset.green] / 255, bytes[base + offset.blue] / 255);
    colors.set([color.r, color.g, color.b], i * 3);
  }
  points.geometry.dispose();
  points.geometry = new THREE.BufferGeometry();
  points.geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  points.geometry.setAttribute("color", new THREE.BufferAttribute(colors, 3));
  state.cloudPoints = n;
}

function showTrajectory(message) {
  const positions = message.poses.flatMap((p) => [p.position.x, p.position.y, p.position.z]);
  trajectory.geometry.dispose();
  trajectory.geometry = new THREE.BufferGeometry();
  trajectory.geometry.setAttribute("position", new THREE.Float32BufferAttribute(positions, 3));
  state.trajectoryPoses = message.poses.length;
}

function showCamera(message) {
  const t = message.translation;
  const q = message.rotation;
  cameraMarker.position.set(t.x, t.y, t.z);
  cameraMarker.quaternion.set(q.x, q.y, q.z, q.w);
  cameraMarker.visible = document.getElementById("show-trajectory").checked;
}

function showFrontiers(update) {
  for (const child of [...frontiers.children]) {
    frontiers.remove(child);
    child.geometry?.dispose();
  }
  for (const entity of update.entities ?? []) {
    for (const cube of entity.cubes) {
      const box = new THREE.LineSegments(
        new THREE.EdgesGeometry(new THREE.BoxGeometry(cube.size.x, cube.size.y, cube.size.z)),
        new THREE.LineBasicMaterial({ color: 0x33ee66 }),
      );
      box.position.set(cube.pose.position.x, cube.pose.position.y, cube.pose.position.z);
      frontiers.add(box);
    }
    for (const sphere of entity.spheres) {
      const ball = new THREE.Mesh(
        new THREE.SphereGeometry(sphere.size.x / 2, 12, 8),
        new THREE.MeshBasicMaterial({ color: 0xffcc22 }),
      );
      ball.position.set(sphere.pose.position.x, sphere.pose.position.y, sphere.pose.position.z);
      frontiers.add(ball);
    }
  }
  state.frontierClusters = (update.entities ?? []).length;
}

const statsTable = document.getElementById("stats");
function showStats() {
  const s = state.stats;
  const rows = [
    ["voxels received", state.voxels.toLocaleString()],
    ["blocks (coarse)", `${state.blocks} (${state.coarseBlocks})`],
    ["frames received", state.framesReceived.toLocaleString()],
    ["MB received", (state.bytesReceived / 1e6).toFixed(2)],
  ];
  if (s) {
    rows.push(["map occupied", s.occupied.toLocaleString()]);
    rows.push(["map free", s.free.toLocaleString()]);
    rows.push(["map memory MB", (s.memory_bytes / 1e6).toFixed(1)]);
    rows.push(["batches", s.batches]);
    for (const stage of s.stages) rows.push([`${stage.name} fps`, stage.fps.toFixed(1)]);
  }
  statsTable.innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join("");
}

const connection = new FoxgloveConnection(
  wsUrl,
  ["/map", "/camera", "/trajectory", "/cloud", "/frontiers", "/stats", "/camera/image", "/camera/disparity"],
  {
    onOpen() {
      state.connected = true;
      document.getElementById("connection").textContent = `connected to ${wsUrl.replace(/\?.*/, "")}`;
    },
    onClose(reason) {
      state.connected = false;
      document.getElementById("connection").textContent = `disconnected: ${reason}`;
    },
    onStatus(level, message) {
      state.statuses.push({ level, message });
    },
    onMessage(topic, message) {
      state.framesReceived += 1;
      state.messages[topic] = (state.messages[topic] ?? 0) + 1;
      if (topic === "/map") voxels.apply(message);
      else if (topic === "/cloud") showCloud(message);
      else if (topic === "/trajectory") showTrajectory(message);
      else if (topic === "/camera") showCamera(message);
      else if (topic === "/frontiers") showFrontiers(message);
      else if (topic === "/stats") state.stats = message;
      else if (topic === "/camera/image") showImage("camera-image", message);
      else if (topic === "/camera/disparity") showImage("disparity-image", message);
    },
  },
);

// --- controls ---------------------------------------------------------------------------------
const toggle = (id, apply) => document.getElementById(id).addEventListener("change", (e) => apply(e.target.checked));
toggle("show-voxels", (on) => voxels.setVisible(on));
toggle("show-points", (on) => (points.visible = on));
toggle("show-trajectory", (on) => {
  trajectory.visible = on;
  cameraMarker.visible = on;
});
toggle("show-frontiers", (on) => (frontiers.visible = on));
toggle("show-images", (on) => (document.getElementById("images").hidden = !on));
for (const radio of document.querySelectorAll("input[name=color]")) {
  radio.addEventListener("change", (e) => voxels.setColorBy(e.target.value));
}
// Frames the whole map: from below-left and above, looking at the middle of its cubes.
function fitMap() {
  if (!voxels.mesh) return false;
  voxels.mesh.computeBoundingBox();
  const box = voxels.mesh.boundingBox;
  if (box.isEmpty()) return false;
  const centre = box.getCenter(new THREE.Vector3());
  const size = Math.max(box.getSize(new THREE.Vector3()).length(), 0.5);
  controls.target.copy(centre);
  camera.position.copy(centre).add(new THREE.Vector3(-0.55, -0.75, 0.6).multiplyScalar(size));
  return true;
}
let fitted = false;
document.getElementById("fit").addEventListener("click", fitMap);
document.getElementById("follow").addEventListener("click", () => {
  if (!cameraMarker.visible && state.trajectoryPoses === 0) return;
  controls.target.copy(cameraMarker.position);
  camera.position.copy(cameraMarker.position).add(new THREE.Vector3(-2, -2, 2));
});

// Click: the voxel under the pointer (its state and probability), or with "measure" on, the
// distance between two clicked points.
const raycaster = new THREE.Raycaster();
let measureStart = null;
renderer.domElement.addEventListener("click", (event) => {
  if (!voxels.mesh) return;
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(
    ((event.clientX - rect.left) / rect.width) * 2 - 1,
    -((event.clientY - rect.top) / rect.height) * 2 + 1,
  );
  raycaster.setFromCamera(ndc, camera);
  const hit = raycaster.intersectObject(voxels.mesh)[0];
  const picked = document.getElementById("picked");
  if (!hit) return;
  const info = voxels.instanceToCube[hit.instanceId];
  if (document.getElementById("measure").checked) {
    if (!measureStart) {
      measureStart = hit.point.clone();
      picked.textContent = "measure: click the second point";
      return;
    }
    const d = measureStart.distanceTo(hit.point);
    measureGroup.clear();
    measureGroup.add(
      new THREE.Line(
        new THREE.BufferGeometry().setFromPoints([measureStart, hit.point]),
        new THREE.LineBasicMaterial({ color: 0xff4466 }),
      ),
    );
    picked.textContent = `distance ${d.toFixed(3)} m`;
    state.lastMeasure = d;
    measureStart = null;
    return;
  }
  const c = info.cube;
  picked.textContent =
    info.lod === "coarse"
      ? `block ${info.id.replace("block/", "")} (coarse): ${info.voxels} occupied voxels, detail on its way`
      : `voxel at (${c.x.toFixed(3)}, ${c.y.toFixed(3)}, ${c.z.toFixed(3)}) m\noccupied, p = ${c.p?.toFixed(2) ?? "?"}`;
});

// Fly: W / S forward and back along the view, A / D sideways, Q / E down and up (world z), Shift
// four times faster; the orbit's centre travels with the camera, so orbiting goes on from there.
const FLY_SPEED_M_S = 1.0;
const FLY_KEYS = { KeyW: [1, 0, 0], KeyS: [-1, 0, 0], KeyD: [0, 1, 0], KeyA: [0, -1, 0], KeyE: [0, 0, 1], KeyQ: [0, 0, -1] };
const flying = new Set();
let flyFast = false;
window.addEventListener("keydown", (e) => {
  if (e.target instanceof HTMLInputElement || !(e.code in FLY_KEYS)) return;
  flying.add(e.code);
  flyFast = e.shiftKey;
});
window.addEventListener("keyup", (e) => flying.delete(e.code));
window.addEventListener("blur", () => flying.clear());
function fly(dt_s) {
  if (flying.size === 0) return;
  const forward = camera.getWorldDirection(new THREE.Vector3());
  const side = new THREE.Vector3().crossVectors(forward, camera.up).normalize();
  const step = new THREE.Vector3();
  for (const code of flying) {
    const [f, s, u] = FLY_KEYS[code];
    step.addScaledVector(forward, f).addScaledVector(side, s).addScaledVector(camera.up, u);
  }
  if (step.lengthSq() === 0) return;
  step.normalize().multiplyScalar((flyFast ? 4 : 1) * FLY_SPEED_M_S * dt_s);
  camera.position.add(step);
  controls.target.add(step);
  state.flownMetres += step.length();
}

// --- loop -------------------------------------------------------------------------------------
let lastRebuild = 0;
let lastFrame = null;
function frame(time) {
  requestAnimationFrame(frame);
  fly(lastFrame === null ? 0 : Math.min((time - lastFrame) / 1000, 0.1));
  lastFrame = time;
  if (time - lastRebuild > 250) {
    lastRebuild = time;
    voxels.rebuild();
    if (!fitted) fitted = fitMap();
    const counts = voxels.counts();
    state.voxels = counts.voxels;
    state.coarseBlocks = counts.coarse;
    state.blocks = counts.blocks;
    state.bytesReceived = connection.bytesReceived;
    showStats();
  }
  controls.update();
  renderer.render(scene, camera);
}
requestAnimationFrame(frame);
