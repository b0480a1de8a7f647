//! `gridrt`: without a subcommand it opens the desktop app (egui on wgpu); the subcommands
//! expose each stage of the pipeline from the command line: scene → grid → trace → hits.
//! Built for wasm32, the same app runs in a browser on WebGPU (`gui::start_web`).

mod cli;
#[cfg(not(target_arch = "wasm32"))]
mod commands;
mod config;
mod format;
mod gui;
mod lab;
mod limits;

/// Runs the command line; any error is printed on one line (its causes joined by ": ") and the
/// process exits with status 1 (usage errors: 2, from clap).
#[cfg(not(target_arch = "wasm32"))]
fn main() {
    // Rust ignores SIGPIPE, so a write to a closed pipe (`gridrt render --json | head`) would
    // panic with a backtrace; with the signal's default the process ends quietly instead.
    #[cfg(unix)]
    sigpipe::reset();
    if let Err(e) = run() {
        eprintln!("error: {}", one_line(&e));
        std::process::exit(1);
    }
}

/// An error and its causes on one line, joined by ": ". A cause the message before it already
/// quotes (library errors name their source in their own text) is not repeated.
#[cfg(not(target_arch = "wasm32"))]
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string().replace('\n', " ");
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(not(target_arch = "wasm32"))]
fn run() -> anyhow::Result<()> {
    use clap::Parser;
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = match cli::Cli::try_parse() {
        Ok(cli) => cli,
        // Help and version go out as clap writes them; a usage error on one line, exit 2.
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.render().to_string();
            let lines: Vec<&str> = text
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
                .collect();
            eprintln!("{}", lines.join(" "));
            std::process::exit(2);
        }
    };
    limits::set(cli.load_limits());
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
        Some(cli::Command::Experiment(a)) => commands::experiment::run(a),
        Some(cli::Command::Bench(a)) => commands::bench::run(a),
        Some(cli::Command::Animate(a)) => commands::animate::run(a),
    }
}

/// In a browser the page's script calls the wasm module's start; `main` only starts the app.
/// The build worker (web/worker.js) loads the same module and has no window: nothing starts.
#[cfg(target_arch = "wasm32")]
fn main() {
    if web_sys::window().is_some() {
        gui::start_web();
    }
}
