//! One module per subcommand, plus the helpers they share.

pub mod animate;
pub mod bench;
pub mod bench_trace;
pub mod build;
pub mod demo;
pub mod experiment;
pub mod generate;
pub mod info;
pub mod rays;
pub mod render;
pub mod trace;

use std::path::Path;

use anyhow::Context;
use glam::Vec3;
use gridrt_grid::{AnyGrid, BuildReport, GridConfig, structure};
use gridrt_scene::{ClipTime, LoadReport, Loaded, Mesh, PoseScratch, Rig};

use crate::cli::SceneArg;

/// Loads the scene named on the command line (`@default`: the embedded one), posed at
/// `--animation` / `--time` when given.
pub fn load_scene(arg: &SceneArg) -> anyhow::Result<(Mesh, LoadReport)> {
    let posed = arg.animation.is_some() || arg.time.is_some();
    if arg.scene == "@default" {
        anyhow::ensure!(!posed, "the embedded default scene has no animations (--animation / --time)");
        return Ok(gridrt_scene::load_default());
    }
    if !posed {
        return Ok(gridrt_scene::gltf_load::load_path_with(Path::new(&arg.scene), &crate::limits::get())?);
    }
    let Loaded { mut mesh, rig, mut report } = load_rigged(arg)?;
    let time = clip_time(&rig, arg)?;
    rig.pose(Some(time), &mut PoseScratch::default(), &mut mesh.positions)?;
    report.reposed(&mesh, rig.note(time));
    Ok((mesh, report))
}

/// Loads the scene file with its rig (for commands that pose it themselves).
pub fn load_rigged(arg: &SceneArg) -> anyhow::Result<Loaded> {
    anyhow::ensure!(arg.scene != "@default", "the embedded default scene has no animations");
    Ok(gridrt_scene::gltf_load::load_rigged_path_with(Path::new(&arg.scene), &crate::limits::get())?)
}

/// The clip and time `--animation` / `--time` ask for: clip 0 and the clip's start by default.
pub fn clip_time(rig: &Rig, arg: &SceneArg) -> anyhow::Result<ClipTime> {
    let clip = match &arg.animation {
        Some(key) => rig.find_clip(key)?,
        None => {
            anyhow::ensure!(!rig.clips().is_empty(), "{}: --time: the file has no animations", arg.scene);
            0
        }
    };
    if let Some(t) = arg.time {
        anyhow::ensure!(t.is_finite(), "--time must be a finite number of seconds, not {t}");
    }
    Ok(ClipTime { clip, seconds: arg.time.unwrap_or(rig.clips()[clip].start) })
}

/// Builds the structure `cfg` (from the grid flags).
pub fn build_grid(tris: &[[Vec3; 3]], cfg: &GridConfig) -> anyhow::Result<(AnyGrid, BuildReport)> {
    structure::build(tris, cfg).with_context(|| format!("building the {} grid", cfg.kind))
}

pub use crate::format::human_bytes;

/// `r`, an upload of a scene or grid to the device, with a hint where the device cannot hold it:
/// the CPU backend has no such limit.
pub fn on_device<T>(r: Result<T, gridrt_gpu::GpuError>) -> anyhow::Result<T> {
    r.map_err(|e| match e {
        gridrt_gpu::GpuError::BufferTooLarge { .. } => anyhow::Error::new(e).context(format!(
            "the device cannot hold this scene or grid ({} has no such limit)",
            CpuRoute::BackendCpu.flag()
        )),
        e => e.into(),
    })
}

/// How a command runs without a GPU, named in its errors when the GPU cannot serve it.
#[derive(Clone, Copy, Debug)]
pub enum CpuRoute {
    /// `render`, `trace`, `build`, `animate`: `--backend cpu`.
    BackendCpu,
    /// `bench` and the experiments: `--no-gpu`.
    NoGpu,
}

impl CpuRoute {
    /// The command-line flag.
    pub fn flag(self) -> &'static str {
        match self {
            CpuRoute::BackendCpu => "--backend cpu",
            CpuRoute::NoGpu => "--no-gpu",
        }
    }
}

/// The GPU device, with its adapter reported on stderr. `cpu_route`: how the command runs
/// without a GPU, named when there is no adapter (`None`: it cannot).
pub fn gpu_context(cpu_route: Option<CpuRoute>) -> anyhow::Result<gridrt_gpu::GpuContext> {
    let ctx = gridrt_gpu::GpuContext::new_headless_blocking().map_err(|e| without_gpu(e, cpu_route))?;
    eprintln!("GPU adapter: {}", ctx.adapter_name());
    if ctx.is_software() && matches!(cpu_route, Some(CpuRoute::BackendCpu)) {
        // The question users ask first when the "GPU" is slow (README, "Structures and CPU vs GPU").
        eprintln!(
            "note: this adapter is a software one, running on the CPU's own cores: `--backend cpu` gives the \
             same results, usually several times faster"
        );
    }
    Ok(ctx)
}

/// The GPU device unless `no_gpu` (`bench` and the experiments' `--no-gpu`, which their
/// errors name when there is no adapter).
pub fn gpu_unless(no_gpu: bool) -> anyhow::Result<Option<gridrt_gpu::GpuContext>> {
    if no_gpu { Ok(None) } else { gpu_context(Some(CpuRoute::NoGpu)).map(Some) }
}

/// `e`, the failure to open the device, with `cpu_route` (the flag that runs the command
/// without a GPU) named when there is no adapter at all.
fn without_gpu(e: gridrt_gpu::GpuError, cpu_route: Option<CpuRoute>) -> anyhow::Error {
    match (e, cpu_route) {
        (e @ gridrt_gpu::GpuError::NoAdapter { .. }, Some(route)) => anyhow::Error::new(e)
            .context(format!("this command needs a GPU adapter ({} runs it without one)", route.flag())),
        (e, _) => e.into(),
    }
}

#[cfg(test)]
mod tests {
    use gridrt_gpu::GpuError;

    /// A scene or grid the device cannot hold points to the CPU backend; other errors pass as
    /// they are.
    #[test]
    fn a_buffer_too_large_points_to_the_cpu_backend() {
        let e = GpuError::BufferTooLarge { buffer: "triangles", size: 2, limit: 1, which: "max_buffer_size" };
        let text = format!("{:#}", super::on_device::<()>(Err(e)).unwrap_err());
        assert!(text.contains("--backend cpu") && text.contains("triangles needs 2 bytes"), "{text}");
        let text = format!("{:#}", super::on_device::<()>(Err(GpuError::Device("lost".into()))).unwrap_err());
        assert!(!text.contains("--backend cpu"), "{text}");
        assert_eq!(super::on_device(Ok(3)).unwrap(), 3);
    }

    /// No adapter at all names the command's way to run without one; another device error
    /// (an adapter asked for by name and not found) does not.
    #[test]
    fn no_adapter_points_to_the_cpu_route() {
        let none = || GpuError::NoAdapter { backends: wgpu::Backends::all() };
        let text = format!("{:#}", super::without_gpu(none(), Some(super::CpuRoute::BackendCpu)));
        assert!(text.contains("--backend cpu runs it without one") && text.contains("mesa-vulkan-drivers"), "{text}");
        let text = format!("{:#}", super::without_gpu(none(), None));
        assert!(!text.contains("without one") && text.contains("no GPU adapter"), "{text}");
        let e = GpuError::AdapterNotFound { wanted: "x".into(), found: vec![] };
        let text = format!("{:#}", super::without_gpu(e, Some(super::CpuRoute::NoGpu)));
        assert!(!text.contains("--no-gpu"), "{text}");
    }
}
