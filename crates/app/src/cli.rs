//! Command-line definitions (clap). Every subcommand has `--help`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use gridrt_grid::cell_plane::CellPlanes;
use gridrt_grid::multires::{MultiresOptions, Policy};
use gridrt_grid::twolevel::TwoLevelOptions;
use gridrt_grid::{CostModel, GridKind, Resolution, Traversal};

#[derive(Debug, Parser)]
#[command(
    name = "gridrt",
    version,
    about = "Grid ray tracer and grid-structure laboratory",
    long_about = "Grid ray tracer and grid-structure laboratory.\n\nWithout a subcommand, opens the desktop app \
                  (on SCENE, or on the embedded default scene); the subcommands run each stage from the command line.",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// Worker threads for parallel builds and tracing (default: all cores).
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// Most triangles a scene may have after instancing (default 2^26 = 67108864).
    #[arg(long, global = true, value_parser = parse_count)]
    pub max_triangles: Option<u64>,
    /// Most bytes loading one scene may allocate, e.g. 512M or 8G (default: a quarter of
    /// physical memory, at most half the address-space limit).
    #[arg(long, global = true, value_parser = parse_bytes)]
    pub max_load_bytes: Option<u64>,
    #[command(flatten)]
    pub app: AppArgs,
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// Options of the desktop app (no subcommand).
#[derive(Debug, Args, Clone, Default)]
pub struct AppArgs {
    /// Scene to open (.glb or .gltf); default: the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Smoke mode: render `--frames` frames in the real window, save a screenshot of it to
    /// this PNG and exit (non-zero on any error).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to render before the screenshot.
    #[arg(long, default_value_t = 3, requires = "screenshot")]
    pub frames: u32,
    /// Grid structure to start with (overrides the saved settings).
    #[arg(long, value_parser = parse_grid)]
    pub grid: Option<GridKind>,
    /// View to start with: shaded, normals, depth, heatmap-cells, heatmap-tests.
    #[arg(long, value_parser = parse_view)]
    pub view: Option<gridrt_gpu::View>,
    /// Traversal to start with: aw, cw or liu.
    #[arg(long, value_parser = parse_traversal)]
    pub traversal: Option<Traversal>,
    /// Coherent 8×8 packets for primary and shadow rays (flat and macrocell grids), on or off.
    #[arg(long, value_enum)]
    pub packets: Option<Switch>,
    /// Camera to start with: auto (frames the scene bounds, the default), framed (the model
    /// fills the image), interior (a view along the scene from inside, for buildings) or
    /// eye_x,eye_y,eye_z,target_x,target_y,target_z,fov.
    #[arg(long, value_parser = CameraArg::parse, allow_hyphen_values = true)]
    pub camera: Option<CameraArg>,
    /// Window size WIDTHxHEIGHT in logical pixels.
    #[arg(long, default_value = "1280x800", value_parser = parse_size)]
    pub window_size: (u32, u32),
    /// Render frames of exactly WIDTHxHEIGHT pixels, shown scaled to the view (default: the
    /// view's size times the render scale).
    #[arg(long, value_parser = parse_size)]
    pub frame_size: Option<(u32, u32)>,
    /// Rendered pixels per screen pixel, 0.05..=1 (default: saved setting; 1 in smoke mode).
    #[arg(long, value_parser = parse_render_scale)]
    pub render_scale: Option<f32>,
    /// Windows to open at start (repeatable): cost-model, explainer.
    #[arg(long, value_enum)]
    pub open: Vec<AppWindow>,
    /// Start the cost-model window's frame-time measurement once the first structure is built
    /// (implies --open cost-model; a smoke run waits for it).
    #[arg(long)]
    pub measure: bool,
    /// Animated scene: the clip to play, by index or name (default: the first).
    #[arg(long)]
    pub animation: Option<String>,
    /// Animated scene: the clip time to start at, in seconds (default: the clip's start).
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Animated scene: start paused (it plays when it opens otherwise).
    #[arg(long)]
    pub paused: bool,
    /// Build flat and macrocell grids on the GPU (overrides the saved setting).
    #[arg(long)]
    pub gpu_build: bool,
    /// Insert triangles by exact triangle/box overlap (overrides the saved setting).
    #[arg(long)]
    pub exact: bool,
    /// Where to trace the frames (overrides the saved setting): auto (the default) traces on
    /// the CPU, on every core, when the adapter is a software one (lavapipe, SwiftShader), and
    /// on the GPU otherwise. The same image either way.
    #[arg(long, value_enum)]
    pub trace_on: Option<crate::gui::settings::TraceOn>,
    /// The same as `--trace-on cpu`.
    #[arg(long, conflicts_with = "trace_on")]
    pub cpu_trace: bool,
    /// Cap the device's storage-buffer binding size at this many bytes, e.g. 128M (WebGPU's
    /// default and lavapipe's limit), to see how the app handles a device that cannot hold a
    /// scene: natively its frames are then traced on the CPU.
    #[arg(long, value_parser = parse_bytes)]
    pub max_gpu_buffer: Option<u64>,
}

/// The app's extra windows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AppWindow {
    /// The cost-model plot.
    CostModel,
    /// The 2-D traversal explainer.
    Explainer,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Load a scene and print its load report.
    Info(InfoArgs),
    /// Build a grid over a scene and print its size and build time per phase.
    Build(BuildArgs),
    /// Generate a procedural scene and write it as .glb.
    Gen(GenArgs),
    /// Generate a ray file (32 bytes per ray: f32 ox oy oz tmin dx dy dz tmax, little-endian).
    Rays(RaysArgs),
    /// Trace a ray file and write the closest hits (16 bytes per ray: f32 t, u32 triangle, f32 u, f32 v).
    Trace(TraceArgs),
    /// Render an image (camera rays, closest hit, shadow rays, shading) on the GPU or the CPU
    /// (coherent packets by default) and write a PNG.
    Render(RenderArgs),
    /// Measure Mrays/s of the CPU (all threads) and the GPU on primary and random rays.
    BenchTrace(BenchTraceArgs),
    /// Run one of the survey's experiments: CSV/JSON rows, SVG/PNG charts and a table.
    Experiment(ExperimentArgs),
    /// Every grid kind against the `bvh` and `obvhs` BVHs on the same scenes and rays: build
    /// time, memory, Mrays/s, build time against N, the auto resolution, and the targets.
    Bench(BenchArgs),
    /// Build and trace the embedded default scene on the CPU, check against brute force, print a summary.
    Demo,
    /// Play an animation: per frame pose the scene, rebuild the grid from scratch, trace primary
    /// and shadow rays; pose/build/trace ms per frame, PNG frames and a timeline.
    Animate(AnimateArgs),
}

#[derive(Debug, Args)]
pub struct AnimateArgs {
    /// Scene file, --animation (default clip 0) and --time (the first frame's time; default the clip's start).
    #[command(flatten)]
    pub scene: SceneArg,
    /// Frames per second of animation time.
    #[arg(long, default_value_t = 30.0, value_parser = parse_fps)]
    pub fps: f64,
    /// Number of frames (default: one pass over the clip at --fps). Playback loops over the clip.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: Option<u32>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Where the rays are traced: cpu (all threads) or gpu (the structure's WGSL kernels).
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Device,
    /// Image size WIDTHxHEIGHT (one primary and one shadow ray per pixel).
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub packets: PacketArgs,
    /// Write every frame as DIR/frame_NNNNN.png.
    #[arg(long)]
    pub frames_dir: Option<PathBuf>,
    /// Write the timeline (timeline.csv, timeline.json) and its chart (timeline.svg/.png) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the timeline as JSON on stdout (and nothing else there).
    #[arg(long)]
    pub json: bool,
}

/// Coherent packets for a frame's primary and shadow rays (`render`, `animate`).
#[derive(Clone, Copy, Debug, Args)]
pub struct PacketArgs {
    /// Coherent packets for the primary and shadow rays (CPU: flat, macrocell and proximity
    /// grids in --tile packets; GPU: the flat and macrocell packet kernels, 8×8).
    #[arg(long, value_enum, default_value = "on")]
    pub packets: Switch,
    /// Packet edge in pixels (the GPU's is 8).
    #[arg(long, default_value_t = gridrt_grid::coherent::DEFAULT_TILE, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub tile: u32,
}

// Read by the commands (native only).
#[cfg(not(target_arch = "wasm32"))]
impl PacketArgs {
    pub fn on(&self) -> bool {
        self.packets == Switch::On
    }

    /// The CPU's packet settings, `None` for single rays.
    pub fn options(&self, mailbox: bool) -> Option<gridrt_grid::PacketOptions> {
        self.on().then_some(gridrt_grid::PacketOptions { tile: self.tile, mailbox })
    }
}

/// On or off (`render --packets`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    On,
    Off,
}

/// Where a stage runs (`animate --backend`, `build --backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Device {
    Cpu,
    Gpu,
}

fn parse_fps(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 && v <= 10_000.0 { Ok(v) } else { Err("must be in (0, 10000]".into()) }
}

/// A scene: a .glb/.gltf path, or `@default` for the embedded default scene.
#[derive(Debug, Args)]
pub struct SceneArg {
    /// Scene file (.glb or .gltf), or @default for the embedded default scene.
    pub scene: String,
    /// Animation clip to pose the scene with, by index or name (`gridrt info` lists them).
    /// Without --time: the clip's start.
    #[arg(long)]
    pub animation: Option<String>,
    /// Pose the scene at this time in seconds (clamped to the clip). Without --animation: clip 0.
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<f64>,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Grid construction options shared by `build` and `trace`.
#[derive(Debug, Args)]
pub struct GridArgs {
    /// Grid structure: flat, macrocell, multires, twolevel or proximity.
    #[arg(long, default_value = "flat", value_parser = parse_grid)]
    pub grid: GridKind,
    /// Resolution of the flat / fine / top grid: auto (cost-model guess-and-check), density=λ,
    /// point, line, m=N, or mx,my,mz. Default: auto (multires: density=0.0625; twolevel: λ₁·N cells).
    #[arg(long, value_parser = parse_resolution)]
    pub resolution: Option<Resolution>,
    /// Insert triangles by exact triangle/box overlap instead of by bounding box (the auto
    /// resolution is the one bounding-box insertion would get).
    #[arg(long)]
    pub exact: bool,
    /// Build on one thread (the result is identical to the parallel build).
    #[arg(long)]
    pub serial: bool,
    /// Cost model Tsetup (survey §3.2). Without any of --t-setup/--t-step/--t-inter, the
    /// calibration saved by `gridrt experiment cost-constants --save` is used when it exists,
    /// else the memory-aware model's 1.0, 0.1, 0.35 (the survey's Tinter is 0.5).
    #[arg(long)]
    pub t_setup: Option<f64>,
    /// Cost model Tstep (default 0.1, or the calibration's).
    #[arg(long)]
    pub t_step: Option<f64>,
    /// Cost model Tinter (default 0.35, or the calibration's).
    #[arg(long)]
    pub t_inter: Option<f64>,
    /// Memory weight of the auto resolution: cell steps' worth of time per byte of grid per
    /// triangle (default 2; 0 with --t-inter 0.5 is the survey's model and interval).
    #[arg(long, value_parser = parse_memory_weight)]
    pub memory_weight: Option<f64>,
    /// Cache the memory term assumes, in KiB: a grid of B bytes pays B / (B + cache) of the
    /// term (default 1024; 0: the whole term at every size).
    #[arg(long, value_parser = parse_memory_weight)]
    pub cache_kib: Option<f64>,
    /// Grid size in MiB beyond which the auto resolution counts every further byte as read from
    /// DRAM (default 16) …
    #[arg(long, value_parser = parse_memory_weight)]
    pub dram_mib: Option<f64>,
    /// … at this many more cell steps per byte per triangle (default 8; 0: no DRAM tier).
    #[arg(long, value_parser = parse_memory_weight)]
    pub dram_weight: Option<f64>,
    /// Guess-and-check's tie tolerance: from the least T(m), the auto resolution moves to each
    /// coarser sample whose T(m) is within this fraction of it (default 0.03; 0: the least T(m)).
    #[arg(long, value_parser = parse_memory_weight)]
    pub tie_tolerance: Option<f64>,
    /// Number of resolutions sampled by guess-and-check.
    #[arg(long, default_value_t = CostModel::memory_aware().samples)]
    pub samples: u32,
    /// macrocell: fine cells per macrocell edge, a power of two (default: chosen by the cost model).
    #[arg(long)]
    pub macro_size: Option<u32>,
    /// multires: sub-grid policy: adaptive, octree, constant[=k], max-depth[=leaf_size].
    #[arg(long, default_value = "adaptive", value_parser = parse_policy)]
    pub policy: Policy,
    /// multires: deepest sub-grid level (top = 0).
    #[arg(long, default_value_t = MultiresOptions::default().max_depth)]
    pub max_depth: u32,
    /// multires: cells per triangle of an adaptive sub-grid.
    #[arg(long, default_value_t = MultiresOptions::default().density)]
    pub density: f64,
    /// twolevel: top-grid cells per triangle (λ₁).
    #[arg(long, default_value_t = TwoLevelOptions::default().top_density)]
    pub top_density: f64,
    /// twolevel: leaf-grid cells per triangle (λ₂).
    #[arg(long, default_value_t = TwoLevelOptions::default().leaf_density)]
    pub leaf_density: f64,
    /// twolevel: a leaf grid under every non-empty top cell (Kalojanov et al.'s rule) instead of
    /// where the cost model predicts it pays.
    #[arg(long)]
    pub every_top_cell: bool,
    /// Cell slabs, which skip an occupied cell whose slab the ray passes (auto: macrocell grids
    /// and exact-insertion flat grids whose references mostly lie in cells of 6 or more; on:
    /// every flat and macrocell grid; off: none).
    #[arg(long, default_value = "auto", value_parser = parse_cell_planes)]
    pub cell_planes: CellPlanes,
    /// Most cells a structure may have (all levels), whatever chose its resolution.
    #[arg(long, default_value_t = CostModel::default().max_cells, value_parser = parse_count)]
    pub max_cells: u64,
}

fn parse_grid(s: &str) -> Result<GridKind, String> {
    s.parse()
}

fn parse_cell_planes(s: &str) -> Result<CellPlanes, String> {
    s.parse()
}

fn parse_policy(s: &str) -> Result<Policy, String> {
    s.parse()
}

fn parse_resolution(s: &str) -> Result<Resolution, String> {
    s.parse()
}

#[derive(Debug, Args)]
pub struct BuildArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Where the grid is built: cpu, or gpu (flat and macrocell grids, box or exact insertion, through
    /// WGSL kernels; bit-identical to the CPU build: compare `cells_digest`).
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Device,
    /// Print the result as JSON (includes the sampled cost curve).
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GenKind {
    Mountain,
    Sphereflake,
    Particles,
    Slivers,
    TeapotInStadium,
    /// Animated: skinned tubes swaying (one skin each) and rigid balls orbiting, on a floor;
    /// --size is the number of tubes (500: about 1M triangles).
    Crowd,
}

#[derive(Debug, Args)]
pub struct GenArgs {
    /// Scene kind.
    #[arg(value_enum)]
    pub kind: GenKind,
    /// Size parameter (meaning depends on the kind; see the printed summary). Default per kind.
    #[arg(long)]
    pub size: Option<u32>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output .glb file.
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RayKind {
    /// Origins uniform in the scene bounds (+10%), directions uniform on the sphere.
    Random,
    /// Primary rays of the camera that frames the scene bounds (`--camera auto`), 4:3, row-major.
    Camera,
    /// Primary rays of a camera the model fills (at least 75% of a probe image hits), 4:3.
    Framed,
    /// Primary rays of a view along the scene from inside (for buildings), 4:3.
    Interior,
    /// From one point (--origin, default the bounds centre) aimed at vertices, edge points and random directions.
    Inside,
}

#[derive(Debug, Args)]
pub struct RaysArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[arg(long, value_enum)]
    pub kind: RayKind,
    /// Number of rays.
    #[arg(long, default_value_t = 100_000, value_parser = parse_ray_count)]
    pub count: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Origin for --kind inside, as x,y,z.
    #[arg(long)]
    pub origin: Option<String>,
    /// Output ray file.
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// Grid traversal on the CPU (all threads).
    Cpu,
    /// Brute force over every triangle (the reference).
    Brute,
    /// The structure's WGSL trace kernel through wgpu (WGPU_ADAPTER_NAME picks the adapter).
    Gpu,
}

#[derive(Debug, Args)]
pub struct TraceArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    /// Input ray file.
    #[arg(long)]
    pub rays: PathBuf,
    /// Output hits file.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Traversal: aw (Amanatides–Woo), cw (Cleary–Wyvill), liu (Liu et al.), bresenham (incomplete: misses hits).
    #[arg(long, default_value = "aw", value_parser = parse_traversal)]
    pub traversal: Traversal,
    /// Skip triangles this ray already tested (hashed per-ray mailbox).
    #[arg(long)]
    pub mailbox: bool,
    /// Walk every ray alone. By default incoherent rays on a flat, macrocell or proximity grid
    /// larger than 2 MiB walk eight at a time, interleaved so that their cache misses overlap
    /// (same hits).
    #[arg(long)]
    pub no_interleave: bool,
    /// closest: each ray's closest hit (t, then triangle index; the same bits on every
    /// structure and backend). any: occlusion (shadow rays): a ray's search ends at the first hit
    /// found, so whether it hits is defined (and equals the closest query's), not which hit.
    #[arg(long, value_enum, default_value = "closest")]
    pub query: QueryArg,
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `trace --query`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum QueryArg {
    Closest,
    Any,
}

impl From<QueryArg> for gridrt_grid::Query {
    fn from(q: QueryArg) -> gridrt_grid::Query {
        match q {
            QueryArg::Closest => gridrt_grid::Query::Closest,
            QueryArg::Any => gridrt_grid::Query::Any,
        }
    }
}

fn parse_traversal(s: &str) -> Result<Traversal, String> {
    s.parse()
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Traversal: aw, cw or liu.
    #[arg(long, default_value = "aw", value_parser = parse_traversal)]
    pub traversal: Traversal,
    /// Disable the per-ray mailbox.
    #[arg(long)]
    pub no_mailbox: bool,
    /// View: shaded, normals, depth, heatmap-cells, heatmap-tests.
    #[arg(long, default_value = "shaded", value_parser = parse_view)]
    pub view: gridrt_gpu::View,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Camera: auto (frames the scene bounds), framed (the model fills the image), interior (a
    /// view along the scene from inside, for buildings) or eye_x,eye_y,eye_z,target_x,target_y,target_z,fov.
    #[arg(long, default_value = "auto", value_parser = CameraArg::parse, allow_hyphen_values = true)]
    pub camera: CameraArg,
    /// Count at the top of the heatmap colour scale (positive).
    #[arg(long, default_value_t = 64.0, value_parser = parse_heat_max)]
    pub heat_max: f32,
    /// Where the rays are traced: gpu (the WGSL kernels) or cpu (all threads).
    #[arg(long, value_enum, default_value = "gpu")]
    pub backend: Device,
    #[command(flatten)]
    pub packets: PacketArgs,
    /// Write the per-pixel primary hits (row-major) in the hits format.
    #[arg(long)]
    pub hits_out: Option<PathBuf>,
    /// Write the primary rays (row-major) in the ray format.
    #[arg(long)]
    pub rays_out: Option<PathBuf>,
    /// Print a JSON summary on stdout (and nothing else there).
    #[arg(long)]
    pub json: bool,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
}

fn parse_view(s: &str) -> Result<gridrt_gpu::View, String> {
    s.parse()
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("expected WIDTHxHEIGHT, got \"{s}\""))?;
    let w: u32 = w.parse().map_err(|_| format!("bad width in \"{s}\""))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height in \"{s}\""))?;
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err("width and height must be in 1..=16384".into());
    }
    Ok((w, h))
}

#[derive(Debug, Args)]
pub struct ExperimentArgs {
    /// Which experiment: fig5 (time, N_m and memory against m per scene kind, with the cost
    /// model), bresenham (cells a naive Bresenham misses), models (fastest m against N for
    /// point- and line-like scenes), hierarchy (the five structures side by side),
    /// cost-constants (Tsetup, Tstep, Tinter fitted on this machine), cgt (coherent packets
    /// against single rays by scene, packet size and resolution).
    #[arg(value_enum)]
    pub name: ExperimentName,
    /// Folder of .glb scenes with a manifest.json giving each file's kind (fig5; default:
    /// ../shared/scenes when present, else procedural stand-ins).
    #[arg(long)]
    pub scenes: Option<PathBuf>,
    /// Output folder for the CSV, JSON, SVG and PNG files.
    #[arg(long, default_value = "out/experiments")]
    pub out: PathBuf,
    /// Rays per measurement.
    #[arg(long, default_value_t = 100_000, value_parser = parse_ray_count)]
    pub rays: usize,
    /// Fewer and smaller cases (a smoke run in seconds).
    #[arg(long)]
    pub quick: bool,
    /// Skip the GPU measurements (fig5).
    #[arg(long)]
    pub no_gpu: bool,
    /// fig5, hierarchy, cgt: use the procedural stand-in scenes even when a scenes folder exists.
    #[arg(long, conflicts_with = "scenes")]
    pub procedural: bool,
    /// cost-constants: save the fitted CPU constants as the calibration the command line's
    /// auto resolution uses ($GRIDRT_CALIBRATION, else ~/.config/gridrt/cost-constants.json).
    #[arg(long)]
    pub save: bool,
}

/// The experiments of `gridrt experiment`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExperimentName {
    Fig5,
    Bresenham,
    Models,
    Hierarchy,
    CostConstants,
    Cgt,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Folder of .glb scenes (every scene of its manifest.json, else every .glb/.gltf in it;
    /// default: ../shared/scenes when present, else procedural stand-ins).
    #[arg(long)]
    pub scenes: Option<PathBuf>,
    /// Use the procedural stand-in scenes even when a scenes folder exists.
    #[arg(long, conflicts_with = "scenes")]
    pub procedural: bool,
    /// Rays per set (camera rays and random rays, each).
    #[arg(long, default_value_t = 250_000, value_parser = parse_ray_count)]
    pub rays: usize,
    /// Repetitions of every build and trace (the best is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Output folder for the CSV, JSON, SVG and PNG files.
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
    /// Print everything as one JSON document on stdout instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Skip the GPU columns.
    #[arg(long)]
    pub no_gpu: bool,
    /// Skip the bvh/obvhs rows.
    #[arg(long)]
    pub no_peers: bool,
    /// Skip build time against N.
    #[arg(long)]
    pub no_scaling: bool,
    /// Largest triangle count of the scaling run (at least 1.6M).
    #[arg(long, default_value_t = 2_400_000)]
    pub scaling_max: usize,
    /// Skip the sweep around the auto resolution.
    #[arg(long)]
    pub no_auto_check: bool,
    /// Two scenes, fewer rays, small scaling sizes (a smoke run).
    #[arg(long)]
    pub quick: bool,
    /// Dynamic scenes instead: every animated scene (<scenes>/animated) and a generated crowd of
    /// ≥ 1M triangles, posed per frame; every grid rebuilt and every BVH rebuilt or refit per
    /// frame, tracing 512×512 primary and shadow rays.
    #[arg(long)]
    pub dynamic: bool,
    /// Edge of the CPU's square ray packets on the camera sets, in pixels (the flat, macrocell
    /// and proximity grids get a packet row each; --dynamic's packet rows use it too).
    #[arg(long, default_value_t = gridrt_grid::coherent::DEFAULT_TILE, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub tile: u32,
    /// Frames per animated scene (evenly over its first clip) with --dynamic, after one warm-up
    /// frame that is not counted.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
}

#[derive(Debug, Args)]
pub struct BenchTraceArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Rays per set (primary and random).
    #[arg(long, default_value_t = 1_000_000, value_parser = parse_ray_count)]
    pub rays: usize,
    /// Traversal: aw, cw or liu.
    #[arg(long, default_value = "aw", value_parser = parse_traversal)]
    pub traversal: Traversal,
    /// Repetitions (the best is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Edge of the CPU's square ray packets, in pixels (the packet column).
    #[arg(long, default_value_t = gridrt_grid::coherent::DEFAULT_TILE, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub tile: u32,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

fn parse_memory_weight(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(w) if w.is_finite() && w >= 0.0 => Ok(w),
        _ => Err(format!("expected a finite number ≥ 0, got \"{s}\"")),
    }
}

/// A camera named on the command line (`--camera`): one of the benchmark's views of the scene
/// ([`crate::lab::views`]) or given outright.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraArg {
    /// Frames the scene bounds ([`gridrt_scene::Camera::fit`]).
    Auto,
    /// The model fills the image ([`crate::lab::views::framed_camera`]).
    Framed,
    /// Along the scene from inside ([`crate::lab::views::interior_camera`]).
    Interior,
    /// eye_x,eye_y,eye_z,target_x,target_y,target_z,fov.
    At(gridrt_scene::Camera),
}

impl CameraArg {
    pub fn parse(s: &str) -> Result<CameraArg, String> {
        Ok(match s {
            "auto" => CameraArg::Auto,
            "framed" => CameraArg::Framed,
            "interior" => CameraArg::Interior,
            _ if !s.contains(',') => {
                return Err(format!(
                    "expected auto, framed, interior or eye_x,eye_y,eye_z,target_x,target_y,target_z,fov, got \"{s}\""
                ));
            }
            _ => CameraArg::At(gridrt_scene::Camera::parse(s)?),
        })
    }
}

/// A count of at least 1.
fn parse_count(s: &str) -> Result<u64, String> {
    match s.trim().parse::<u64>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("expected a whole number of at least 1, got \"{s}\"")),
    }
}

/// Rays to make: at least 1, at most what a quarter of memory holds (32 bytes each, and the hits).
fn parse_ray_count(s: &str) -> Result<usize, String> {
    let n = parse_count(s)?;
    let max = gridrt_scene::load_budget::default_max_bytes() / 48;
    if n > max {
        return Err(format!("{n} rays need {} bytes with their hits; at most {max} fit in the memory budget", n * 48));
    }
    Ok(n as usize)
}

/// Bytes, optionally with a binary suffix: 1048576, 512K, 64M, 8G, 1T.
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, shift) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(format!("unknown unit in \"{s}\": use K, M, G or T")),
            };
            (&t[..i], shift)
        }
        _ => (t, 0),
    };
    let n: u64 = digits.trim().parse().map_err(|_| format!("expected bytes such as 512M or 8G, got \"{s}\""))?;
    n.checked_mul(1 << shift).filter(|&b| b >= 1).ok_or_else(|| format!("\"{s}\" is not a usable number of bytes"))
}

fn parse_heat_max(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("the heatmap scale must be a positive number, got \"{s}\"")),
    }
}

fn parse_render_scale(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if (0.05..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("the render scale must be in 0.05..=1, got \"{s}\"")),
    }
}
