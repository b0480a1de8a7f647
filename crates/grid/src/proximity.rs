//! Proximity clouds (Cohen & Sheffer 1994): every empty cell of a flat grid stores its distance,
//! in cells, to the nearest non-empty cell, and a ray in an empty cell jumps across the whole
//! empty neighbourhood at once.
//!
//! Distance is the chessboard (L∞) distance: k means every cell whose index differs by less
//! than k on every axis is empty, so the cube of (2k − 1)³ cells around the current one holds no
//! triangle, and the ray may resume where it leaves that cube. It is computed in linear time by
//! a two-pass raster distance transform over the 26-neighbourhood (Rosenfeld & Pfaltz), which
//! is exact for the chessboard metric.
//!
//! # Layout (GPU-ready)
//! The flat grid (`occupied`, `ref_start`, `refs`) plus `distance`: one byte per cell (0 = occupied,
//! capped at 255), packed four to a u32 word for the GPU.

use glam::{UVec3, Vec3};
use gridrt_scene::{Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::flat::FlatGrid;
use crate::geometry::GridRay;
use crate::stats::RayStats;
use crate::trace::TraceOptions;
use crate::trace::closest_hit::closest_hit;
use crate::traversal::walk_counted;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProximityGrid {
    pub grid: FlatGrid,
    /// Chessboard distance to the nearest non-empty cell, per cell (x fastest).
    pub distance: Vec<u8>,
}

impl ProximityGrid {
    pub fn new(grid: FlatGrid) -> ProximityGrid {
        let distance = distance_transform(&grid);
        ProximityGrid { grid, distance }
    }

    pub fn memory_bytes(&self) -> u64 {
        self.grid.memory_bytes() + self.distance.len().div_ceil(4) as u64 * 4
    }

    /// The empty cells a ray jumps out of (distance ≥ [`MIN_JUMP_DISTANCE`]).
    pub fn jump_cells(&self) -> u64 {
        self.distance.iter().filter(|&&d| d as u32 >= MIN_JUMP_DISTANCE).count() as u64
    }

    /// Closest hit; empty cells with distance ≥ [`MIN_JUMP_DISTANCE`] are skipped in one jump
    /// (counted as one cell).
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        let traversal = opts.traversal;
        closest_hit(tris, ray, opts, |search| {
            let Some(mut gr) = self.grid.geom.clip(&search.ray) else { return };
            let res = self.grid.geom.res;
            loop {
                // Set when the walk leaves an empty cube: it restarts at the cube's exit.
                let mut restart = None;
                let (_, cells) =
                    walk_counted(traversal, &gr, res, |cell, idx, t_exit| match self.jump(&gr, cell, idx) {
                        Jump::Restart(t) => {
                            restart = Some(t);
                            true
                        }
                        Jump::End => true,
                        Jump::Step { empty: true } => search.done_at(t_exit),
                        // The tests are a call, as in the flat grid.
                        Jump::Step { empty: false } => self.grid.test_occupied(search, None, idx, t_exit),
                    });
                search.visit_cells(cells);
                match restart {
                    Some(t) => gr.t0 = t,
                    None => return,
                }
            }
        })
    }
}

/// What a ray does in a cell of a proximity grid ([`ProximityGrid::jump`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Jump {
    /// Leave the empty cube around the cell: the walk restarts at this `t`.
    Restart(f32),
    /// The empty cube reaches past the segment's end: the walk ends.
    End,
    /// Step on through the cell (occupied, or empty with too small a cube to jump out of).
    Step { empty: bool },
}

impl ProximityGrid {
    /// What `ray` (its segment clipped to the grid) does in cell `cell` at address `idx`: jump out
    /// of the empty cube around it when the cube is at least [`MIN_JUMP_DISTANCE`] across and
    /// the jump moves the ray on, else step. The one rule of the single-ray walk and the
    /// interleaved one ([`crate::trace::interleaved`]).
    #[inline(always)]
    pub fn jump(&self, ray: &GridRay, cell: UVec3, idx: usize) -> Jump {
        let k = self.distance[idx] as u32;
        if k >= MIN_JUMP_DISTANCE {
            // Leave the empty cube around this cell.
            let lo = cell.saturating_sub(UVec3::splat(k - 1));
            let hi = (cell + UVec3::splat(k)).min(self.grid.geom.res);
            let t = exit_of_box(ray, lo, hi).min(ray.t1);
            if t > ray.t0 && t < ray.t1 {
                return Jump::Restart(t);
            }
            if t >= ray.t1 {
                return Jump::End;
            }
        }
        // Distance 0 is an occupied cell.
        Jump::Step { empty: k != 0 }
    }
}

/// Smallest distance at which a ray jumps out of the empty cube around its cell rather than
/// stepping on: a jump restarts the walk (its set-up costs several steps), so a cube only a few
/// cells across is crossed faster cell by cell. WGSL: `MIN_JUMP_DISTANCE` in
/// shaders/proximity.wgsl.
pub const MIN_JUMP_DISTANCE: u32 = 4;

/// Where the ray leaves the box of cells `[lo, hi)` (grid space): the nearest far-side plane.
fn exit_of_box(r: &GridRay, lo: UVec3, hi: UVec3) -> f32 {
    let mut t = f32::INFINITY;
    for a in 0..3 {
        if r.d[a] != 0.0 {
            let plane = if r.d[a] > 0.0 { hi[a] } else { lo[a] } as f32;
            t = t.min((plane - r.o[a]) * r.inv_d[a]);
        }
    }
    t
}

/// Chessboard distance from every cell to the nearest non-empty one (0 for non-empty cells),
/// capped at 255; all 255 when the grid is empty.
pub fn distance_transform(grid: &FlatGrid) -> Vec<u8> {
    let r = grid.geom.res.as_ivec3();
    let n = grid.geom.cell_count() as usize;
    let mut d: Vec<u8> = (0..n).map(|i| if grid.is_occupied(i) { 0 } else { 255 }).collect();
    let idx = |x: i32, y: i32, z: i32| (x + r.x * (y + r.y * z)) as usize;
    // Neighbours that precede a cell in raster order (13 of the 26); the backward pass mirrors.
    let mut before = Vec::new();
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                if (dz, dy, dx) < (0, 0, 0) {
                    before.push((dx, dy, dz));
                }
            }
        }
    }
    for pass in 0..2 {
        let s = if pass == 0 { 1 } else { -1 };
        let range = |len: i32| -> Vec<i32> { if s > 0 { (0..len).collect() } else { (0..len).rev().collect() } };
        for z in range(r.z) {
            for y in range(r.y) {
                for x in range(r.x) {
                    let i = idx(x, y, z);
                    if d[i] == 0 {
                        continue;
                    }
                    let mut m = d[i];
                    for &(dx, dy, dz) in &before {
                        let (nx, ny, nz) = (x + s * dx, y + s * dy, z + s * dz);
                        if nx >= 0 && ny >= 0 && nz >= 0 && nx < r.x && ny < r.y && nz < r.z {
                            m = m.min(d[idx(nx, ny, nz)].saturating_add(1));
                        }
                    }
                    d[i] = m;
                }
            }
        }
    }
    d
}
