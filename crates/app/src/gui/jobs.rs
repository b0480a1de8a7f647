//! Work that must not block the UI: loading a scene and building a structure run on a thread
//! (natively) and hand their result back through a channel; the UI polls each frame and shows
//! a spinner with the elapsed time meanwhile. In the browser, where std threads do not exist,
//! builds go to the build worker ([`spawn_build`]); loads, and builds when the worker cannot
//! start, run on the page's thread once the browser has painted.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::sync::{Arc, Mutex};

use glam::Vec3;
use gridrt_grid::GridConfig;

#[cfg(target_arch = "wasm32")]
use super::built::decode_structure;
use super::built::{Built, GpuBuild, Posed, build_structure};
use gridrt_scene::{Aabb, Clip, ClipTime, LoadReport, Player};
use web_time::Instant;

/// A scene ready for building: triangles shared with build threads.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    pub name: String,
    /// The rest pose.
    pub tris: Arc<Vec<[Vec3; 3]>>,
    /// The rest pose's bounds, joined with the first clip's (sampled) so that the camera and
    /// the light frame the whole animation.
    pub bounds: Aabb,
    pub report: LoadReport,
    /// The file's clips (empty: nothing to play).
    pub clips: Vec<Clip>,
    /// Poses the scene for the timeline (one posing job at a time holds it).
    pub player: Option<Arc<Mutex<Player>>>,
}

/// Times sampled over the first clip for the animated scene's bounds.
const CLIP_BOUNDS_SAMPLES: u32 = 16;

/// Where a scene comes from.
#[derive(Debug, Clone)]
pub enum SceneSource {
    Default,
    Path(PathBuf),
    /// A dropped file's contents (the browser gives bytes, not a path).
    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    Bytes {
        name: String,
        bytes: Arc<[u8]>,
    },
}

impl SceneSource {
    pub fn label(&self) -> String {
        match self {
            SceneSource::Default => gridrt_scene::DEFAULT_SCENE_NAME.to_string(),
            SceneSource::Path(p) => p.display().to_string(),
            SceneSource::Bytes { name, .. } => name.clone(),
        }
    }
}

/// Loads and validates a scene; the error is the loader's message, for the UI.
pub fn load_scene(source: &SceneSource) -> Result<LoadedScene, String> {
    let loaded = match source {
        SceneSource::Default => {
            let (mesh, report) = gridrt_scene::load_default();
            return Ok(LoadedScene {
                name: source.label(),
                tris: Arc::new(mesh.triangles()),
                bounds: mesh.bounds(),
                report,
                clips: Vec::new(),
                player: None,
            });
        }
        SceneSource::Path(p) => gridrt_scene::gltf_load::load_rigged_path_with(p, &crate::limits::get()),
        SceneSource::Bytes { name, bytes } => {
            gridrt_scene::gltf_load::load_rigged_slice_with(bytes, name, None, &crate::limits::get())
        }
    }
    .map_err(|e| e.to_string())?;
    if loaded.mesh.triangle_count() == 0 {
        return Err(format!("{}: the scene has no triangles", source.label()));
    }
    let name = match source {
        SceneSource::Path(p) => p.file_name().map_or_else(|| source.label(), |f| f.to_string_lossy().into_owned()),
        _ => source.label(),
    };
    let tris = Arc::new(loaded.mesh.triangles());
    let mut bounds = loaded.mesh.bounds();
    let report = loaded.report.clone();
    let clips = loaded.rig.clips().to_vec();
    let player = if clips.is_empty() {
        None
    } else {
        let mut player = Player::new(loaded, 0);
        bounds = bounds.union(&player.clip_bounds(CLIP_BOUNDS_SAMPLES).map_err(|e| e.to_string())?);
        Some(Arc::new(Mutex::new(player)))
    };
    Ok(LoadedScene { name, tris, bounds, report, clips, player })
}

/// Poses `player` at `time` and builds `config` over the posed triangles, off the UI thread
/// (natively); in the browser the pose is computed on the page and the build goes to the
/// build worker, as for [`spawn_build`].
pub fn spawn_pose_build(
    ui: &eframe::egui::Context,
    player: Arc<Mutex<Player>>,
    time: ClipTime,
    config: GridConfig,
    scene_generation: u64,
    gpu: Option<GpuBuild>,
) -> Job<Result<Built, String>> {
    let pose = move || -> Result<Posed, String> {
        let started = Instant::now();
        let mut p = player.lock().map_err(|_| "the posing state was poisoned by an earlier panic".to_string())?;
        p.clip = time.clip;
        p.pose(time.seconds).map_err(|e| e.to_string())?;
        let tris = Arc::new(p.tris.clone());
        Ok(Posed { time, tris, pose_ms: started.elapsed().as_secs_f64() * 1e3 })
    };
    #[cfg(target_arch = "wasm32")]
    {
        match pose() {
            Ok(posed) => spawn_build(ui, posed.tris.clone(), config, scene_generation, Some(posed), gpu),
            Err(e) => {
                let (tx, rx) = channel();
                let _ = tx.send(Err(e));
                Job { rx, started: Instant::now(), what: "posing".into() }
            }
        }
    }
    #[cfg(not(target_arch = "wasm32"))]
    Job::spawn(format!("posing and building the {} grid", config.kind), ui, move || {
        let posed = pose()?;
        let mut built = build_here(&posed.tris, &config, scene_generation, gpu.as_ref())?;
        built.pose = Some(posed);
        Ok(built)
    })
}

/// Starts building `config` for the scene of `scene_generation`: natively on a thread; in the
/// browser in the build worker (web/worker.js: a second instance of this wasm), so that the
/// page keeps running, or on the page's thread if the worker cannot start.
pub fn spawn_build(
    ui: &eframe::egui::Context,
    tris: Arc<Vec<[Vec3; 3]>>,
    config: GridConfig,
    scene_generation: u64,
    pose: Option<Posed>,
    gpu: Option<GpuBuild>,
) -> Job<Result<Built, String>> {
    let what = format!("building the {} grid", config.kind);
    // In the browser a GPU build is awaited on the page: its passes run on the device and its
    // readbacks resolve between frames.
    #[cfg(target_arch = "wasm32")]
    if let Some(g) = gpu.as_ref().filter(|_| gridrt_gpu::build::GridBuilder::supports(&config)).cloned() {
        let (tx, rx) = channel();
        let wake = ui.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let built = super::built::build_on_gpu_async(&g, &tris, &config, scene_generation).await;
            let _ = tx.send(built.map(|b| Built { pose, ..b }));
            wake.request_repaint();
        });
        return Job { rx, started: Instant::now(), what: format!("building the {} grid on the GPU", config.kind) };
    }
    #[cfg(target_arch = "wasm32")]
    {
        let (tx, rx) = channel();
        let wake = ui.clone();
        let worker_pose = pose.clone();
        let sent = super::web::build_in_worker_async(&tris, &config, move |r| {
            let built = r.and_then(|bytes| decode_structure(&bytes)).map(|(grid, report)| Built {
                scene_generation,
                config,
                grid: Arc::new(grid),
                report,
                built_on: super::built::BuiltOn::Worker,
                pose: worker_pose,
                on_gpu: None,
            });
            let _ = tx.send(built);
            wake.request_repaint();
        });
        match sent {
            Ok(()) => return Job { rx, started: Instant::now(), what },
            Err(e) => log::warn!("the build worker is unavailable ({e}): building on the page's thread"),
        }
    }
    Job::spawn(what, ui, move || {
        let mut built = build_here(&tris, &config, scene_generation, gpu.as_ref())?;
        built.pose = pose;
        Ok(built)
    })
}

/// Builds on this thread: on the GPU when asked and it builds `config` (natively), else on the
/// CPU.
fn build_here(
    tris: &[[Vec3; 3]],
    config: &GridConfig,
    scene_generation: u64,
    gpu: Option<&GpuBuild>,
) -> Result<Built, String> {
    #[cfg(not(target_arch = "wasm32"))]
    if let Some(g) = gpu.filter(|_| gridrt_gpu::build::GridBuilder::supports(config)) {
        return super::built::build_on_gpu(g, tris, config, scene_generation);
    }
    #[cfg(target_arch = "wasm32")]
    let _ = gpu;
    build_structure(tris, config, scene_generation)
}

/// One background job and its result channel.
#[derive(Debug)]
pub struct Job<T> {
    rx: Receiver<T>,
    pub started: Instant,
    pub what: String,
}

impl<T: Send + 'static> Job<T> {
    /// Runs `f` off the UI thread and wakes the UI when it is done.
    pub fn spawn(
        what: impl Into<String>,
        ui: &eframe::egui::Context,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Job<T> {
        let (tx, rx) = channel();
        let ui = ui.clone();
        let run = move || {
            let _ = tx.send(f());
            ui.request_repaint();
        };
        #[cfg(not(target_arch = "wasm32"))]
        std::thread::Builder::new().name("gridrt job".into()).spawn(run).expect("spawning a job thread");
        // No threads in the browser: the job runs on the page's thread, after a zero-delay
        // timeout so that the page first paints the spinner saying what is about to happen.
        #[cfg(target_arch = "wasm32")]
        wasm_bindgen_futures::spawn_local(async move {
            super::web::yield_to_browser().await;
            run();
        });
        Job { rx, started: Instant::now(), what: what.into() }
    }

    /// The result once the job is done; `Some(Err)` if the job's thread died.
    pub fn poll(&mut self) -> Option<Result<T, String>> {
        match self.rx.try_recv() {
            Ok(v) => Some(Ok(v)),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(format!("{} stopped unexpectedly (a panic?)", self.what))),
        }
    }

    pub fn elapsed_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gui::built::{decode_structure, encode_structure};

    #[test]
    fn scenes_load_from_bytes_and_bad_files_give_messages() {
        let bytes: Arc<[u8]> = gridrt_scene::DEFAULT_SCENE_GLB.into();
        let s = load_scene(&SceneSource::Bytes { name: "dropped.glb".into(), bytes }).unwrap();
        assert_eq!(s.tris.len(), s.report.triangles);
        assert!(s.tris.len() > 1000);
        let bad: Arc<[u8]> = b"glTF\x02\x00\x00\x00garbage".as_slice().into();
        let e = load_scene(&SceneSource::Bytes { name: "bad.glb".into(), bytes: bad }).unwrap_err();
        assert!(e.contains("bad.glb"), "{e}");
        let e = load_scene(&SceneSource::Path("/nonexistent/x.glb".into())).unwrap_err();
        assert!(e.contains("x.glb"), "{e}");
    }

    #[test]
    fn every_kind_survives_the_worker_encoding() {
        let s = load_scene(&SceneSource::Default).unwrap();
        for kind in gridrt_grid::GridKind::ALL {
            let cfg = GridConfig { kind, ..GridConfig::default() };
            let b = build_structure(&s.tris, &cfg, 1).unwrap();
            let bytes = encode_structure(&b.grid, &b.report).unwrap();
            let (grid, report) = decode_structure(&bytes).unwrap();
            assert_eq!(grid, *b.grid, "{kind}");
            assert_eq!(serde_json::to_string(&report).unwrap(), serde_json::to_string(&b.report).unwrap());
        }
        assert!(decode_structure(&[1, 2, 3]).is_err());
    }

    #[test]
    fn builds_report_the_configuration_they_were_asked_for() {
        let s = load_scene(&SceneSource::Default).unwrap();
        let cfg = GridConfig { kind: gridrt_grid::GridKind::Macrocell, ..GridConfig::default() };
        let b = build_structure(&s.tris, &cfg, 7).unwrap();
        assert_eq!((b.scene_generation, b.config, b.grid.kind()), (7, cfg, gridrt_grid::GridKind::Macrocell));
        let bad = GridConfig { macro_size: Some(3), ..cfg };
        assert!(build_structure(&s.tris, &bad, 7).unwrap_err().contains("macrocell"));
    }
}
