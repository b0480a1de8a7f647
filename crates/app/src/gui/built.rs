//! A structure built for the app: [`build_structure`] (on a native thread, in the browser's
//! build worker, or for a measurement) and the byte form the build worker hands to the page.

use std::sync::Arc;

use glam::Vec3;
use gridrt_grid::{AnyGrid, BuildReport, GridConfig, structure};
use gridrt_scene::ClipTime;

/// A structure built for one scene (by scene generation number) and configuration.
#[derive(Debug)]
pub struct Built {
    pub scene_generation: u64,
    pub config: GridConfig,
    /// Shared with the threads that trace frames on the CPU.
    pub grid: Arc<AnyGrid>,
    pub report: BuildReport,
    /// Where it was built.
    pub built_on: BuiltOn,
    /// The pose it was built over (`None`: the scene's rest pose).
    pub pose: Option<Posed>,
    /// Built on the GPU: the structure (and the posed triangles) already on the device (taken
    /// when it goes on screen).
    pub on_gpu: Option<OnGpu>,
}

/// Where a structure was built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuiltOn {
    /// On the CPU, on a thread of this process (the app's job thread, or the page's thread).
    Cpu,
    /// On the CPU, in the browser's build worker.
    Worker,
    /// By the WGSL build kernels.
    Gpu,
    /// On the CPU, because the GPU build asked for was beyond the device's buffer limits
    /// (natively; the app's job thread).
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    CpuForGpu,
}

impl BuiltOn {
    pub fn name(self) -> &'static str {
        match self {
            BuiltOn::Cpu => "the CPU",
            BuiltOn::Worker => "the build worker",
            BuiltOn::Gpu => "the GPU",
            BuiltOn::CpuForGpu => "the CPU (the device cannot hold the GPU build)",
        }
    }

    /// Whether it answers a request for a GPU build: built there, or on the CPU because the
    /// device could not hold it (asking again would fail again).
    pub fn answers_gpu_build(self) -> bool {
        matches!(self, BuiltOn::Gpu | BuiltOn::CpuForGpu)
    }
}

/// What a GPU build leaves on the device, used as is.
#[derive(Debug)]
pub struct OnGpu {
    pub structure: gridrt_gpu::upload::GpuStructure,
    /// The triangles it was built over (posed ones for an animation frame).
    pub scene: gridrt_gpu::upload::GpuScene,
    /// Uploading the triangles, milliseconds.
    pub upload_ms: f64,
}

/// The app's device and the grid build's pipelines, for builds on a job thread.
#[derive(Clone, Debug)]
pub struct GpuBuild {
    pub ctx: gridrt_gpu::GpuContext,
    pub builder: Arc<gridrt_gpu::build::GridBuilder>,
}

/// Builds `config` over `tris` on the GPU (flat or macrocell, box or exact insertion; see
/// [`gridrt_gpu::build`]) and reads it back for the stats panel and the measurements, in a
/// browser (awaited on the page: the readbacks resolve between frames). Natively it runs to the
/// end on a job thread ([`build_on_gpu`]).
#[cfg(target_arch = "wasm32")]
pub async fn build_on_gpu_async(
    gpu: &GpuBuild,
    tris: &[[Vec3; 3]],
    config: &GridConfig,
    scene_generation: u64,
) -> Result<Built, String> {
    try_build_on_gpu(gpu, tris, config, scene_generation).await.map_err(|e| gpu_build_failed(config, &e))
}

fn gpu_build_failed(config: &GridConfig, e: &gridrt_gpu::GpuError) -> String {
    format!("building the {} grid on the GPU: {e}", config.kind)
}

/// The GPU build, with the device's error.
async fn try_build_on_gpu(
    gpu: &GpuBuild,
    tris: &[[Vec3; 3]],
    config: &GridConfig,
    scene_generation: u64,
) -> Result<Built, gridrt_gpu::GpuError> {
    let started = web_time::Instant::now();
    let scene = gridrt_gpu::upload::GpuScene::new(&gpu.ctx, tris)?;
    let upload_ms = started.elapsed().as_secs_f64() * 1e3;
    let mut g = gpu.builder.build_async(&gpu.ctx, &scene, tris, config).await?;
    let start = web_time::Instant::now();
    let grid = gpu.builder.read_back_async(&gpu.ctx, &g).await?;
    g.times.record_since("read back", start);
    let report = BuildReport {
        kind: config.kind,
        triangles: tris.len(),
        resolution_choice: g.choice,
        macro_samples: g.macro_samples,
        times: g.times,
        stats: grid.stats(tris.len()),
    };
    let on_gpu = Some(OnGpu { structure: g.structure, scene, upload_ms });
    let grid = Arc::new(grid);
    Ok(Built { scene_generation, config: *config, grid, report, built_on: BuiltOn::Gpu, pose: None, on_gpu })
}

/// The GPU build on this (job) thread, blocking; a build beyond the device's buffer
/// limits is made on the CPU instead ([`BuiltOn::CpuForGpu`]; its frames are then traced there
/// when the device cannot hold the grid either).
#[cfg(not(target_arch = "wasm32"))]
pub fn build_on_gpu(
    gpu: &GpuBuild,
    tris: &[[Vec3; 3]],
    config: &GridConfig,
    scene_generation: u64,
) -> Result<Built, String> {
    match pollster::block_on(try_build_on_gpu(gpu, tris, config, scene_generation)) {
        Err(e @ gridrt_gpu::GpuError::BufferTooLarge { .. }) => {
            log::warn!("{}: built on the CPU instead", gpu_build_failed(config, &e));
            let built = build_structure(tris, config, scene_generation)?;
            Ok(Built { built_on: BuiltOn::CpuForGpu, ..built })
        }
        r => r.map_err(|e| gpu_build_failed(config, &e)),
    }
}

/// A scene posed for one animation frame.
#[derive(Clone, Debug)]
pub struct Posed {
    pub time: ClipTime,
    pub tris: Arc<Vec<[Vec3; 3]>>,
    pub pose_ms: f64,
}

/// Builds `config` over `tris`.
pub fn build_structure(tris: &[[Vec3; 3]], config: &GridConfig, scene_generation: u64) -> Result<Built, String> {
    let (grid, report) =
        structure::build(tris, config).map_err(|e| format!("building the {} grid: {e}", config.kind))?;
    let grid = Arc::new(grid);
    Ok(Built { scene_generation, config: *config, grid, report, built_on: BuiltOn::Cpu, pose: None, on_gpu: None })
}

/// A built structure as bytes: how the browser's build worker hands it to the page.
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
pub fn encode_structure(grid: &AnyGrid, report: &BuildReport) -> Result<Vec<u8>, String> {
    postcard::to_allocvec(&(grid, report)).map_err(|e| format!("encoding the structure: {e}"))
}

/// The inverse of [`encode_structure`].
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
pub fn decode_structure(bytes: &[u8]) -> Result<(AnyGrid, BuildReport), String> {
    postcard::from_bytes(bytes).map_err(|e| format!("decoding the structure from the build worker: {e}"))
}
