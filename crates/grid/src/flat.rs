//! The flat uniform grid in the compact layout of Lagae & Dutré (2008): `cell_start` (M + 1
//! offsets) and `refs` (triangle indices), cell `c` owning `refs[cell_start[c]..cell_start[c+1]]`.
//!
//! Built sort-last in linear time by [`crate::build::bucket`] (serial) or
//! [`crate::build::parallel`] (bit-identical): references in a cell are in increasing triangle
//! order.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::{BuildOptions, PhaseTimes, bucket};
use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlatGrid {
    pub geom: GridGeometry,
    pub cell_start: Vec<u32>,
    pub refs: Vec<u32>,
}

/// Size figures of a built grid (`gridrt build`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlatGridStats {
    pub resolution: [u32; 3],
    pub cells: u64,
    pub refs: u64,
    pub empty_cells: u64,
    pub empty_percent: f64,
    pub max_refs_per_cell: u32,
    pub refs_per_triangle: f64,
    pub memory_bytes: u64,
}

impl FlatGrid {
    /// Triangle indices in cell `index`.
    #[inline]
    pub fn cell(&self, index: usize) -> &[u32] {
        &self.refs[self.cell_start[index] as usize..self.cell_start[index + 1] as usize]
    }

    pub fn memory_bytes(&self) -> u64 {
        (self.cell_start.len() + self.refs.len()) as u64 * 4
    }

    pub fn stats(&self, triangles: usize) -> FlatGridStats {
        let cells = self.geom.cell_count();
        let mut empty = 0;
        let mut max = 0;
        for w in self.cell_start.windows(2) {
            let n = w[1] - w[0];
            empty += (n == 0) as u64;
            max = max.max(n);
        }
        FlatGridStats {
            resolution: self.geom.res.to_array(),
            cells,
            refs: self.refs.len() as u64,
            empty_cells: empty,
            empty_percent: 100.0 * empty as f64 / cells as f64,
            max_refs_per_cell: max,
            refs_per_triangle: self.refs.len() as f64 / triangles.max(1) as f64,
            memory_bytes: self.memory_bytes(),
        }
    }

    /// Builds the grid `geom` over `tris`. Timings are appended to `times`.
    pub fn build(
        tris: &[[Vec3; 3]],
        geom: GridGeometry,
        opts: BuildOptions,
        times: &mut PhaseTimes,
    ) -> Result<FlatGrid, BuildError> {
        if tris.len() as u64 >= u32::MAX as u64 {
            return Err(BuildError::TooManyTriangles(tris.len() as u64));
        }
        #[cfg(feature = "parallel")]
        if opts.parallel {
            let (cell_start, refs) = crate::build::parallel::bucket(tris, &geom, opts.insert, times)?;
            return Ok(FlatGrid { geom, cell_start, refs });
        }
        let (cell_start, refs) = bucket::bucket(tris, None, &geom, opts.insert, INSERT_MARGIN_CELLS, Some(times))?;
        Ok(FlatGrid { geom, cell_start, refs })
    }
}
