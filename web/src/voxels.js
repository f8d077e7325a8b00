// voxels.js: the map as the page holds it: one record per scene entity of /map (a block: its cubes,
// their colours and occupancy probabilities, full or coarse), drawn as one instanced mesh of unit
// cubes rebuilt when something changed.
import * as THREE from "three";

// The server's height colours (server/viewer/scene_messages.cpp heightColor): a hue cycle every 4 m.
export function heightColor(z, out) {
  const phase = (2 * Math.PI * z) / 4;
  out.setRGB(
    0.5 + 0.5 * Math.cos(phase),
    0.5 + 0.5 * Math.cos(phase + (2 * Math.PI) / 3),
    0.5 + 0.5 * Math.cos(phase + (4 * Math.PI) / 3),
  );
  return out;
}

export class VoxelLayer {
  constructor(scene) {
    this.scene = scene;
    this.blocks = new Map(); // entity id -> {lod, voxels, cubes: [{x,y,z,size,r,g,b,p}]}
    this.mesh = null;
    this.dirty = false;
    this.colorBy = "image";
    this.visible = true;
    this.instanceToCube = [];
  }

  // One foxglove.SceneUpdate of /map.
  apply(update) {
    for (const deletion of update.deletions ?? []) {
      if (deletion.type === 1) this.blocks.clear();
      else this.blocks.delete(deletion.id);
    }
    for (const entity of update.entities ?? []) {
      const meta = Object.fromEntries((entity.metadata ?? []).map((kv) => [kv.key, kv.value]));
      const probabilities = meta.probabilities ? meta.probabilities.split(",").map(Number) : [];
      const cubes = entity.cubes.map((c, i) => ({
        x: c.pose.position.x,
        y: c.pose.position.y,
        z: c.pose.position.z,
        size: c.size.x,
        r: c.color.r,
        g: c.color.g,
        b: c.color.b,
        p: probabilities[i],
      }));
      this.blocks.set(entity.id, { lod: meta.lod ?? "full", voxels: Number(meta.voxels ?? cubes.length), cubes });
    }
    this.dirty = true;
  }

  // Occupied voxels the page has at full detail, and blocks still coarse.
  counts() {
    let voxels = 0;
    let coarse = 0;
    let cubes = 0;
    for (const block of this.blocks.values()) {
      cubes += block.cubes.length;
      if (block.lod === "coarse") coarse += 1;
      else voxels += block.cubes.length;
    }
    return { voxels, coarse, cubes, blocks: this.blocks.size };
  }

  rebuild() {
    if (!this.dirty) return;
    this.dirty = false;
    if (this.mesh) {
      this.scene.remove(this.mesh);
      this.mesh.geometry.dispose();
      this.mesh.material.dispose();
      this.mesh = null;
    }
    const { cubes } = this.counts();
    this.instanceToCube = [];
    if (cubes === 0) return;
    const mesh = new THREE.InstancedMesh(
      new THREE.BoxGeometry(1, 1, 1),
      new THREE.MeshLambertMaterial({ color: 0xffffff }),
      cubes,
    );
    const matrix = new THREE.Matrix4();
    const color = new THREE.Color();
    let i = 0;
    for (const [id, block] of this.blocks) {
      for (const c of block.cubes) {
        matrix.makeScale(c.size * 0.98, c.size * 0.98, c.size * 0.98);
        matrix.setPosition(c.x, c.y, c.z);
        mesh.setMatrixAt(i, matrix);
        if (this.colorBy === "height") heightColor(c.z, color);
        else color.setRGB(c.r, c.g, c.b);
        mesh.setColorAt(i, color);
        this.instanceToCube.push({ id, lod: block.lod, voxels: block.voxels, cube: c });
        i += 1;
      }
    }
    mesh.instanceMatrix.needsUpdate = true;
    mesh.instanceColor.needsUpdate = true;
    mesh.visible = this.visible;
    this.mesh = mesh;
    this.scene.add(mesh);
  }

  setColorBy(mode) {
    this.colorBy = mode;
    this.dirty = true;
  }

  setVisible(visible) {
    this.visible = visible;
    if (this.mesh) this.mesh.visible = visible;
  }
}
