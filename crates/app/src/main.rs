//! `gridrt`: the command-line front end. Without a subcommand it runs the demo (builds and
//! traces the embedded default scene and prints a summary); the subcommands expose each stage
//! of the pipeline: scene → grid → trace → hits.

mod cli;
mod commands;

use clap::Parser;

fn main() -> anyhow::Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = cli::Cli::parse();
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global()?;
    }
    match cli.command {
        None => commands::demo::run(),
        Some(cli::Command::Info(a)) => commands::info::run(a),
        Some(cli::Command::Build(a)) => commands::build::run(a),
        Some(cli::Command::Gen(a)) => commands::generate::run(a),
        Some(cli::Command::Rays(a)) => commands::rays::run(a),
        Some(cli::Command::Trace(a)) => commands::trace::run(a),
        Some(cli::Command::Render(a)) => commands::render::run(a),
        Some(cli::Command::BenchTrace(a)) => commands::bench_trace::run(a),
    }
}
