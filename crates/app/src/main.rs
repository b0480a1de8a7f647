//! `gridrt`: without a subcommand it opens the desktop app (egui on wgpu); the subcommands
//! expose each stage of the pipeline from the command line: scene → grid → trace → hits.

mod cli;
mod commands;
mod gui;

use clap::Parser;

fn main() -> anyhow::Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = cli::Cli::parse();
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global()?;
    }
    match cli.command {
        None => gui::run_native(cli.app),
        Some(cli::Command::Demo) => commands::demo::run(),
        Some(cli::Command::Info(a)) => commands::info::run(a),
        Some(cli::Command::Build(a)) => commands::build::run(a),
        Some(cli::Command::Gen(a)) => commands::generate::run(a),
        Some(cli::Command::Rays(a)) => commands::rays::run(a),
        Some(cli::Command::Trace(a)) => commands::trace::run(a),
        Some(cli::Command::Render(a)) => commands::render::run(a),
        Some(cli::Command::BenchTrace(a)) => commands::bench_trace::run(a),
    }
}
