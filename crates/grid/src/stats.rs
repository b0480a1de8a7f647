//! Per-ray counters (the quantities of the survey's cost model) and their batch means.

use serde::Serialize;

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
