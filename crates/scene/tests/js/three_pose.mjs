// The independent reference of crates/scene/tests/suite/pose_three.rs: three.js poses a glTF file
// with its own loader (GLTFLoader) and animation system (AnimationMixer: slerp, STEP and
// CUBICSPLINE interpolants, morph targets, skinning) and writes the posed triangles.
//
// node three_pose.mjs THREE_DIR FILE OUT CLIP:SECONDS...
//   THREE_DIR: a folder with node_modules/three (npm install three@0.170.0 --prefix THREE_DIR).
//   OUT: for each CLIP:SECONDS pair in order, every triangle's three corners as 9 little-endian
//   f32, in the file's triangle order (nodes depth-first in document order, each node's mesh
//   primitives in order, triangles in index order), world space.
import fs from 'fs';
import path from 'path';
import { pathToFileURL } from 'url';

const [threeDir, file, out, ...pairs] = process.argv.slice(2);
const lib = (p) => pathToFileURL(path.join(threeDir, 'node_modules', 'three', p)).href;
const THREE = await import(lib('build/three.module.js'));
const { GLTFLoader } = await import(lib('examples/jsm/loaders/GLTFLoader.js'));

// Textures cannot load without a browser; the geometry does not need them.
console.warn = () => {};
const data = fs.readFileSync(file);
const gltf = await new Promise((resolve, reject) =>
  new GLTFLoader().parse(data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength), '', resolve, reject));

const scene = gltf.scene;
const chunks = [];
for (const pair of pairs) {
  const [clip, seconds] = pair.split(':').map(Number);
  const mixer = new THREE.AnimationMixer(scene);
  const action = mixer.clipAction(gltf.animations[clip]);
  // Played once and held at its ends: times outside the clip clamp, as gridrt's do.
  action.setLoop(THREE.LoopOnce);
  action.clampWhenFinished = true;
  action.play();
  mixer.setTime(seconds);
  // Rotations are unit quaternions (glTF); three.js leaves a key's value as stored, which for
  // normalized-integer rotations is off unit by the quantization, and builds a scaled matrix from
  // it. Normalized here, as gridrt normalizes every rotation it interpolates.
  scene.traverse((o) => o.quaternion.normalize());
  scene.updateMatrixWorld(true);
  const tris = [];
  const v = new THREE.Vector3();
  // One primitive's triangles, its vertices through `instance` (a node's EXT_mesh_gpu_instancing
  // transform) and the mesh's world matrix.
  const emit = (o, instance) => {
    const pos = o.geometry.attributes.position;
    const world = new Float32Array(pos.count * 3);
    for (let i = 0; i < pos.count; i++) {
      // Morph targets, then skinning (in the mesh's space), then the mesh's world matrix:
      // for a skinned mesh three.js keeps the skinned result in the mesh's space and the
      // product is the glTF rule's Σ w·joint·inverse bind (the mesh node's transform cancels).
      o.getVertexPosition(i, v).applyMatrix4(instance).applyMatrix4(o.matrixWorld);
      world.set([v.x, v.y, v.z], 3 * i);
    }
    const index = o.geometry.index ? o.geometry.index.array : null;
    const n = index ? index.length : pos.count;
    for (let k = 0; k + 2 < n; k += 3) {
      for (let j = 0; j < 3; j++) {
        const i = index ? index[k + j] : k + j;
        tris.push(world[3 * i], world[3 * i + 1], world[3 * i + 2]);
      }
    }
  };
  // An instanced node's primitives in gridrt's order: instance after instance, each instance
  // all of the node's primitives (three.js keeps one InstancedMesh per primitive).
  const emitInstanced = (prims) => {
    const m = new THREE.Matrix4();
    for (let q = 0; q < prims[0].count; q++) {
      for (const o of prims) {
        o.getMatrixAt(q, m);
        emit(o, m);
      }
    }
  };
  const identity = new THREE.Matrix4();
  const visit = (o) => {
    let kids = o.children;
    if (o.isInstancedMesh) {
      emitInstanced([o]);
    } else if (o.isMesh) {
      emit(o, identity);
    } else if (o.isGroup) {
      // A node of several instanced primitives: a group whose first children they are.
      let k = 0;
      while (k < kids.length && kids[k].isInstancedMesh) k++;
      if (k > 0) emitInstanced(kids.slice(0, k));
      kids = kids.slice(k);
    }
    kids.forEach(visit);
  };
  visit(scene);
  mixer.stopAllAction();
  mixer.uncacheRoot(scene);
  chunks.push(Buffer.from(new Float32Array(tris).buffer));
}
fs.writeFileSync(out, Buffer.concat(chunks));
