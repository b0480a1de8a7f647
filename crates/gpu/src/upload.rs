//! The GPU layout stage: a scene's triangles and a built structure become storage buffers in
//! exactly the layouts the WGSL kernels read (see each structure's module doc in
//! `gridrt-grid`). Every buffer is checked against the device limits first.

use glam::Vec3;
use gridrt_grid::{AnyGrid, GridKind};
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::layout::{GpuNode, GridParams};

/// Triangles, 48 bytes each as three vec4: `a.xyz b.x | b.yz c.xy | c.z` (three pad floats).
/// The 9 coordinates lead so a kernel reads them in 9 components, not 12: on lavapipe every
/// storage read with a per-ray address is a scalar loop over the 8 SIMD lanes per component,
/// and vertex reads were a third of a trace kernel's time. Keep in sync with
/// `shaders/shared/types.wgsl` (`unpack_triangle`).
#[derive(Debug)]
pub struct GpuScene {
    pub triangles: wgpu::Buffer,
    pub triangle_count: u32,
}

/// A storage buffer holding `data` (at least 4 bytes: empty bindings are not allowed).
pub(crate) fn storage(
    ctx: &GpuContext,
    label: &'static str,
    data: &[u8],
    extra: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    ctx.check_buffer(label, data.len() as u64, true)?;
    let contents: &[u8] = if data.is_empty() { &[0u8; 4] } else { data };
    Ok(ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::STORAGE | extra,
    }))
}

impl GpuScene {
    pub fn new(ctx: &GpuContext, tris: &[[Vec3; 3]]) -> Result<GpuScene, GpuError> {
        let data: Vec<[f32; 4]> = tris.iter().flat_map(pack_triangle).collect();
        let triangles = storage(ctx, "triangles", bytemuck::cast_slice(&data), wgpu::BufferUsages::empty())?;
        Ok(GpuScene { triangles, triangle_count: tris.len() as u32 })
    }
}

/// One triangle in the packed layout of [`GpuScene`].
pub fn pack_triangle(t: &[Vec3; 3]) -> [[f32; 4]; 3] {
    let [a, b, c] = *t;
    [[a.x, a.y, a.z, b.x], [b.y, b.z, c.x, c.y], [c.z, 0.0, 0.0, 0.0]]
}

/// A structure's buffers: references, cell data, and the kind's extra array.
#[derive(Debug)]
pub struct GpuStructure {
    pub kind: GridKind,
    /// Grid box, cell size, resolution and macrocell edge; the ray range and the mailbox are
    /// filled per dispatch.
    pub params: GridParams,
    pub refs: wgpu::Buffer,
    /// The occupied cells' starts (flat, macrocell, proximity: [`gridrt_grid::FlatGrid::ref_start`])
    /// or the hierarchy's `cells`.
    pub cells: wgpu::Buffer,
    /// Occupancy bits (macrocell), nodes (hierarchies), packed distances (proximity).
    pub extra: Option<wgpu::Buffer>,
    /// The flat grid's occupancy words (flat, macrocell, proximity;
    /// `shaders/shared/flat_grid.wgsl`): [`gridrt_grid::OccupancyWord`]s, bits and rank.
    pub occupied: Option<wgpu::Buffer>,
    pub bytes: u64,
}

impl GpuStructure {
    pub fn new(ctx: &GpuContext, grid: &AnyGrid) -> Result<GpuStructure, GpuError> {
        let g = grid.geometry();
        let mut params = GridParams {
            grid_min: g.min.extend(0.0).to_array(),
            inv_cell: g.inv_cell.extend(0.0).to_array(),
            res: g.res.to_array(),
            ..GridParams::default()
        };
        let none = wgpu::BufferUsages::empty();
        // The flat-grid kernels read the CPU's compact arrays: occupancy words, the occupied
        // cells' offsets, the references.
        let fine = grid.flat();
        let occupied: Option<Vec<[u32; 2]>> = fine.map(|f| f.occupied.iter().map(|w| [w.bits, w.rank]).collect());
        let (refs, cells, extra): (&[u32], &[u8], Option<Vec<u8>>) = match grid {
            AnyGrid::Flat(f) => (&f.refs, bytemuck::cast_slice(&f.ref_start), None),
            AnyGrid::Macrocell(m) => {
                params.macro_edge = m.a;
                let f = &m.fine;
                (&f.refs, bytemuck::cast_slice(&f.ref_start), Some(bytemuck::cast_slice(&m.occupancy).to_vec()))
            }
            AnyGrid::Proximity(p) => {
                let mut packed = p.distance.clone();
                packed.resize(packed.len().div_ceil(4) * 4, 0);
                (&p.grid.refs, bytemuck::cast_slice(&p.grid.ref_start), Some(packed))
            }
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => {
                let nodes: Vec<GpuNode> =
                    h.nodes.iter().map(|n| GpuNode { res_first: [n.res.x, n.res.y, n.res.z, n.first_cell] }).collect();
                (&h.refs, bytemuck::cast_slice(&h.cells), Some(bytemuck::cast_slice(&nodes).to_vec()))
            }
        };
        let refs_buf = storage(ctx, "refs", bytemuck::cast_slice(refs), none)?;
        let cells_buf = storage(ctx, "cells", cells, none)?;
        let extra_buf = match &extra {
            Some(e) => Some(storage(ctx, "structure extra (occupancy/nodes/distance)", e, none)?),
            None => None,
        };
        let occupied_buf = match &occupied {
            Some(o) => Some(storage(ctx, "cell occupancy words", bytemuck::cast_slice(o), none)?),
            None => None,
        };
        let bytes = refs.len() as u64 * 4
            + cells.len() as u64
            + extra.as_ref().map_or(0, |e| e.len() as u64)
            + occupied.as_ref().map_or(0, |o| o.len() as u64 * 8);
        Ok(GpuStructure {
            kind: grid.kind(),
            params,
            refs: refs_buf,
            cells: cells_buf,
            extra: extra_buf,
            occupied: occupied_buf,
            bytes,
        })
    }
}
