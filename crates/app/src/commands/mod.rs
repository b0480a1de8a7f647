//! One module per subcommand, plus the helpers they share.

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
use gridrt_scene::{LoadReport, Mesh};

use crate::cli::SceneArg;

/// Loads the scene named on the command line (`@default`: the embedded one).
pub fn load_scene(arg: &SceneArg) -> anyhow::Result<(Mesh, LoadReport)> {
    if arg.scene == "@default" {
        return Ok(gridrt_scene::load_default());
    }
    Ok(gridrt_scene::gltf_load::load_path_with(Path::new(&arg.scene), &crate::limits::get())?)
}

/// Builds the structure `cfg` (from the grid flags).
pub fn build_grid(tris: &[[Vec3; 3]], cfg: &GridConfig) -> anyhow::Result<(AnyGrid, BuildReport)> {
    structure::build(tris, cfg).with_context(|| format!("building the {} grid", cfg.kind))
}

pub use crate::format::human_bytes;

/// The GPU device, with its adapter reported on stderr.
pub fn gpu_context() -> anyhow::Result<gridrt_gpu::GpuContext> {
    let ctx = gridrt_gpu::GpuContext::new_headless_blocking()?;
    eprintln!("GPU adapter: {}", ctx.adapter_name());
    Ok(ctx)
}
