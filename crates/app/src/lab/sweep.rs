//! One point of a resolution sweep: a flat grid at a given resolution, built and traced on the
//! CPU (all threads) and, when a device is given, on the GPU, timed best-of-`repeat`.

use std::time::Instant;

use glam::Vec3;
use gridrt_gpu::{GpuContext, GpuError, GpuSession};
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{GridConfig, GridKind, Resolution, structure};
use gridrt_scene::Ray;
use serde::Serialize;

use super::scenes::LabScene;

#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// ∛cells (the survey's m).
    pub m: f64,
    pub resolution: [u32; 3],
    pub cells: u64,
    /// Triangle references N_m.
    pub n_m: u64,
    pub memory_bytes: u64,
    pub build_ms: f64,
    /// Nanoseconds per ray, CPU (all threads) and GPU, over all the ray sets given.
    pub cpu_ns_per_ray: f64,
    pub gpu_ns_per_ray: Option<f64>,
    pub mean_cells_per_ray: f64,
    pub mean_tests_per_ray: f64,
}

/// Best wall-clock seconds of `repeat` runs of `f`, and the last run's result.
pub fn best_of<T>(repeat: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat.max(1) {
        let s = Instant::now();
        let r = f();
        best = best.min(s.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.expect("at least one run"))
}

/// The scene on the device when there is one (each experiment uploads once per scene); `None`
/// with a warning when the device cannot hold it ([`fits_on_gpu`]).
pub fn session<'a>(ctx: Option<&'a GpuContext>, sc: &LabScene) -> anyhow::Result<Option<GpuSession<'a>>> {
    Ok(match ctx {
        Some(c) => fits_on_gpu(GpuSession::new(c, &sc.tris, sc.bounds), &sc.name)?,
        None => None,
    })
}

/// `r`'s value, or `None` with a warning when the device's buffers cannot hold what `what`
/// needed (a scene or grid beyond its `max_storage_buffer_binding_size`; README, Limits): a
/// measurement leaves the GPU out of it, as it would without a device, rather than end. Every
/// other GPU error stays an error.
pub fn fits_on_gpu<T>(r: Result<T, GpuError>, what: &str) -> Result<Option<T>, GpuError> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(e @ GpuError::BufferTooLarge { .. }) => {
            log::warn!("{what}: the GPU is left out: {e}");
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// "CPU n threads[, GPU adapter]": what a measurement ran on.
pub fn machine(ctx: Option<&GpuContext>) -> String {
    let gpu = ctx.map_or(String::new(), |c| format!(", GPU {}", c.adapter_name()));
    format!("CPU {} threads{gpu}", rayon::current_num_threads())
}

/// Builds a flat grid at `res` and times tracing `rays`.
pub fn measure(
    tris: &[[Vec3; 3]],
    res: [u32; 3],
    rays: &[Ray],
    gpu: Option<&GpuSession>,
    repeat: usize,
) -> anyhow::Result<Point> {
    let cfg = GridConfig { kind: GridKind::Flat, resolution: Some(Resolution::Explicit(res)), ..GridConfig::default() };
    measure_config(tris, &cfg, rays, gpu, repeat)
}

/// Builds `cfg` and times tracing `rays` (m, cells and N_m are those of the top/flat grid's
/// resolution and of the whole structure).
pub fn measure_config(
    tris: &[[Vec3; 3]],
    cfg: &GridConfig,
    rays: &[Ray],
    gpu: Option<&GpuSession>,
    repeat: usize,
) -> anyhow::Result<Point> {
    let (grid, report) = structure::build(tris, cfg)?;
    let res = report.stats.resolution;
    let opts = TraceOptions::MAILBOX;
    let (_, stats) = grid.trace_batch(tris, rays, opts, true);
    let (cpu_s, _) = best_of(repeat, || grid.trace_batch(tris, rays, opts, true));
    let uploaded = match gpu {
        Some(g) => fits_on_gpu(g.upload(&grid), &format!("the {} grid at {res:?}", cfg.kind))?.map(|gs| (g, gs)),
        None => None,
    };
    let gpu_s = match uploaded {
        Some((g, gs)) => {
            // One untimed warm-up (pipeline creation, first upload).
            g.trace(&gs, &rays[..rays.len().min(64)], opts)?;
            let (secs, r) = best_of(repeat, || g.trace(&gs, rays, opts));
            r?;
            Some(secs)
        }
        None => None,
    };
    let n = rays.len().max(1) as f64;
    let cells = report.stats.cells;
    Ok(Point {
        m: (cells as f64).cbrt(),
        resolution: res,
        cells,
        n_m: report.stats.refs,
        memory_bytes: report.stats.memory_bytes,
        build_ms: report.times.total(),
        cpu_ns_per_ray: cpu_s * 1e9 / n,
        gpu_ns_per_ray: gpu_s.map(|s| s * 1e9 / n),
        mean_cells_per_ray: stats.cells as f64 / n,
        mean_tests_per_ray: stats.tests as f64 / n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer beyond the device's limits leaves the GPU out (`None`); any other GPU error
    /// stays an error, and a value passes through.
    #[test]
    fn only_a_buffer_too_large_leaves_the_gpu_out() {
        let too_large = GpuError::BufferTooLarge { buffer: "triangles", size: 2, limit: 1, which: "max_buffer_size" };
        assert!(matches!(fits_on_gpu::<u8>(Err(too_large), "scene"), Ok(None)));
        assert!(matches!(fits_on_gpu(Ok(7u8), "scene"), Ok(Some(7))));
        assert!(fits_on_gpu::<u8>(Err(GpuError::Device("lost".into())), "scene").is_err());
    }
}
