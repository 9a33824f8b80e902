// Loads a .glb with three.js's GLTFLoader (Debian's libjs-three, copied beside this script
// as three.module.mjs and GLTFLoader.mjs by the test), plays its first animation with an
// AnimationMixer and prints, as one JSON line, each skinned mesh's name, bone count and
// the box of its skinned vertices (world space) at the times given, and for meshes of at
// most 64 vertices the vertices themselves (x, y, z each).
// Usage: node threejs_check.mjs FILE.glb T1 [T2 ...]
import * as THREE from './three.module.mjs';
import { GLTFLoader } from './GLTFLoader.mjs';
import { readFileSync } from 'fs';

const bytes = readFileSync(process.argv[2]);
const times = process.argv.slice(3).map(Number);
const data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);

// A skinned vertex in world space, as three's skinning shader computes it.
function skinned(mesh, i) {
  const g = mesh.geometry.attributes;
  const bind = new THREE.Vector3().fromBufferAttribute(g.position, i).applyMatrix4(mesh.bindMatrix);
  const out = new THREE.Vector3();
  for (let k = 0; k < 4; ++k) {
    const w = g.skinWeight.array[i * 4 + k];
    if (!w) continue;
    const b = g.skinIndex.array[i * 4 + k];
    const m = new THREE.Matrix4().multiplyMatrices(mesh.skeleton.bones[b].matrixWorld,
                                                   mesh.skeleton.boneInverses[b]);
    out.add(bind.clone().applyMatrix4(m).multiplyScalar(w));
  }
  return out.applyMatrix4(mesh.bindMatrixInverse).applyMatrix4(mesh.matrixWorld);
}

new GLTFLoader().parse(data, '', (gltf) => {
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isSkinnedMesh) meshes.push(o); });
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const clip = gltf.animations[0];
  mixer.clipAction(clip).play();
  const result = { animations: gltf.animations.length, duration: clip.duration, meshes: [] };
  for (const mesh of meshes) {
    const entry = { name: mesh.name, bones: mesh.skeleton.bones.filter((b) => b).length, boxes: [],
                    vertices: [] };
    const count = mesh.geometry.attributes.position.count;
    for (const t of times) {
      mixer.setTime(t);
      gltf.scene.updateMatrixWorld(true);
      const box = new THREE.Box3();
      const points = [];
      for (let i = 0; i < count; ++i) {
        const p = skinned(mesh, i);
        box.expandByPoint(p);
        if (count <= 64) points.push(...p.toArray());
      }
      entry.boxes.push([...box.min.toArray(), ...box.max.toArray()]);
      entry.vertices.push(points);
    }
    result.meshes.push(entry);
  }
  console.log(JSON.stringify(result));
}, (error) => { console.error(String(error)); process.exit(1); });
