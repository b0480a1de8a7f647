//! A corpus of malformed files, generated here, each with the specific error it must produce;
//! plus random corruption of a valid file, which must never panic.

use gridrt_scene::SceneError;
use gridrt_scene::gltf_load::{load_path, load_slice};
use gridrt_scene::rng::Rng;
use serde_json::json;

use super::builder::{Doc, temp_dir};

fn load(bytes: &[u8]) -> Result<usize, SceneError> {
    load_slice(bytes, "case.glb", None).map(|(m, _)| m.triangle_count())
}

/// Runs one case: the error must match `check`, and its message must name the file.
fn expect(name: &str, bytes: &[u8], check: impl Fn(&SceneError) -> bool) {
    match load(bytes) {
        Ok(n) => panic!("{name}: loaded {n} triangles, expected an error"),
        Err(e) => {
            let msg = e.to_string();
            assert!(check(&e), "{name}: wrong error: {e:?}");
            assert!(msg.contains("case.glb"), "{name}: message does not name the file: {msg}");
            println!("{name}: {msg}");
        }
    }
}

fn with_json(mut d: Doc, f: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    f(&mut d.json);
    d.glb()
}

#[test]
fn malformed_corpus_gives_specific_errors() {
    let valid = Doc::single_triangle().glb();
    assert_eq!(load(&valid).unwrap(), 1);
    let mut cases = 0;
    let mut case = |name: &str, bytes: Vec<u8>, check: &dyn Fn(&SceneError) -> bool| {
        expect(name, &bytes, check);
        cases += 1;
    };

    case("empty file", vec![], &|e| matches!(e, SceneError::NotGltf { .. }));
    case("PNG, not glTF", b"\x89PNG\r\n\x1a\n0000000000".to_vec(), &|e| matches!(e, SceneError::NotGltf { .. }));
    case("truncated glb (half)", valid[..valid.len() / 2].to_vec(), &|e| matches!(e, SceneError::TruncatedGlb { .. }));
    case("truncated glb header", valid[..7].to_vec(), &|e| matches!(e, SceneError::TruncatedGlb { .. }));
    // Byte 12..16 is the JSON chunk length: make it run past the end.
    let mut w = valid.clone();
    w[12..16].copy_from_slice(&(valid.len() as u32).to_le_bytes());
    case("chunk longer than file", w, &|e| matches!(e, SceneError::TruncatedGlb { .. }));
    let mut w = valid.clone();
    w[4..8].copy_from_slice(&1u32.to_le_bytes());
    case("glb version 1", w, &|e| matches!(e, SceneError::Unsupported { .. }));
    let mut w = valid.clone();
    w[16..20].copy_from_slice(b"BIN\0");
    case("first chunk not JSON", w, &|e| matches!(e, SceneError::InvalidGlb { .. }));
    case("invalid JSON syntax", br#"{"asset": {"version": "2.0"}, "meshes": [ "#.to_vec(), &|e| {
        matches!(e, SceneError::InvalidJson { .. })
    });
    case(
        "dangling accessor reference",
        with_json(Doc::single_triangle(), |j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(42)),
        &|e| matches!(e, SceneError::InvalidJson { .. }),
    );
    case(
        "accessor count beyond its buffer view",
        with_json(Doc::single_triangle(), |j| j["accessors"][0]["count"] = json!(1000)),
        &|e| matches!(e, SceneError::AccessorOutOfBounds { accessor: 0, .. }),
    );
    case(
        "accessor offset beyond its buffer view",
        with_json(Doc::single_triangle(), |j| j["accessors"][1]["byteOffset"] = json!(64)),
        &|e| matches!(e, SceneError::AccessorOutOfBounds { accessor: 1, semantic: "indices", .. }),
    );
    case(
        "buffer view beyond the buffer",
        with_json(Doc::single_triangle(), |j| j["bufferViews"][0]["byteLength"] = json!(4096)),
        &|e| matches!(e, SceneError::AccessorOutOfBounds { .. } | SceneError::InvalidJson { .. }),
    );
    case(
        "absurd accessor count",
        with_json(Doc::single_triangle(), |j| j["accessors"][0]["count"] = json!(4_000_000_000u64)),
        &|e| matches!(e, SceneError::OverBudget { flag: "--max-load-bytes", .. }),
    );
    case(
        "byteStride smaller than a VEC3",
        with_json(Doc::single_triangle(), |j| j["bufferViews"][0]["byteStride"] = json!(4)),
        &|e| matches!(e, SceneError::InvalidAccessor { semantic: "POSITION", .. }),
    );
    {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let i = d.indices_u16(&[0, 1, 7]);
        let m = d.mesh(p, Some(i), 4);
        let n = d.node(json!({"mesh": m}));
        d.root(n);
        case("index out of range", d.glb(), &|e| {
            matches!(e, SceneError::IndexOutOfRange { index: 7, vertex_count: 3, index_position: 2, .. })
        });
    }
    case(
        "non-float positions",
        with_json(Doc::single_triangle(), |j| {
            j["accessors"][0]["componentType"] = json!(5123);
            j["accessors"][0]["normalized"] = json!(false);
        }),
        &|e| matches!(e, SceneError::NonFloatPositions { accessor: 0, .. }),
    );
    case("VEC2 positions", with_json(Doc::single_triangle(), |j| j["accessors"][0]["type"] = json!("VEC2")), &|e| {
        matches!(e, SceneError::NonFloatPositions { .. } | SceneError::InvalidJson { .. })
    });
    for (what, x) in [("NaN position", f32::NAN), ("infinite position", f32::INFINITY)] {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0; 3], [x, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let m = d.mesh(p, None, 4);
        let n = d.node(json!({"mesh": m}));
        d.root(n);
        case(what, d.glb(), &|e| matches!(e, SceneError::NonFiniteVertex { vertex: 1, .. }));
    }
    case(
        "absurd coordinates after the transform",
        with_json(Doc::single_triangle(), |j| j["nodes"][0]["scale"] = json!([3e37, 3e37, 3e37])),
        &|e| matches!(e, SceneError::CoordinateOutOfRange { node: 0, vertex: 1, .. }),
    );
    case(
        "transform overflows to infinity",
        with_json(Doc::single_triangle(), |j| {
            j["nodes"][0]["scale"] = json!([3e38, 3e38, 3e38]);
            j["nodes"][0]["translation"] = json!([-3e38, 3e38, 3e38]);
        }),
        &|e| {
            matches!(
                e,
                SceneError::NonFiniteVertex { node: Some(0), .. } | SceneError::CoordinateOutOfRange { node: 0, .. }
            )
        },
    );
    case(
        "only points, no triangles",
        with_json(Doc::single_triangle(), |j| j["meshes"][0]["primitives"][0]["mode"] = json!(0)),
        &|e| matches!(e, SceneError::NoTriangles { detail, .. } if detail.contains("Points")),
    );
    case("no meshes at all", with_json(Doc::new(), |_| {}), &|e| matches!(e, SceneError::NoTriangles { .. }));
    case(
        "node cycle",
        with_json(Doc::single_triangle(), |j| {
            j["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
        }),
        &|e| matches!(e, SceneError::InvalidNode { .. } | SceneError::InvalidJson { .. }),
    );
    case(
        "float indices",
        with_json(Doc::single_triangle(), |j| j["accessors"][1]["componentType"] = json!(5126)),
        &|e| matches!(e, SceneError::InvalidAccessor { semantic: "indices", .. } | SceneError::InvalidJson { .. }),
    );
    case(
        "missing POSITION",
        with_json(Doc::single_triangle(), |j| j["meshes"][0]["primitives"][0]["attributes"] = json!({"NORMAL": 0})),
        &|e| matches!(e, SceneError::MissingPositions { .. } | SceneError::InvalidJson { .. }),
    );
    {
        // The buffer declares more bytes than the BIN chunk holds.
        let mut d = Doc::single_triangle();
        let g = {
            d.json["buffers"] = json!([{"byteLength": 10_000}]);
            let mut j = serde_json::to_vec(&d.json).unwrap();
            while !j.len().is_multiple_of(4) {
                j.push(b' ');
            }
            gridrt_scene::glb_write::assemble_glb(&j, Some(&d.bin))
        };
        case("buffer longer than the BIN chunk", g, &|e| matches!(e, SceneError::Buffer { .. }));
    }
    {
        let mut d = Doc::single_triangle();
        d.json["buffers"] = json!([{"byteLength": 44, "uri": "data:application/octet-stream;base64,@@@not-base64@@@"}]);
        let j = serde_json::to_vec(&d.json).unwrap();
        case("bad base64 data URI", j, &|e| matches!(e, SceneError::Buffer { .. }));
    }
    {
        let (j, _) = Doc::single_triangle().gltf_external("missing.bin");
        // Loaded from memory with no base directory.
        case("external buffer without a directory", j, &|e| matches!(e, SceneError::Buffer { .. }));
    }
    println!("{cases} malformed cases");
    assert!(cases >= 15);
}

#[test]
fn file_level_errors_name_the_path() {
    let tmp = temp_dir("files");
    let dir = tmp.path();
    let missing = dir.join("nope.glb");
    let e = load_path(&missing).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }) && e.to_string().contains("nope.glb"), "{e}");
    // A directory is not a scene file.
    let e = load_path(dir).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }), "{e}");
    // External buffer that does not exist next to the .gltf.
    let (j, _) = Doc::single_triangle().gltf_external("gone.bin");
    std::fs::write(dir.join("a.gltf"), j).unwrap();
    let e = load_path(&dir.join("a.gltf")).unwrap_err();
    assert!(matches!(e, SceneError::Buffer { .. }) && e.to_string().contains("gone.bin"), "{e}");
    // External buffer that is a directory.
    std::fs::create_dir_all(dir.join("d.bin")).unwrap();
    let (j, _) = Doc::single_triangle().gltf_external("d.bin");
    std::fs::write(dir.join("b.gltf"), j).unwrap();
    let e = load_path(&dir.join("b.gltf")).unwrap_err();
    assert!(matches!(e, SceneError::Buffer { .. }), "{e}");
    // External buffer shorter than declared.
    let (j, bin) = Doc::single_triangle().gltf_external("short.bin");
    std::fs::write(dir.join("short.bin"), &bin[..bin.len() - 8]).unwrap();
    std::fs::write(dir.join("c.gltf"), j).unwrap();
    let e = load_path(&dir.join("c.gltf")).unwrap_err();
    assert!(matches!(e, SceneError::Buffer { .. }), "{e}");
}

#[test]
fn random_corruption_never_panics() {
    // Flip, truncate and splice bytes of valid files; every outcome must be Ok or a typed error.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    let i = d.indices_u32(&[0, 1, 2, 2, 1, 3]);
    let m = d.mesh(p, Some(i), 4);
    let n = d.node(json!({"mesh": m, "translation": [1.0, 2.0, 3.0]}));
    d.root(n);
    let glb = d.glb();
    let gltf = Doc::single_triangle().gltf_embedded();
    let mut rng = Rng::new(3);
    let mut errors = 0;
    for k in 0..3000 {
        let mut b = if k % 2 == 0 { glb.clone() } else { gltf.clone() };
        match k % 3 {
            0 => {
                for _ in 0..1 + rng.below(4) {
                    let i = rng.below(b.len() as u64) as usize;
                    b[i] = rng.next_u64() as u8;
                }
            }
            1 => b.truncate(rng.below(b.len() as u64) as usize),
            _ => {
                let i = rng.below(b.len() as u64) as usize;
                let v = rng.next_u64().to_le_bytes();
                for (j, x) in v.iter().enumerate() {
                    if i + j < b.len() {
                        b[i + j] = *x;
                    }
                }
            }
        }
        if load(&b).is_err() {
            errors += 1;
        }
    }
    assert!(errors > 1000, "corruption should mostly be detected: {errors}");
}
