//! From arguments to configuration: the grid flags to a [`GridConfig`], the global limits to
//! [`LoadLimits`], and (natively) the cost-model calibration file ([`calibration`]).

#[cfg(not(target_arch = "wasm32"))]
pub mod calibration;

use gridrt_grid::multires::MultiresOptions;
use gridrt_grid::twolevel::TwoLevelOptions;
use gridrt_grid::{BuildOptions, CostModel, GridConfig, InsertMode};
#[cfg(not(target_arch = "wasm32"))]
use gridrt_scene::LoadLimits;

use crate::cli::{Cli, GridArgs};

// The subcommands are native-only; the browser build keeps the definitions for the app's flags.
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
impl GridArgs {
    pub fn cost_model(&self) -> anyhow::Result<CostModel> {
        let d = CostModel::memory_aware();
        // Only the native build reads a saved calibration into `m`.
        #[cfg_attr(target_arch = "wasm32", allow(unused_mut))]
        let mut m = CostModel {
            t_setup: self.t_setup.unwrap_or(d.t_setup),
            t_step: self.t_step.unwrap_or(d.t_step),
            t_inter: self.t_inter.unwrap_or(d.t_inter),
            samples: self.samples,
            max_cells: self.max_cells,
            memory_weight: self.memory_weight.unwrap_or(d.memory_weight),
            cache_bytes: self.cache_kib.map_or(d.cache_bytes, |k| k * 1024.0),
            dram_bytes: self.dram_mib.map_or(d.dram_bytes, |k| k * 1024.0 * 1024.0),
            dram_weight: self.dram_weight.unwrap_or(d.dram_weight),
            tie_tolerance: self.tie_tolerance.unwrap_or(d.tie_tolerance),
            ..d
        };
        #[cfg(not(target_arch = "wasm32"))]
        if self.t_setup.is_none()
            && self.t_step.is_none()
            && self.t_inter.is_none()
            && let Some((path, c)) = calibration::load()
        {
            eprintln!(
                "cost model: calibrated constants from {} (Tsetup {:.2}, Tstep {:.3}, Tinter {:.3} ns)",
                path.display(),
                c.cpu.t_setup,
                c.cpu.t_step,
                c.cpu.t_inter
            );
            c.apply_to(&mut m);
        }
        anyhow::ensure!(
            m.t_setup >= 0.0 && m.t_step > 0.0 && m.t_inter > 0.0 && m.t_step.is_finite() && m.t_inter.is_finite(),
            "cost constants must be finite, Tstep and Tinter positive"
        );
        anyhow::ensure!((2..=256).contains(&m.samples), "--samples must be in 2..=256");
        Ok(m)
    }

    /// The full structure configuration these flags describe.
    pub fn config(&self) -> anyhow::Result<GridConfig> {
        let cost = self.cost_model()?;
        anyhow::ensure!(self.max_depth <= 7, "--max-depth must be at most 7");
        Ok(GridConfig {
            kind: self.grid,
            resolution: self.resolution,
            build: BuildOptions {
                insert: if self.exact { InsertMode::Exact } else { InsertMode::BoundingBox },
                parallel: !self.serial,
            },
            cost,
            macro_size: self.macro_size,
            multires: MultiresOptions {
                policy: self.policy,
                max_depth: self.max_depth,
                density: self.density,
                cost,
                always_subdivide: false,
            },
            twolevel: TwoLevelOptions {
                top_density: self.top_density,
                leaf_density: self.leaf_density,
                every_cell: self.every_top_cell,
            },
            cell_planes: self.cell_planes,
        })
    }
}

impl Cli {
    /// The scene load limits these flags describe (the command line's; the browser has none).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn load_limits(&self) -> LoadLimits {
        let d = LoadLimits::default();
        LoadLimits {
            max_triangles: self.max_triangles.unwrap_or(d.max_triangles),
            max_bytes: self.max_load_bytes.unwrap_or(d.max_bytes),
        }
    }
}
