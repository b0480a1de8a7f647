//! Data the shaders read and write, as `#[repr(C)]` Pod structs. Hits and per-ray counters are
//! the CPU's own records (WGSL `Hit` is [`gridrt_scene::Hit`], WGSL `RayStats` is
//! [`gridrt_grid::RayStats`]), read back without conversion.
//! Keep in sync with shaders/shared/bindings.wgsl and shaders/shared/hierarchy.wgsl (a test
//! compares every struct's size and member offsets with naga's layout of the WGSL).
//! Everything is vec4-aligned: no bare vec3 in storage.

use bytemuck::{Pod, Zeroable};
use gridrt_grid::{Query, RayStats};
use gridrt_scene::Hit;

/// Bytes per record of the per-ray buffers, from the structs below (one place for every
/// buffer size and binding range).
pub const RAY_BYTES: u64 = size_of::<GpuRay>() as u64;
pub const HIT_BYTES: u64 = size_of::<Hit>() as u64;
pub const STATS_BYTES: u64 = size_of::<RayStats>() as u64;
/// One packed RGBA8 pixel.
pub const PIXEL_BYTES: u64 = size_of::<u32>() as u64;

/// One ray: `origin.xyz, tmin`, `dir.xyz, tmax` (the ray file's record). WGSL `Ray`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    pub origin_tmin: [f32; 4],
    pub dir_tmax: [f32; 4],
}

/// Per-dispatch parameters (uniform). WGSL `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridParams {
    /// xyz: grid box minimum.
    pub grid_min: [f32; 4],
    /// xyz: 1 / cell size.
    pub inv_cell: [f32; 4],
    /// Resolution of the flat / fine / top grid.
    pub res: [u32; 3],
    /// Rays in this dispatch.
    pub ray_count: u32,
    /// 1: skip triangles already tested by this ray (the mailbox).
    pub mailbox: u32,
    /// Fine cells per macrocell edge (the macrocell kernel).
    pub macro_edge: u32,
    /// Index of this dispatch's first ray in the whole ray set.
    pub first_ray: u32,
    /// Pixels per row of the image the rays form (the packet kernels; 0 for other rays).
    pub image_width: u32,
    /// What the search looks for: [`QUERY_CLOSEST`] or [`QUERY_ANY`] (occlusion).
    pub query: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// `GridParams::query`: the closest hit (WGSL `QUERY_CLOSEST`).
pub const QUERY_CLOSEST: u32 = 0;
/// `GridParams::query`: any hit, the search ends at the first (WGSL `QUERY_ANY`).
pub const QUERY_ANY: u32 = 1;

/// The `GridParams::query` of a [`Query`].
pub fn query_code(q: Query) -> u32 {
    match q {
        Query::Closest => QUERY_CLOSEST,
        Query::Any => QUERY_ANY,
    }
}

/// One grid of a hierarchy: xyz = resolution, w = first cell. WGSL `Node`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuNode {
    pub res_first: [u32; 4],
}

/// Camera for the render pass (uniform). WGSL `Camera` in shaders/shared/render_bindings.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    pub eye: [f32; 3],
    /// tan(vfov / 2).
    pub tan_half_vfov: f32,
    /// Unit vector to the image's right.
    pub right: [f32; 3],
    /// Image size in pixels.
    pub width: f32,
    /// Unit vector to the image's top.
    pub up: [f32; 3],
    pub height: f32,
    /// Unit view direction.
    pub forward: [f32; 3],
    /// width / height.
    pub aspect: f32,
}

/// Shading parameters (uniform). WGSL `ShadeParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadeParams {
    /// Point light position.
    pub light: [f32; 3],
    /// Scene diagonal (the shadow-ray offset scale).
    pub diagonal: f32,
    /// [`crate::View::code`].
    pub view: u32,
    /// Heatmap count mapped to the top colour.
    pub heat_max: f32,
    pub width: u32,
    pub height: u32,
    /// The depth view's range.
    pub depth_near: f32,
    pub depth_far: f32,
    /// First pixel of this dispatch (a tile of the frame) and pixels in it. The per-pixel
    /// buffers are bound from the tile's first pixel, so kernels index them from 0.
    pub first_pixel: u32,
    pub pixel_count: u32,
}

/// Sums over a frame's primary rays, written by shaders/present.wgsl into an
/// `array<atomic<u32>, 8>` (keep in sync): 64-bit counts as (lo, hi) word pairs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct FrameTotals {
    pub cells: [u32; 2],
    pub tests: [u32; 2],
    pub hits: u32,
    pub rays: u32,
    pub pad: [u32; 2],
}

impl FrameTotals {
    pub fn cells(&self) -> u64 {
        self.cells[0] as u64 | (self.cells[1] as u64) << 32
    }
    pub fn tests(&self) -> u64 {
        self.tests[0] as u64 | (self.tests[1] as u64) << 32
    }
}

/// Parameters of one pass of the GPU grid build (uniform). WGSL `BuildParams` in
/// shaders/shared/build.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BuildParams {
    /// xyz: grid box minimum.
    pub grid_min: [f32; 4],
    /// xyz: 1 / cell size.
    pub inv_cell: [f32; 4],
    pub res: [u32; 3],
    pub triangle_count: u32,
    /// Insertion margin, in cells.
    pub margin: f32,
    /// Elements of the array a scan or per-cell pass covers.
    pub count: u32,
    /// Workgroups along x of the pass's 2-D dispatch.
    pub groups_x: u32,
    /// Fine cells per macrocell edge (the occupancy pass).
    pub macro_edge: u32,
    /// The exact insertion pass: 0 counts, 1 scatters.
    pub scatter: u32,
    pub _pad: [u32; 3],
}
