//! A generated animated scene of any size, written as `.glb`: a crowd of skinned tubes that
//! sway on three-joint skeletons (each with its own skin and phase), balls that orbit and spin
//! as rigid nodes, and a floor. It exercises the whole posing path (LINEAR rotations and
//! translations, STEP scales, CUBICSPLINE, skins sharing one mesh and one set of inverse bind
//! matrices, a skinned mesh under a transformed parent) and scales to millions of triangles
//! for `gridrt bench --dynamic`. Deterministic in `seed`.

use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

use crate::glb_write::assemble_glb;
use crate::rng::Rng;

/// Triangles of one tube (segments × rings quads).
const TUBE_SEGMENTS: u32 = 20;
const TUBE_RINGS: u32 = 51;
/// Triangles of one ball (a UV sphere).
const BALL_SLICES: u32 = 16;
const BALL_STACKS: u32 = 8;
/// Joints per tube skeleton, along its height.
const JOINTS: usize = 3;
const TUBE_HEIGHT: f32 = 4.0;
/// Clip length, seconds; keys every quarter second.
const CLIP_SECONDS: f32 = 4.0;
const KEYS: usize = 17;
/// Phase buckets: tubes share the key outputs of their bucket.
const PHASES: usize = 8;

/// Triangles of a crowd of `tubes` tubes (`tubes / 2` balls and the floor).
pub fn crowd_triangles(tubes: u32) -> u64 {
    let tube = 2 * TUBE_SEGMENTS as u64 * (TUBE_RINGS as u64 - 1);
    let ball = 2 * BALL_SLICES as u64 * (BALL_STACKS as u64 - 1);
    tubes as u64 * tube + (tubes / 2) as u64 * ball + 2
}

/// The number of tubes whose crowd has at least `triangles` triangles.
pub fn tubes_for(triangles: u64) -> u32 {
    let mut n = 1;
    while crowd_triangles(n) < triangles {
        n += 1;
    }
    n
}

struct Builder {
    json: Value,
    bin: Vec<u8>,
}

impl Builder {
    fn push(&mut self, key: &str, v: Value) -> usize {
        let a = self.json[key].as_array_mut().expect("an array");
        a.push(v);
        a.len() - 1
    }

    fn accessor(&mut self, bytes: &[u8], component: u32, count: usize, ty: &str, extra: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view =
            self.push("bufferViews", json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        let mut a = json!({"bufferView": view, "componentType": component, "count": count, "type": ty});
        if let (Value::Object(a), Value::Object(e)) = (&mut a, extra) {
            a.extend(e);
        }
        self.push("accessors", a)
    }

    fn floats(&mut self, v: &[f32], ty: &str, width: usize) -> usize {
        self.accessor(bytemuck::cast_slice(v), 5126, v.len() / width, ty, json!({}))
    }

    fn positions(&mut self, p: &[Vec3]) -> usize {
        let lo = p.iter().fold(Vec3::INFINITY, |a, &b| a.min(b));
        let hi = p.iter().fold(Vec3::NEG_INFINITY, |a, &b| a.max(b));
        let flat: Vec<f32> = p.iter().flat_map(|v| v.to_array()).collect();
        self.accessor(
            bytemuck::cast_slice(&flat),
            5126,
            p.len(),
            "VEC3",
            json!({"min": lo.to_array(), "max": hi.to_array()}),
        )
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        self.accessor(bytemuck::cast_slice(idx), 5125, idx.len(), "SCALAR", json!({}))
    }
}

/// Grid triangles of a (rings × segments) surface, wrapping around the segments.
fn wrap_indices(rings: u32, segments: u32) -> Vec<u32> {
    let mut idx = Vec::new();
    for r in 0..rings - 1 {
        for s in 0..segments {
            let (a, b) = (r * segments + s, r * segments + (s + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            idx.extend_from_slice(&[a, b, d, a, d, c]);
        }
    }
    idx
}

/// The crowd as `.glb` bytes: `tubes` skinned tubes and `tubes / 2` balls on a square floor.
pub fn crowd_glb(tubes: u32, seed: u64) -> Vec<u8> {
    let tubes = tubes.max(1);
    let balls = tubes / 2;
    let mut rng = Rng::new(seed);
    let mut b = Builder {
        json: json!({
            "asset": {"version": "2.0", "generator": "gridrt crowd"},
            "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "skins": [],
            "accessors": [], "bufferViews": [], "buffers": [],
            "animations": [{"name": "sway", "samplers": [], "channels": []}]
        }),
        bin: Vec::new(),
    };

    // The tube in bind space (base at the origin, along +y), weights blending neighbouring joints.
    let mut pos = Vec::new();
    let (mut joints, mut weights) = (Vec::<u8>::new(), Vec::<f32>::new());
    for r in 0..TUBE_RINGS {
        let y = TUBE_HEIGHT * r as f32 / (TUBE_RINGS - 1) as f32;
        let radius = 0.3 * (1.0 - 0.5 * y / TUBE_HEIGHT);
        for s in 0..TUBE_SEGMENTS {
            let a = std::f32::consts::TAU * s as f32 / TUBE_SEGMENTS as f32;
            pos.push(Vec3::new(radius * a.cos(), y, radius * a.sin()));
            let f = (y / TUBE_HEIGHT * JOINTS as f32 - 0.5).clamp(0.0, (JOINTS - 1) as f32);
            let j = (f.floor() as usize).min(JOINTS - 2);
            let w = f - j as f32;
            joints.extend_from_slice(&[j as u8, j as u8 + 1, 0, 0]);
            weights.extend_from_slice(&[1.0 - w, w, 0.0, 0.0]);
        }
    }
    let tube_pos = b.positions(&pos);
    let tube_idx = b.indices(&wrap_indices(TUBE_RINGS, TUBE_SEGMENTS));
    let tube_joints = b.accessor(&joints, 5121, pos.len(), "VEC4", json!({}));
    let tube_weights = b.floats(&weights, "VEC4", 4);
    let tube = b.push(
        "meshes",
        json!({"name": "tube", "primitives": [{"attributes": {"POSITION": tube_pos, "JOINTS_0": tube_joints,
               "WEIGHTS_0": tube_weights}, "indices": tube_idx}]}),
    );
    // Joint k rests at height k·H/3 in bind space: the shared inverse bind matrices.
    let joint_y = |k: usize| TUBE_HEIGHT * k as f32 / JOINTS as f32;
    let ibm: Vec<f32> =
        (0..JOINTS).flat_map(|k| Mat4::from_translation(Vec3::new(0.0, -joint_y(k), 0.0)).to_cols_array()).collect();
    let ibm = b.floats(&ibm, "MAT4", 16);

    let mut ball_pos = Vec::new();
    for st in 0..BALL_STACKS {
        let phi = std::f32::consts::PI * (st as f32 + 0.5) / BALL_STACKS as f32;
        for sl in 0..BALL_SLICES {
            let th = std::f32::consts::TAU * sl as f32 / BALL_SLICES as f32;
            ball_pos.push(0.35 * Vec3::new(phi.sin() * th.cos(), phi.cos(), phi.sin() * th.sin()));
        }
    }
    let ball_p = b.positions(&ball_pos);
    let ball_i = b.indices(&wrap_indices(BALL_STACKS, BALL_SLICES));
    let ball = b.push(
        "meshes",
        json!({"name": "ball", "primitives": [{"attributes": {"POSITION": ball_p}, "indices": ball_i}]}),
    );

    // Shared keys: times, sway rotations per phase bucket and joint, orbits, pulsing scales.
    let times: Vec<f32> = (0..KEYS).map(|k| CLIP_SECONDS * k as f32 / (KEYS - 1) as f32).collect();
    let t_acc =
        b.accessor(bytemuck::cast_slice(&times), 5126, KEYS, "SCALAR", json!({"min": [0.0], "max": [CLIP_SECONDS]}));
    let mut sway = Vec::new();
    for p in 0..PHASES {
        let mut per_joint = Vec::new();
        for k in 0..JOINTS {
            let q: Vec<f32> = times
                .iter()
                .map(|&t| {
                    let w = std::f32::consts::TAU * (t / CLIP_SECONDS + p as f32 / PHASES as f32);
                    let amp = 0.35 * (k + 1) as f32 / JOINTS as f32;
                    Quat::from_rotation_z(amp * w.sin()) * Quat::from_rotation_x(0.5 * amp * w.cos())
                })
                .flat_map(|q| q.to_array())
                .collect();
            per_joint.push(b.floats(&q, "VEC4", 4));
        }
        sway.push(per_joint);
    }
    // Ball spin: CUBICSPLINE rotation about y (in-tangent, value, out-tangent per key).
    let spin: Vec<f32> = times
        .iter()
        .flat_map(|&t| {
            let q = Quat::from_rotation_y(std::f32::consts::TAU * t / CLIP_SECONDS);
            [[0.0f32; 4], q.to_array(), [0.0; 4]].concat()
        })
        .collect();
    let spin = b.floats(&spin, "VEC4", 4);
    // A pulse on STEP keys.
    let pulse: Vec<f32> = (0..KEYS).flat_map(|k| [1.0 + 0.15 * (k % 2) as f32; 3]).collect();
    let pulse = b.floats(&pulse, "VEC3", 3);

    let side = ((tubes + balls) as f32).sqrt().ceil() as u32;
    let spacing = 1.6;
    let extent = side as f32 * spacing;
    let root = b.push("nodes", json!({"name": "crowd", "children": [], "scale": [1.0, 1.0, 1.0]}));
    b.json["scenes"][0]["nodes"].as_array_mut().expect("nodes").push(json!(root));
    let add_child = |b: &mut Builder, parent: usize, child: usize| {
        b.json["nodes"][parent]["children"].as_array_mut().expect("children").push(json!(child));
    };
    let sampler = |b: &mut Builder, output: usize, interpolation: &str| -> usize {
        let s = json!({"input": t_acc, "output": output, "interpolation": interpolation});
        let a = b.json["animations"][0]["samplers"].as_array_mut().expect("samplers");
        a.push(s);
        a.len() - 1
    };
    let channel = |b: &mut Builder, s: usize, node: usize, path: &str| {
        b.json["animations"][0]["channels"]
            .as_array_mut()
            .expect("channels")
            .push(json!({"sampler": s, "target": {"node": node, "path": path}}));
    };
    // Samplers of each phase bucket's joints, made once.
    let sway_samplers: Vec<Vec<usize>> =
        sway.iter().map(|per_joint| per_joint.iter().map(|&out| sampler(&mut b, out, "LINEAR")).collect()).collect();
    // A skinned mesh's own node transform is ignored: the meshes hang under a moved parent.
    let skinned_parent =
        b.push("nodes", json!({"name": "skinned meshes", "children": [], "translation": [1e3, 0.0, 0.0]}));
    add_child(&mut b, root, skinned_parent);
    let spin_s = sampler(&mut b, spin, "CUBICSPLINE");
    let pulse_s = sampler(&mut b, pulse, "STEP");
    let cells: Vec<u32> = (0..side * side).collect();
    for (slot, &cell) in cells.iter().take((tubes + balls) as usize).enumerate() {
        let (x, z) = ((cell % side) as f32 * spacing, (cell / side) as f32 * spacing);
        let jitter = Vec3::new(rng.f32() * 0.4 - 0.2, 0.0, rng.f32() * 0.4 - 0.2);
        let at = Vec3::new(x - extent * 0.5, 0.0, z - extent * 0.5) + jitter;
        if slot < tubes as usize {
            let phase = rng.below(PHASES as u64) as usize;
            let mut chain = Vec::new();
            let mut parent = root;
            for (k, &joint_sampler) in sway_samplers[phase].iter().enumerate() {
                let t = if k == 0 { at } else { Vec3::new(0.0, joint_y(k) - joint_y(k - 1), 0.0) };
                let n = b.push("nodes", json!({"translation": t.to_array(), "children": []}));
                add_child(&mut b, parent, n);
                channel(&mut b, joint_sampler, n, "rotation");
                chain.push(n);
                parent = n;
            }
            let skin = b.push("skins", json!({"joints": chain, "inverseBindMatrices": ibm, "skeleton": chain[0]}));
            let m = b.push("nodes", json!({"mesh": tube, "skin": skin}));
            add_child(&mut b, skinned_parent, m);
        } else {
            let n = b.push("nodes", json!({"mesh": ball, "translation": (at + Vec3::Y * 0.5).to_array()}));
            add_child(&mut b, root, n);
            // An orbit of radius 0.4 (LINEAR translation keys) with a spin and a pulse.
            let orbit: Vec<f32> = times
                .iter()
                .flat_map(|&t| {
                    let a = std::f32::consts::TAU * (t / CLIP_SECONDS + slot as f32 * 0.137);
                    (at + Vec3::new(0.4 * a.cos(), 0.5 + 0.3 * (2.0 * a).sin().abs(), 0.4 * a.sin())).to_array()
                })
                .collect();
            let orbit = b.floats(&orbit, "VEC3", 3);
            let s = sampler(&mut b, orbit, "LINEAR");
            channel(&mut b, s, n, "translation");
            channel(&mut b, spin_s, n, "rotation");
            channel(&mut b, pulse_s, n, "scale");
        }
    }
    // The floor.
    let h = extent * 0.6;
    let floor_p =
        b.positions(&[Vec3::new(-h, 0.0, -h), Vec3::new(h, 0.0, -h), Vec3::new(h, 0.0, h), Vec3::new(-h, 0.0, h)]);
    let floor_i = b.indices(&[0, 2, 1, 0, 3, 2]);
    let floor = b.push(
        "meshes",
        json!({"name": "floor", "primitives": [{"attributes": {"POSITION": floor_p}, "indices": floor_i}]}),
    );
    let n = b.push("nodes", json!({"mesh": floor}));
    add_child(&mut b, root, n);

    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    b.json["buffers"] = json!([{"byteLength": b.bin.len()}]);
    let mut j = serde_json::to_vec(&b.json).expect("plain JSON values serialise");
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    assemble_glb(&j, Some(&b.bin))
}
