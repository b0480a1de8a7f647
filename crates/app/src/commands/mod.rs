//! One module per subcommand, plus the helpers they share.

pub mod build;
pub mod demo;
pub mod generate;
pub mod info;
pub mod rays;
pub mod trace;

use std::path::Path;

use anyhow::Context;
use glam::Vec3;
use gridrt_grid::{BuildOptions, FlatGrid, InsertMode, PhaseTimes, ResolutionChoice};
use gridrt_scene::{LoadReport, Mesh};

use crate::cli::{GridArgs, SceneArg};

/// Loads the scene named on the command line (`@default`: the embedded one).
pub fn load_scene(arg: &SceneArg) -> anyhow::Result<(Mesh, LoadReport)> {
    if arg.scene == "@default" {
        return Ok(gridrt_scene::load_default());
    }
    Ok(gridrt_scene::gltf_load::load_path(Path::new(&arg.scene))?)
}

/// A built grid with how it was chosen and how long it took.
pub struct Built {
    pub grid: FlatGrid,
    pub choice: ResolutionChoice,
    pub times: PhaseTimes,
    pub options: BuildOptions,
}

pub fn build_grid(tris: &[[Vec3; 3]], args: &GridArgs) -> anyhow::Result<Built> {
    let options = BuildOptions {
        insert: if args.exact { InsertMode::Exact } else { InsertMode::BoundingBox },
        parallel: !args.serial,
    };
    let model = args.cost_model()?;
    let (grid, choice, times) =
        gridrt_grid::build_flat(tris, args.resolution, &model, options).context("building the grid")?;
    Ok(Built { grid, choice, times, options })
}

/// "12.3 MiB" style.
pub fn human_bytes(b: u64) -> String {
    let b = b as f64;
    if b >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", b / (1024.0 * 1024.0))
    } else if b >= 1024.0 {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{b} B")
    }
}
