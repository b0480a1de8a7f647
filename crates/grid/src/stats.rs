//! Per-ray counters (the quantities of the survey's cost model) and their batch means, and the
//! size figures of a built structure.

use serde::{Deserialize, Serialize};

/// What one ray cost: cells visited (m in T = Tsetup + m·Tstep + μ·Tinter) and triangle tests
/// performed (μ; mailboxed skips are not tests).
/// The same record as WGSL `RayStats` (shaders/shared/types.wgsl): the GPU writes these.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayStats {
    pub cells: u32,
    pub tests: u32,
}

/// Sums over a batch of rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BatchStats {
    pub rays: u64,
    pub hits: u64,
    pub cells: u64,
    pub tests: u64,
}

impl BatchStats {
    pub fn add(&mut self, s: RayStats, hit: bool) {
        self.rays += 1;
        self.hits += hit as u64;
        self.cells += s.cells as u64;
        self.tests += s.tests as u64;
    }
    pub fn merge(mut self, o: BatchStats) -> BatchStats {
        self.rays += o.rays;
        self.hits += o.hits;
        self.cells += o.cells;
        self.tests += o.tests;
        self
    }
    pub fn mean_cells(&self) -> f64 {
        self.cells as f64 / self.rays.max(1) as f64
    }
    pub fn mean_tests(&self) -> f64 {
        self.tests as f64 / self.rays.max(1) as f64
    }
}

/// Size figures common to all kinds (`gridrt build --json`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct StructureStats {
    /// Resolution of the flat / fine / top grid.
    pub resolution: [u32; 3],
    /// Grids in the structure (1 for flat grids; macro + fine for macrocells).
    pub nodes: u64,
    pub levels: u32,
    /// Cells over all levels.
    pub cells: u64,
    /// Empty cells (leaves, in a hierarchy).
    pub empty_cells: u64,
    pub refs: u64,
    /// Grids per depth (hierarchies), or cells per level (macro, fine) for macrocells.
    pub depth_histogram: Vec<u64>,
    pub memory_bytes: u64,
    pub memory_bytes_per_triangle: f64,
    /// Macrocell edge, when the structure has macrocells.
    pub macro_size: Option<u32>,
    pub occupied_macrocells: Option<u64>,
    /// Cells whose proximity distance lets a ray jump (distance ≥ `proximity::MIN_JUMP_DISTANCE`).
    pub jump_cells: Option<u64>,
    pub hierarchy: Option<HierarchyStats>,
}

impl StructureStats {
    /// Only the memory figures: `memory_bytes` over `triangles`.
    pub fn sized(memory_bytes: u64, triangles: usize) -> StructureStats {
        StructureStats {
            memory_bytes,
            memory_bytes_per_triangle: memory_bytes as f64 / triangles.max(1) as f64,
            ..Default::default()
        }
    }

    /// Empty cells as a percentage of all cells.
    pub fn empty_percent(&self) -> f64 {
        100.0 * self.empty_cells as f64 / self.cells.max(1) as f64
    }
}

/// What only a hierarchy has to say about its size (the rest is in [`StructureStats`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HierarchyStats {
    /// Cells that hold references rather than a child grid.
    pub leaves: u64,
    /// Number of references held in leaves at each depth, top = 0.
    pub refs_per_depth: Vec<u64>,
}
