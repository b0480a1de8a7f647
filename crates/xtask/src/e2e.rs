//! The browser demo's end-to-end test (`cargo xtask web-test`).
//!
//! Serves `web/dist/` on 127.0.0.1, opens it in headless Chromium (WebGPU over SwiftShader),
//! and through the page's `window.gridrt` hook:
//! 1. checks WebGPU and an adapter exist (a clear failure otherwise) and waits for the first
//!    frame of the default scene (time to first frame);
//! 2. for the flat and macrocell grids renders the shaded view at a fixed camera and size,
//!    reads the frame back and compares it with `gridrt render` (native, lavapipe) for the same
//!    scene, camera and size: same hit/miss on ≥ 99 % of pixels and a small mean colour error;
//!    Then the same frame with coherent packets (the packet kernels) must be identical;
//! 3. switches the view to a heatmap (the frame must change) and the traversal to Liu;
//! 4. opens a generated .glb through the same path a dropped or picked file takes, and a
//!    corrupt one, which must show an error without losing the page.
//!
//! Screenshots, frames and `report.json` (wasm size, time to first frame, agreement) go to
//! the output directory.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail, ensure};
use serde_json::{Value, json};

use crate::cdp::{Browser, Page, find_chromium};
use crate::serve::Server;

/// Image size and camera of the comparison (the embedded default scene, seen from above).
const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;
const CAMERA: &str = "3.2,2.6,4.4,0,0.1,0,42";
/// The shaded view's background (shade.wgsl: `pack_rgba(vec3(0.08, 0.09, 0.12))`).
const BACKGROUND: [u8; 3] = [20, 23, 31];
/// Required share of pixels with the same hit/miss as the native render.
const MIN_AGREEMENT: f64 = 0.99;
/// Longest gap between animation frames allowed while a large scene builds.
const MAX_FRAME_GAP_MS: f64 = 1500.0;
/// Tubes in the generated animated scene, and the frames it must show playing.
const CROWD_TUBES: u32 = 6;
const ANIMATION_FRAMES: u64 = 5;
/// Largest mean absolute colour difference (0–255 per channel) against the native render.
const MAX_MEAN_DIFF: f64 = 3.0;

fn is_hit(p: &[u8]) -> bool {
    p[..3] != BACKGROUND
}

/// Hit/miss agreement, mean absolute channel difference, and the hit share of `a`.
pub fn compare(a: &[u8], b: &[u8]) -> (f64, f64, f64) {
    let n = (a.len() / 4).max(1);
    let (mut same, mut diff, mut hits) = (0usize, 0u64, 0usize);
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        same += usize::from(is_hit(p) == is_hit(q));
        hits += usize::from(is_hit(p));
        diff += (0..3).map(|c| p[c].abs_diff(q[c]) as u64).sum::<u64>();
    }
    (same as f64 / n as f64, diff as f64 / (3 * n) as f64, hits as f64 / n as f64)
}

/// Renders the reference with the native `gridrt render`.
fn native_render(root: &Path, grid: &str, out: &Path) -> anyhow::Result<Vec<u8>> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(root)
        .args(["run", "-q", "-p", "gridrt", "--", "render", "@default", "--grid", grid, "--view", "shaded"])
        .arg("--size")
        .arg(format!("{WIDTH}x{HEIGHT}"))
        .args(["--camera", CAMERA, "-o"])
        .arg(out)
        .status()
        .context("running gridrt render")?;
    ensure!(status.success(), "gridrt render --grid {grid} failed ({status})");
    Ok(image::open(out)?.to_rgba8().into_raw())
}

fn save_png(path: &Path, rgba: &[u8], w: u32, h: u32) -> anyhow::Result<()> {
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", path.display()))
}

/// `window.gridrt.stats()` once the app is idle with `cond` (a JS expression over `s`) true.
fn wait_idle(page: &mut Page, what: &str, cond: &str, timeout: Duration) -> anyhow::Result<Value> {
    let expr = format!(
        "(() => {{ const m = document.querySelector('#message.error'); \
         if (m) throw new Error('the page shows: ' + m.innerText); \
         const s = window.gridrt && window.gridrt.stats(); \
         if (s && s.idle && s.error) throw new Error('the app reports: ' + s.error); \
         return s && s.idle && ({cond}) ? s : null; }})()"
    );
    page.wait_for(what, &expr, timeout)
}

/// Asks the app for its last frame and returns (width, height, rgba).
fn read_frame(page: &mut Page, timeout: Duration) -> anyhow::Result<(u32, u32, Vec<u8>)> {
    use base64::Engine as _;
    let id = page.eval("window.gridrt.capture()")?;
    let expr = format!(
        "(() => {{ const f = window.gridrt.last_frame(); if (!f || f.id < {id}) return null; \
         let s = ''; for (let i = 0; i < f.rgba.length; i += 0x8000) \
         s += String.fromCharCode.apply(null, f.rgba.subarray(i, i + 0x8000)); \
         return {{ width: f.width, height: f.height, b64: btoa(s) }}; }})()"
    );
    let v = page.wait_for("the frame readback", &expr, timeout)?;
    let rgba = base64::engine::general_purpose::STANDARD.decode(v["b64"].as_str().context("no frame data")?)?;
    let (w, h) = (v["width"].as_u64().unwrap_or(0) as u32, v["height"].as_u64().unwrap_or(0) as u32);
    ensure!(rgba.len() == (w * h * 4) as usize, "frame readback has {} bytes for {w}x{h}", rgba.len());
    Ok((w, h, rgba))
}

/// A 1 KB .glb whose node i lists node i+1 twice, `levels` deep, over a one-triangle mesh:
/// 2^levels instances, which the load budget must refuse before allocating.
fn graph_bomb_glb(levels: usize) -> Vec<u8> {
    let mut nodes: Vec<Value> = (0..levels).map(|i| json!({"children": [i + 1, i + 1]})).collect();
    nodes.push(json!({"mesh": 0}));
    let doc = json!({
        "asset": {"version": "2.0"}, "buffers": [{"byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": nodes, "scenes": [{"nodes": [0]}], "scene": 0
    });
    let mut json = serde_json::to_vec(&doc).expect("JSON");
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.].iter().flat_map(|x| x.to_le_bytes()).collect();
    gridrt_scene::glb_write::assemble_glb(&json, Some(&bin))
}

pub fn run(root: &Path, dist: &Path, out: &Path, chromium: Option<PathBuf>, timeout: Duration) -> anyhow::Result<()> {
    ensure!(dist.join("index.html").is_file(), "{} has no index.html: run `cargo xtask web` first", dist.display());
    std::fs::create_dir_all(out)?;
    let (wasm_raw, wasm_gz) = crate::wasm::sizes(&dist.join("gridrt_bg.wasm"))?;

    // Test scenes served next to the page: a generated one and a corrupt one.
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let gen_path = dist.join("e2e-scene.glb");
    let st = Command::new(&cargo)
        .current_dir(root)
        .args(["run", "-q", "-p", "gridrt", "--", "gen", "mountain", "--size", "6", "-o"])
        .arg(&gen_path)
        .status()?;
    ensure!(st.success(), "gridrt gen failed");
    let gen_tris = gltf_triangles(root, &gen_path)?;
    // A large one, to check that the page keeps drawing while it builds in the worker.
    let st = Command::new(&cargo)
        .current_dir(root)
        .args(["run", "-q", "-p", "gridrt", "--", "gen", "mountain", "--size", "9", "-o"])
        .arg(dist.join("e2e-large.glb"))
        .status()?;
    ensure!(st.success(), "gridrt gen failed");
    // An animated one (skinned tubes, rigid balls, a floor): it plays with a rebuild per frame.
    std::fs::write(dist.join("e2e-crowd.glb"), gridrt_scene::crowd::crowd_glb(CROWD_TUBES, 7))?;
    std::fs::write(dist.join("e2e-corrupt.glb"), b"glTF\x02\x00\x00\x00\xff\xff\x00\x00not a glb at all")?;
    std::fs::write(dist.join("e2e-bomb.glb"), graph_bomb_glb(29))?;

    println!("web-test: native reference renders ({WIDTH}x{HEIGHT}, camera {CAMERA})");
    let mut native = Vec::new();
    for grid in ["flat", "macrocell"] {
        native.push(native_render(root, grid, &out.join(format!("native-{grid}.png")))?);
    }

    let server = Server::start(dist, 0)?;
    let url = format!("http://{}/index.html", server.addr);
    let chromium = find_chromium(chromium)?;
    println!("web-test: {} on {url}", chromium.display());
    let browser = Browser::launch(&chromium, &out.join("chromium-profile"), Duration::from_secs(60))?;
    let mut page = Page::attach(&browser)?;
    let result = drive(&mut page, &url, out, &native, gen_tris, (wasm_raw, wasm_gz), timeout);
    if let Ok(png) = page.screenshot() {
        let _ = std::fs::write(out.join("final-screenshot.png"), png);
    }
    std::fs::write(out.join("console.log"), page.console.iter().cloned().collect::<Vec<_>>().join("\n"))?;
    drop(browser);
    drop(server);
    result
}

/// Triangle count of a .glb, from `gridrt info`.
fn gltf_triangles(root: &Path, path: &Path) -> anyhow::Result<u64> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let o =
        Command::new(cargo).current_dir(root).args(["run", "-q", "-p", "gridrt", "--", "info"]).arg(path).output()?;
    ensure!(o.status.success(), "gridrt info failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    text.lines()
        .find_map(|l| l.strip_prefix("triangles:").map(|v| v.trim().parse::<u64>()))
        .context("gridrt info printed no triangle count")?
        .context("parsing the triangle count")
}

fn drive(
    page: &mut Page,
    url: &str,
    out: &Path,
    native: &[Vec<u8>],
    gen_tris: u64,
    (wasm_raw, wasm_gz): (u64, u64),
    timeout: Duration,
) -> anyhow::Result<()> {
    let t0 = Instant::now();
    page.call("Page.navigate", json!({"url": url}), true)?;
    page.wait_for("the page to load", "document.readyState === 'complete'", Duration::from_secs(60))?;
    let gpu = page.eval(
        "(async () => { if (!navigator.gpu) return 'navigator.gpu is missing'; \
         const a = await navigator.gpu.requestAdapter(); return a ? 'ok' : 'requestAdapter() returned null'; })()",
    )?;
    if gpu != "ok" {
        bail!(
            "WebGPU is unavailable in this Chromium ({}): the browser demo cannot run. \
             Check the browser flags in crates/xtask/src/cdp.rs (--enable-unsafe-webgpu, Vulkan over SwiftShader).",
            gpu.as_str().unwrap_or("?")
        );
    }
    let first = wait_idle(page, "the first frame", "s.frames >= 1", timeout)?;
    let ttff = t0.elapsed().as_secs_f64() * 1e3;
    println!(
        "web-test: first frame after {ttff:.0} ms (page's own clock: {} ms) on adapter {:?}: {} tris, {}x{}, {:.1} ms",
        first["first_frame_ms"],
        first["adapter"],
        first["triangles"],
        first["width"],
        first["height"],
        first["frame_ms"]
    );
    std::fs::write(out.join("first-frame.png"), page.screenshot()?)?;

    let mut rows = Vec::new();
    for (grid, reference) in ["flat", "macrocell"].iter().zip(native) {
        let before = page.eval("window.gridrt.stats().frames")?.as_u64().unwrap_or(0);
        page.eval(&format!(
            "window.gridrt.set_frame_size({WIDTH}, {HEIGHT}); window.gridrt.set_camera('{CAMERA}'); \
             window.gridrt.set_view('shaded'); window.gridrt.set_traversal('aw'); window.gridrt.set_grid('{grid}'); true"
        ))?;
        let s = wait_idle(
            page,
            &format!("a {grid} frame"),
            &format!(
                "s.grid === '{grid}' && s.view === 'shaded' && s.width === {WIDTH} && s.height === {HEIGHT} && s.frames > {before}"
            ),
            timeout,
        )?;
        let (w, h, rgba) = read_frame(page, timeout)?;
        ensure!((w, h) == (WIDTH, HEIGHT), "the {grid} frame is {w}x{h}, not {WIDTH}x{HEIGHT}");
        save_png(&out.join(format!("browser-{grid}.png")), &rgba, w, h)?;
        std::fs::write(out.join(format!("screenshot-{grid}.png")), page.screenshot()?)?;
        let (agree, mean_diff, hit_share) = compare(&rgba, reference);
        println!(
            "web-test: {grid:9} {:.4} same hit/miss, mean colour difference {mean_diff:.3}/255, {:.1}% hits, \
             {:.2} cells/ray, {:.1} ms/frame",
            agree,
            hit_share * 100.0,
            s["mean_cells_per_ray"].as_f64().unwrap_or(f64::NAN),
            s["frame_ms"].as_f64().unwrap_or(f64::NAN)
        );
        ensure!(
            hit_share > 0.1,
            "the {grid} frame hits almost nothing ({:.1}% of pixels): wrong camera?",
            hit_share * 100.0
        );
        ensure!(
            agree >= MIN_AGREEMENT,
            "the browser's {grid} frame agrees with gridrt render on only {:.2}% of pixels (need {:.0}%)",
            agree * 100.0,
            MIN_AGREEMENT * 100.0
        );
        ensure!(
            mean_diff <= MAX_MEAN_DIFF,
            "the browser's {grid} frame differs from gridrt render by {mean_diff:.2}/255 on average (limit {MAX_MEAN_DIFF})"
        );
        // The packet kernels: the same pixels as the single-ray kernels.
        let before = page.eval("window.gridrt.stats().frames")?.as_u64().unwrap_or(0);
        page.eval("window.gridrt.set_packets('on'); true")?;
        let p = wait_idle(
            page,
            &format!("a {grid} frame in packets"),
            &format!("s.packets && s.frames > {before}"),
            timeout,
        )?;
        let (_, _, packed) = read_frame(page, timeout)?;
        let differ = packed.chunks_exact(4).zip(rgba.chunks_exact(4)).filter(|(a, b)| a != b).count();
        println!(
            "web-test: {grid:9} in 8x8 packets: {differ} pixels differ, {:.1} ms/frame",
            p["frame_ms"].as_f64().unwrap_or(f64::NAN)
        );
        ensure!(differ == 0, "the browser's {grid} frame in packets differs from single rays on {differ} pixels");
        page.eval("window.gridrt.set_packets('off'); true")?;
        wait_idle(page, "packets off", "!s.packets", timeout)?;
        rows.push(
            json!({"grid": grid, "agreement": agree, "mean_colour_diff": mean_diff, "hit_share": hit_share, "stats": s,
                         "packet_pixels_differing": differ, "packet_frame_ms": p["frame_ms"]}),
        );
    }
    let macro_shaded = read_frame(page, timeout)?.2;

    // View and traversal switches.
    let before = page.eval("window.gridrt.stats().frames")?.as_u64().unwrap_or(0);
    page.eval("window.gridrt.set_view('heatmap-cells'); window.gridrt.set_traversal('liu'); true")?;
    let s = wait_idle(
        page,
        "a heatmap frame",
        &format!("s.view === 'heatmap-cells' && s.traversal === 'liu' && s.frames > {before}"),
        timeout,
    )?;
    let (w, h, heat) = read_frame(page, timeout)?;
    save_png(&out.join("browser-macrocell-heatmap.png"), &heat, w, h)?;
    let changed = heat.chunks_exact(4).zip(macro_shaded.chunks_exact(4)).filter(|(a, b)| a != b).count();
    ensure!(changed * 2 > heat.len() / 4, "switching to the heatmap changed only {changed} pixels");
    println!("web-test: heatmap-cells with Liu: {changed} pixels changed, {:.2} cells/ray", s["mean_cells_per_ray"]);

    // Opening files: the bytes path a dropped or picked file takes.
    page.eval("window.gridrt.set_frame_size(0, 0); window.gridrt.set_view('shaded'); true")?;
    page.eval(
        "fetch('e2e-scene.glb').then(r => r.arrayBuffer()).then(b => window.gridrt.open_bytes('e2e-scene.glb', new Uint8Array(b)))",
    )?;
    let s = wait_idle(
        page,
        "the generated scene",
        &format!("s.scene === 'e2e-scene.glb' && s.triangles === {gen_tris} && s.frames > 0"),
        timeout,
    )?;
    println!("web-test: opened e2e-scene.glb from bytes: {} triangles, {} grid", s["triangles"], s["grid"]);
    std::fs::write(out.join("screenshot-opened.png"), page.screenshot()?)?;
    page.eval(
        "fetch('e2e-corrupt.glb').then(r => r.arrayBuffer()).then(b => window.gridrt.open_bytes('e2e-corrupt.glb', new Uint8Array(b)))",
    )?;
    let err = page.wait_for(
        "the corrupt file's error",
        "(() => { const s = window.gridrt.stats(); return s.error && s.error.includes('e2e-corrupt.glb') ? s.error : null; })()",
        timeout,
    )?;
    let s = page.eval("window.gridrt.stats()")?;
    ensure!(
        s["scene"] == "e2e-scene.glb",
        "after the corrupt file the scene is {} (the previous one should stay)",
        s["scene"]
    );
    ensure!(page.eval("window.gridrt.panic()")?.is_null(), "the app panicked");
    println!("web-test: the corrupt file shows {err} and the previous scene stays");
    std::fs::write(out.join("screenshot-corrupt.png"), page.screenshot()?)?;

    // A node-graph bomb (2^29 instances in 1 KB): refused by the load budget, the scene stays.
    page.eval(
        "window.gridrt.dismiss_error(); \
         fetch('e2e-bomb.glb').then(r => r.arrayBuffer()).then(b => window.gridrt.open_bytes('e2e-bomb.glb', new Uint8Array(b)))",
    )?;
    let err = page.wait_for(
        "the graph bomb's error",
        "(() => { const s = window.gridrt.stats(); return s.error && s.error.includes('e2e-bomb.glb') ? s.error : null; })()",
        timeout,
    )?;
    ensure!(err.to_string().contains("load limits"), "the bomb's error does not name the load limits: {err}");
    let s = page.eval("window.gridrt.stats()")?;
    ensure!(s["scene"] == "e2e-scene.glb", "after the bomb the scene is {} (the previous one should stay)", s["scene"]);
    println!("web-test: the graph bomb shows {err}");

    // Frame sizes: beyond the device's textures an error (never a panic); a frame of several
    // tiles renders.
    page.eval("window.gridrt.dismiss_error(); window.gridrt.set_frame_size(9000, 100); true")?;
    let r = page.wait_for(
        "a 9000x100 frame or its error",
        "(() => { const s = window.gridrt.stats(); \
           return (s.error && s.error.includes('9000')) ? s.error : (s.width === 9000 && s.idle ? 'rendered' : null); })()",
        timeout,
    )?;
    ensure!(page.eval("window.gridrt.panic()")?.is_null(), "the app panicked on a 9000x100 frame");
    println!("web-test: set_frame_size(9000, 100): {r}");
    page.eval("window.gridrt.dismiss_error(); window.gridrt.set_frame_size(1600, 1000); true")?;
    let s =
        wait_idle(page, "a 1600x1000 frame (two tiles)", "s.width === 1600 && s.height === 1000 && !s.error", timeout)?;
    println!("web-test: a 1600x1000 frame in {:.0} ms", s["frame_ms"].as_f64().unwrap_or(0.0));
    page.eval("window.gridrt.set_frame_size(0, 0); true")?;

    // The page keeps drawing while a large scene builds in the worker: animation frames keep
    // coming (a build on the page's thread would stall them for the whole build).
    page.eval("window.gridrt.dismiss_error(); window.gridrt.set_grid('multires'); true")?;
    wait_idle(page, "the multires grid", "s.grid === 'multires' && s.scene === 'e2e-scene.glb'", timeout)?;
    let workers_before = page.eval("window.gridrt.stats().worker_builds")?.as_u64().unwrap_or(0);
    let r = page.eval(
        "(async () => { \
           const b = await (await fetch('e2e-large.glb')).arrayBuffer(); \
           window.gridrt.open_bytes('e2e-large.glb', new Uint8Array(b)); \
           const gaps = []; let last = performance.now(), prev = false, seen = false; const t0 = last; \
           while (performance.now() - t0 < 600000) { \
             await new Promise(r => requestAnimationFrame(r)); \
             const now = performance.now(), s = window.gridrt.stats(); \
             const building = s.scene === 'e2e-large.glb' && s.building; \
             if (building && prev) gaps.push(now - last); \
             if (building) seen = true; else if (seen) break; \
             prev = building; last = now; } \
           return { seen, frames: gaps.length, max_gap_ms: Math.max(0, ...gaps), \
                    mean_gap_ms: gaps.reduce((a, b) => a + b, 0) / Math.max(1, gaps.length) }; })()",
    )?;
    let s = wait_idle(page, "the large scene", "s.scene === 'e2e-large.glb' && s.grid === 'multires'", timeout)?;
    let workers = s["worker_builds"].as_u64().unwrap_or(0);
    println!(
        "web-test: e2e-large.glb ({} tris) built in the worker in {:.0} ms; meanwhile {} animation frames, \
         longest gap {:.0} ms, mean {:.0} ms",
        s["triangles"],
        s["build_ms"].as_f64().unwrap_or(0.0),
        r["frames"],
        r["max_gap_ms"].as_f64().unwrap_or(0.0),
        r["mean_gap_ms"].as_f64().unwrap_or(0.0)
    );
    ensure!(workers > workers_before, "the large scene was not built in the build worker");
    ensure!(r["seen"] == true && r["frames"].as_u64().unwrap_or(0) >= 2, "no animation frames while building: {r}");
    ensure!(
        r["max_gap_ms"].as_f64().unwrap_or(f64::MAX) < MAX_FRAME_GAP_MS,
        "the page stalled for {} ms while building (limit {MAX_FRAME_GAP_MS} ms)",
        r["max_gap_ms"]
    );
    std::fs::write(out.join("screenshot-large.png"), page.screenshot()?)?;

    // An animated scene plays: each frame posed on the page, rebuilt in the worker, rendered.
    // (Small frames: SwiftShader takes seconds for a window-sized one.)
    let workers_before = workers;
    page.eval(
        "window.gridrt.set_frame_size(160, 120); \
         fetch('e2e-crowd.glb').then(r => r.arrayBuffer()).then(b => window.gridrt.open_bytes('e2e-crowd.glb', new Uint8Array(b)))",
    )?;
    let a = page.wait_for(
        "animation frames of e2e-crowd.glb",
        &format!(
            "(() => {{ const s = window.gridrt.stats(); if (s.error) throw new Error('the app reports: ' + s.error); \
               return s.scene === 'e2e-crowd.glb' && s.animation && s.animation.playing \
                 && s.animation.frames_shown >= {ANIMATION_FRAMES} ? s : null; }})()"
        ),
        timeout,
    )?;
    let anim = &a["animation"];
    println!(
        "web-test: e2e-crowd.glb ({} tris) plays: {} frames shown, {:.2} fps (pose {:.1}, build {:.1}, upload {:.1}, \
         trace {:.1} ms), {} worker builds",
        a["triangles"],
        anim["frames_shown"],
        anim["fps"].as_f64().unwrap_or(0.0),
        anim["pose_ms"].as_f64().unwrap_or(0.0),
        anim["build_ms"].as_f64().unwrap_or(0.0),
        anim["upload_ms"].as_f64().unwrap_or(0.0),
        anim["trace_ms"].as_f64().unwrap_or(0.0),
        a["worker_builds"]
    );
    let worker_frames = a["worker_builds"].as_u64().unwrap_or(0).saturating_sub(workers_before);
    ensure!(worker_frames >= ANIMATION_FRAMES, "only {worker_frames} animation frames were built in the worker");
    // Built on the GPU instead (a flat grid; the page awaits the build's readbacks): frames keep
    // coming.
    let shown = anim["frames_shown"].as_u64().unwrap_or(0);
    page.eval("window.gridrt.set_grid('flat'); window.gridrt.set_gpu_build('on'); true")?;
    let g = page.wait_for(
        "animation frames built on the GPU",
        &format!(
            "(() => {{ const s = window.gridrt.stats(); if (s.error) throw new Error('the app reports: ' + s.error); \
               return s.gpu_built && s.animation.frames_shown >= {} ? s : null; }})()",
            shown + ANIMATION_FRAMES
        ),
        timeout,
    )?;
    println!(
        "web-test: e2e-crowd.glb rebuilt on the GPU: {} frames shown, {:.2} fps (build {:.1} ms)",
        g["animation"]["frames_shown"],
        g["animation"]["fps"].as_f64().unwrap_or(0.0),
        g["animation"]["build_ms"].as_f64().unwrap_or(0.0)
    );
    page.eval("window.gridrt.set_gpu_build('off'); true")?;
    // Paused and moved, it settles on the pose asked for.
    page.eval("window.gridrt.set_playing('pause'); window.gridrt.seek('1.25'); true")?;
    let paused = wait_idle(
        page,
        "the paused pose at 1.25 s",
        "s.animation && !s.animation.playing && s.animation.shown_seconds === 1.25",
        timeout,
    )?;
    ensure!(page.eval("window.gridrt.panic()")?.is_null(), "the app panicked while playing");
    println!("web-test: paused at {} s", paused["animation"]["shown_seconds"]);
    page.eval("window.gridrt.set_frame_size(0, 0); true")?;
    std::fs::write(out.join("screenshot-animated.png"), page.screenshot()?)?;

    // Without WebGPU the page explains itself instead of staying blank: a browser without
    // navigator.gpu, and one whose requestAdapter() finds nothing.
    let cases = [
        (
            "no-webgpu",
            "Object.defineProperty(Navigator.prototype, 'gpu', { get: () => undefined, configurable: true });",
            "does not offer WebGPU",
        ),
        ("no-adapter", "if (navigator.gpu) navigator.gpu.requestAdapter = async () => null;", "no GPU adapter"),
    ];
    for (name, script, expect) in cases {
        let added = page.call("Page.addScriptToEvaluateOnNewDocument", json!({"source": script}), true)?;
        page.call("Page.navigate", json!({"url": url}), true)?;
        let text = page.wait_for(
            &format!("the page's {name} message"),
            "(() => { const m = document.querySelector('#message.error'); return m ? m.innerText : null; })()",
            Duration::from_secs(60),
        )?;
        let text = text.as_str().unwrap_or_default().to_string();
        ensure!(
            text.contains(expect) && text.contains("no WebGL fallback"),
            "the {name} page says {text:?}, expected {expect:?} and the missing WebGL fallback"
        );
        std::fs::write(out.join(format!("screenshot-{name}.png")), page.screenshot()?)?;
        page.call("Page.removeScriptToEvaluateOnNewDocument", json!({"identifier": added["identifier"]}), true)?;
        println!("web-test: {name}: the page says \"{}\"", text.lines().next().unwrap_or_default());
    }

    let report = json!({
        "animation": anim,
        "responsiveness": r,
        "large_scene": s,
        "wasm_bytes": wasm_raw,
        "wasm_gzip_bytes": wasm_gz,
        "time_to_first_frame_ms": ttff,
        "first_frame": first,
        "comparisons": rows,
        "size": [WIDTH, HEIGHT],
        "camera": CAMERA,
    });
    std::fs::write(out.join("report.json"), serde_json::to_string_pretty(&report)?)?;
    println!(
        "web-test: passed. wasm {:.2} MB raw / {:.2} MB gzip; time to first frame {:.1} s; report in {}",
        wasm_raw as f64 / 1e6,
        wasm_gz as f64 / 1e6,
        ttff / 1e3,
        out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comparison_counts_hits_and_colour() {
        let bg = [BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 255];
        let a: Vec<u8> = [bg, [100, 100, 100, 255], [100, 100, 100, 255], bg].concat();
        let b: Vec<u8> = [bg, [103, 100, 100, 255], bg, bg].concat();
        let (agree, diff, hits) = compare(&a, &b);
        assert_eq!(agree, 0.75);
        assert_eq!(hits, 0.5);
        let expected = (3.0 + 80.0 + 77.0 + 69.0) / 12.0;
        assert!((diff - expected).abs() < 1e-9, "{diff}");
    }
}
