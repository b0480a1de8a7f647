//! End-to-end tests of the `gridrt` binary: every subcommand, the file formats between them,
//! and clear failures on bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `GRIDRT_SKIP_GPU_TESTS=1`: the GPU is skipped explicitly (never in CI); commands then run
/// with `--no-gpu` and GPU columns are not asserted.
fn skip_gpu() -> bool {
    std::env::var("GRIDRT_SKIP_GPU_TESTS").is_ok_and(|v| v == "1")
}

/// The binary, without any machine calibration of the cost model (tests stay hermetic).
fn gridrt_cmd() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gridrt"));
    c.env("GRIDRT_CALIBRATION", "/nonexistent/gridrt-calibration.json");
    c
}

fn gridrt(args: &[&str]) -> Output {
    gridrt_cmd().args(args).output().expect("running gridrt")
}

fn ok(args: &[&str]) -> String {
    let out = gridrt(args);
    assert!(
        out.status.success(),
        "gridrt {args:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn fails(args: &[&str], needle: &str) {
    let out = gridrt(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "gridrt {args:?} should fail");
    assert!(err.contains(needle), "gridrt {args:?}: stderr lacks \"{needle}\":\n{err}");
}

/// A path named `name` in a fresh temporary directory, removed with everything under it when
/// the value is dropped (at the end of the test that made it).
struct TmpPath {
    _dir: tempfile::TempDir,
    path: PathBuf,
}

impl std::ops::Deref for TmpPath {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TmpPath {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

fn tmp(name: &str) -> TmpPath {
    let dir = tempfile::Builder::new().prefix("gridrt-cli-test-").tempdir().unwrap();
    let path = dir.path().join(name);
    TmpPath { _dir: dir, path }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn pipeline_gen_info_build_rays_trace() {
    let scene = tmp("tis.glb");
    let out = ok(&["gen", "teapot-in-stadium", "--size", "1", "-o", s(&scene)]);
    assert!(out.contains("1036 triangles"), "{out}");
    let info = ok(&["info", s(&scene), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(v["triangles"], 1036);

    let build = ok(&["build", s(&scene), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&build).unwrap();
    for key in ["resolution", "cells", "refs", "empty_percent", "memory_bytes", "build_ms", "cost_curve"] {
        assert!(!v[key].is_null(), "build --json lacks {key}: {build}");
    }
    // Per phase: the parallel box-inserted build counts and scatters in one phase.
    assert!(v["build_ms"]["bounds"].as_f64().is_some(), "{build}");
    assert!(v["build_ms"]["count and scatter"].as_f64().is_some(), "{build}");
    let text = ok(&["build", s(&scene), "--resolution", "10,20,30", "--exact", "--serial"]);
    assert!(text.contains("10 x 20 x 30"), "{text}");
    for grid in ["macrocell", "multires", "twolevel", "proximity"] {
        let v: serde_json::Value = serde_json::from_str(&ok(&["build", s(&scene), "--grid", grid, "--json"])).unwrap();
        for key in ["nodes", "levels", "depth_histogram", "memory_bytes_per_triangle", "build_ms"] {
            assert!(!v[key].is_null(), "build --grid {grid} --json lacks {key}");
        }
        assert_eq!(v["grid"], grid);
    }
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["build", s(&scene), "--grid", "multires", "--json"])).unwrap();
    assert!(v["levels"].as_u64().unwrap() >= 2, "the teapot-in-stadium cell must be subdivided: {v}");

    for kind in ["random", "camera", "inside"] {
        let rays = tmp(&format!("{kind}.bin"));
        ok(&["rays", s(&scene), "--kind", kind, "--count", "5000", "-o", s(&rays)]);
        assert_eq!(std::fs::metadata(&rays).unwrap().len(), 5000 * 32);
        let reference = tmp(&format!("{kind}-brute.hits"));
        ok(&["trace", s(&scene), "--rays", s(&rays), "-o", s(&reference), "--backend", "brute"]);
        let want = std::fs::read(&reference).unwrap();
        assert_eq!(want.len(), 5000 * 16);
        for traversal in ["aw", "cw", "liu"] {
            for extra in [
                &[][..],
                &["--mailbox", "--exact"][..],
                &["--resolution", "m=7"][..],
                &["--grid", "macrocell", "--mailbox"][..],
                &["--grid", "macrocell", "--macro-size", "4"][..],
                &["--grid", "multires"][..],
                &["--grid", "multires", "--policy", "octree", "--max-depth", "5"][..],
                &["--grid", "multires", "--policy", "max-depth=2", "--exact"][..],
                &["--grid", "multires", "--policy", "constant=3"][..],
                &["--grid", "twolevel", "--mailbox"][..],
                &["--grid", "proximity"][..],
            ] {
                let hits = tmp(&format!("{kind}-{traversal}.hits"));
                let mut args = vec!["trace", s(&scene), "--rays", s(&rays), "-o", s(&hits), "--traversal", traversal];
                args.extend_from_slice(extra);
                let summary = ok(&args);
                assert!(summary.contains("Mrays/s") && summary.contains("cells visited"), "{summary}");
                assert!(
                    std::fs::read(&hits).unwrap() == want,
                    "{kind} {traversal} {extra:?}: hits differ from brute force"
                );
            }
        }
        // Occlusion queries: the same rays hit, each at a real hit no closer than the closest.
        for grid in ["flat", "macrocell", "multires", "twolevel", "proximity"] {
            let hits = tmp(&format!("{kind}-{grid}-any.hits"));
            let args = ["trace", s(&scene), "--rays", s(&rays), "-o", s(&hits), "--grid", grid, "--query", "any"];
            let out = ok(&args);
            assert!(out.contains("any hit"), "{out}");
            assert_any_hits(&std::fs::read(&hits).unwrap(), &want, &format!("{kind} {grid}"));
        }
    }
}

/// `any` (a hits file of `--query any`) against `closest` (brute force's closest hits): the same
/// rays hit, and each any-hit's t is no less than the closest hit's.
fn assert_any_hits(any: &[u8], closest: &[u8], what: &str) {
    assert_eq!(any.len(), closest.len(), "{what}: one hit per ray");
    let field = |h: &[u8], k: usize| [h[4 * k], h[4 * k + 1], h[4 * k + 2], h[4 * k + 3]];
    let mut differ = 0;
    for (a, c) in any.chunks(16).zip(closest.chunks(16)) {
        let (ta, tc) = (f32::from_le_bytes(field(a, 0)), f32::from_le_bytes(field(c, 0)));
        let (ia, ic) = (u32::from_le_bytes(field(a, 1)), u32::from_le_bytes(field(c, 1)));
        if (ia == u32::MAX) != (ic == u32::MAX) {
            panic!("{what}: an any-hit query and the closest hit disagree on whether a ray hits");
        }
        assert!(ia == u32::MAX || ta >= tc, "{what}: an any hit at t {ta} before the closest hit's {tc}");
        differ += (ia != ic) as usize;
    }
    eprintln!("{what}: {differ} of {} any hits are not the closest", any.len() / 16);
}

/// The dynamic path on a generated animated scene: info lists the clip, --animation/--time pose
/// it (grid hits equal brute force over the posed triangles at several times, and differ from
/// the rest pose), animate writes frames, a timeline and JSON, and bench --dynamic compares
/// every grid with the BVH strategies.
#[test]
fn animated_scene_info_pose_trace_animate_and_bench() {
    let scene = tmp("crowd.glb");
    ok(&["gen", "crowd", "--size", "6", "-o", s(&scene)]);
    let v: serde_json::Value = serde_json::from_str(&ok(&["info", s(&scene), "--json"])).unwrap();
    assert_eq!(v["animation"]["clips"][0]["name"], "sway");
    assert_eq!(v["animation"]["skins"], 6);
    let text = ok(&["info", s(&scene), "--animation", "sway", "--time", "1.5"]);
    assert!(text.contains("posed at:    animation 0 \"sway\", t = 1.5 s"), "{text}");
    fails(&["info", s(&scene), "--animation", "walk"], "no animation \"walk\"");
    fails(&["info", "@default", "--time", "1"], "no animations");

    let rays = tmp("crowd-rays.bin");
    ok(&["rays", s(&scene), "--time", "0.7", "--kind", "framed", "--count", "4000", "-o", s(&rays)]);
    let mut poses = Vec::new();
    for time in ["0.7", "2.2", "-5", "99"] {
        let brute = tmp(&format!("crowd-{time}-brute.hits"));
        ok(&["trace", s(&scene), "--time", time, "--rays", s(&rays), "-o", s(&brute), "--backend", "brute"]);
        let want = std::fs::read(&brute).unwrap();
        for grid in ["flat", "macrocell", "multires", "twolevel", "proximity"] {
            let hits = tmp(&format!("crowd-{time}-{grid}.hits"));
            ok(&["trace", s(&scene), "--time", time, "--rays", s(&rays), "-o", s(&hits), "--grid", grid]);
            assert!(std::fs::read(&hits).unwrap() == want, "t = {time}, {grid}: hits differ from brute force");
        }
        poses.push(want);
    }
    assert!(poses[0] != poses[1], "the crowd moves between t = 0.7 and t = 2.2");
    let rest = tmp("crowd-rest.hits");
    ok(&["trace", s(&scene), "--rays", s(&rays), "-o", s(&rest), "--backend", "brute"]);
    assert!(std::fs::read(&rest).unwrap() != poses[0], "a pose differs from the rest pose");

    let frames = tmp("crowd-frames");
    let out = tmp("crowd-timeline");
    let json = ok(&[
        "animate",
        s(&scene),
        "--frames",
        "3",
        "--size",
        "48x32",
        "--grid",
        "twolevel",
        "--frames-dir",
        s(&frames),
        "--out",
        s(&out),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["frames"].as_array().unwrap().len(), 3);
    for key in
        ["time", "pose_ms", "build_ms", "trace_ms", "primary_ms", "shadow_ms", "total_ms", "primary_hits", "shadowed"]
    {
        assert!(!v["frames"][2][key].is_null(), "animate --json lacks {key}: {json}");
    }
    assert!((v["frames"][1]["time"].as_f64().unwrap() - 1.0 / 30.0).abs() < 1e-9);
    assert!(v["frames"][0]["primary_hits"].as_u64().unwrap() > 0);
    for f in ["frame_00000.png", "frame_00002.png"] {
        let img = image::open(frames.join(f)).unwrap();
        assert_eq!((img.width(), img.height()), (48, 32));
    }
    for f in ["timeline.csv", "timeline.json", "timeline.svg", "timeline.png"] {
        assert!(out.join(f).exists(), "animate --out lacks {f}");
    }
    // Packets (the default) and single rays see the same hits and shadows every frame.
    let counts = |packets: &str| -> (serde_json::Value, Vec<(u64, u64)>) {
        let args = ["animate", s(&scene), "--frames", "2", "--size", "40x30", "--grid", "flat", "--packets", packets];
        let v: serde_json::Value = serde_json::from_str(&ok(&[&args[..], &["--json"]].concat())).unwrap();
        let f = v["frames"].as_array().unwrap().iter();
        let counts = f.map(|f| (f["primary_hits"].as_u64().unwrap(), f["shadowed"].as_u64().unwrap())).collect();
        (v["packets"].clone(), counts)
    };
    let (on, with) = counts("on");
    let (off, without) = counts("off");
    assert_eq!((on, off), (serde_json::json!(true), serde_json::json!(false)));
    assert_eq!(with, without, "animate: packets change the hits");
    if !skip_gpu() {
        // The GPU renders every frame with one renderer: the same primary hits as the CPU.
        let args = ["animate", s(&scene), "--frames", "2", "--size", "40x30", "--grid", "flat", "--backend", "gpu"];
        let v: serde_json::Value = serde_json::from_str(&ok(&[&args[..], &["--json"]].concat())).unwrap();
        let gpu: Vec<u64> =
            v["frames"].as_array().unwrap().iter().map(|f| f["primary_hits"].as_u64().unwrap()).collect();
        assert_eq!(gpu, with.iter().map(|c| c.0).collect::<Vec<_>>(), "animate: the GPU's hits differ");
        assert!(v["frames"][1]["primary_ms"].as_f64().unwrap() > 0.0, "{v}");
    }

    let bench = tmp("crowd-bench");
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "bench",
        "--dynamic",
        "--procedural",
        "--quick",
        "--frames",
        "2",
        "--out",
        s(&bench),
        "--json",
    ]))
    .unwrap();
    let rows = v["rows"].as_array().unwrap();
    for refit in ["obvhs BVH2 medium, refit", "bvh, update_shapes"] {
        assert!(rows.iter().any(|r| r["structure"] == refit && r["strategy"] == "refit"), "no {refit} row");
    }
    // Every structure that uses the grids' triangle test agrees with the flat grid on every ray
    // (the updated trees too: an update may slow a tree, never change its hits).
    for r in rows.iter().filter(|r| r["family"] == "grid" || r["strategy"] == "refit") {
        assert_eq!(r["mismatches"], 0, "{r}");
    }
    // The trace split into its primary and shadow rays.
    for r in rows {
        let ms = |k: &str| r[k].as_f64().unwrap();
        assert!(ms("primary_ms") > 0.0 && ms("shadow_ms") > 0.0, "{r}");
        assert!((ms("primary_ms") + ms("shadow_ms") - ms("trace_ms")).abs() <= 1e-6 * ms("trace_ms"), "{r}");
    }
    assert!(v["targets"][0]["speedup"].as_f64().unwrap() > 0.0);
}

#[test]
fn bad_inputs_fail_with_clear_messages() {
    let scene = tmp("one.glb");
    ok(&["gen", "particles", "--size", "50", "-o", s(&scene)]);
    let bad = tmp("bad.bin");
    std::fs::write(&bad, [0u8; 33]).unwrap();
    fails(&["trace", s(&scene), "--rays", s(&bad), "-o", s(&tmp("x.hits"))], "not a multiple of 32");
    let junk = tmp("junk.glb");
    std::fs::write(&junk, b"hello world").unwrap();
    fails(&["info", s(&junk)], "not a glTF file");
    fails(&["info", s(&tmp("missing.glb"))], "missing.glb");
    fails(&["build", s(&scene), "--resolution", "m=0"], "m must be");
    fails(&["build", s(&scene), "--resolution", "bogus"], "bad resolution");
    fails(&["trace", s(&scene), "--rays", s(&bad), "-o", "x", "--traversal", "zigzag"], "unknown traversal");
    fails(&["build", s(&scene), "--t-step", "0"], "Tstep");
    fails(&["build", s(&scene), "--grid", "octree"], "unknown grid");
    fails(&["build", s(&scene), "--grid", "macrocell", "--macro-size", "3"], "power of two");
    fails(&["build", s(&scene), "--grid", "multires", "--policy", "fancy"], "unknown policy");
}

/// A .glb of `json` and `bin`.
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    gridrt_scene::glb_write::assemble_glb(&j, Some(bin))
}

/// Runs gridrt under a 2 GiB address-space limit; returns the exit code and stderr.
fn run_limited(args: &[&str]) -> (Option<i32>, String, std::time::Duration) {
    let start = std::time::Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2097152 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_gridrt"))
        .args(args)
        .env("GRIDRT_CALIBRATION", "/nonexistent/gridrt-calibration.json")
        .output()
        .expect("running gridrt under ulimit");
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned(), start.elapsed())
}

/// Hostile files and oversized requests, as a new user would meet them: each ends in a
/// one-line error with exit code 1 (a bad flag: 2) within 2 GiB of address space and 30 s.
#[test]
fn hostile_files_and_sizes_end_in_one_line_errors() {
    use serde_json::json;
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.].iter().flat_map(|x| x.to_le_bytes()).collect();
    let base = |nodes: serde_json::Value, accessor: serde_json::Value| {
        json!({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}], "accessors": [accessor],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": nodes, "scenes": [{"nodes": [0]}]})
    };
    let dense = json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"});
    let chain = |levels: usize, fanout: usize| {
        let mut n: Vec<serde_json::Value> = (0..levels).map(|i| json!({"children": vec![i + 1; fanout]})).collect();
        n.push(json!({"mesh": 0}));
        serde_json::Value::Array(n)
    };
    let files = [
        ("graph-bomb.glb", glb(&base(chain(29, 2), dense.clone()), &tri), "--max-triangles"),
        ("wide-bomb.glb", glb(&base(chain(8, 16), dense.clone()), &tri), "--max-triangles"),
        (
            "sparse-bomb.glb",
            glb(
                &base(
                    json!([{"mesh": 0}]),
                    json!({"componentType": 5126, "count": 805_306_368u64, "type": "VEC3",
                        "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}}),
                ),
                &tri,
            ),
            "--max-load-bytes",
        ),
    ];
    let mut cases: Vec<(Vec<String>, &str, i32)> = Vec::new();
    let mut written = Vec::new();
    for (name, bytes, needle) in &files {
        let path = tmp(name);
        std::fs::write(&path, bytes).unwrap();
        cases.push((vec!["info".into(), s(&path).into()], needle, 1));
        written.push(path);
    }
    let mut uri = base(json!([{"mesh": 0}]), dense);
    uri["buffers"][0]["uri"] = json!("/etc/passwd");
    let gltf = tmp("absolute-uri.gltf");
    std::fs::write(&gltf, serde_json::to_vec(&uri).unwrap()).unwrap();
    cases.push((vec!["info".into(), s(&gltf).into()], "absolute path", 1));
    let words = |a: &[&str]| a.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    for (args, needle, code) in [
        (&["build", "@default", "--resolution", "1024,1024,1024"][..], "--max-cells", 1),
        (&["build", "@default", "--resolution", "density=1e9"], "--max-cells", 1),
        (&["build", "@default", "--grid", "twolevel", "--top-density", "inf"], "finite", 1),
        (&["build", "@default", "--grid", "twolevel", "--leaf-density", "1e6"], "--max-cells", 1),
        (&["build", "@default", "--grid", "multires", "--density", "1e9"], "--max-cells", 1),
        (&["trace", "@default", "--rays", "/dev/zero", "-o", "/dev/null"], "not a regular file", 1),
        (&["gen", "sphereflake", "--size", "9", "-o", "/dev/null"], "out of range", 1),
        (&["gen", "particles", "--size", "0", "-o", "/dev/null"], "out of range", 1),
        (&["render", "@default", "--camera", "1,2,3,1,2,3,45", "-o", "/dev/null"], "same point", 2),
        (&["render", "@default", "--camera", "3e38,0,0,-3e38,0,0,45", "-o", "/dev/null"], "too far apart", 2),
        (&["render", "@default", "--heat-max", "0", "-o", "/dev/null"], "positive", 2),
        (&["bench", "--rays", "0"], "at least 1", 2),
        (&["rays", "@default", "--kind", "random", "--count", "1000000000000", "-o", "/dev/null"], "memory", 2),
        (&["--view", "bogus"], "unknown view", 2),
        (&["--camera", "sideways"], "expected auto, framed, interior", 2),
        (&["info", "@default", "--max-load-bytes", "12Q"], "unit", 2),
    ] {
        cases.push((words(args), needle, code));
    }
    for (args, needle, code) in &cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (got, err, took) = run_limited(&a);
        let err = err.trim();
        println!("{args:?}: {err}");
        assert_eq!(got, Some(*code), "{args:?}: exit code, stderr: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: not one line: {err}");
        assert!(err.contains(needle), "{args:?}: \"{needle}\" missing: {err}");
        assert!(took.as_secs() < 30, "{args:?} took {took:?}");
    }
}

#[test]
fn help_on_everything_and_default_scene() {
    for sub in [&[][..], &["info"], &["build"], &["gen"], &["rays"], &["trace"]] {
        let mut a = sub.to_vec();
        a.push("--help");
        let out = ok(&a);
        assert!(out.contains("Usage"), "{a:?}: {out}");
    }
    let info = ok(&["info", "@default"]);
    assert!(info.contains("embedded"), "{info}");
}

#[test]
fn experiments_write_rows_and_charts() {
    let out = tmp("experiments");
    for (name, extra) in [
        ("bresenham", &[][..]),
        ("models", &[][..]),
        ("fig5", &["--procedural"][..]),
        ("hierarchy", &["--procedural"][..]),
        ("cgt", &["--procedural"][..]),
    ] {
        let mut args = vec!["experiment", name, "--quick", "--out", s(&out)];
        args.extend_from_slice(extra);
        if skip_gpu() {
            args.push("--no-gpu");
        }
        let text = ok(&args);
        assert!(text.contains("wrote"), "{name}: {text}");
        let csv = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        assert!(csv.lines().count() >= 3, "{name}.csv has too few rows:\n{csv}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join(format!("{name}.json"))).unwrap()).unwrap();
        assert!(json.as_array().is_some_and(|a| !a.is_empty()), "{name}.json");
    }
    let charts = [
        "bresenham",
        "models",
        "fig5-sphereflakeprocedural-time",
        "fig5-particlesprocedural-size",
        "hierarchy-cpu-mrays",
        "cgt-speedup",
        "cgt-tile",
        "cgt-resolution",
    ];
    let gpu_charts = if skip_gpu() { &[][..] } else { &["hierarchy-gpu-mrays"][..] };
    for chart in charts.iter().chain(gpu_charts) {
        assert!(std::fs::read_to_string(out.join(format!("{chart}.svg"))).unwrap().contains("<svg"), "{chart}.svg");
        let png = image::open(out.join(format!("{chart}.png"))).unwrap().to_rgb8();
        assert!(png.pixels().any(|p| p.0 != [255, 255, 255]), "{chart}.png is blank");
    }
    // fig5 marks exactly one auto-chosen m per scene.
    let fig5: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fig5.json")).unwrap()).unwrap();
    let autos = fig5.as_array().unwrap().iter().filter(|r| r["auto"] == true).count();
    assert_eq!(autos, 2, "two procedural scenes, one auto m each");
    // cgt: every image traced single and in packets, the packets' hits equal bit for bit.
    let cgt: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cgt.json")).unwrap()).unwrap();
    let rows = cgt.as_array().unwrap();
    // 2 scenes × 3 grids (flat, macrocell, twolevel) × 2 ray kinds: at 96² single + 8×8, at
    // 192² single + 4×4 + 8×8.
    assert_eq!(rows.len(), 2 * 3 * 2 * 5, "{rows:?}");
    assert!(rows.iter().all(|r| r["mismatches"] == 0 && r["ms"].as_f64().unwrap() > 0.0));
    assert!(rows.iter().any(|r| r["tile"] == 8 && r["packets"].as_u64().unwrap() > 0), "some packets walked");
    let hier: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("hierarchy.json")).unwrap()).unwrap();
    let rows = hier.as_array().unwrap();
    assert_eq!(rows.len(), 10, "2 scenes × 5 structures");
    assert!(rows.iter().all(|r| r["cpu_mrays_s"].as_f64().unwrap() > 0.0));
    if !skip_gpu() {
        assert!(rows.iter().all(|r| r["gpu_mrays_s"].as_f64().unwrap() > 0.0));
    }
    fails(&["experiment", "fig5", "--scenes", "/nonexistent", "--out", s(&out)], "manifest.json");

    // cost-constants: a fit, and with --save a calibration that auto resolution then uses.
    let cal = out.join("calibration.json");
    let o = gridrt_cmd()
        .args(["experiment", "cost-constants", "--quick", "--procedural", "--save", "--out", s(&out)])
        .args(skip_gpu().then_some("--no-gpu"))
        .env("GRIDRT_CALIBRATION", &cal)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fit: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    for k in ["t_setup", "t_step", "t_inter", "rel_rms_error", "r_squared"] {
        assert!(fit["cpu"][k].as_f64().is_some_and(f64::is_finite), "cpu.{k}: {fit}");
    }
    let o = gridrt_cmd().args(["build", "@default"]).env("GRIDRT_CALIBRATION", &cal).output().unwrap();
    assert!(o.status.success(), "build with the calibration {fit}: {}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("calibrated constants"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o =
        gridrt_cmd().args(["build", "@default", "--t-step", "0.2"]).env("GRIDRT_CALIBRATION", &cal).output().unwrap();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("calibrated"), "explicit constants win");
}

#[test]
fn demo_runs_and_checks_itself() {
    let out = ok(&["demo"]);
    assert!(out.contains("brute-force check: 2000 of 2000"), "{out}");
}

#[test]
fn gpu_trace_and_render() {
    if skip_gpu() {
        eprintln!("GRIDRT_SKIP_GPU_TESTS=1: skipping");
        return;
    }
    let scene = tmp("gpu-scene.glb");
    ok(&["gen", "sphereflake", "--size", "1", "-o", s(&scene)]);
    let rays = tmp("gpu-rays.bin");
    ok(&["rays", s(&scene), "--kind", "random", "--count", "20000", "-o", s(&rays)]);
    let cpu = tmp("cpu.hits");
    ok(&["trace", s(&scene), "--rays", s(&rays), "-o", s(&cpu)]);
    for grid in ["flat", "macrocell", "multires", "twolevel", "proximity"] {
        let gpu = tmp(&format!("gpu-{grid}.hits"));
        let out = ok(&[
            "trace",
            s(&scene),
            "--rays",
            s(&rays),
            "-o",
            s(&gpu),
            "--backend",
            "gpu",
            "--grid",
            grid,
            "--traversal",
            "liu",
        ]);
        assert!(out.contains("on the GPU"), "{out}");
        let (a, b) = (std::fs::read(&cpu).unwrap(), std::fs::read(&gpu).unwrap());
        assert_eq!(a.len(), b.len());
        let same = a.chunks(16).zip(b.chunks(16)).filter(|(x, y)| x[4..8] == y[4..8]).count();
        assert!(same >= a.len() / 16 - 2, "{grid}: only {same} of {} rays hit the same triangle", a.len() / 16);
    }
    let brute = tmp("gpu-brute.hits");
    ok(&["trace", s(&scene), "--rays", s(&rays), "-o", s(&brute), "--backend", "brute"]);
    for grid in ["flat", "macrocell", "proximity"] {
        let any = tmp(&format!("gpu-{grid}-any.hits"));
        let args = ["trace", s(&scene), "--rays", s(&rays), "-o", s(&any), "--backend", "gpu", "--grid", grid];
        ok(&[&args[..], &["--query", "any"]].concat());
        assert_any_hits(&std::fs::read(&any).unwrap(), &std::fs::read(&brute).unwrap(), &format!("GPU {grid}"));
    }
    let png = tmp("render.png");
    let out = ok(&[
        "render",
        s(&scene),
        "--size",
        "160x120",
        "--view",
        "heatmap-cells",
        "--grid",
        "macrocell",
        "-o",
        s(&png),
    ]);
    assert!(out.contains("colour scale"), "{out}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // On a software adapter the GPU commands point to the CPU backend (and on no other).
    let out = gridrt(&["render", s(&scene), "--size", "64x48", "--camera", "0,0.5,6,0,0,0,40", "-o", s(&png)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let adapter = err.lines().find(|l| l.starts_with("GPU adapter:")).unwrap_or_else(|| panic!("no adapter:\n{err}"));
    assert_eq!(adapter.ends_with(", Cpu)"), err.contains("`--backend cpu` gives the same results"), "{err}");
    // The GPU frame's passes timed apart: the shaded view traces shadow rays, a heatmap none.
    for (view, shadows) in [("shaded", true), ("heatmap-tests", false)] {
        let out = ok(&["render", s(&scene), "--size", "64x48", "--view", view, "--json", "-o", s(&png)]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["backend"], "gpu", "{out}");
        assert!(v["primary_ms"].as_f64().unwrap() > 0.0, "{out}");
        assert_eq!(v["shadow_ms"].as_f64().is_some_and(|ms| ms > 0.0), shadows, "{out}");
    }
    fails(&["render", s(&scene), "--view", "xray", "-o", s(&png)], "unknown view");
    fails(&["render", s(&scene), "--size", "0x10", "-o", s(&png)], "width and height");
    // Larger than one dispatch and one storage binding: rendered in tiles.
    let big = tmp("render-2304.png");
    ok(&["render", "@default", "--size", "2304x2304", "-o", s(&big)]);
    let img = image::open(&big).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (2304, 2304));
    let centre = centre_pixels(&img);
    assert!(centre.iter().any(|p| p.iter().map(|&c| c as u32).sum::<u32>() > 200), "the 2304² render is blank");
    let bench = ok(&["bench-trace", s(&scene), "--rays", "2000", "--repeat", "1"]);
    assert!(bench.contains("GPU Mrays/s") && bench.contains("primary") && bench.contains("random"), "{bench}");
}

/// An Xvfb server on a free display, killed on drop.
struct Xvfb {
    child: std::process::Child,
    display: String,
}

impl Xvfb {
    /// Runs the app with `args` on this display: whether it succeeded, and its stdout and stderr.
    fn app(&self, args: &[&str]) -> (bool, String) {
        let out = gridrt_cmd()
            .args(args)
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("running the app");
        (
            out.status.success(),
            format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)),
        )
    }

    fn start() -> Xvfb {
        for n in 90..200 {
            if Path::new(&format!("/tmp/.X{n}-lock")).exists() || Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                continue;
            }
            let child = Command::new("Xvfb")
                .args([&format!(":{n}"), "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .expect("starting Xvfb (apt-get install xvfb; .ci/run installs it)");
            let mut x = Xvfb { child, display: format!(":{n}") };
            for _ in 0..100 {
                if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                    return x;
                }
                if let Ok(Some(status)) = x.child.try_wait() {
                    panic!("Xvfb :{n} exited: {status}");
                }
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            panic!("Xvfb :{n} did not come up");
        }
        panic!("no free X display");
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The central image region of a screenshot (between the side panels), as RGB triples.
fn centre_pixels(img: &image::RgbaImage) -> Vec<[u8; 3]> {
    let (w, h) = img.dimensions();
    let mut v = Vec::new();
    for y in (h / 4)..(3 * h / 4) {
        for x in (2 * w / 5)..(3 * w / 5) {
            let p = img.get_pixel(x, y).0;
            v.push([p[0], p[1], p[2]]);
        }
    }
    v
}

/// The desktop app in its real window, under Xvfb on the software adapter: for every grid
/// kind a few frames are rendered and the window is saved; the images are not blank, and the
/// cells-visited heatmaps of the flat and macrocell grids differ on teapot-in-stadium.
#[test]
fn app_screenshots_under_xvfb() {
    if skip_gpu() {
        eprintln!("GRIDRT_SKIP_GPU_TESTS=1: skipping");
        return;
    }
    let x = Xvfb::start();
    let scene = tmp("app-teapot.glb");
    ok(&["gen", "teapot-in-stadium", "--size", "1", "-o", s(&scene)]);
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let shot_on = |grid: &str, view: &str, packets: &str, cpu: bool| -> image::RgbaImage {
        let png = out_dir.join(format!("app-{grid}-{view}-packets-{packets}-cpu-{cpu}.png"));
        let _ = std::fs::remove_file(&png);
        let out = gridrt_cmd()
            // Inside the stadium, close to the knot: the walls are far behind it.
            .args([s(&scene), "--screenshot", s(&png), "--frames", "2", "--grid", grid, "--view", view])
            .args(["--camera", "0.25,0.18,0.35,0,0,0,50", "--render-scale", "0.5", "--packets", packets])
            .args(["--trace-on", if cpu { "cpu" } else { "gpu" }])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("running the app");
        let log = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        assert!(out.status.success(), "app --grid {grid} --view {view} failed:\n{log}");
        assert!(log.contains("saved"), "{log}");
        println!("{grid} {view}: {}", log.lines().find(|l| l.contains("saved")).unwrap_or_default());
        image::open(&png).expect("reading the screenshot").to_rgba8()
    };
    let shot = |grid: &str, view: &str, packets: &str| shot_on(grid, view, packets, false);
    for grid in ["flat", "macrocell", "multires", "twolevel", "proximity"] {
        let img = shot(grid, "shaded", "off");
        assert!(img.width() >= 640 && img.height() >= 400, "{grid}: {}x{}", img.width(), img.height());
        let px = centre_pixels(&img);
        let mut colours = px.clone();
        colours.sort();
        colours.dedup();
        assert!(colours.len() > 50, "{grid}: the image looks blank ({} colours)", colours.len());
        // The scene is lit: a fair share of the centre is brighter than the background.
        let bright = px.iter().filter(|p| p.iter().map(|&c| c as u32).sum::<u32>() > 200).count();
        assert!(bright * 10 > px.len(), "{grid}: only {bright} of {} centre pixels are lit", px.len());
    }
    let flat = centre_pixels(&shot("flat", "heatmap-cells", "off"));
    let macrocell = centre_pixels(&shot("macrocell", "heatmap-cells", "off"));
    let differ = flat.iter().zip(&macrocell).filter(|(a, b)| a != b).count();
    println!("heatmap-cells: {differ} of {} centre pixels differ between flat and macrocell", flat.len());
    assert!(differ * 20 > flat.len(), "flat and macrocell heatmaps should differ: {differ} of {}", flat.len());

    // Coherent packets (the packet kernels): the same shaded image.
    let (single, packets) =
        (centre_pixels(&shot("flat", "shaded", "off")), centre_pixels(&shot("flat", "shaded", "on")));
    assert_eq!(single, packets, "the app's flat frame in packets differs from single rays");

    // Frames traced on the CPU (`--trace-on cpu`): the GPU's image, in single rays, in packets and
    // in a heatmap.
    for (grid, view, packets) in
        [("flat", "shaded", "off"), ("macrocell", "shaded", "on"), ("macrocell", "heatmap-cells", "off")]
    {
        let (gpu, cpu) =
            (centre_pixels(&shot(grid, view, packets)), centre_pixels(&shot_on(grid, view, packets, true)));
        let differ = gpu.iter().zip(&cpu).filter(|(a, b)| a != b).count();
        assert_eq!(
            differ,
            0,
            "{grid} {view} packets {packets}: {differ} of {} centre pixels differ on the CPU",
            gpu.len()
        );
    }

    // A screenshot of `scene` with the flags `extra`: its centre pixels and the run's log.
    let shot_with = |scene: &Path, png: &str, extra: &[&str]| -> (Vec<[u8; 3]>, String) {
        let png = out_dir.join(png);
        let _ = std::fs::remove_file(&png);
        let mut args = vec![s(scene), "--screenshot", s(&png)];
        args.extend_from_slice(extra);
        let (succeeded, log) = x.app(&args);
        assert!(succeeded, "app {extra:?} failed:\n{log}");
        (centre_pixels(&image::open(&png).expect("reading the screenshot").to_rgba8()), log)
    };

    // A scene the device cannot hold (its storage bindings capped below the triangles' size by
    // `--max-gpu-buffer`): the app keeps it on the CPU, which traces the frames, and says why;
    // the image is the one `--cpu-trace` gives. (Asked to trace on the GPU, which auto would
    // not do on a software adapter.)
    let teapot =
        ["--frames", "2", "--grid", "macrocell", "--view", "shaded", "--render-scale", "0.5", "--packets", "on"];
    let inside = ["--camera", "0.25,0.18,0.35,0,0,0,50"];
    let (capped, log) = shot_with(
        scene.as_ref(),
        "app-capped.png",
        &[&teapot[..], &inside, &["--max-gpu-buffer", "4K", "--trace-on", "gpu"]].concat(),
    );
    assert!(
        log.contains("on the CPU,") && log.contains("the device cannot hold the triangles"),
        "the capped device's frames should be traced on the CPU, saying why:\n{log}"
    );
    let (cpu, _) = shot_with(scene.as_ref(), "app-capped-cpu.png", &[&teapot[..], &inside, &["--cpu-trace"]].concat());
    let differ = capped.iter().zip(&cpu).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} of {} centre pixels differ from --cpu-trace's", cpu.len());
    // A grid the device cannot hold while it holds the triangles: a fan of 200 thin triangles
    // (9,600 bytes on the device) whose references take about twice that. Asked to build on the
    // GPU, the app builds on the CPU instead and traces there.
    let fan = tmp("app-fan.glb");
    let ring = (0..200).map(|k| {
        let a = k as f32 * std::f32::consts::TAU / 200.0;
        glam::Vec3::new(a.cos(), 0.3 * (5.0 * a).sin(), a.sin())
    });
    let mesh = gridrt_scene::Mesh {
        positions: std::iter::once(glam::Vec3::ZERO).chain(ring).collect(),
        indices: (0..200u32).map(|k| [0, 1 + k, 1 + (k + 1) % 200]).collect(),
    };
    std::fs::write(&fan, gridrt_scene::glb_write::to_glb(&mesh, "fan")).unwrap();
    let fan_flags = ["--frames", "3", "--render-scale", "0.5"];
    let (capped, log) = shot_with(
        fan.as_ref(),
        "app-fan-capped.png",
        &[&fan_flags[..], &["--max-gpu-buffer", "12K", "--gpu-build", "--trace-on", "gpu"]].concat(),
    );
    assert!(
        log.contains("on the CPU,") && log.contains("the device cannot hold the refs"),
        "the fan's grid should be traced on the CPU, saying why:\n{log}"
    );
    let (cpu, _) = shot_with(fan.as_ref(), "app-fan-cpu.png", &[&fan_flags[..], &["--trace-on", "cpu"]].concat());
    let differ = capped.iter().zip(&cpu).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "the fan: {differ} of {} centre pixels differ from --cpu-trace's", cpu.len());

    // `--camera auto|framed|interior` (the Camera menu's views): the framed view fills the image
    // with the model, so its centre is lit and differs from the bounds-framing view's.
    // These run with the default `--trace-on auto`: the CPU traces on a software adapter.
    let view_shot = |camera: &str| -> Vec<[u8; 3]> {
        let png = out_dir.join(format!("app-camera-{camera}.png"));
        let (succeeded, log) =
            x.app(&[s(&scene), "--screenshot", s(&png), "--frames", "2", "--render-scale", "0.5", "--camera", camera]);
        assert!(succeeded && log.contains("saved"), "app --camera {camera} failed:\n{log}");
        let software = log.contains(", Cpu)");
        assert!(
            log.contains("trace on auto") && log.contains(if software { "ms on the CPU" } else { "ms on the GPU" }),
            "auto should trace on the {}:\n{log}",
            if software { "CPU (software adapter)" } else { "GPU" }
        );
        centre_pixels(&image::open(&png).expect("reading the screenshot").to_rgba8())
    };
    let auto = view_shot("auto");
    for camera in ["framed", "interior"] {
        let px = view_shot(camera);
        let differ = px.iter().zip(&auto).filter(|(a, b)| a != b).count();
        assert!(differ * 4 > px.len(), "--camera {camera}: only {differ} of {} centre pixels moved", px.len());
        let bright = px.iter().filter(|p| p.iter().map(|&c| c as u32).sum::<u32>() > 200).count();
        assert!(bright * 2 > px.len(), "--camera {camera}: only {bright} of {} centre pixels are lit", px.len());
    }

    // A 3840×2160 frame (more pixels than one storage binding holds): rendered in tiles.
    let png = out_dir.join("app-3840x2160.png");
    let (succeeded, log) =
        x.app(&["--screenshot", s(&png), "--frames", "1", "--frame-size", "3840x2160", "--trace-on", "gpu"]);
    assert!(
        succeeded && log.contains("last frame 3840x2160") && log.contains("on the GPU"),
        "a 3840x2160 frame:\n{log}"
    );

    // The cost-model window's measurement: a flat grid timed at every sampled resolution.
    let png = out_dir.join("app-cost-model.png");
    let out = gridrt_cmd()
        .args(["--screenshot", s(&png), "--frames", "1", "--measure", "--render-scale", "0.3", "--open", "explainer"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("running the app");
    let log = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "--measure failed: {log}{}", String::from_utf8_lossy(&out.stderr));
    let timed: usize = log
        .split("cost model: ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no measurement in: {log}"));
    assert!(timed >= 2, "{log}");
    println!("{log}");

    // An animated scene plays: every shown frame posed, rebuilt and rendered; paused at two
    // times it shows two poses; an unknown clip fails the run.
    let crowd = tmp("app-crowd.glb");
    ok(&["gen", "crowd", "--size", "4", "-o", s(&crowd)]);
    let app = |args: &[&str]| {
        let out = gridrt_cmd()
            .arg(s(&crowd))
            .args(args)
            .args(["--render-scale", "0.3"])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("running the app");
        let log = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        (out.status.success(), log)
    };
    let png = out_dir.join("app-crowd-playing.png");
    let (good, log) = app(&["--screenshot", s(&png), "--frames", "8", "--grid", "macrocell"]);
    assert!(good, "playing the crowd:\n{log}");
    // Animation frames shown, from the smoke run's log.
    let shown = |log: &str| -> u64 {
        log.split("animation: ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no animation stats in: {log}"))
    };
    assert!(shown(&log) >= 6, "only {} animation frames shown: {log}", shown(&log));
    assert!(log.contains(" fps (pose "), "{log}");
    println!("{}", log.lines().find(|l| l.contains("saved")).unwrap_or_default());
    let paused = |t: &str| {
        let png = out_dir.join(format!("app-crowd-{t}.png"));
        let (good, log) = app(&["--screenshot", s(&png), "--frames", "1", "--paused", "--time", t]);
        // One pose, shown once or (when a settings change rebuilds it before the screenshot,
        // which depends on timing) twice.
        assert!(good && (1..=2).contains(&shown(&log)), "paused at {t}:\n{log}");
        centre_pixels(&image::open(&png).expect("reading the screenshot").to_rgba8())
    };
    let (a, b) = (paused("0.3"), paused("2.1"));
    let differ = a.iter().zip(&b).filter(|(p, q)| p != q).count();
    assert!(differ * 100 > a.len(), "the poses at 0.3 s and 2.1 s look the same ({differ} pixels differ)");
    // Rebuilt on the GPU every frame (the same grid; its stats show it was built there).
    let png = out_dir.join("app-crowd-gpu-build.png");
    let (good, log) = app(&["--screenshot", s(&png), "--frames", "5", "--gpu-build", "--trace-on", "gpu"]);
    assert!(good && log.contains("structure built on the GPU"), "--gpu-build:\n{log}");
    // One frame more or less than asked: the screenshot's own frame may show the next pose.
    assert!((4..=6).contains(&shown(&log)), "{log}");
    println!("{}", log.lines().find(|l| l.contains("saved")).unwrap_or_default());
    let (good, log) = app(&["--screenshot", s(&out_dir.join("app-crowd-bad.png")), "--animation", "nope"]);
    assert!(!good && log.contains("no animation \"nope\""), "an unknown clip must fail the run:\n{log}");

    // A scene that does not load: the app says why and exits non-zero.
    let bad = tmp("app-bad.glb");
    std::fs::write(&bad, b"glTF\x02\x00\x00\x00 not really").unwrap();
    let out = gridrt_cmd()
        .args([s(&bad), "--screenshot", s(&out_dir.join("app-bad.png")), "--frames", "1"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("running the app");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a bad scene must fail the smoke run");
    assert!(err.contains("app-bad.glb"), "the error names the file: {err}");
}

/// `gridrt bench --quick --procedural`: every grid kind (both insertion modes) and every peer BVH on two scenes, with
/// hits that agree with the flat grid's, the scaling run and the targets, as JSON and files.
#[test]
fn bench_compares_grids_and_peers_on_the_same_rays() {
    let out = tmp("bench");
    let mut args =
        vec!["bench", "--quick", "--procedural", "--repeat", "1", "--rays", "4000", "--json", "--out", s(&out)];
    if skip_gpu() {
        args.push("--no-gpu");
    }
    let text = ok(&args);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"));
    let rows = v["rows"].as_array().unwrap();
    let structures: Vec<&str> = rows.iter().map(|r| r["structure"].as_str().unwrap()).collect();
    for name in ["flat", "macrocell", "multires", "twolevel", "proximity", "bvh (build_par)", "obvhs BVH2 fastest"] {
        assert!(structures.contains(&name), "{name} missing from {structures:?}");
        if !name.contains(' ') {
            let exact = format!("{name}, exact");
            assert!(structures.contains(&exact.as_str()), "{exact} missing from {structures:?}");
        }
    }
    // 5 grids with each insertion mode + 5 peer configurations per scene and ray set, and on the
    // camera sets 10 rows of packets (every grid, each insertion mode).
    for set in ["framed", "random"] {
        let of_set: Vec<_> = rows.iter().filter(|r| r["rays"] == set).collect();
        let packets = of_set.iter().filter(|r| r["family"] == "grid packets").count();
        assert!(!of_set.is_empty(), "no {set} rows");
        let scenes = 2;
        let want = if set == "random" { 0 } else { 10 * scenes };
        assert_eq!((of_set.len(), packets), (15 * scenes + want, want), "{set} rows");
    }
    assert!(structures.contains(&"flat, 8×8 packets"), "{structures:?}");
    for r in rows {
        assert!(r["mrays_s"].as_f64().unwrap() > 0.0, "{r}");
        let share = r["hit_share"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&share), "{r}");
        // The framed camera is narrowed until most of its rays hit the model (a particle cloud
        // leaves gaps from every side).
        if r["rays"] == "framed" && r["kind"] != "particles" {
            assert!(share >= 0.7, "framed hit share {share}: {r}");
        }
        assert!(r["memory_bytes"].as_u64().unwrap() > 0, "{r}");
        // Everything on the shared watertight test gives the flat grid's answers on every ray.
        if r["shared_triangle_test"] == true {
            assert_eq!(r["mismatches"], 0, "{r}");
        }
        if r["family"] == "grid packets" {
            assert!(r["gpu_mrays_s"].is_null(), "packet rows are CPU rows: {r}");
        }
        if r["family"] == "grid" && !skip_gpu() {
            assert!(r["gpu_mrays_s"].as_f64().unwrap() > 0.0, "{r}");
        }
    }
    let scaling = v["scaling"].as_array().unwrap();
    assert_eq!(scaling.len(), 27, "(3 + 3 particle + 3 mountain sizes) × (flat, bvh, obvhs)");
    // Both particle families (fixed size; size shrinking as N^-1/3), and the grid's references.
    assert!(scaling.iter().any(|p| p["scene"] == "particles, size ∝ N^-1/3"), "{scaling:?}");
    for p in scaling.iter().filter(|p| p["structure"] == "flat") {
        assert!(p["refs"].as_u64().unwrap() >= p["triangles"].as_u64().unwrap(), "{p}");
    }
    let refs_slopes = v["targets"].as_array().unwrap().iter();
    let refs_slopes = refs_slopes.filter(|t| t["target"] == "flat build: log–log slope of time against references");
    assert_eq!(refs_slopes.count(), 3, "a slope in references per family");
    let targets = v["targets"].as_array().unwrap();
    for t in [
        "best grid / best BVH Mrays/s, framed",
        "best grid / best BVH Mrays/s, random",
        "best grid packets / best BVH Mrays/s, framed",
        "auto m time / best swept time (CPU)",
    ] {
        assert!(targets.iter().any(|x| x["target"] == t), "target {t} missing");
    }
    assert!(v["auto_m"].as_array().unwrap().iter().any(|p| p["factor"] == 1.0));
    for f in ["bench.csv", "bench.json", "bench-scaling.csv", "bench-targets.csv", "bench-auto-m.csv"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    for chart in ["bench-framed", "bench-random", "bench-build", "bench-memory", "bench-scaling"] {
        assert!(std::fs::read_to_string(out.join(format!("{chart}.svg"))).unwrap().contains("<svg"), "{chart}.svg");
    }
    fails(&["bench", "--scenes", "/nonexistent", "--no-gpu", "--out", s(&out)], "/nonexistent");
}

/// `gridrt build --backend gpu`: the same cells, references and digest as the CPU build for
/// flat and macrocell grids, box and exact insertion, on a generated scene; kinds the GPU does
/// not build are refused.
#[test]
fn build_on_the_gpu_matches_the_cpu_digest() {
    if skip_gpu() {
        eprintln!("GRIDRT_SKIP_GPU_TESTS=1: skipping");
        return;
    }
    let scene = tmp("gpu-build-particles.glb");
    ok(&["gen", "particles", "--size", "20000", "-o", s(&scene)]);
    let mut box_refs = None;
    for (grid, exact) in [("flat", false), ("macrocell", false), ("flat", true), ("macrocell", true)] {
        let run = |backend: &str| -> serde_json::Value {
            let mut args = vec!["build", s(&scene), "--grid", grid, "--backend", backend, "--json"];
            if exact {
                args.push("--exact");
            }
            let text = ok(&args);
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
        };
        let (cpu, gpu) = (run("cpu"), run("gpu"));
        for key in ["cells", "refs", "cells_digest", "resolution", "memory_bytes"] {
            assert_eq!(cpu[key], gpu[key], "{grid} exact {exact}: {key}");
        }
        assert_eq!(gpu["backend"], "gpu");
        assert!(gpu["adapter"].as_str().is_some_and(|a| !a.is_empty()), "{gpu}");
        // Exact insertion really ran: fewer references than box insertion's at that resolution.
        match (grid, exact) {
            ("flat", false) => box_refs = gpu["refs"].as_u64(),
            ("flat", true) => assert!(gpu["refs"].as_u64() < box_refs, "{gpu}"),
            _ => {}
        }
        println!(
            "{grid} exact {exact}: {} cells, {} refs, digest {} on both",
            gpu["cells"], gpu["refs"], gpu["cells_digest"]
        );
    }
    fails(&["build", s(&scene), "--grid", "multires", "--backend", "gpu"], "use the CPU build");
    fails(&["build", s(&scene), "--grid", "proximity", "--exact", "--backend", "gpu"], "use the CPU build");
}

#[test]
fn cpu_render_with_and_without_packets_gives_the_same_hits() {
    let scene = tmp("packets-tis.glb");
    ok(&["gen", "teapot-in-stadium", "--size", "1", "-o", s(&scene)]);
    let trace_hits = tmp("packets-trace.hits");
    for grid in ["flat", "macrocell", "multires", "twolevel"] {
        let mut hits = Vec::new();
        for packets in ["on", "off"] {
            let (png, h, r) = (tmp("packets.png"), tmp(&format!("{grid}-{packets}.hits")), tmp("packets.rays"));
            let out = ok(&[
                "render",
                s(&scene),
                "--backend",
                "cpu",
                "--packets",
                packets,
                "--grid",
                grid,
                "--size",
                "97x61",
                "--camera",
                "framed",
                "--hits-out",
                s(&h),
                "--rays-out",
                s(&r),
                "--json",
                "-o",
                s(&png),
            ]);
            let v: serde_json::Value = serde_json::from_str(&out).unwrap();
            assert_eq!(v["rays"], 97 * 61, "{out}");
            assert!(v["primary_ms"].as_f64().unwrap() > 0.0 && v["shadow_ms"].as_f64().unwrap() > 0.0, "{out}");
            let walked = v["packets"].as_u64().unwrap();
            match (grid, packets) {
                // 13 × 8 tiles of 8×8, primary and shadow passes.
                (_, "on") => assert!(walked > 0 && walked <= 2 * 13 * 8, "{out}"),
                _ => assert_eq!(walked, 0, "{out}"),
            }
            let img = image::open(&png).unwrap().to_rgba8();
            assert_eq!(img.dimensions(), (97, 61));
            // Brute force over the written rays gives the same hits.
            ok(&["trace", s(&scene), "--rays", s(&r), "--backend", "brute", "-o", s(&trace_hits)]);
            assert_eq!(std::fs::read(&h).unwrap(), std::fs::read(&trace_hits).unwrap(), "{grid} packets {packets}");
            hits.push(std::fs::read(&h).unwrap());
        }
        assert_eq!(hits[0], hits[1], "{grid}: packets change the hits");
    }
    fails(
        &["render", s(&scene), "--backend", "cpu", "--view", "heatmap-cells", "-o", s(&tmp("h.png"))],
        "--packets off",
    );
    let out = ok(&["render", s(&scene), "--backend", "cpu", "--size", "64x48", "-o", s(&tmp("p.png"))]);
    assert!(out.contains("8x8 packets"), "{out}");
}

/// A scene in nanometres or in light years renders as the same scene in metres: scaled by a
/// power of two (exact in f32), its auto camera, grid, hits, shadow offsets and shading scale
/// alike, so the CPU image is the same pixel for pixel, and so is the GPU's. (An absolute floor
/// on the camera's distance and the grid box once left a 1e-9 scene a dot in one cell, and an
/// overflowing diagonal left a 1e20 scene without a camera.)
#[test]
fn renders_are_the_same_at_every_scale() {
    let base = tmp("tis.glb");
    ok(&["gen", "teapot-in-stadium", "--size", "1", "-o", s(&base)]);
    let (mesh, _) = gridrt_scene::gltf_load::load_path(&base).unwrap();
    let backends: &[&str] = if skip_gpu() { &["cpu"] } else { &["cpu", "gpu"] };
    let render = |scene: &Path, backend: &str| {
        let png = tmp("scaled.png");
        ok(&["render", s(scene), "--backend", backend, "--size", "96x64", "-o", s(&png)]);
        image::open(&*png).unwrap().to_rgba8()
    };
    for backend in backends {
        let reference = render(&base, backend);
        let lit = reference.pixels().filter(|p| p.0[..3] != reference.get_pixel(0, 0).0[..3]).count();
        assert!(lit > 96 * 64 / 10, "{backend}: the scene covers only {lit} pixels at scale 1");
        for k in [-60, -30, 30, 60] {
            let f = 2f32.powi(k);
            let scaled =
                gridrt_scene::Mesh { positions: mesh.positions.iter().map(|p| *p * f).collect(), ..mesh.clone() };
            let path = tmp("scaled.glb");
            std::fs::write(&path, gridrt_scene::glb_write::to_glb(&scaled, "scale test")).unwrap();
            let img = render(&path, backend);
            let off = reference.pixels().zip(img.pixels()).filter(|(a, b)| a != b).count();
            assert_eq!(off, 0, "{backend} at 2^{k}: {off} pixels differ from the render at scale 1");
        }
    }
}
