//! The WGSL sources, embedded at compile time (`include_str!`) so binaries and the wasm build
//! carry them, and their composition: a line `//!include shared/x.wgsl` is replaced by that
//! file (itself composed), each file at most once per module. In an include path,
//! `{TRAVERSAL}` stands for the walker the module is composed with (`aw`, `cw` or `liu`): each
//! trace pipeline carries only its own walker's code and state; `{HIT_FLOAT}` for how a hit's
//! t, u, v are computed ([`HitFloat`]: f64 where the device has it).

use crate::kernel::GpuWalker;

/// Every WGSL file under `shaders/`, by its path relative to that folder.
pub const SOURCES: &[(&str, &str)] = &[
    ("flat.wgsl", include_str!("../../../shaders/flat.wgsl")),
    ("macrocell.wgsl", include_str!("../../../shaders/macrocell.wgsl")),
    ("hierarchy.wgsl", include_str!("../../../shaders/hierarchy.wgsl")),
    ("proximity.wgsl", include_str!("../../../shaders/proximity.wgsl")),
    ("coherent_flat.wgsl", include_str!("../../../shaders/coherent_flat.wgsl")),
    ("coherent_macrocell.wgsl", include_str!("../../../shaders/coherent_macrocell.wgsl")),
    ("camera.wgsl", include_str!("../../../shaders/camera.wgsl")),
    ("shadow.wgsl", include_str!("../../../shaders/shadow.wgsl")),
    ("shade.wgsl", include_str!("../../../shaders/shade.wgsl")),
    ("present.wgsl", include_str!("../../../shaders/present.wgsl")),
    ("build_bounds.wgsl", include_str!("../../../shaders/build_bounds.wgsl")),
    ("build_count.wgsl", include_str!("../../../shaders/build_count.wgsl")),
    ("build_scan.wgsl", include_str!("../../../shaders/build_scan.wgsl")),
    ("build_scan_add.wgsl", include_str!("../../../shaders/build_scan_add.wgsl")),
    ("build_scatter.wgsl", include_str!("../../../shaders/build_scatter.wgsl")),
    ("build_insert_exact.wgsl", include_str!("../../../shaders/build_insert_exact.wgsl")),
    ("build_sort_cells.wgsl", include_str!("../../../shaders/build_sort_cells.wgsl")),
    ("build_occupancy.wgsl", include_str!("../../../shaders/build_occupancy.wgsl")),
    ("build_cell_bits.wgsl", include_str!("../../../shaders/build_cell_bits.wgsl")),
    ("build_compact.wgsl", include_str!("../../../shaders/build_compact.wgsl")),
    ("shared/types.wgsl", include_str!("../../../shaders/shared/types.wgsl")),
    ("shared/bindings.wgsl", include_str!("../../../shaders/shared/bindings.wgsl")),
    ("shared/ray.wgsl", include_str!("../../../shaders/shared/ray.wgsl")),
    ("shared/triangle.wgsl", include_str!("../../../shaders/shared/triangle.wgsl")),
    ("shared/hit_f32.wgsl", include_str!("../../../shaders/shared/hit_f32.wgsl")),
    ("shared/hit_f64.wgsl", include_str!("../../../shaders/shared/hit_f64.wgsl")),
    ("shared/walker_common.wgsl", include_str!("../../../shaders/shared/walker_common.wgsl")),
    ("shared/walker_aw.wgsl", include_str!("../../../shaders/shared/walker_aw.wgsl")),
    ("shared/walker_cw.wgsl", include_str!("../../../shaders/shared/walker_cw.wgsl")),
    ("shared/walker_liu.wgsl", include_str!("../../../shaders/shared/walker_liu.wgsl")),
    ("shared/macrocell_aw.wgsl", include_str!("../../../shaders/shared/macrocell_aw.wgsl")),
    ("shared/macrocell_cw.wgsl", include_str!("../../../shaders/shared/macrocell_cw.wgsl")),
    ("shared/macrocell_liu.wgsl", include_str!("../../../shaders/shared/macrocell_liu.wgsl")),
    ("shared/macrocell_nested.wgsl", include_str!("../../../shaders/shared/macrocell_nested.wgsl")),
    ("shared/coherent.wgsl", include_str!("../../../shaders/shared/coherent.wgsl")),
    ("shared/closest_hit.wgsl", include_str!("../../../shaders/shared/closest_hit.wgsl")),
    ("shared/flat_grid.wgsl", include_str!("../../../shaders/shared/flat_grid.wgsl")),
    ("shared/render_bindings.wgsl", include_str!("../../../shaders/shared/render_bindings.wgsl")),
    ("shared/build.wgsl", include_str!("../../../shaders/shared/build.wgsl")),
    ("shared/build_triangles.wgsl", include_str!("../../../shaders/shared/build_triangles.wgsl")),
    ("shared/u64.wgsl", include_str!("../../../shaders/shared/u64.wgsl")),
    ("shared/soft_f64.wgsl", include_str!("../../../shaders/shared/soft_f64.wgsl")),
    ("shared/overlap.wgsl", include_str!("../../../shaders/shared/overlap.wgsl")),
    ("shared/build_exact.wgsl", include_str!("../../../shaders/shared/build_exact.wgsl")),
];

/// Error composing a shader: an unknown file or include.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("shader {file}: {detail}")]
pub struct ComposeError {
    pub file: String,
    pub detail: String,
}

pub fn source(name: &str) -> Option<&'static str> {
    SOURCES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// How the triangle test computes a hit's t, u and v once the exact edge signs have accepted it:
/// `{HIT_FLOAT}` in an include (`shaders/shared/hit_{f32,f64}.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HitFloat {
    /// In f32 (WebGPU has no f64): the same triangle as the CPU, t, u, v within a few ulps.
    #[default]
    F32,
    /// In f64, the CPU's operations: bit-identical hits. Needs `wgpu::Features::SHADER_F64`.
    F64,
}

impl HitFloat {
    pub const ALL: [HitFloat; 2] = [HitFloat::F32, HitFloat::F64];

    pub fn name(self) -> &'static str {
        match self {
            HitFloat::F32 => "f32",
            HitFloat::F64 => "f64",
        }
    }

    /// F64 where the device was created with f64 shaders, else F32.
    pub fn for_features(features: wgpu::Features) -> HitFloat {
        if features.contains(wgpu::Features::SHADER_F64) { HitFloat::F64 } else { HitFloat::F32 }
    }
}

/// The composed module for `name` (e.g. `"flat.wgsl"`) with the Amanatides–Woo walker and f32
/// hits.
pub fn compose(name: &str) -> Result<String, ComposeError> {
    compose_with(name, GpuWalker::default())
}

/// The composed module for `name` with `walker` standing for `{TRAVERSAL}` (f32 hits).
pub fn compose_with(name: &str, walker: GpuWalker) -> Result<String, ComposeError> {
    compose_for(name, walker, HitFloat::F32)
}

/// The composed module for `name` with `walker` standing for `{TRAVERSAL}` and `hit` for
/// `{HIT_FLOAT}`.
pub fn compose_for(name: &str, walker: GpuWalker, hit: HitFloat) -> Result<String, ComposeError> {
    let mut out = String::new();
    let mut seen = Vec::new();
    compose_into(name, (walker, hit), &mut out, &mut seen)?;
    Ok(out)
}

fn compose_into(
    name: &str,
    (walker, hit): (GpuWalker, HitFloat),
    out: &mut String,
    seen: &mut Vec<String>,
) -> Result<(), ComposeError> {
    if seen.iter().any(|s| s == name) {
        return Ok(());
    }
    seen.push(name.to_string());
    let src = source(name).ok_or_else(|| ComposeError { file: name.into(), detail: "no such shader".into() })?;
    for line in src.lines() {
        if let Some(inc) = line.trim().strip_prefix("//!include ") {
            let inc = inc.trim().replace("{TRAVERSAL}", walker.name()).replace("{HIT_FLOAT}", hit.name());
            compose_into(&inc, (walker, hit), out, seen)
                .map_err(|e| ComposeError { file: name.into(), detail: format!("including {inc}: {e}") })?;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Ok(())
}
