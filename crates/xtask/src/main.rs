//! `cargo xtask`: gridrt's build tasks (run through the alias in `.cargo/config.toml`).
//!
//! - `cargo xtask web [--serve] [--port P]` builds the browser demo into `web/dist/` (wasm,
//!   wasm-bindgen, wasm-opt when available) and optionally serves it on 127.0.0.1.
//! - `cargo xtask web-test` builds it, serves it, drives headless Chromium with WebGPU through
//!   the DevTools protocol and compares the browser's frames with `gridrt render`.

mod cdp;
mod e2e;
mod serve;
mod wasm;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "cargo xtask", about = "gridrt build tasks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Build the browser demo into web/dist/ (and serve it with --serve).
    Web {
        /// Serve web/dist/ on 127.0.0.1 after building.
        #[arg(long)]
        serve: bool,
        /// Port to serve on.
        #[arg(long, default_value_t = 8080)]
        port: u16,
        #[command(flatten)]
        build: wasm::BuildArgs,
    },
    /// End-to-end test: build, serve, run in headless Chromium (WebGPU), compare with the
    /// native renderer. Fails when WebGPU is unavailable.
    WebTest {
        /// Where screenshots, frames and the report go.
        #[arg(long, default_value = "target/web-test")]
        out: PathBuf,
        /// Chromium binary (default: chromium, chromium-browser or google-chrome on PATH).
        #[arg(long)]
        chromium: Option<PathBuf>,
        /// Use the existing web/dist/ instead of building.
        #[arg(long)]
        no_build: bool,
        /// Seconds to wait for each step in the browser.
        #[arg(long, default_value_t = 300)]
        timeout: u64,
        #[command(flatten)]
        build: wasm::BuildArgs,
    },
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let root = workspace_root();
    match cli.command {
        Command::Web { serve, port, build } => {
            let dist = wasm::build_web(&root, &build)?;
            if serve {
                let server = serve::Server::start(&dist, port)?;
                println!("serving {} on http://{} (Ctrl-C to stop)", dist.display(), server.addr);
                server.join();
            }
            Ok(())
        }
        Command::WebTest { out, chromium, no_build, timeout, build } => {
            let dist = if no_build { root.join("web/dist") } else { wasm::build_web(&root, &build)? };
            let out = if out.is_absolute() { out } else { root.join(out) };
            e2e::run(&root, &dist, &out, chromium, std::time::Duration::from_secs(timeout))
        }
    }
}

/// The workspace root: two levels above this crate's manifest.
fn workspace_root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().and_then(|p| p.parent()).map_or(here.clone(), |p| p.to_path_buf())
}
