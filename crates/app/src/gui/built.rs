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
    pub grid: AnyGrid,
    pub report: BuildReport,
    /// Built by the browser's build worker (not on the page's or the app's thread).
    pub in_worker: bool,
    /// The pose it was built over (`None`: the scene's rest pose).
    pub pose: Option<Posed>,
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
    Ok(Built { scene_generation, config: *config, grid, report, in_worker: false, pose: None })
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
