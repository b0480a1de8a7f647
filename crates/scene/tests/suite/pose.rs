//! Posing against poses known analytically, on small generated files: a joint rotated 90°, a
//! morph weight of 0.5, STEP keys, a CUBICSPLINE curve, a skinned mesh under a transformed
//! parent (whose transform the glTF rule ignores); clip lookup, clamping and looping; and, on
//! the shared animated scenes, invariants that hold whatever the file.

use glam::{DMat4, DQuat, DVec3, Vec3};
use gridrt_scene::gltf_load::{Loaded, load_rigged_slice_with};
use gridrt_scene::{ClipTime, LoadLimits, PoseScratch, SceneError};
use serde_json::json;

use super::builder::Doc;

fn load(d: Doc) -> Loaded {
    load_rigged_slice_with(&d.glb(), "posed.glb", None, &LoadLimits::default()).unwrap()
}

fn pose(l: &Loaded, clip: usize, seconds: f64) -> Vec<Vec3> {
    let mut out = Vec::new();
    l.rig.pose(Some(ClipTime { clip, seconds }), &mut PoseScratch::default(), &mut out).unwrap();
    out
}

fn close(a: Vec3, b: DVec3) -> bool {
    (a.as_dvec3() - b).abs().max_element() <= 1e-5 * (1.0 + b.abs().max_element())
}

fn assert_points(got: &[Vec3], want: &[DVec3], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(close(*g, *w), "{what}: vertex {i} is {g:?}, want {w:?}");
    }
}

/// A skinned triangle pair under a parent moved by (100, 0, 0) and scaled by 2: joint 0 at the
/// origin, joint 1 at (0, 1, 0) rotating about z from 0° at t = 0 to 90° at t = 1. Vertices 0–2
/// follow joint 1 alone, vertex 3 half joint 0, half joint 1.
fn skinned_doc() -> Doc {
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0]]);
    let i = d.indices_u16(&[0, 1, 2, 2, 1, 3]);
    let joints = d.accessor(&[1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0], 5121, 4, "VEC4");
    let weights = d.floats(&[1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 0.5, 0.5, 0., 0.], "VEC4", 4);
    let mut ibm: Vec<f32> = DMat4::IDENTITY.to_cols_array().iter().map(|&x| x as f32).collect();
    ibm.extend(DMat4::from_translation(DVec3::new(0.0, -1.0, 0.0)).to_cols_array().iter().map(|&x| x as f32));
    let ibm = d.floats(&ibm, "MAT4", 16);
    let m = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": p, "JOINTS_0": joints, "WEIGHTS_0": weights}, "indices": i}]}),
    );
    let times = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let q90 = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let rot = d.floats(&[0., 0., 0., 1., q90.x as f32, q90.y as f32, q90.z as f32, q90.w as f32], "VEC4", 4);
    d.json["nodes"] = json!([
        {"children": [1]},
        {"translation": [0.0, 1.0, 0.0]},
        {"children": [3], "translation": [100.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0]},
        {"mesh": m, "skin": 0, "translation": [5.0, 5.0, 5.0]}
    ]);
    d.json["scenes"] = json!([{"nodes": [0, 2]}]);
    d.json["skins"] = json!([{"joints": [0, 1], "inverseBindMatrices": ibm}]);
    d.json["animations"] = json!([{
        "name": "bend",
        "samplers": [{"input": times, "output": rot}],
        "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}]
    }]);
    d
}

/// Where joint 1 (at (0, 1, 0), rotated `angle` about z) takes bind-pose point `p`.
fn about_joint1(p: DVec3, angle: f64) -> DVec3 {
    let pivot = DVec3::new(0.0, 1.0, 0.0);
    DQuat::from_rotation_z(angle) * (p - pivot) + pivot
}

#[test]
fn a_joint_rotated_90_degrees_moves_its_vertices_and_ignores_the_mesh_parents() {
    let l = load(skinned_doc());
    let bind = [DVec3::new(0., 1., 0.), DVec3::new(0., 2., 0.), DVec3::new(1., 1., 0.), DVec3::new(1., 2., 0.)];
    // At rest the inverse bind matrices undo the joints: the bind pose, not moved by the mesh
    // node's parent (100, 0, 0) × 2 or its own (5, 5, 5).
    assert_points(&l.mesh.positions, &bind, "rest pose");
    for (t, angle) in [(0.0, 0.0), (0.5, std::f64::consts::FRAC_PI_4), (1.0, std::f64::consts::FRAC_PI_2)] {
        let mut want: Vec<DVec3> = bind[..3].iter().map(|&p| about_joint1(p, angle)).collect();
        want.push(0.5 * bind[3] + 0.5 * about_joint1(bind[3], angle));
        assert_points(&pose(&l, 0, t), &want, &format!("t = {t}"));
    }
    // 90°: (0, 2, 0) → (-1, 1, 0) and (1, 1, 0) → (0, 2, 0), exactly what the rotation says.
    let p = pose(&l, 0, 1.0);
    assert!(close(p[1], DVec3::new(-1.0, 1.0, 0.0)) && close(p[2], DVec3::new(0.0, 2.0, 0.0)));
    // Clamped outside the clip, looped for playback.
    assert_eq!(pose(&l, 0, 7.0), pose(&l, 0, 1.0));
    assert_eq!(pose(&l, 0, -3.0), pose(&l, 0, 0.0));
    let clip = &l.rig.clips()[0];
    assert_eq!((clip.start, clip.end, clip.channel_count()), (0.0, 1.0, 1));
    assert!((clip.looped(2.25) - 0.25).abs() < 1e-12);
    // The index list never changes: triangle i stays triangle i.
    assert_eq!(l.mesh.indices, vec![[0, 1, 2], [2, 1, 3]]);
}

/// One triangle with one morph target (+1 on z everywhere), mesh default weight 0.25, node
/// weight animated LINEAR 0 → 1 over [0, 2]; a second node moved by STEP keys and a third by a
/// CUBICSPLINE curve.
fn keyed_doc() -> Doc {
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let i = d.indices_u16(&[0, 1, 2]);
    let delta = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3", 3);
    let morphed = d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": p}, "indices": i, "targets": [{"POSITION": delta}]}],
               "weights": [0.25]}),
    );
    let plain = d.mesh(p, Some(i), 4);
    let t02 = d.floats(&[0.0, 2.0], "SCALAR", 1);
    let w = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let t012 = d.floats(&[0.0, 1.0, 2.0], "SCALAR", 1);
    let steps = d.floats(&[0., 0., 0., 5., 0., 0., 7., 0., 0.], "VEC3", 3);
    // CUBICSPLINE on x: value 0 → 4 over [0, 2], out-tangent 3 at the first key, in-tangent -1
    // at the second (in-tangent of key 0 and out-tangent of key 1 unused).
    let curve = d.floats(&[9., 0., 0., 0., 0., 0., 3., 0., 0., -1., 0., 0., 4., 0., 0., 9., 0., 0.], "VEC3", 3);
    d.json["nodes"] = json!([
        {"mesh": morphed},
        {"mesh": plain, "translation": [0.0, 0.0, 10.0]},
        {"mesh": plain, "translation": [0.0, 0.0, 20.0]}
    ]);
    d.json["scenes"] = json!([{"nodes": [0, 1, 2]}]);
    d.json["animations"] = json!([
        {"name": "morph", "samplers": [{"input": t02, "output": w}],
         "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]},
        {"name": "keys",
         "samplers": [{"input": t012, "output": steps, "interpolation": "STEP"},
                      {"input": t02, "output": curve, "interpolation": "CUBICSPLINE"}],
         "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}},
                      {"sampler": 1, "target": {"node": 2, "path": "translation"}}]}
    ]);
    d
}

fn base(z: f64) -> Vec<DVec3> {
    vec![DVec3::new(0., 0., z), DVec3::new(1., 0., z), DVec3::new(0., 1., z)]
}

#[test]
fn morph_weights_step_keys_and_a_cubic_spline() {
    let l = load(keyed_doc());
    // Rest: the mesh's default weight 0.25 applies; the other nodes stand at their TRS.
    assert_points(&l.mesh.positions[..3], &base(0.25), "rest morph");
    assert_points(&l.mesh.positions[3..6], &base(10.0), "rest step node");
    // A morph weight of 0.5 at t = 1.
    let morph = l.rig.find_clip("morph").unwrap();
    assert_points(&pose(&l, morph, 1.0)[..3], &base(0.5), "weight 0.5");
    assert_points(&pose(&l, morph, 2.0)[..3], &base(1.0), "weight 1");
    // An animated clip leaves what it does not drive at rest.
    assert_points(&pose(&l, morph, 1.0)[3..6], &base(10.0), "undriven node");

    let keys = l.rig.find_clip("1").unwrap();
    let shifted = |x: f64, z: f64| -> Vec<DVec3> { base(z).iter().map(|p| *p + DVec3::new(x, 0.0, -z)).collect() };
    for (t, x) in [(-1.0, 0.0), (0.0, 0.0), (0.999, 0.0), (1.0, 5.0), (1.5, 5.0), (2.0, 7.0), (9.0, 7.0)] {
        // STEP replaces the whole translation (z = 10 goes to 0).
        assert_points(&pose(&l, keys, t)[3..6], &shifted(x, 0.0), &format!("STEP at t = {t}"));
    }
    for t in [0.0, 0.5, 1.0, 1.5, 2.0] {
        let (s, dt): (f64, f64) = (t / 2.0, 2.0);
        let (v0, out0, v1, in1) = (0.0, 3.0, 4.0, -1.0);
        let x = (2.0 * s.powi(3) - 3.0 * s * s + 1.0) * v0
            + (s.powi(3) - 2.0 * s * s + s) * dt * out0
            + (-2.0 * s.powi(3) + 3.0 * s * s) * v1
            + (s.powi(3) - s * s) * dt * in1;
        assert_points(&pose(&l, keys, t)[6..9], &shifted(x, 0.0), &format!("CUBICSPLINE at t = {t}"));
    }
}

#[test]
fn clips_are_found_by_index_or_name_and_unknown_ones_are_errors() {
    let l = load(keyed_doc());
    assert_eq!(l.rig.find_clip("0").unwrap(), 0);
    assert_eq!(l.rig.find_clip("keys").unwrap(), 1);
    let e = l.rig.find_clip("walk").unwrap_err();
    assert!(matches!(e, SceneError::UnknownAnimation { .. }));
    let msg = e.to_string();
    assert!(msg.contains("\"morph\"") && msg.contains("\"keys\""), "{msg}");
    let s = l.rig.summary();
    assert_eq!((s.clips.len(), s.morph_targets, s.morphed_instances, s.skins), (2, 1, 1, 0));
}

#[test]
fn a_pose_that_leaves_the_supported_range_is_an_error_not_a_panic() {
    let mut d = keyed_doc();
    // Scale key 1e31 at t = 1: every vertex of node 1 beyond MAX_COORDINATE.
    let t = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let s = d.floats(&[1., 1., 1., 1e31, 1e31, 1e31], "VEC3", 3);
    d.json["animations"][1]["samplers"].as_array_mut().unwrap().push(json!({"input": t, "output": s}));
    d.json["animations"][1]["channels"]
        .as_array_mut()
        .unwrap()
        .push(json!({"sampler": 2, "target": {"node": 1, "path": "scale"}}));
    let l = load(d);
    let mut out = Vec::new();
    let mut scratch = PoseScratch::default();
    l.rig.pose(Some(ClipTime { clip: 1, seconds: 0.0 }), &mut scratch, &mut out).unwrap();
    let e = l.rig.pose(Some(ClipTime { clip: 1, seconds: 1.0 }), &mut scratch, &mut out).unwrap_err();
    let SceneError::AtTime { clip: 1, inner, .. } = e else { panic!("{e}") };
    assert!(matches!(*inner, SceneError::CoordinateOutOfRange { node: 1, vertex: 1, .. }), "{inner}");
}

/// A rotation key of length zero has no direction: refused on load, naming its key, instead of
/// posing every vertex it moves to NaN at that key's time. Keys of other lengths pose as unit ones
/// at their times (rotations are normalised after interpolation).
#[test]
fn a_zero_quaternion_key_is_refused_and_other_lengths_are_normalised() {
    let rotation_keys = |keys: &[f32]| {
        let mut d = skinned_doc();
        let times = d.floats(&[0.0, 1.0], "SCALAR", 1);
        let rot = d.floats(keys, "VEC4", 4);
        d.json["animations"][0]["samplers"][0]["input"] = json!(times);
        d.json["animations"][0]["samplers"][0]["output"] = json!(rot);
        d
    };
    let zero = rotation_keys(&[0., 0., 0., 1., 0., 0., 0., 0.]).glb();
    let Err(e) = load_rigged_slice_with(&zero, "zero.glb", None, &LoadLimits::default()) else {
        panic!("a zero rotation key must be refused")
    };
    assert!(matches!(e, SceneError::InvalidAnimation { animation: 0, sampler: Some(0), .. }), "{e}");
    assert!(e.to_string().contains("rotation key 1 is the zero quaternion"), "{e}");
    // Keys of other lengths (3 × identity, 2 × the 90° key) pose at their times as the unit keys.
    let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2) * 2.0;
    let scaled = load(rotation_keys(&[0., 0., 0., 3., q.x as f32, q.y as f32, q.z as f32, q.w as f32]));
    let unit = load(skinned_doc());
    for t in [0.0, 1.0] {
        let want: Vec<DVec3> = pose(&unit, 0, t).iter().map(|p| p.as_dvec3()).collect();
        assert_points(&pose(&scaled, 0, t), &want, &format!("scaled keys at t = {t}"));
    }
}

/// Invariants on the shared animated scenes: every clip poses at any time into finite
/// positions of the same count; a pose is the same computed twice or one loop later; the
/// clamped ends equal the ends; a clip moves something over its duration.
#[test]
fn shared_animated_scenes_pose_at_any_time() {
    let files = gridrt_testkit::shared_scenes_in(&["animated"], &["glb", "gltf"]);
    for f in &files {
        let bytes = std::fs::read(f).unwrap();
        let l = load_rigged_slice_with(&bytes, &f.display().to_string(), None, &LoadLimits::default()).unwrap();
        let diag = l.mesh.bounds().diagonal() as f64;
        let mut scratch = PoseScratch::default();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for clip in l.rig.clips() {
            let mut moved: f64 = 0.0;
            for k in 0..=6 {
                let t = clip.start + clip.duration() * k as f64 / 6.0;
                let at = |s: f64| Some(ClipTime { clip: clip.index, seconds: s });
                l.rig.pose(at(t), &mut scratch, &mut a).unwrap();
                assert_eq!(a.len(), l.mesh.positions.len());
                assert!(a.iter().all(|p| p.is_finite()));
                l.rig.pose(at(clip.looped(t - clip.start + 2.0 * clip.duration())), &mut scratch, &mut b).unwrap();
                if k < 6 {
                    let d = a.iter().zip(&b).map(|(p, q)| (*p - *q).length() as f64).fold(0.0, f64::max);
                    assert!(d <= 1e-4 * diag, "{}: clip {} loop at t = {t}: {d}", f.display(), clip.index);
                }
                l.rig.pose(at(t), &mut scratch, &mut b).unwrap();
                assert_eq!(a, b, "{}: posing is deterministic", f.display());
                moved = moved
                    .max(a.iter().zip(&l.mesh.positions).map(|(p, q)| (*p - *q).length() as f64).fold(0.0, f64::max));
            }
            l.rig.pose(Some(ClipTime { clip: clip.index, seconds: clip.end + 100.0 }), &mut scratch, &mut a).unwrap();
            l.rig.pose(Some(ClipTime { clip: clip.index, seconds: clip.end }), &mut scratch, &mut b).unwrap();
            assert_eq!(a, b);
            if clip.channel_count() > 0 {
                println!("{} clip {} moves up to {:.3} of the diagonal", f.display(), clip.index, moved / diag);
            }
        }
    }
}
