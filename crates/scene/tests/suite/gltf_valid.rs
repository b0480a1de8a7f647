//! Valid glTF: the triangle order contract, node transforms, strips and fans, non-indexed
//! primitives, skipped modes, buffers embedded, external and in the GLB chunk, sparse accessors.

use glam::Vec3;
use gridrt_scene::gltf_load::{load_path, load_slice};
use serde_json::json;

use super::builder::{Doc, temp_dir};

fn tri(p: Vec3) -> [[f32; 3]; 3] {
    [p.to_array(), (p + Vec3::X).to_array(), (p + Vec3::Y).to_array()]
}

#[test]
fn triangle_order_is_depth_first_document_order() {
    // Nodes: 0 = root with mesh A and children [2, 1]; 1 = mesh B at +10y; 2 = no mesh, child 3;
    // 3 = mesh B at +100z (child of 2, so visited before node 1); 4 = second root, mesh A.
    let mut d = Doc::new();
    let pa = d.positions(&tri(Vec3::ZERO));
    let ma = d.mesh(pa, None, 4);
    let pb = d.positions(&[tri(Vec3::ZERO), tri(Vec3::Z)].concat());
    let ib = d.indices_u16(&[3, 4, 5, 0, 1, 2]);
    let mb = d.mesh(pb, Some(ib), 4);
    d.node(json!({"mesh": ma, "children": [2, 1]}));
    d.node(json!({"mesh": mb, "translation": [0.0, 10.0, 0.0]}));
    d.node(json!({"children": [3], "translation": [0.0, 0.0, 100.0]}));
    d.node(json!({"mesh": mb, "scale": [2.0, 2.0, 2.0]}));
    d.node(json!({"mesh": ma, "translation": [5.0, 0.0, 0.0]}));
    d.root(0);
    d.root(4);
    let (mesh, report) = load_slice(&d.glb(), "order.glb", None).unwrap();
    assert_eq!(report.triangles, 6);
    let first = |i: usize| mesh.triangle(i)[0];
    assert_eq!(first(0), Vec3::ZERO); // node 0, mesh A
    assert_eq!(first(1), Vec3::new(0.0, 0.0, 102.0)); // node 3 (via 2): B's first triangle is the +z one, scaled 2
    assert_eq!(first(2), Vec3::new(0.0, 0.0, 100.0));
    assert_eq!(first(3), Vec3::new(0.0, 10.0, 1.0)); // node 1
    assert_eq!(first(4), Vec3::new(0.0, 10.0, 0.0));
    assert_eq!(first(5), Vec3::new(5.0, 0.0, 0.0)); // node 4
    assert_eq!(mesh.triangle(2)[1], Vec3::new(2.0, 0.0, 100.0));
}

#[test]
fn strips_fans_and_non_indexed_primitives() {
    let pts: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, (i % 2) as f32, 0.0]).collect();
    for (mode, expect) in [
        (4u32, vec![[0u32, 1, 2], [3, 4, 5]]),
        (5, vec![[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]]),
        (6, vec![[1, 2, 0], [2, 3, 0], [3, 4, 0], [4, 5, 0]]),
    ] {
        for indexed in [false, true] {
            let mut d = Doc::new();
            let p = d.positions(&pts);
            let i = indexed.then(|| d.indices_u32(&[0, 1, 2, 3, 4, 5]));
            let m = d.mesh(p, i, mode);
            let n = d.node(json!({"mesh": m}));
            d.root(n);
            let (mesh, _) = load_slice(&d.glb(), "modes.glb", None).unwrap();
            let got: Vec<[Vec3; 3]> = (0..mesh.triangle_count()).map(|t| mesh.triangle(t)).collect();
            let want: Vec<[Vec3; 3]> = expect.iter().map(|t| t.map(|k| Vec3::from_array(pts[k as usize]))).collect();
            assert_eq!(got, want, "mode {mode} indexed {indexed}");
        }
    }
}

#[test]
fn other_modes_are_skipped_and_reported() {
    let mut d = Doc::single_triangle();
    let p = d.positions(&[[0.0; 3], [1.0, 1.0, 1.0]]);
    let m = d.mesh(p, None, 1);
    let n = d.node(json!({"mesh": m}));
    d.root(n);
    let (mesh, report) = load_slice(&d.glb(), "lines.glb", None).unwrap();
    assert_eq!(mesh.triangle_count(), 1);
    assert_eq!(report.skipped_primitives.len(), 1);
    assert!(report.skipped_primitives[0].contains("Lines"), "{:?}", report.skipped_primitives);
}

#[test]
fn embedded_external_and_glb_buffers_load_the_same() {
    let make = || {
        let mut d = Doc::new();
        let p = d.positions(&[tri(Vec3::ZERO), tri(Vec3::ONE)].concat());
        let i = d.indices_u16(&[0, 1, 2, 3, 4, 5]);
        let m = d.mesh(p, Some(i), 4);
        let n = d.node(json!({"mesh": m, "rotation": [0.0, std::f32::consts::FRAC_1_SQRT_2, 0.0, std::f32::consts::FRAC_1_SQRT_2]}));
        d.root(n);
        d
    };
    let (a, _) = load_slice(&make().glb(), "a.glb", None).unwrap();
    let (b, _) = load_slice(&make().gltf_embedded(), "b.gltf", None).unwrap();
    let tmp = temp_dir("ext");
    let dir = tmp.path();
    let (j, bin) = make().gltf_external("c.bin");
    std::fs::write(dir.join("c.gltf"), j).unwrap();
    std::fs::write(dir.join("c.bin"), bin).unwrap();
    let (c, report) = load_path(&dir.join("c.gltf")).unwrap();
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(report.triangles, 2);
    assert_eq!(report.degenerate_triangles, 0);
}

#[test]
fn sparse_positions_and_default_scene_selection() {
    let mut d = Doc::single_triangle();
    // Sparse: replace vertex 2 by (0, 5, 0).
    let idx = d.view(&2u16.to_le_bytes());
    let vals = d.view(&[0f32, 5.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>());
    d.json["accessors"][0]["sparse"] =
        json!({"count": 1, "indices": {"bufferView": idx, "componentType": 5123}, "values": {"bufferView": vals}});
    // Scene 1 is the default: it holds a second instance, translated.
    d.json["nodes"].as_array_mut().unwrap().push(json!({"mesh": 0, "translation": [0.0, 0.0, 7.0]}));
    d.json["scenes"].as_array_mut().unwrap().push(json!({"nodes": [1]}));
    d.json["scene"] = json!(1);
    let (mesh, _) = load_slice(&d.glb(), "sparse.glb", None).unwrap();
    assert_eq!(mesh.triangle_count(), 1);
    assert_eq!(mesh.triangle(0)[2], Vec3::new(0.0, 5.0, 7.0));
}

#[test]
fn degenerate_triangles_are_kept_and_counted() {
    let mut d = Doc::new();
    let p = d.positions(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let i = d.indices_u16(&[0, 1, 2, 0, 1, 3, 1, 1, 3]);
    let m = d.mesh(p, Some(i), 4);
    let n = d.node(json!({"mesh": m}));
    d.root(n);
    let (mesh, report) = load_slice(&d.glb(), "degen.glb", None).unwrap();
    assert_eq!(mesh.triangle_count(), 3);
    assert_eq!(report.degenerate_triangles, 2);
}

#[test]
fn embedded_default_scene_loads() {
    let (mesh, report) = gridrt_scene::load_default();
    assert!(mesh.triangle_count() > 1000);
    assert_eq!(report.skipped_primitives.len(), 0);
}

/// Every shared scene, the animated ones included, loads: the load budget and the animation,
/// skin and morph-target validation accept what real exporters write.
#[test]
fn every_shared_scene_loads() {
    let files = gridrt_testkit::shared_scenes_in(&["", "animated"], &["glb", "gltf"]);
    for f in &files {
        let (mesh, report) = load_path(f).unwrap_or_else(|e| panic!("{e}"));
        println!("{}: {} triangles", f.display(), mesh.triangle_count());
        assert!(mesh.triangle_count() > 0 && report.triangles == mesh.triangle_count());
    }
}

/// KHR_mesh_quantization: 8- and 16-bit integer positions, normalized or not, decoded by the
/// accessor rules and dequantized by the node's transform; refused without the extension.
#[test]
fn quantized_positions_load_under_khr_mesh_quantization() {
    // (component type, normalized, the three corners' raw values, what one unit decodes to)
    let cases: [(u32, bool, [[i32; 3]; 3], f32); 5] = [
        (5122, true, [[0, 0, 0], [32767, 0, 0], [0, -32767, 16384]], 1.0 / 32767.0),
        (5123, true, [[0, 0, 0], [65535, 0, 0], [0, 65535, 1000]], 1.0 / 65535.0),
        (5120, true, [[0, 0, 0], [127, 0, 0], [0, -127, 64]], 1.0 / 127.0),
        (5121, false, [[0, 0, 0], [200, 0, 0], [0, 3, 9]], 1.0),
        (5122, false, [[-3, 0, 0], [1000, 0, 0], [0, -20, 7]], 1.0),
    ];
    for (ct, normalized, raw, unit) in cases {
        let size = if matches!(ct, 5120 | 5121) { 1 } else { 2 };
        // Each vertex padded to four bytes, as the extension's alignment rule asks.
        let mut bytes = Vec::new();
        for v in raw {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes()[..size]);
            }
            bytes.resize(bytes.len().next_multiple_of(4), 0);
        }
        let build = |with_extension: bool| {
            let mut d = Doc::new();
            let view = d.view(&bytes);
            d.json["bufferViews"][view]["byteStride"] = json!(4 * (3 * size).div_ceil(4));
            let p = d.push(
                "accessors",
                json!({"bufferView": view, "componentType": ct, "normalized": normalized, "count": 3, "type": "VEC3"}),
            );
            let m = d.mesh(p, None, 4);
            let n = d.node(json!({"mesh": m, "scale": [2.0, 2.0, 2.0], "translation": [1.0, 0.0, 0.0]}));
            d.root(n);
            if with_extension {
                d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
                d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
            }
            d.glb()
        };
        let (mesh, _) = load_slice(&build(true), "quantized.glb", None).unwrap();
        let decode = |c: i32| {
            let v = if normalized { (c as f32 * unit).max(-1.0) } else { c as f32 };
            2.0 * v
        };
        let expected = raw.map(|v| [decode(v[0]) + 1.0, decode(v[1]), decode(v[2])]);
        let got = mesh.triangle(0).map(|p| p.to_array());
        for (g, e) in got.iter().flatten().zip(expected.iter().flatten()) {
            assert!(
                (g - e).abs() <= 1e-6 * e.abs().max(1.0),
                "type {ct} normalized {normalized}: {got:?} against {expected:?}"
            );
        }
        let refused = load_slice(&build(false), "integer.glb", None).unwrap_err();
        assert!(refused.to_string().contains("KHR_mesh_quantization"), "{refused}");
    }
}

#[test]
fn ext_mesh_gpu_instancing_expands_each_instance_in_order() {
    use glam::{DMat4, DQuat, DVec3};
    let corners = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let t = [[0.0f32, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 7.0]];
    let half = std::f32::consts::FRAC_1_SQRT_2;
    // Identity, 90° about z, 90° about x.
    let r = [[0.0f32, 0.0, 0.0, 1.0], [0.0, 0.0, half, half], [half, 0.0, 0.0, half]];
    let s = [[1.0f32, 1.0, 1.0], [2.0, 2.0, 2.0], [1.0, 1.0, 3.0]];
    // Node 0 (root, +10x, ×2) and node 1 (root, +100y) both have node 2 as a child: node 2's
    // three instances appear under each, node 0's visit first.
    let build = |required: bool, edit: &dyn Fn(&mut Doc, usize)| {
        let mut d = Doc::new();
        let p = d.positions(&corners);
        let m = d.mesh(p, None, 4);
        let ta = d.floats(t.as_flattened(), "VEC3", 3);
        let ra = d.floats(r.as_flattened(), "VEC4", 4);
        let sa = d.floats(s.as_flattened(), "VEC3", 3);
        let inst = d.node(json!({"mesh": m, "extensions": {"EXT_mesh_gpu_instancing":
            {"attributes": {"TRANSLATION": ta, "ROTATION": ra, "SCALE": sa}}}}));
        let a = d.node(json!({"children": [inst], "translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0]}));
        let b = d.node(json!({"children": [inst], "translation": [0.0, 100.0, 0.0]}));
        d.root(a);
        d.root(b);
        d.json["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
        if required {
            d.json["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
        }
        edit(&mut d, inst);
        d.glb()
    };
    for required in [true, false] {
        let (mesh, report) = load_slice(&build(required, &|_, _| ()), "instanced.glb", None).unwrap();
        assert_eq!(report.triangles, 6, "three instances under each of two parents");
        let parents = [
            DMat4::from_scale_rotation_translation(DVec3::splat(2.0), DQuat::IDENTITY, DVec3::new(10.0, 0.0, 0.0)),
            DMat4::from_translation(DVec3::new(0.0, 100.0, 0.0)),
        ];
        for (k, parent) in parents.iter().enumerate() {
            for i in 0..3 {
                let q = r[i].map(f64::from);
                let local = DMat4::from_scale_rotation_translation(
                    DVec3::from(s[i].map(f64::from)),
                    DQuat::from_xyzw(q[0], q[1], q[2], q[3]).normalize(),
                    DVec3::from(t[i].map(f64::from)),
                );
                let got = mesh.triangle(3 * k + i);
                for (g, c) in got.iter().zip(corners) {
                    let e = (*parent * local).transform_point3(DVec3::from(c.map(f64::from)));
                    assert!(
                        (g.as_dvec3() - e).abs().max_element() < 1e-5,
                        "parent {k} instance {i}: {got:?}, expected corner {e:?}"
                    );
                }
            }
        }
    }
    // Malformed instancing: an error naming the extension and the node.
    let refused =
        |edit: &dyn Fn(&mut Doc, usize)| load_slice(&build(true, edit), "bad.glb", None).unwrap_err().to_string();
    let different_counts = refused(&|d, n| {
        let two = d.floats(&[1.0, 1.0, 1.0, 2.0, 2.0, 2.0], "VEC3", 3);
        d.json["nodes"][n]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["SCALE"] = json!(two);
    });
    assert!(
        different_counts.contains("EXT_mesh_gpu_instancing") && different_counts.contains("node 0"),
        "{different_counts}"
    );
    let wrong_type = refused(&|d, n| {
        let bytes = d.accessor(&[0u8; 12], 5121, 3, "VEC4");
        d.json["nodes"][n]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] = json!(bytes);
    });
    assert!(wrong_type.contains("ROTATION"), "{wrong_type}");
    let zero_rotation = refused(&|d, n| {
        let zeros = d.floats(&[0.0; 12], "VEC4", 4);
        d.json["nodes"][n]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] = json!(zeros);
    });
    assert!(zero_rotation.contains("zero quaternion"), "{zero_rotation}");
    let missing = refused(&|d, n| {
        d.json["nodes"][n]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = json!(99);
    });
    assert!(missing.contains("does not exist"), "{missing}");
    // An instancing bomb (2^30 instances declared over a 12-byte buffer view) is refused by the
    // budget before anything is read.
    let bomb = refused(&|d, n| {
        let view = d.view(&[0u8; 12]);
        let huge = d
            .push("accessors", json!({"bufferView": view, "componentType": 5126, "count": 1u64 << 30, "type": "VEC3"}));
        let attrs = &mut d.json["nodes"][n]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        *attrs = json!({"TRANSLATION": huge});
    });
    assert!(bomb.contains("--max-triangles") || bomb.contains("--max-load-bytes"), "{bomb}");
}
