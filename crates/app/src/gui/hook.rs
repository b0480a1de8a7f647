//! The app's test hook: what `window.gridrt` exposes in the browser (see `web.rs`), kept
//! platform-independent so that it is unit-tested natively.
//!
//! The page (or a test driving it) sends [`HookCommand`]s, which the app applies at the start
//! of its next update; the app publishes a [`HookStats`] snapshot at the end of each update and,
//! on request, reads its last finished frame back into [`CapturedFrame`].

// Natively only the unit tests and the app's side use this; the commands come from the page.
#![cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use gridrt_gpu::View;
use gridrt_grid::{GridKind, Traversal};
use gridrt_scene::Camera;
use serde::Serialize;

/// What `window.gridrt.stats()` returns.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct HookStats {
    /// Frames rendered since start.
    pub frames: u64,
    pub adapter: String,
    /// Kind of the structure on screen (not the one being built).
    pub grid: String,
    pub traversal: String,
    /// Primary and shadow rays in coherent packets (the setting).
    pub packets: bool,
    pub view: String,
    /// Name of the scene on screen.
    pub scene: String,
    pub triangles: u64,
    /// Of the last frame's primary rays.
    pub mean_cells_per_ray: f64,
    pub mean_tests_per_ray: f64,
    /// Size and GPU time of the last frame.
    pub width: u32,
    pub height: u32,
    pub frame_ms: f64,
    /// Build time of the structure on screen.
    pub build_ms: f64,
    /// A structure is being built (the previous one stays on screen meanwhile).
    pub building: bool,
    /// Structures built so far by the browser's build worker.
    pub worker_builds: u64,
    /// The structure on screen was built on the GPU.
    pub gpu_built: bool,
    /// No load or build running, no frame in flight, the last frame shows the current settings
    /// and no command is waiting.
    pub idle: bool,
    /// The error the UI shows (load, build, GPU), if any.
    pub error: Option<String>,
    /// Milliseconds from page start to the first frame (browser clock).
    pub first_frame_ms: Option<f64>,
    /// The timeline of an animated scene (`None`: the scene has no clips).
    pub animation: Option<AnimationStats>,
}

/// The timeline as `stats().animation` shows it.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct AnimationStats {
    pub clip: usize,
    /// The timeline's clip time, and the pose on screen.
    pub seconds: f64,
    pub shown_seconds: Option<f64>,
    pub playing: bool,
    /// Animation frames shown (each one posed, rebuilt and rendered).
    pub frames_shown: u64,
    /// Over the last few seconds.
    pub fps: Option<f64>,
    /// Means over the newest frames.
    pub pose_ms: f64,
    pub build_ms: f64,
    pub upload_ms: f64,
    pub trace_ms: f64,
}

fn on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" | "true" => Ok(true),
        "off" | "false" => Ok(false),
        _ => Err(format!("{s:?}: expected on or off")),
    }
}

/// A command from the page.
#[derive(Clone, Debug, PartialEq)]
pub enum HookCommand {
    Grid(GridKind),
    View(View),
    Traversal(Traversal),
    Camera(Camera),
    /// Render at this fixed size instead of following the window (`None`: follow it again).
    FrameSize(Option<[u32; 2]>),
    /// Read back the last finished frame (`id` is returned to the caller).
    Capture(u64),
    /// Open a scene from bytes (a file the page fetched, picked or had dropped).
    Open {
        name: String,
        bytes: Arc<[u8]>,
    },
    /// Dismiss the error the UI shows (as its "dismiss" button does).
    DismissError,
    /// Play or pause the timeline.
    Playing(bool),
    /// Move the timeline to this clip time (seconds).
    Seek(f64),
    /// Build flat and macrocell grids on the GPU (or not).
    GpuBuild(bool),
    /// Trace primary and shadow rays in coherent packets (or not).
    Packets(bool),
}

impl HookCommand {
    /// Parses the string forms `window.gridrt.set_*` take; errors name what was expected.
    pub fn grid(s: &str) -> Result<HookCommand, String> {
        s.parse::<GridKind>().map(HookCommand::Grid)
    }
    pub fn view(s: &str) -> Result<HookCommand, String> {
        s.parse::<View>().map(HookCommand::View)
    }
    pub fn traversal(s: &str) -> Result<HookCommand, String> {
        match s.parse::<Traversal>()? {
            Traversal::Bresenham => Err("bresenham has no GPU walker (it misses cells); use aw, cw or liu".into()),
            t => Ok(HookCommand::Traversal(t)),
        }
    }
    pub fn playing(s: &str) -> Result<HookCommand, String> {
        match s {
            "true" | "play" => Ok(HookCommand::Playing(true)),
            "false" | "pause" => Ok(HookCommand::Playing(false)),
            _ => Err(format!("{s:?}: expected play or pause")),
        }
    }
    pub fn gpu_build(s: &str) -> Result<HookCommand, String> {
        on_off(s).map(HookCommand::GpuBuild)
    }
    pub fn packets(s: &str) -> Result<HookCommand, String> {
        on_off(s).map(HookCommand::Packets)
    }
    pub fn seek(s: &str) -> Result<HookCommand, String> {
        match s.trim().parse::<f64>() {
            Ok(t) if t.is_finite() => Ok(HookCommand::Seek(t)),
            _ => Err(format!("{s:?}: expected a clip time in seconds")),
        }
    }
    pub fn camera(s: &str) -> Result<HookCommand, String> {
        Camera::parse(s).map(HookCommand::Camera)
    }
    pub fn frame_size(w: u32, h: u32) -> Result<HookCommand, String> {
        let max = gridrt_gpu::render::MAX_IMAGE_SIDE;
        match (w, h) {
            (0, 0) => Ok(HookCommand::FrameSize(None)),
            (1.., 1..) if w <= max && h <= max => Ok(HookCommand::FrameSize(Some([w, h]))),
            _ => Err(format!("frame size {w}x{h}: each side must be 1..={max} (0, 0 follows the window)")),
        }
    }
}

/// A frame read back for the page: RGBA8, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct CapturedFrame {
    /// The `Capture` id it answers.
    pub id: u64,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// State shared between the app and the page.
#[derive(Debug, Default)]
pub struct HookState {
    pub stats: HookStats,
    pub commands: VecDeque<HookCommand>,
    pub frame: Option<CapturedFrame>,
    next_capture: u64,
    /// Wakes the app when a command arrives.
    pub repaint: Option<eframe::egui::Context>,
}

pub type Hook = Arc<Mutex<HookState>>;

impl HookState {
    /// The stats as the page sees them: not idle while commands wait (the published snapshot
    /// is from the app's last update, which may predate them).
    pub fn snapshot(&self) -> HookStats {
        HookStats { idle: self.stats.idle && self.commands.is_empty(), ..self.stats.clone() }
    }

    /// Queues a capture and returns its id.
    pub fn capture(&mut self) -> u64 {
        self.next_capture += 1;
        self.commands.push_back(HookCommand::Capture(self.next_capture));
        self.next_capture
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_parse_and_bad_values_are_explained() {
        assert_eq!(HookCommand::grid("macrocell"), Ok(HookCommand::Grid(GridKind::Macrocell)));
        assert!(HookCommand::grid("octree").is_err());
        assert_eq!(HookCommand::view("heatmap-cells"), Ok(HookCommand::View(View::HeatmapCells)));
        assert!(HookCommand::view("wireframe").unwrap_err().contains("shaded"));
        assert_eq!(HookCommand::traversal("liu"), Ok(HookCommand::Traversal(Traversal::Liu)));
        assert!(HookCommand::traversal("bresenham").unwrap_err().contains("GPU"));
        let HookCommand::Camera(c) = HookCommand::camera("1,2,3,0,0,0,45").unwrap() else { panic!() };
        assert_eq!((c.eye, c.vfov_deg), (glam::Vec3::new(1.0, 2.0, 3.0), 45.0));
        assert!(HookCommand::camera("1,2").is_err());
        assert_eq!(HookCommand::frame_size(0, 0), Ok(HookCommand::FrameSize(None)));
        assert_eq!(HookCommand::frame_size(320, 240), Ok(HookCommand::FrameSize(Some([320, 240]))));
        assert!(HookCommand::frame_size(0, 240).is_err());
        assert!(HookCommand::frame_size(1 << 20, 2).is_err());
        assert_eq!(HookCommand::playing("pause"), Ok(HookCommand::Playing(false)));
        assert!(HookCommand::playing("maybe").unwrap_err().contains("play or pause"));
        assert_eq!(HookCommand::seek(" 1.5"), Ok(HookCommand::Seek(1.5)));
        assert!(HookCommand::seek("NaN").is_err());
        assert_eq!(HookCommand::gpu_build("on"), Ok(HookCommand::GpuBuild(true)));
        assert!(HookCommand::gpu_build("maybe").is_err());
        assert_eq!(HookCommand::packets("off"), Ok(HookCommand::Packets(false)));
        assert!(HookCommand::packets("8").is_err());
    }

    #[test]
    fn captures_get_increasing_ids_and_queue_in_order() {
        let mut h = HookState::default();
        h.commands.push_back(HookCommand::Grid(GridKind::Flat));
        assert_eq!((h.capture(), h.capture()), (1, 2));
        assert_eq!(h.commands.len(), 3);
        assert_eq!(h.commands[1], HookCommand::Capture(1));
        h.stats.idle = true;
        assert!(!h.snapshot().idle, "commands are waiting");
        h.commands.clear();
        assert!(h.snapshot().idle);
        let json = serde_json::to_value(&h.stats).unwrap();
        for key in ["frames", "adapter", "grid", "triangles", "mean_cells_per_ray", "idle", "error"] {
            assert!(json.get(key).is_some(), "stats() lacks {key}");
        }
    }
}
