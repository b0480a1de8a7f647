//! From arguments to configuration: the grid flags to a [`GridConfig`], the global limits to
//! [`LoadLimits`], and the cost-model calibration file (`gridrt experiment cost-constants
//! --save` writes it; auto resolution reads it).

#[cfg(not(target_arch = "wasm32"))]
use std::path::PathBuf;

use gridrt_grid::multires::MultiresOptions;
use gridrt_grid::twolevel::TwoLevelOptions;
use gridrt_grid::{BuildOptions, CostModel, GridConfig, InsertMode};
use gridrt_scene::LoadLimits;
#[cfg(not(target_arch = "wasm32"))]
use serde::{Deserialize, Serialize};

use crate::cli::{Cli, GridArgs};

// The subcommands are native-only; the browser build keeps the definitions for the app's flags.
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
impl GridArgs {
    pub fn cost_model(&self) -> anyhow::Result<CostModel> {
        let d = CostModel::default();
        // Only the native build reads a saved calibration into `m`.
        #[cfg_attr(target_arch = "wasm32", allow(unused_mut))]
        let mut m = CostModel {
            t_setup: self.t_setup.unwrap_or(d.t_setup),
            t_step: self.t_step.unwrap_or(d.t_step),
            t_inter: self.t_inter.unwrap_or(d.t_inter),
            samples: self.samples,
            max_cells: self.max_cells,
            ..d
        };
        #[cfg(not(target_arch = "wasm32"))]
        if self.t_setup.is_none()
            && self.t_step.is_none()
            && self.t_inter.is_none()
            && let Some((path, c)) = load_calibration()
        {
            eprintln!(
                "cost model: calibrated constants from {} (Tsetup {:.2}, Tstep {:.3}, Tinter {:.3} ns)",
                path.display(),
                c.cpu.t_setup,
                c.cpu.t_step,
                c.cpu.t_inter
            );
            (m.t_setup, m.t_step, m.t_inter) = (c.cpu.t_setup, c.cpu.t_step, c.cpu.t_inter);
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
            twolevel: TwoLevelOptions { top_density: self.top_density, leaf_density: self.leaf_density },
        })
    }
}

impl Cli {
    /// The scene load limits these flags describe.
    pub fn load_limits(&self) -> LoadLimits {
        let d = LoadLimits::default();
        LoadLimits {
            max_triangles: self.max_triangles.unwrap_or(d.max_triangles),
            max_bytes: self.max_load_bytes.unwrap_or(d.max_bytes),
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// Fitted constants in nanoseconds per ray, and how well they fit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    pub t_setup: f64,
    pub t_step: f64,
    pub t_inter: f64,
    /// RMS of (predicted − measured) / measured.
    pub rel_rms_error: f64,
    pub r_squared: f64,
    pub points: usize,
}

#[cfg(not(target_arch = "wasm32"))]
/// What the calibration file holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Calibration {
    pub cpu: Fit,
    pub gpu: Option<Fit>,
    pub machine: String,
    pub date: String,
}

#[cfg(not(target_arch = "wasm32"))]
/// Where `--save` writes the calibration and where the command line looks for it:
/// `$GRIDRT_CALIBRATION`, else `$XDG_CONFIG_HOME/gridrt/cost-constants.json`, else
/// `~/.config/gridrt/cost-constants.json`.
pub fn calibration_path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("GRIDRT_CALIBRATION") {
        return Some(PathBuf::from(p));
    }
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("gridrt/cost-constants.json"))
}

#[cfg(not(target_arch = "wasm32"))]
/// The cost model the command line's auto resolution uses: the saved calibration's CPU
/// constants when there is one, else the survey's; and a note saying which.
pub fn active_cost_model() -> (CostModel, String) {
    let mut m = CostModel::default();
    match load_calibration() {
        Some((path, c)) => {
            (m.t_setup, m.t_step, m.t_inter) = (c.cpu.t_setup, c.cpu.t_step, c.cpu.t_inter);
            (m, format!("calibrated constants from {}", path.display()))
        }
        None => (m, "the survey's constants (Tsetup 1.0, Tstep 0.1, Tinter 0.5)".into()),
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// The saved calibration, if the file exists and is valid.
pub fn load_calibration() -> Option<(PathBuf, Calibration)> {
    let path = calibration_path()?;
    let text = std::fs::read_to_string(&path).ok()?;
    match serde_json::from_str::<Calibration>(&text) {
        Ok(c) if c.cpu.t_step > 0.0 && c.cpu.t_inter > 0.0 && c.cpu.t_setup >= 0.0 => Some((path, c)),
        _ => {
            log::warn!("ignoring {}: not a valid gridrt calibration", path.display());
            None
        }
    }
}
