//! Posing against an independent implementation: three.js (r170), whose GLTFLoader and
//! AnimationMixer Node runs through `tests/js/three_pose.mjs`. The same files are posed by both at
//! times before, at, inside and after every clip, and every triangle corner must agree within
//! 10⁻⁵ of the scene's diagonal (they agree to ~10⁻⁷: f32 data, f64 arithmetic on both sides).
//!
//! The files: generated ones that combine what the analytic tests of `pose.rs` check one at a
//! time (a rigid hierarchy under a `matrix` node with sign-flipped rotation keys, STEP and
//! CUBICSPLINE channels and a clip that starts late; skins with u8, u16 and float weights under
//! transformed parents, non-uniform joint scale and an animated armature; morph targets with mesh
//! and node default weights, a sparse target and LINEAR, STEP and CUBICSPLINE weights; quantized
//! positions and morph deltas on a skin without inverse bind matrices whose joint is the mesh
//! node's parent; instanced nodes under animated parents), random scenes ([`random_doc`]: what
//! no hand-made file thought of) and every shared animated scene.
//!
//! three.js is found by [`gridrt_testkit::three_js_dir`] (`npm install three@0.170.0 --prefix
//! ~/.cache/gridrt/three-0.170.0`, with `node` on the PATH); `.ci/run` installs it and sets
//! `GRIDRT_REQUIRE_THREE=1`, which makes its absence a failure.

use std::path::Path;
use std::process::Command;

use glam::{DMat4, DQuat, DVec3, Vec3};
use gridrt_scene::gltf_load::{Loaded, load_rigged_slice_with};
use gridrt_scene::{ClipTime, LoadLimits, PoseScratch};
use serde_json::json;

use super::builder::{Doc, temp_dir};

fn f32s(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

fn quat(axis: DVec3, angle: f64) -> [f64; 4] {
    DQuat::from_axis_angle(axis.normalize(), angle).to_array()
}

/// A sampler over `keys` (times, then values: per key one value of `path`'s type, or with
/// CUBICSPLINE its in-tangent, value and out-tangent) driving `path` of `node`.
fn channel(d: &mut Doc, anim: &mut serde_json::Value, node: usize, path: &str, keys: (&[f64], &[f64]), interp: &str) {
    let (times, values) = keys;
    let n = values.len() / times.len() / if interp == "CUBICSPLINE" { 3 } else { 1 };
    let ty = match path {
        "rotation" => "VEC4",
        "weights" => "SCALAR",
        _ => "VEC3",
    };
    let input = d.floats(&f32s(times), "SCALAR", 1);
    d.json["accessors"][input]["min"] = json!([times[0]]);
    d.json["accessors"][input]["max"] = json!([times[times.len() - 1]]);
    let output = d.floats(&f32s(values), ty, if ty == "SCALAR" { 1 } else { n });
    let samplers = anim["samplers"].as_array_mut().unwrap();
    samplers.push(json!({"input": input, "output": output, "interpolation": interp}));
    let k = samplers.len() - 1;
    anim["channels"].as_array_mut().unwrap().push(json!({"sampler": k, "target": {"node": node, "path": path}}));
}

fn new_clip(name: &str) -> serde_json::Value {
    json!({"name": name, "samplers": [], "channels": []})
}

/// An nx × ny sheet of triangles over [0, w] × [0, h], gently curved in z.
fn sheet(nx: u32, ny: u32, w: f32, h: f32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = (0..=ny)
        .flat_map(|y| (0..=nx).map(move |x| (x, y)))
        .map(|(x, y)| [x as f32 * w / nx as f32, y as f32 * h / ny as f32, 0.1 * ((x + y) as f32).sin()])
        .collect();
    let mut i = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            let a = y * (nx + 1) + x;
            let c = a + nx + 1;
            i.extend([a, a + 1, c + 1, a, c + 1, c]);
        }
    }
    (p, i)
}

/// Deterministic values in [-1, 1), one per `k` (the scene crate's SplitMix64).
fn noise(k: u32) -> f64 {
    gridrt_scene::rng::Rng::new(k as u64).range(-1.0, 1.0) as f64
}

fn tangents(k: u32, n: usize, scale: f64) -> Vec<f64> {
    (0..n as u32).map(|i| noise(k * 31 + i) * scale).collect()
}

/// CUBICSPLINE output: per key its in-tangent, value and out-tangent.
fn spline(values: &[Vec<f64>], seed: u32, scale: f64) -> Vec<f64> {
    let n = values[0].len();
    let mut out = Vec::new();
    for (k, v) in values.iter().enumerate() {
        out.extend(tangents(seed + 2 * k as u32, n, scale));
        out.extend(v);
        out.extend(tangents(seed + 2 * k as u32 + 1, n, scale));
    }
    out
}

/// Rigid nodes: a static `matrix` parent, an animated child (LINEAR rotations whose second key
/// is sign-flipped, STEP translation), a mesh of an indexed and a non-indexed primitive with a
/// CUBICSPLINE scale; a second clip starting at 0.5 s drives another node by a CUBICSPLINE
/// rotation.
fn rigid_doc() -> Doc {
    let mut d = Doc::new();
    let (p, i) = sheet(4, 3, 1.0, 1.0);
    let pa = d.positions(&p);
    let ia = d.indices_u32(&i);
    let loose: Vec<[f32; 3]> =
        i.iter().map(|&k| [p[k as usize][0], p[k as usize][1], p[k as usize][2] + 0.5]).collect();
    let pb = d.positions(&loose);
    let m = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": pa}, "indices": ia}, {"attributes": {"POSITION": pb}}]}),
    );
    let mesh_node = d.node(json!({"mesh": m, "translation": [0.2, 0.0, 0.0], "scale": [1.0, 2.0, 1.0]}));
    let child = d.node(json!({"children": [mesh_node], "rotation": quat(DVec3::Y, 0.3)}));
    let root = d.node(json!({"children": [child], "matrix": [2, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 1, 2, 3, 1]}));
    let other = d.node(json!({"mesh": m}));
    d.root(root);
    d.root(other);
    let mut a = new_clip("rigid");
    let mut flipped = quat(DVec3::Z, 1.0);
    flipped.iter_mut().for_each(|x| *x = -*x);
    let rot: Vec<f64> =
        [quat(DVec3::Z, 0.0), flipped, quat(DVec3::Z, 2.2), quat(DVec3::new(1.0, 1.0, 0.0), -0.7)].concat();
    channel(&mut d, &mut a, child, "rotation", (&[0.0, 0.6, 1.3, 2.0], &rot), "LINEAR");
    let steps = [0., 0., 0., 1., 0., 0., 1., 1., 0.];
    channel(&mut d, &mut a, child, "translation", (&[0.1, 0.9, 1.5], &steps), "STEP");
    let scale = spline(&[vec![1., 1., 1.], vec![2., 1., 0.5], vec![0.5, 0.5, 3.]], 1, 1.0);
    channel(&mut d, &mut a, mesh_node, "scale", (&[0.0, 1.0, 2.0], &scale), "CUBICSPLINE");
    let mut late = new_clip("late");
    let axis = DVec3::new(1.0, 2.0, 3.0);
    let rot = spline(&[quat(axis, 0.2).to_vec(), quat(axis, 1.4).to_vec(), quat(axis, -0.8).to_vec()], 7, 0.5);
    channel(&mut d, &mut late, other, "rotation", (&[0.5, 1.2, 2.0], &rot), "CUBICSPLINE");
    channel(&mut d, &mut late, other, "translation", (&[0.7, 1.0], &[0., 0., 0., 0., 3., 0.]), "LINEAR");
    d.json["animations"] = json!([a, late]);
    d
}

/// JOINTS_0 of `joints` (four per vertex) as `component_type` 5121 (u8) or 5123 (u16).
fn joints_accessor(d: &mut Doc, joints: &[u16], component_type: u32) -> usize {
    let bytes: Vec<u8> = match component_type {
        5121 => joints.iter().map(|&j| j as u8).collect(),
        _ => joints.iter().flat_map(|j| j.to_le_bytes()).collect(),
    };
    d.accessor(&bytes, component_type, joints.len() / 4, "VEC4")
}

/// WEIGHTS_0 of `weights` (each vertex's summing to 1) as `component_type` 5126 (float) or
/// 5121/5123 (normalized u8/u16, quantized so that each vertex's sum is exactly the maximum).
fn weights_accessor(d: &mut Doc, weights: &[[f64; 4]], component_type: u32) -> usize {
    if component_type == 5126 {
        return d.floats(&f32s(&weights.concat()), "VEC4", 4);
    }
    let max = if component_type == 5121 { 255.0 } else { 65535.0 };
    let mut bytes = Vec::new();
    for w in weights {
        let mut q = w.map(|x| (x * max).round());
        q[0] += max - q.iter().sum::<f64>();
        for x in q {
            if component_type == 5121 {
                bytes.push(x as u8);
            } else {
                bytes.extend((x as u16).to_le_bytes());
            }
        }
    }
    let k = d.accessor(&bytes, component_type, weights.len(), "VEC4");
    d.json["accessors"][k]["normalized"] = json!(true);
    k
}

/// A sheet skinned to a chain of three joints and a fourth beside them (weights of every vertex
/// on all four), stored as `weights` (5121/5123 normalized or 5126 float) and u8 or u16 joints;
/// the mesh node and its parent are transformed (ignored, per the glTF rule) and move; the
/// armature is scaled, rotated and animated; a joint's scale is non-uniform.
fn skin_doc(joint_type: u32, weight_type: u32) -> Doc {
    let mut d = Doc::new();
    let (p, i) = sheet(6, 10, 1.0, 3.0);
    let pa = d.positions(&p);
    let ia = d.indices_u32(&i);
    let mut joints = Vec::new();
    let mut weights = Vec::new();
    for v in &p {
        let y = v[1] as f64;
        let w = [(1.0 - y.abs()).max(0.0), (1.0 - (y - 1.5).abs()).max(0.0), (1.0 - (y - 3.0).abs()).max(0.0), 0.15];
        let sum: f64 = w.iter().sum();
        weights.push(w.map(|x| x / sum));
        joints.push([0u16, 1, 2, 3]);
    }
    let ja = joints_accessor(&mut d, &joints.concat(), joint_type);
    let wa = weights_accessor(&mut d, &weights, weight_type);
    let m = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": pa, "JOINTS_0": ja, "WEIGHTS_0": wa}, "indices": ia}]}),
    );
    let j2 = d.node(json!({"translation": [0.0, 1.5, 0.0]}));
    let j1 = d.node(json!({"translation": [0.0, 1.5, 0.0], "rotation": quat(DVec3::Z, 0.1), "children": [j2]}));
    let j0 = d.node(json!({"translation": [0.5, 0.0, 0.0], "children": [j1]}));
    let j3 = d.node(json!({"translation": [0.0, 0.0, 1.0]}));
    let arm_rot = quat(DVec3::X, -std::f64::consts::FRAC_PI_2);
    let arm = d.node(json!({"translation": [1, 2, 3], "rotation": arm_rot, "scale": [2, 2, 2], "children": [j0, j3]}));
    // The inverse bind matrices: the inverses of the joints' world matrices at rest.
    let trs = |t: DVec3, r: [f64; 4], s: f64| {
        DMat4::from_scale_rotation_translation(DVec3::splat(s), DQuat::from_array(r), t)
    };
    let a = trs(DVec3::new(1.0, 2.0, 3.0), arm_rot, 2.0);
    let w0 = a * trs(DVec3::new(0.5, 0.0, 0.0), DQuat::IDENTITY.to_array(), 1.0);
    let w1 = w0 * trs(DVec3::new(0.0, 1.5, 0.0), quat(DVec3::Z, 0.1), 1.0);
    let w2 = w1 * trs(DVec3::new(0.0, 1.5, 0.0), DQuat::IDENTITY.to_array(), 1.0);
    let w3 = a * trs(DVec3::Z, DQuat::IDENTITY.to_array(), 1.0);
    let ibm: Vec<f64> = [w0, w1, w2, w3].iter().flat_map(|w| w.inverse().to_cols_array()).collect();
    let ibm = d.floats(&f32s(&ibm), "MAT4", 16);
    d.json["skins"] = json!([{"joints": [j0, j1, j2, j3], "inverseBindMatrices": ibm, "skeleton": arm}]);
    let mesh_node = d.node(json!({"mesh": m, "skin": 0, "translation": [5, 5, 5], "rotation": quat(DVec3::Y, 0.7)}));
    let parent = d.node(json!({"children": [mesh_node], "translation": [-3, 0, 0], "scale": [3, 3, 3]}));
    d.root(arm);
    d.root(parent);
    let mut c = new_clip("bend");
    let rot = [quat(DVec3::Z, 0.1), quat(DVec3::Z, 1.2), quat(DVec3::new(1.0, 0.0, 1.0), -0.9)].concat();
    channel(&mut d, &mut c, j1, "rotation", (&[0.0, 1.0, 2.0], &rot), "LINEAR");
    let scale = [1., 1., 1., 2., 0.5, 1., 0.3, 1., 3.];
    channel(&mut d, &mut c, j2, "scale", (&[0.0, 1.0, 2.0], &scale), "LINEAR");
    let tr = spline(&[vec![0.5, 0., 0.], vec![0.5, 1., 0.], vec![0., 0., 2.]], 11, 1.0);
    channel(&mut d, &mut c, j0, "translation", (&[0.0, 0.8, 2.0], &tr), "CUBICSPLINE");
    let rot = [arm_rot, quat(DVec3::Y, 1.0)].concat();
    channel(&mut d, &mut c, arm, "rotation", (&[0.0, 2.0], &rot), "LINEAR");
    channel(&mut d, &mut c, parent, "translation", (&[0.0, 2.0], &[-3., 0., 0., 10., 10., 10.]), "LINEAR");
    d.json["animations"] = json!([c]);
    d
}

/// One mesh of three morph targets (one sparse) with default weights, on three nodes: the mesh's
/// weights, a node's own weights, and weights animated by CUBICSPLINE, STEP and LINEAR.
fn morph_doc() -> Doc {
    let mut d = Doc::new();
    let (p, i) = sheet(5, 5, 1.0, 1.0);
    let pa = d.positions(&p);
    let ia = d.indices_u32(&i);
    let wave: Vec<f32> = p.iter().flat_map(|v| [0.0, 0.0, (v[0] * 3.0).sin() * 0.5]).collect();
    let t1 = d.floats(&wave, "VEC3", 3);
    // Sparse: zeros but for five vertices.
    let idx: Vec<u8> = [0u16, 7, 14, 20, 35].iter().flat_map(|k| k.to_le_bytes()).collect();
    let vals: Vec<u8> = (0..15).flat_map(|k| (noise(100 + k) as f32).to_le_bytes()).collect();
    let (iv, vv) = (d.view(&idx), d.view(&vals));
    let t2 = d.push(
        "accessors",
        json!({"componentType": 5126, "count": p.len(), "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1],
               "sparse": {"count": 5, "indices": {"bufferView": iv, "componentType": 5123}, "values": {"bufferView": vv}}}),
    );
    let jitter: Vec<f32> = (0..p.len() as u32 * 3).map(|k| noise(200 + k) as f32 * 0.2).collect();
    let t3 = d.floats(&jitter, "VEC3", 3);
    let targets = json!([{"POSITION": t1}, {"POSITION": t2}, {"POSITION": t3}]);
    let m = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": pa}, "indices": ia, "targets": targets}], "weights": [0.3, 0.1, 0.0]}),
    );
    let n1 = d.node(json!({"mesh": m}));
    let n2 = d.node(json!({"mesh": m, "weights": [0.5, 0.25, 1.0], "translation": [2, 0, 0]}));
    let n3 = d.node(json!({"mesh": m, "translation": [0, 2, 0]}));
    [n1, n2, n3].into_iter().for_each(|n| d.root(n));
    let mut c = new_clip("weights");
    let w = spline(&[vec![0., 0., 0.], vec![1., 0.5, -0.5], vec![0.2, 1.5, 0.3]], 21, 1.0);
    channel(&mut d, &mut c, n1, "weights", (&[0.0, 1.0, 2.0], &w), "CUBICSPLINE");
    let steps = [1., 0., 0., 0., 1., 0., 0., 0., 1.];
    channel(&mut d, &mut c, n2, "weights", (&[0.25, 1.0, 1.75], &steps), "STEP");
    channel(&mut d, &mut c, n3, "weights", (&[0.0, 2.0], &[0., 0., 0., 1., 1., 1.]), "LINEAR");
    d.json["animations"] = json!([c]);
    d
}

/// KHR_mesh_quantization: normalized i16 positions and i8 morph deltas, on a skin without
/// inverse bind matrices whose first joint is the mesh node's parent.
fn quantized_doc() -> Doc {
    let mut d = Doc::new();
    d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let (p, i) = sheet(4, 4, 1.0, 1.0);
    let q: Vec<[i16; 3]> = p.iter().map(|v| v.map(|x| (x / 2.0 * 32767.0).round() as i16)).collect();
    // Each VEC3 of i16 padded to 8 bytes (vertex attributes are 4-byte aligned).
    let bytes: Vec<u8> = q.iter().flat_map(|v| [v[0], v[1], v[2], 0]).flat_map(|x| x.to_le_bytes()).collect();
    let pa = d.accessor(&bytes, 5122, p.len(), "VEC3");
    let pv = d.json["accessors"][pa]["bufferView"].as_u64().unwrap() as usize;
    d.json["bufferViews"][pv]["byteStride"] = json!(8);
    let lo = (0..3).map(|c| q.iter().map(|v| v[c]).min().unwrap()).collect::<Vec<_>>();
    let hi = (0..3).map(|c| q.iter().map(|v| v[c]).max().unwrap()).collect::<Vec<_>>();
    d.json["accessors"][pa]["normalized"] = json!(true);
    d.json["accessors"][pa]["min"] = json!(lo);
    d.json["accessors"][pa]["max"] = json!(hi);
    // i8 deltas, each VEC3 padded to 4 bytes (the byte stride must be a multiple of 4).
    let deltas: Vec<[i8; 3]> =
        (0..p.len() as u32).map(|k| [0, 1, 2].map(|c| (noise(300 + 3 * k + c) * 40.0) as i8)).collect();
    let bytes: Vec<u8> = deltas.iter().flat_map(|v| [v[0] as u8, v[1] as u8, v[2] as u8, 0]).collect();
    let tv = d.view(&bytes);
    d.json["bufferViews"][tv]["byteStride"] = json!(4);
    let lo = (0..3).map(|c| deltas.iter().map(|v| v[c]).min().unwrap()).collect::<Vec<_>>();
    let hi = (0..3).map(|c| deltas.iter().map(|v| v[c]).max().unwrap()).collect::<Vec<_>>();
    let ta = d.push(
        "accessors",
        json!({"bufferView": tv, "componentType": 5120, "normalized": true, "count": p.len(), "type": "VEC3", "min": lo, "max": hi}),
    );
    let ia = d.indices_u32(&i);
    let joints: Vec<u8> = p.iter().flat_map(|_| [0, 1, 0, 0]).collect();
    let ja = d.accessor(&joints, 5121, p.len(), "VEC4");
    let weights: Vec<f32> = p.iter().flat_map(|v| [v[0], 1.0 - v[0], 0.0, 0.0]).collect();
    let wa = d.floats(&weights, "VEC4", 4);
    let m = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": pa, "JOINTS_0": ja, "WEIGHTS_0": wa}, "indices": ia,
                               "targets": [{"POSITION": ta}]}], "weights": [0.5]}),
    );
    let mesh_node = d.node(json!({"mesh": m, "skin": 0, "scale": [2, 2, 2]}));
    let j1 = d.node(json!({"translation": [0, 0, 1]}));
    let j0 = d.node(json!({"translation": [1, 0, 0], "children": [mesh_node, j1]}));
    d.json["skins"] = json!([{"joints": [j0, j1]}]);
    d.root(j0);
    let mut c = new_clip("quantized");
    let rot = [quat(DVec3::Y, 0.0), quat(DVec3::Y, 2.0)].concat();
    channel(&mut d, &mut c, j0, "rotation", (&[0.0, 1.0], &rot), "LINEAR");
    channel(&mut d, &mut c, j1, "translation", (&[0.0, 1.0], &[0., 0., 1., 0., 2., 1.]), "LINEAR");
    channel(&mut d, &mut c, mesh_node, "weights", (&[0.0, 1.0], &[0., 1.]), "LINEAR");
    d.json["animations"] = json!([c]);
    d
}

/// EXT_mesh_gpu_instancing under animation: a node of two primitives drawn three times
/// (translation, rotation, scale per instance) under a moving, scaled parent, and a
/// one-primitive instanced node with a child.
fn instanced_doc() -> Doc {
    let mut d = Doc::new();
    d.json["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    let (p, i) = sheet(2, 2, 1.0, 1.0);
    let pa = d.positions(&p);
    let lifted: Vec<[f32; 3]> = p.iter().map(|v| [v[0], v[1], v[2] + 1.0]).collect();
    let pb = d.positions(&lifted);
    let ia = d.indices_u32(&i);
    let two = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": pa}, "indices": ia}, {"attributes": {"POSITION": pb}, "indices": ia}]}),
    );
    let one = d.mesh(pa, Some(ia), 4);
    let t = d.floats(&[0., 0., 0., 3., 0., 0., 0., 3., 0.], "VEC3", 3);
    let r = d.floats(
        &f32s(&[quat(DVec3::Z, 0.0), quat(DVec3::X, 0.5), quat(DVec3::new(0.0, 1.0, 1.0), 1.0)].concat()),
        "VEC4",
        4,
    );
    let sc = d.floats(&[1., 1., 1., 2., 1., 1., 0.5, 0.5, 2.], "VEC3", 3);
    let attrs = json!({"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": t, "ROTATION": r, "SCALE": sc}}});
    let leaf = d.node(json!({"mesh": one, "translation": [0, 0, -2]}));
    let single = d.node(json!({"mesh": one, "children": [leaf], "translation": [-4, 0, 0],
                               "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": t}}}}));
    let node = d.node(json!({"mesh": two, "translation": [1, 0, 0], "extensions": attrs}));
    let parent = d.node(json!({"children": [node, single], "scale": [1, 2, 1]}));
    d.root(parent);
    let mut c = new_clip("instances");
    let rot = [quat(DVec3::Z, 0.0), quat(DVec3::Z, 1.5)].concat();
    channel(&mut d, &mut c, node, "rotation", (&[0.0, 1.0], &rot), "LINEAR");
    channel(&mut d, &mut c, parent, "translation", (&[0.0, 1.0], &[0., 0., 0., 0., 0., 4.]), "LINEAR");
    channel(&mut d, &mut c, leaf, "scale", (&[0.0, 1.0], &[1., 1., 1., 3., 1., 1.]), "STEP");
    d.json["animations"] = json!([c]);
    d
}

/// A random animated scene from `seed`: a forest of 3 to 9 nodes with TRS transforms (uniform,
/// non-uniform and sometimes mirroring scales) or static `matrix` ones; on some nodes a mesh of
/// one or two primitives, rigid, with morph targets, skinned, or skinned with morph targets;
/// skins over 1 to 4 other nodes (any: ancestors, descendants, unrelated) with inverse bind
/// matrices of the rest pose, arbitrary ones or none, u8/u16 joints and float or normalized
/// integer weights; one or two clips whose channels pick node, path, interpolation and 1 to 5
/// keys at random, starting anywhere in the first second, rotations and weights sometimes
/// stored as normalized integers. No mesh is shared (three.js cannot load a mesh used both
/// skinned and unskinned), no `matrix` node is animated (glTF) and no weights channel targets a
/// node with a morphed mesh below it (three.js drives those too).
fn random_doc(seed: u64) -> Doc {
    let mut r = gridrt_scene::rng::Rng::new(seed);
    let mut d = Doc::new();
    d.json["skins"] = json!([]);
    let range = |r: &mut gridrt_scene::rng::Rng, lo: f64, hi: f64| r.range(lo as f32, hi as f32) as f64;
    let unit_quat = |r: &mut gridrt_scene::rng::Rng| {
        let axis = r.unit_vector().as_dvec3();
        quat(axis, r.range(-3.1, 3.1) as f64)
    };
    let n = 3 + r.below(7) as usize;
    let parent: Vec<Option<usize>> =
        (0..n).map(|k| if k == 0 || r.f32() < 0.3 { None } else { Some(r.below(k as u64) as usize) }).collect();
    let is_matrix: Vec<bool> = (0..n).map(|_| r.f32() < 0.2).collect();
    // Rest transforms (f64, as the file stores them in f32).
    let mut local = Vec::new();
    for &m in &is_matrix {
        let t = DVec3::new(range(&mut r, -2.0, 2.0), range(&mut r, -2.0, 2.0), range(&mut r, -2.0, 2.0));
        let q = unit_quat(&mut r);
        let mut s = if r.f32() < 0.5 {
            DVec3::splat(range(&mut r, 0.5, 2.0))
        } else {
            DVec3::new(range(&mut r, 0.5, 2.0), range(&mut r, 0.5, 2.0), range(&mut r, 0.5, 2.0))
        };
        if !m && r.f32() < 0.15 {
            s.x = -s.x;
        }
        let round = |v: &[f64]| v.iter().map(|&x| x as f32 as f64).collect::<Vec<_>>();
        let (t, q, s) = (round(&t.to_array()), round(&q), round(&s.to_array()));
        local.push((DVec3::from_slice(&t), DQuat::from_slice(&q), DVec3::from_slice(&s)));
    }
    let trs = |(t, q, s): (DVec3, DQuat, DVec3)| DMat4::from_scale_rotation_translation(s, q, t);
    let world = |k: usize| {
        let mut m = trs(local[k]);
        let mut p = parent[k];
        while let Some(j) = p {
            m = trs(local[j]) * m;
            p = parent[j];
        }
        m
    };
    let mut nodes: Vec<serde_json::Value> = (0..n)
        .map(|k| {
            let (t, q, s) = local[k];
            if is_matrix[k] {
                json!({"matrix": f32s(&trs(local[k]).to_cols_array())})
            } else {
                json!({"translation": f32s(&t.to_array()), "rotation": f32s(&q.to_array()), "scale": f32s(&s.to_array())})
            }
        })
        .collect();
    // Meshes: (node, morph target count).
    let mut morphed = Vec::new();
    // A mesh loop indexes `nodes` (skins, weights) while it pushes to `d`.
    #[allow(clippy::needless_range_loop)]
    for k in 0..n {
        if !(k == 0 || r.f32() < 0.6) {
            continue;
        }
        let (nx, ny) = (1 + r.below(4) as u32, 1 + r.below(4) as u32);
        let (p, i) = sheet(nx, ny, range(&mut r, 0.3, 2.0) as f32, range(&mut r, 0.3, 2.0) as f32);
        let pa = d.positions(&p);
        let ia = d.indices_u32(&i);
        let kind = r.below(4); // rigid, morph, skinned, skinned + morph
        let targets = if kind % 2 == 1 { 1 + r.below(3) as usize } else { 0 };
        let mut prim = json!({"attributes": {"POSITION": pa}, "indices": ia});
        if targets > 0 {
            let t: Vec<_> = (0..targets)
                .map(|_| {
                    let deltas: Vec<f32> = (0..3 * p.len()).map(|_| r.range(-0.3, 0.3)).collect();
                    json!({"POSITION": d.floats(&deltas, "VEC3", 3)})
                })
                .collect();
            prim["targets"] = json!(t);
        }
        if kind >= 2 {
            let others: Vec<usize> = (0..n).filter(|&j| j != k).collect();
            let count = 1 + r.below(4.min(others.len()) as u64) as usize;
            let joints: Vec<usize> = (0..count).map(|_| others[r.below(others.len() as u64) as usize]).collect();
            let mut ids: Vec<u16> = Vec::new();
            let mut w: Vec<[f64; 4]> = Vec::new();
            for _ in &p {
                let mut wv = [0.0f64; 4];
                for (c, x) in wv.iter_mut().enumerate() {
                    ids.push(r.below(count as u64) as u16);
                    *x = if c > 0 && r.f32() < 0.3 { 0.0 } else { range(&mut r, 0.05, 1.0) };
                }
                let sum: f64 = wv.iter().sum();
                w.push(wv.map(|x| x / sum));
            }
            let ja = joints_accessor(&mut d, &ids, if r.f32() < 0.5 { 5121 } else { 5123 });
            let wa = weights_accessor(&mut d, &w, [5126, 5121, 5123][r.below(3) as usize]);
            prim["attributes"]["JOINTS_0"] = json!(ja);
            prim["attributes"]["WEIGHTS_0"] = json!(wa);
            let mut skin = json!({"joints": joints});
            match r.below(3) {
                0 => {}
                b => {
                    let m: Vec<f64> = joints
                        .iter()
                        .flat_map(|&j| {
                            let at = if b == 1 { world(j) } else { trs(local[(j + 1) % n]) };
                            at.inverse().to_cols_array()
                        })
                        .collect();
                    skin["inverseBindMatrices"] = json!(d.floats(&f32s(&m), "MAT4", 16));
                }
            }
            nodes[k]["skin"] = json!(d.push("skins", skin));
        }
        let mut mesh = json!({"primitives": [prim]});
        if kind == 0 && r.f32() < 0.3 {
            // A second, non-indexed primitive (rigid meshes: a skinned mesh's primitives all
            // need joints and weights).
            let loose: Vec<[f32; 3]> = i.iter().map(|&v| [p[v as usize][0], p[v as usize][1] + 0.1, 0.3]).collect();
            let pb = d.positions(&loose);
            mesh["primitives"].as_array_mut().unwrap().push(json!({"attributes": {"POSITION": pb}}));
        }
        if targets > 0 {
            if r.f32() < 0.5 {
                mesh["weights"] = json!((0..targets).map(|_| r.range(-0.5, 1.5)).collect::<Vec<_>>());
            }
            if r.f32() < 0.3 {
                nodes[k]["weights"] = json!((0..targets).map(|_| r.range(-0.5, 1.5)).collect::<Vec<_>>());
            }
            morphed.push((k, targets));
        }
        nodes[k]["mesh"] = json!(d.push("meshes", mesh));
    }
    for (k, node) in nodes.iter_mut().enumerate() {
        let kids: Vec<usize> = (0..n).filter(|&j| parent[j] == Some(k)).collect();
        if !kids.is_empty() {
            node["children"] = json!(kids);
        }
    }
    d.json["nodes"] = json!(nodes);
    (0..n).filter(|&k| parent[k].is_none()).for_each(|k| d.root(k));
    let mut clips = Vec::new();
    for c in 0..1 + r.below(2) {
        let mut a = new_clip(&format!("clip{c}"));
        let mut targets: Vec<(usize, &str, usize)> = (0..n)
            .filter(|&k| !is_matrix[k])
            .flat_map(|k| [(k, "translation", 3), (k, "rotation", 4), (k, "scale", 3)])
            .collect();
        // three.js (r170) applies a node's weights channel to every morphed mesh below the node
        // too (its loader traverses the node for a multi-primitive group); glTF drives the
        // node's own mesh only. So weights are animated only on nodes with no morphed mesh below.
        let below = |k: usize, j: usize| {
            let mut p = parent[j];
            while let Some(q) = p {
                if q == k {
                    return true;
                }
                p = parent[q];
            }
            false
        };
        targets.extend(
            morphed
                .iter()
                .filter(|&&(k, _)| !morphed.iter().any(|&(j, _)| below(k, j)))
                .map(|&(k, t)| (k, "weights", t)),
        );
        for _ in 0..1 + r.below(5) {
            if targets.is_empty() {
                break;
            }
            let (node, path, width) = targets.swap_remove(r.below(targets.len() as u64) as usize);
            let interp = ["LINEAR", "STEP", "CUBICSPLINE"][r.below(3) as usize];
            // CUBICSPLINE needs two keys at least (glTF).
            let keys = if interp == "CUBICSPLINE" { 2 + r.below(4) as usize } else { 1 + r.below(5) as usize };
            let mut times = vec![range(&mut r, 0.0, 1.0)];
            while times.len() < keys {
                let last = times[times.len() - 1];
                times.push(last + range(&mut r, 0.1, 0.7));
            }
            let value = |r: &mut gridrt_scene::rng::Rng| -> Vec<f64> {
                match path {
                    "rotation" => {
                        let mut q = unit_quat(r);
                        if r.f32() < 0.3 {
                            q.iter_mut().for_each(|x| *x = -*x);
                        }
                        q.to_vec()
                    }
                    "scale" => (0..3).map(|_| range(r, 0.3, 2.0)).collect(),
                    "translation" => (0..3).map(|_| range(r, -2.0, 2.0)).collect(),
                    _ => (0..width).map(|_| range(r, -0.5, 1.5)).collect(),
                }
            };
            let mut values = Vec::new();
            for _ in 0..keys {
                if interp == "CUBICSPLINE" {
                    values.extend((0..width).map(|_| range(&mut r, -1.0, 1.0)));
                    values.extend(value(&mut r));
                    values.extend((0..width).map(|_| range(&mut r, -1.0, 1.0)));
                } else {
                    values.extend(value(&mut r));
                }
            }
            channel(&mut d, &mut a, node, path, (&times, &values), interp);
            // Rotations and weights may be stored as normalized integers (glTF core): i16 or i8
            // rotations, i16 or u8 weights (values and tangents in their range).
            let quantize = match path {
                "rotation" => [None, None, Some(5122), Some(5120)][r.below(4) as usize],
                "weights" => [None, Some(5122), Some(5121)][r.below(3) as usize],
                _ => None,
            };
            if let Some(ty) = quantize {
                let (max, lo) = match ty {
                    5120 => (127.0, -1.0),
                    5121 => (255.0, 0.0),
                    _ => (32767.0, -1.0),
                };
                let bytes: Vec<u8> = values
                    .iter()
                    .flat_map(|&v| {
                        let q = (v.clamp(lo, 1.0) * max).round();
                        match ty {
                            5120 => vec![q as i8 as u8],
                            5121 => vec![q as u8],
                            _ => (q as i16).to_le_bytes().to_vec(),
                        }
                    })
                    .collect();
                let (ty_name, count) =
                    if path == "rotation" { ("VEC4", values.len() / 4) } else { ("SCALAR", values.len()) };
                // VEC4 of i8 is 4 bytes, of i16 8: aligned as vertex data needs no stride here.
                let out = d.accessor(&bytes, ty, count, ty_name);
                d.json["accessors"][out]["normalized"] = json!(true);
                let samplers = a["samplers"].as_array_mut().unwrap();
                let k = samplers.len() - 1;
                samplers[k]["output"] = json!(out);
            }
        }
        clips.push(a);
    }
    d.json["animations"] = json!(clips);
    d
}

/// Poses `file` with three.js at each (clip, seconds): the triangles' corners per pose.
fn three_poses(three: &Path, file: &Path, times: &[(usize, f64)], work: &Path) -> Vec<Vec<[f32; 9]>> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/js/three_pose.mjs");
    let out = work.join("three.bin");
    let status = Command::new("node")
        .arg(&script)
        .arg(three)
        .arg(file)
        .arg(&out)
        .args(times.iter().map(|(c, t)| format!("{c}:{t}")))
        .status()
        .expect("node runs");
    assert!(status.success(), "three.js failed on {}", file.display());
    let bytes = std::fs::read(&out).unwrap();
    let all: Vec<[f32; 9]> = bytes
        .chunks_exact(36)
        .map(|c| std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap())))
        .collect();
    let per = all.len() / times.len();
    assert_eq!(per * times.len(), all.len(), "{}: a whole number of poses", file.display());
    all.chunks(per).map(<[_]>::to_vec).collect()
}

/// Compares gridrt's poses of `file` with three.js's at times before, at, inside and after each
/// clip; returns how many poses were compared.
fn compare(three: &Path, file: &Path, work: &Path) -> usize {
    let bytes = std::fs::read(file).unwrap();
    let l: Loaded = load_rigged_slice_with(&bytes, &file.display().to_string(), None, &LoadLimits::default()).unwrap();
    let mut times = Vec::new();
    for c in l.rig.clips() {
        let len = c.end - c.start;
        for t in [
            c.start * 0.5,
            c.start,
            c.start + 0.137 * len,
            c.start + 0.5 * len,
            c.start + 0.861 * len,
            c.end,
            c.end + 1.0,
        ] {
            times.push((c.index, t));
        }
    }
    let theirs = three_poses(three, file, &times, work);
    let diag = l.mesh.bounds().diagonal().max(1e-6);
    let mut scratch = PoseScratch::default();
    let mut pos: Vec<Vec3> = Vec::new();
    for (&(clip, seconds), want) in times.iter().zip(&theirs) {
        l.rig.pose(Some(ClipTime { clip, seconds }), &mut scratch, &mut pos).unwrap();
        assert_eq!(want.len(), l.mesh.indices.len(), "{}: triangle count", file.display());
        let mut worst = (0.0f32, 0usize);
        for (k, (tri, w)) in l.mesh.indices.iter().zip(want).enumerate() {
            for (j, &v) in tri.iter().enumerate() {
                let p = pos[v as usize];
                let e = (p - Vec3::new(w[3 * j], w[3 * j + 1], w[3 * j + 2])).abs().max_element();
                if e > worst.0 || e.is_nan() {
                    worst = (e, k);
                }
            }
        }
        assert!(
            worst.0 <= 1e-5 * diag,
            "{} clip {clip} at {seconds} s: triangle {} is {} from three.js's (diagonal {diag})",
            file.display(),
            worst.1,
            worst.0
        );
    }
    times.len()
}

/// Random scenes posed by both (each a Node process: about 0.3 s); `GRIDRT_RANDOM_POSES=N`
/// tries N instead.
const RANDOM_DOCS: u64 = 24;

#[test]
fn poses_agree_with_three_js_on_generated_and_shared_animated_files() {
    let Some(three) = gridrt_testkit::three_js_dir() else { return };
    // Kept when a comparison fails (the failing file stays in `work`); removed at the end.
    let work = temp_dir("three").keep();
    let docs = [
        ("rigid", rigid_doc()),
        ("skin_u8", skin_doc(5121, 5121)),
        ("skin_u16", skin_doc(5123, 5123)),
        ("skin_float", skin_doc(5121, 5126)),
        ("morph", morph_doc()),
        ("quantized", quantized_doc()),
        ("instanced", instanced_doc()),
    ];
    let mut files = Vec::new();
    for (name, d) in docs {
        let f = work.join(format!("{name}.glb"));
        std::fs::write(&f, d.glb()).unwrap();
        files.push(f);
    }
    // Random scenes: what no hand-made file thought of (a failing one stays in `work`).
    let count = std::env::var("GRIDRT_RANDOM_POSES").ok().and_then(|v| v.parse().ok()).unwrap_or(RANDOM_DOCS);
    for seed in 0..count {
        let f = work.join(format!("random_{seed}.glb"));
        std::fs::write(&f, random_doc(seed).glb()).unwrap();
        files.push(f);
    }
    files.extend(gridrt_testkit::shared_scenes_in(&["animated"], &["glb"]));
    for f in &files {
        let n = compare(&three, f, &work);
        println!("{}: {n} poses agree with three.js", f.display());
    }
    let _ = std::fs::remove_dir_all(&work);
}
