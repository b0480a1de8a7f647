//! Hostile files: a generated corpus of small files that describe enormous or forbidden
//! things (node-graph bombs, sparse and morph-target bombs, huge JSON arrays, URIs that leave
//! the folder, broken animation and skin data), plus structured mutation of a rich valid file at
//! the JSON level. Each must end in a typed error or a correct result, quickly, without a
//! panic, and within 1 GiB of peak heap. Its own test binary, because it installs a counting
//! allocator (which also refuses to go past a ceiling, so a regression aborts instead of
//! exhausting the machine).

#[path = "suite/builder.rs"]
#[allow(dead_code)]
mod builder;

use std::alloc::System;
use std::time::{Duration, Instant};

use builder::{Doc, temp_dir};
use cap::Cap;
use gridrt_scene::gltf_load::{load_path_with, load_slice_with};
use gridrt_scene::rng::Rng;
use gridrt_scene::{LoadLimits, SceneError};
use serde_json::{Value, json};

const GIB: usize = 1 << 30;

/// Past this the allocator refuses (the process aborts with "memory allocation … failed").
#[global_allocator]
static ALLOC: Cap<System> = Cap::new(System, 3 * GIB / 2);

/// What a corpus file must give.
#[derive(Debug)]
enum Expect {
    /// An error of this kind (matched by the predicate).
    Error(fn(&SceneError) -> bool),
    /// A load with this many triangles.
    Triangles(usize),
}

struct Case {
    name: &'static str,
    bytes: Vec<u8>,
    expect: Expect,
}

fn over_budget(e: &SceneError) -> bool {
    matches!(e, SceneError::OverBudget { .. })
}

fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    gridrt_scene::glb_write::assemble_glb(&j, if bin.is_empty() { None } else { Some(bin) })
}

fn finish(mut d: Doc) -> Vec<u8> {
    d.json["buffers"] = json!([]);
    let bin = std::mem::take(&mut d.bin);
    let mut j = d.json;
    if !bin.is_empty() {
        j["buffers"] = json!([{"byteLength": bin.len().next_multiple_of(4)}]);
    }
    glb(&j, &bin)
}

/// A chain of `levels` nodes where node i lists node i+1 `fanout` times; the last holds a
/// one-triangle mesh (or nothing).
fn graph_bomb(levels: usize, fanout: usize, with_mesh: bool) -> Vec<u8> {
    let mut d = Doc::single_triangle();
    let mut nodes: Vec<Value> = (0..levels).map(|i| json!({"children": vec![i + 1; fanout]})).collect();
    nodes.push(if with_mesh { json!({"mesh": 0}) } else { json!({}) });
    d.json["nodes"] = Value::Array(nodes);
    d.json["scenes"] = json!([{"nodes": [0]}]);
    finish(d)
}

/// A rich valid file: indexed triangles under a transformed parent, a sparse accessor, a
/// skin with inverse bind matrices, JOINTS/WEIGHTS, a morph target with default weights, and
/// an animation with translation, rotation (CUBICSPLINE) and weight channels.
fn rich_doc() -> Doc {
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    let i = d.indices_u16(&[0, 1, 2, 2, 1, 3]);
    let joints = d.accessor(&[0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0], 5121, 4, "VEC4");
    let weights = d.floats(&[1., 0., 0., 0., 0.5, 0.5, 0., 0., 1., 0., 0., 0., 0.5, 0.5, 0., 0.], "VEC4", 4);
    let delta = d.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3", 3);
    let mut ibm = Vec::new();
    for _ in 0..2 {
        ibm.extend_from_slice(&[1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
    }
    let ibm = d.floats(&ibm, "MAT4", 16);
    // A sparse accessor: zeros except vertex 1.
    let sparse_idx = d.view(&1u16.to_le_bytes());
    let sparse_val = d.view(&[2.0f32, 0.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<_>>());
    let sp = d.push(
        "accessors",
        json!({"componentType": 5126, "count": 3, "type": "VEC3",
               "sparse": {"count": 1, "indices": {"bufferView": sparse_idx, "componentType": 5123},
                          "values": {"bufferView": sparse_val}}}),
    );
    d.push(
        "meshes",
        json!({"primitives": [{"attributes": {"POSITION": p, "JOINTS_0": joints, "WEIGHTS_0": weights},
        "indices": i, "targets": [{"POSITION": delta}]}], "weights": [0.5]}),
    );
    d.push("meshes", json!({"primitives": [{"attributes": {"POSITION": sp}}]}));
    let times = d.floats(&[0.0, 0.5, 1.0], "SCALAR", 1);
    let moves = d.floats(&[0., 0., 0., 1., 0., 0., 2., 0., 0.], "VEC3", 3);
    let cubic_times = d.floats(&[0.0, 1.0], "SCALAR", 1);
    let mut rot = Vec::new();
    for _ in 0..2 {
        rot.extend_from_slice(&[0., 0., 0., 0., 0., 0., 0., 1., 0., 0., 0., 0.]);
    }
    let rot = d.floats(&rot, "VEC4", 4);
    let w = d.floats(&[0.0, 0.5, 1.0], "SCALAR", 1);
    // EXT_mesh_gpu_instancing: two instances, rotations as normalized shorts.
    let inst_t = d.floats(&[0., 0., 0., 0., 0., 4.], "VEC3", 3);
    let r16: Vec<u8> = [0i16, 0, 0, 32767, 0, 23170, 0, 23170].iter().flat_map(|x| x.to_le_bytes()).collect();
    let inst_r = d.accessor(&r16, 5122, 2, "VEC4");
    d.json["accessors"][inst_r]["normalized"] = json!(true);
    let inst_s = d.floats(&[1., 1., 1., 2., 1., 0.5], "VEC3", 3);
    d.json["nodes"] = json!([
        {"children": [1, 2, 3, 4], "translation": [1.0, 2.0, 3.0]},
        {"mesh": 0, "skin": 0},
        {"translation": [0.0, 1.0, 0.0]},
        {"mesh": 1, "scale": [2.0, 2.0, 2.0]},
        {"mesh": 1, "translation": [0.0, 0.0, -3.0], "extensions": {"EXT_mesh_gpu_instancing":
            {"attributes": {"TRANSLATION": inst_t, "ROTATION": inst_r, "SCALE": inst_s}}}}
    ]);
    d.json["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    d.json["scenes"] = json!([{"nodes": [0]}]);
    d.json["skins"] = json!([{"joints": [0, 2], "inverseBindMatrices": ibm}]);
    d.json["animations"] = json!([{
        "samplers": [
            {"input": times, "output": moves},
            {"input": cubic_times, "output": rot, "interpolation": "CUBICSPLINE"},
            {"input": times, "output": w, "interpolation": "STEP"}
        ],
        "channels": [
            {"sampler": 0, "target": {"node": 2, "path": "translation"}},
            {"sampler": 1, "target": {"node": 2, "path": "rotation"}},
            {"sampler": 2, "target": {"node": 1, "path": "weights"}}
        ]
    }]);
    d
}

fn rich_with(f: impl FnOnce(&mut Value)) -> Vec<u8> {
    let mut d = rich_doc();
    f(&mut d.json);
    finish(d)
}

/// The corpus: every file under 1 MB, each with what it must give.
fn corpus() -> Vec<Case> {
    let err = |name, bytes, f: fn(&SceneError) -> bool| Case { name, bytes, expect: Expect::Error(f) };
    let mut c = vec![
        Case { name: "rich valid file", bytes: finish(rich_doc()), expect: Expect::Triangles(5) },
        err("graph bomb, deep (2^28 instances)", graph_bomb(28, 2, true), over_budget),
        err("graph bomb, wide (16 children per level)", graph_bomb(9, 16, true), over_budget),
        err("graph bomb of empty nodes (2^40 visits)", graph_bomb(40, 2, false), over_budget),
        err("graph bomb past 2^128 (saturating counts)", graph_bomb(200, 2, true), over_budget),
        Case {
            name: "2^26 - 1 empty node visits beside a mesh (under the limit: skipped, not walked)",
            bytes: {
                let mut d = Doc::single_triangle();
                let mut nodes: Vec<Value> = (0..25).map(|i| json!({"children": [i + 1, i + 1]})).collect();
                nodes.push(json!({}));
                nodes.push(json!({"mesh": 0}));
                d.json["nodes"] = Value::Array(nodes);
                d.json["scenes"] = json!([{"nodes": [0, 26]}]);
                finish(d)
            },
            expect: Expect::Triangles(1),
        },
        err("chain deeper than the node-depth limit", graph_bomb(30_000, 1, true), |e| {
            matches!(e, SceneError::InvalidNode { .. })
        }),
    ];
    // Sparse bombs: huge counts with no buffer view behind them.
    let sparse = |json: Value| {
        let mut d = Doc::single_triangle();
        d.json["accessors"][0] = json;
        finish(d)
    };
    let sparse_scalar = |count: u64| {
        json!({"componentType": 5125, "count": count, "type": "SCALAR",
            "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}})
    };
    c.push(err("sparse POSITION bomb (805M vertices)", sparse(sparse_accessor(805_306_368, "VEC3")), over_budget));
    c.push(err(
        "zero-filled POSITION bomb (no view, no sparse)",
        sparse(json!({"componentType": 5126, "count": 805_306_368u64, "type": "VEC3"})),
        |e| matches!(e, SceneError::OverBudget { .. } | SceneError::InvalidJson { .. }),
    ));
    c.push(err(
        "dense POSITION count beyond u32",
        sparse(json!({"bufferView": 0, "componentType": 5126, "count": 5_000_000_000u64, "type": "VEC3"})),
        over_budget,
    ));
    c.push(err(
        "sparse index bomb (805M indices)",
        {
            let mut d = Doc::single_triangle();
            d.json["accessors"][1] = sparse_scalar(805_306_368);
            finish(d)
        },
        over_budget,
    ));
    c.push(err(
        "triangle-strip bomb (2^31 indices)",
        {
            let mut d = Doc::single_triangle();
            d.json["accessors"][1] = sparse_scalar(1 << 31);
            d.json["meshes"][0]["primitives"][0]["mode"] = json!(5);
            finish(d)
        },
        over_budget,
    ));
    // A huge sparse accessor appended to the rich document, and `point` aiming a field at it.
    let with_sparse = |count: u64, kind: &'static str, point: fn(&mut Value, usize)| {
        rich_with(move |j| {
            let n = j["accessors"].as_array().unwrap().len();
            j["accessors"].as_array_mut().unwrap().push(sparse_accessor(count, kind));
            point(j, n);
        })
    };
    c.push(err(
        "morph-target bomb (4096 targets × 1M vertices)",
        with_sparse(1_000_000, "VEC3", |j, n| {
            j["meshes"][0]["primitives"][0]["targets"] = Value::Array(vec![json!({"POSITION": n}); 4096]);
        }),
        over_budget,
    ));
    c.push(err(
        "animation-key bomb (10^9 keys)",
        with_sparse(1_000_000_000, "SCALAR", |j, n| j["animations"][0]["samplers"][0]["input"] = json!(n)),
        over_budget,
    ));
    c.push(err(
        "buffer byteLength 2^62",
        {
            let d = rich_doc();
            let mut j = d.json;
            j["buffers"] = json!([{"byteLength": 1u64 << 62}]);
            glb(&j, &d.bin)
        },
        |e| matches!(e, SceneError::OverBudget { .. } | SceneError::Buffer { .. }),
    ));
    // Huge JSON: a quarter of a million empty nodes, 200k numbers in extras, deep nesting.
    c.push(Case {
        name: "250k empty nodes",
        bytes: {
            let mut d = Doc::single_triangle();
            let mut nodes = vec![json!({"mesh": 0})];
            nodes.extend(std::iter::repeat_n(json!({}), 250_000));
            d.json["nodes"] = Value::Array(nodes);
            finish(d)
        },
        expect: Expect::Triangles(1),
    });
    c.push(Case {
        name: "200k numbers in extras",
        bytes: {
            let mut d = Doc::single_triangle();
            d.json["extras"] = Value::Array(vec![json!(1.5); 200_000]);
            finish(d)
        },
        expect: Expect::Triangles(1),
    });
    c.push(err(
        "extras nested 100k deep",
        {
            let body = format!(
                "{{\"asset\":{{\"version\":\"2.0\"}},\"extras\":{}{}}}",
                "[".repeat(100_000),
                "]".repeat(100_000)
            );
            body.into_bytes()
        },
        |e| matches!(e, SceneError::InvalidJson { .. } | SceneError::NoTriangles { .. }),
    ));
    c.push(err(
        "JSON nested 100k deep",
        {
            let body = format!(
                "{{\"asset\":{{\"version\":\"2.0\"}},\"scenes\":{}{}}}",
                "[".repeat(100_000),
                "]".repeat(100_000)
            );
            body.into_bytes()
        },
        |e| matches!(e, SceneError::InvalidJson { .. }),
    ));
    // Broken animation and skin data.
    let anim = |e: &SceneError| matches!(e, SceneError::InvalidAnimation { .. });
    let skin = |e: &SceneError| matches!(e, SceneError::InvalidSkin { .. });
    c.push(err("NaN key time", with_times(&[0.0, f32::NAN, 1.0]), anim));
    c.push(err("non-increasing key times", with_times(&[0.0, 1.0, 1.0]), anim));
    c.push(err("decreasing key times", with_times(&[1.0, 0.5, 2.0]), anim));
    c.push(err(
        "short sampler output",
        rich_with(|j| {
            let out = j["animations"][0]["samplers"][0]["output"].as_u64().unwrap() as usize;
            j["accessors"][out]["count"] = json!(2);
        }),
        |e| matches!(e, SceneError::InvalidAnimation { .. } | SceneError::AccessorOutOfBounds { .. }),
    ));
    c.push(err(
        "CUBICSPLINE output without tangents",
        rich_with(|j| j["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE")),
        anim,
    ));
    c.push(err(
        "weights channel on a node without targets",
        rich_with(|j| j["animations"][0]["channels"][2]["target"]["node"] = json!(3)),
        anim,
    ));
    c.push(err("skin joint index out of range", rich_with(|j| j["skins"][0]["joints"] = json!([0])), skin));
    c.push(err("too few inverse bind matrices", rich_with(|j| j["skins"][0]["joints"] = json!([0, 2, 3])), skin));
    c.push(err(
        "requires Draco compression",
        rich_with(|j| j["extensionsRequired"] = json!(["KHR_draco_mesh_compression"])),
        |e| matches!(e, SceneError::Unsupported { .. }),
    ));
    c.push(Case {
        name: "requires a material extension only",
        bytes: rich_with(|j| j["extensionsRequired"] = json!(["KHR_materials_unlit"])),
        expect: Expect::Triangles(5),
    });
    c.push(err(
        "2^30 instances of a mesh (a sparse accessor with no data)",
        rich_with(|j| {
            let a = j["accessors"].as_array().unwrap().len();
            j["accessors"].as_array_mut().unwrap().push(sparse_accessor(1 << 30, "VEC3"));
            j["nodes"][4]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = json!({"TRANSLATION": a});
        }),
        over_budget,
    ));
    c.push(err("morph weights count mismatch", rich_with(|j| j["meshes"][0]["weights"] = json!([0.5, 0.5])), |e| {
        matches!(e, SceneError::InvalidMorphTargets { .. })
    }));
    c
}

/// A float accessor of `count` elements that are zero but one (sparse, no data of its own).
fn sparse_accessor(count: u64, ty: &str) -> Value {
    json!({"componentType": 5126, "count": count, "type": ty,
        "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}})
}

/// `rich_doc` with the first sampler's key times replaced.
fn with_times(values: &[f32]) -> Vec<u8> {
    let mut d = rich_doc();
    let acc = d.floats(values, "SCALAR", 1);
    d.json["animations"][0]["samplers"][0]["input"] = json!(acc);
    finish(d)
}

/// Loads `bytes`: the triangle count or the error, and the time taken.
fn measure(bytes: &[u8], limits: &LoadLimits) -> (Result<usize, SceneError>, Duration) {
    let t = Instant::now();
    let r = load_slice_with(bytes, "hostile.glb", None, limits).map(|(m, _)| m.triangle_count());
    (r, t.elapsed())
}

fn check_bounds(name: &str, bytes: &[u8], took: Duration) {
    assert!(bytes.len() < 1 << 20, "{name}: the corpus keeps files under 1 MB ({} bytes)", bytes.len());
    assert!(took < Duration::from_secs(10), "{name}: took {took:?}");
    let peak = ALLOC.max_allocated();
    assert!(peak < GIB, "{name}: peak heap {peak} bytes passed 1 GiB");
}

#[test]
fn hostile_corpus_ends_in_errors_or_correct_results_within_bounds() {
    let limits = LoadLimits::default();
    let corpus = corpus();
    assert!(corpus.len() >= 20, "the corpus has {} files", corpus.len());
    for case in &corpus {
        let (r, took) = measure(&case.bytes, &limits);
        match (&case.expect, &r) {
            (Expect::Error(ok), Err(e)) => {
                assert!(ok(e), "{}: wrong error: {e}", case.name);
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "{}: the error is not one line: {msg}", case.name);
                println!("{}: {msg}", case.name);
            }
            (Expect::Triangles(n), Ok(got)) => assert_eq!(got, n, "{}", case.name),
            _ => panic!("{}: expected {:?}, got {r:?}", case.name, case.expect),
        }
        check_bounds(case.name, &case.bytes, took);
    }
    println!("{} hostile files, peak heap {} MiB", corpus.len(), ALLOC.max_allocated() >> 20);
}

#[test]
fn limits_are_honoured_and_name_the_flag() {
    // 1 triangle instanced 2^10 times: over a triangle limit of 1000, within 2000.
    let bomb = graph_bomb(10, 2, true);
    let tight = LoadLimits { max_triangles: 1000, ..LoadLimits::default() };
    let e = load_slice_with(&bomb, "b.glb", None, &tight).unwrap_err();
    assert!(matches!(e, SceneError::OverBudget { flag: "--max-triangles", .. }), "{e}");
    assert!(e.to_string().contains("1024") && e.to_string().contains("1000"), "{e}");
    let loose = LoadLimits { max_triangles: 2000, ..LoadLimits::default() };
    assert_eq!(load_slice_with(&bomb, "b.glb", None, &loose).unwrap().0.triangle_count(), 1024);
    let small = LoadLimits { max_bytes: 1000, ..LoadLimits::default() };
    let e = load_slice_with(&bomb, "b.glb", None, &small).unwrap_err();
    assert!(matches!(e, SceneError::OverBudget { flag: "--max-load-bytes", .. }), "{e}");
    assert!(LoadLimits::default().max_bytes >= 64 << 20);
}

#[test]
fn buffer_uris_stay_inside_the_folder() {
    let tmp = temp_dir("uris");
    let dir = tmp.path();
    let inside = dir.join("scene");
    std::fs::create_dir_all(inside.join("sub")).unwrap();
    std::fs::write(dir.join("secret.bin"), vec![0u8; 64]).unwrap();
    let (_, bin) = Doc::single_triangle().gltf_external("x.bin");
    std::fs::write(inside.join("sub").join("ok bin.bin"), &bin).unwrap();
    let refused = [
        "/etc/passwd",
        "../secret.bin",
        "sub/../../secret.bin",
        "%2e%2e/secret.bin",
        "file:///etc/passwd",
        "file:../secret.bin",
        "http://127.0.0.1/x.bin",
        "C:\\x.bin",
        "%FF.bin",
        "..\\secret.bin",
    ];
    for (k, uri) in refused.iter().enumerate() {
        let (j, _) = Doc::single_triangle().gltf_external(uri);
        let path = inside.join(format!("case{k}.gltf"));
        std::fs::write(&path, j).unwrap();
        let e = load_path_with(&path, &LoadLimits::default()).unwrap_err();
        assert!(matches!(e, SceneError::Buffer { .. }), "{uri}: {e}");
        println!("{uri}: {e}");
    }
    // Relative, percent-encoded and inside the folder: read.
    let (j, _) = Doc::single_triangle().gltf_external("./sub/ok%20bin.bin");
    std::fs::write(inside.join("ok.gltf"), j).unwrap();
    assert_eq!(load_path_with(&inside.join("ok.gltf"), &LoadLimits::default()).unwrap().0.triangle_count(), 1);
}

/// Values that break assumptions when written into a count, index, offset or length.
const NASTY_NUMBERS: [i64; 12] = [0, 1, -1, 2, 3, 255, 65_536, (1 << 31) - 1, 1 << 31, 1 << 32, 805_306_368, 1 << 53];

fn mutate(v: &mut Value, rng: &mut Rng, node_count: usize) {
    // Pick a random leaf or container and change it by the kind of thing it is.
    let mut paths = Vec::new();
    collect_paths(v, &mut paths);
    let path = &paths[rng.below(paths.len() as u64) as usize];
    let target = path.iter().fold(v as &mut Value, |v, k| match k {
        Key::Field(f) => &mut v[f.as_str()],
        Key::Index(i) => &mut v[*i],
    });
    let last = path.last().map(|k| match k {
        Key::Field(f) => f.as_str(),
        Key::Index(_) => "",
    });
    match (last, rng.below(6)) {
        (Some("uri"), _) => {
            let uris = [
                "/etc/passwd",
                "../x.bin",
                "file:///dev/zero",
                "%ZZ",
                "data:,",
                "data:application/octet-stream;base64,AAAA",
            ];
            *target = json!(uris[rng.below(uris.len() as u64) as usize]);
        }
        (Some("children"), _) => {
            // Graph edges: duplicates, self loops, cycles, dangling.
            let mut kids: Vec<Value> = target.as_array().cloned().unwrap_or_default();
            for _ in 0..1 + rng.below(4) {
                kids.push(json!(rng.below(node_count as u64 + 2)));
            }
            *target = Value::Array(kids);
        }
        (_, 0..=2) if target.is_number() => *target = json!(NASTY_NUMBERS[rng.below(12) as usize]),
        (_, 3) if target.is_number() => *target = json!(-target.as_f64().unwrap_or(0.0) * 1e30),
        (_, 4) => *target = Value::Null,
        _ if target.is_array() => {
            let a = target.as_array_mut().unwrap();
            if !a.is_empty() {
                let i = rng.below(a.len() as u64) as usize;
                let copy = a[i].clone();
                for _ in 0..rng.below(3) + 1 {
                    a.push(copy.clone());
                }
            }
        }
        _ => *target = json!(rng.below(8)),
    }
}

enum Key {
    Field(String),
    Index(usize),
}

/// Every path to a field or element of `v`.
fn collect_paths(v: &Value, out: &mut Vec<Vec<Key>>) {
    fn walk(v: &Value, path: &mut Vec<Key>, out: &mut Vec<Vec<Key>>) {
        match v {
            Value::Object(m) => {
                for (k, c) in m {
                    path.push(Key::Field(k.clone()));
                    out.push(path.iter().map(clone_key).collect());
                    walk(c, path, out);
                    path.pop();
                }
            }
            Value::Array(a) => {
                for (i, c) in a.iter().enumerate() {
                    path.push(Key::Index(i));
                    out.push(path.iter().map(clone_key).collect());
                    walk(c, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    walk(v, &mut Vec::new(), out);
}

fn clone_key(k: &Key) -> Key {
    match k {
        Key::Field(f) => Key::Field(f.clone()),
        Key::Index(i) => Key::Index(*i),
    }
}

#[test]
fn structured_json_mutation_never_panics_and_stays_bounded() {
    let base = rich_doc();
    let bin = base.bin.clone();
    let mut json = base.json.clone();
    json["buffers"] = json!([{"byteLength": bin.len().next_multiple_of(4)}]);
    let limits = LoadLimits::default();
    let mut rng = Rng::new(17);
    let (mut ok, mut errors) = (0, 0);
    for k in 0..2500 {
        let mut j = json.clone();
        for _ in 0..1 + rng.below(3) {
            mutate(&mut j, &mut rng, 5);
        }
        let bytes = glb(&j, &bin);
        let (r, took) = measure(&bytes, &limits);
        match r {
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(!e.to_string().contains('\n'), "mutation {k}: {e}");
                errors += 1;
            }
        }
        check_bounds("mutation", &bytes, took);
    }
    println!("{ok} loaded, {errors} refused; peak heap {} MiB", ALLOC.max_allocated() >> 20);
    assert!(errors > 500 && ok > 100, "mutations should both load and fail: {ok} ok, {errors} errors");
}
