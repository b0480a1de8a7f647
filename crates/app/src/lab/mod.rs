//! What benchmarks and experiments share: their scenes, timed measurements (sweeps, best-of
//! timing, the machine's description) and reports (tables, CSV/JSON rows, charts).

pub mod animation;
pub mod frame;
pub mod report;
pub mod scenes;
pub mod sweep;
pub mod views;
