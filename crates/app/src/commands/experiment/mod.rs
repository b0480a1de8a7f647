//! `gridrt experiment NAME`: the survey's experiments. Each writes its rows as CSV and JSON
//! and its charts as SVG and PNG into `--out`, shows progress and prints a short table.
//! Benchmarks print numbers; nothing here asserts a speed.

pub mod bresenham;
pub mod cgt;
pub mod cost_constants;
pub mod fig5;
pub mod hierarchy;
pub mod models;

use crate::cli::{ExperimentArgs, ExperimentName};

pub fn run(args: ExperimentArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)?;
    match args.name {
        ExperimentName::Fig5 => fig5::run(&args),
        ExperimentName::Bresenham => bresenham::run(&args),
        ExperimentName::Models => models::run(&args),
        ExperimentName::Hierarchy => hierarchy::run(&args),
        ExperimentName::CostConstants => cost_constants::run(&args),
        ExperimentName::Cgt => cgt::run(&args),
    }
}
