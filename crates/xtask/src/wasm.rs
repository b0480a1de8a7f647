//! Building the browser demo: the app crate for `wasm32-unknown-unknown`, then
//! `wasm-bindgen --target web` (exactly Cargo.lock's version, installed if missing), then
//! `wasm-opt` when it is on PATH, into `web/dist/` with the page's static files.
//!
//! Two toolchain routes, detected rather than assumed:
//! - the current toolchain has the wasm32 std (`rustup target add wasm32-unknown-unknown`):
//!   a plain `cargo build --target wasm32-unknown-unknown`;
//! - otherwise Debian's `rustc-web` toolchain (`/usr/bin/rustc`, `/usr/bin/cargo`, its std
//!   sources from `rust-web-src`) builds std itself with `-Zbuild-std` and links with `wasm-ld`.

use std::ffi::OsString;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context as _, bail};

const TARGET: &str = "wasm32-unknown-unknown";

#[derive(Debug, Clone, clap::Args)]
pub struct BuildArgs {
    /// Cargo target directory for the wasm build (default: $GRIDRT_WASM_TARGET_DIR, else
    /// target/wasm). It is kept apart from the native one: the Debian route builds std too.
    #[arg(long)]
    pub target_dir: Option<PathBuf>,
    /// Skip wasm-opt even when it is installed.
    #[arg(long)]
    pub no_opt: bool,
}

/// How the wasm is compiled on this machine.
#[derive(Debug)]
enum Route {
    /// The active toolchain has the wasm32 std.
    Rustup { cargo: OsString },
    /// Debian's rustc-web with std built from source.
    Debian { rustc: PathBuf, cargo: PathBuf, linker: PathBuf },
}

fn run(cmd: &mut Command) -> anyhow::Result<()> {
    let shown = format!("{cmd:?}");
    let status = cmd.status().with_context(|| format!("starting {shown}"))?;
    anyhow::ensure!(status.success(), "{shown} failed ({status})");
    Ok(())
}

fn output(cmd: &mut Command) -> Option<String> {
    let out = cmd.output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// A program on PATH.
fn which(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file())
}

fn detect() -> anyhow::Result<Route> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    // The std the active rustc would link for wasm32: present when rustup installed the target.
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    if let Some(dir) = output(Command::new(&rustc).args(["--print", "target-libdir", "--target", TARGET])) {
        let has_std = std::fs::read_dir(&dir)
            .is_ok_and(|entries| entries.flatten().any(|e| e.file_name().to_string_lossy().starts_with("libstd-")));
        if has_std {
            return Ok(Route::Rustup { cargo });
        }
    }
    let (drustc, dcargo) = (PathBuf::from("/usr/bin/rustc"), PathBuf::from("/usr/bin/cargo"));
    let sysroot = output(Command::new(&drustc).args(["--print", "sysroot"]));
    let has_src = sysroot.as_ref().is_some_and(|s| Path::new(s).join("lib/rustlib/src/rust/library/std").is_dir());
    let linker = ["wasm-ld", "wasm-ld-21", "wasm-ld-20", "wasm-ld-19", "wasm-ld-18"].iter().find_map(|n| which(n));
    match (sysroot, has_src, dcargo.is_file(), linker) {
        (Some(_), true, true, Some(linker)) => Ok(Route::Debian { rustc: drustc, cargo: dcargo, linker }),
        _ => bail!(
            "no way to build for {TARGET} here: the active toolchain has no wasm32 std \
             (`rustup target add {TARGET}`), and Debian's route is incomplete \
             (needs /usr/bin/rustc and /usr/bin/cargo with std sources and wasm-ld: \
             `apt-get install rustc-web cargo-web rust-web-src lld-19`)"
        ),
    }
}

/// Cargo.lock's wasm-bindgen version: the CLI must match it exactly.
fn locked_wasm_bindgen(root: &Path) -> anyhow::Result<String> {
    let lock = std::fs::read_to_string(root.join("Cargo.lock")).context("reading Cargo.lock")?;
    let mut lines = lock.lines();
    while let Some(l) = lines.next() {
        if l.trim() == "name = \"wasm-bindgen\""
            && let Some(v) = lines.next().and_then(|v| v.trim().strip_prefix("version = \""))
        {
            return Ok(v.trim_end_matches('"').to_string());
        }
    }
    bail!("Cargo.lock has no wasm-bindgen package (is the app's wasm dependency gone?)")
}

/// A `wasm-bindgen` of exactly `version`, installing it with cargo if needed.
fn wasm_bindgen(version: &str) -> anyhow::Result<PathBuf> {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    let candidates = which("wasm-bindgen").into_iter().chain(home.map(|h| h.join("bin/wasm-bindgen")));
    for c in candidates {
        if output(Command::new(&c).arg("--version")).is_some_and(|v| v.split_whitespace().nth(1) == Some(version)) {
            return Ok(c);
        }
    }
    println!("xtask: installing wasm-bindgen-cli {version} (Cargo.lock's wasm-bindgen)");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    run(Command::new(cargo).args(["install", "wasm-bindgen-cli", "--version", version]))?;
    let found = which("wasm-bindgen")
        .into_iter()
        .chain(std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo/bin/wasm-bindgen")))
        .find(|c| output(Command::new(c).arg("--version")).is_some_and(|v| v.contains(version)));
    found.with_context(|| format!("wasm-bindgen {version} was installed but is not on PATH or in ~/.cargo/bin"))
}

/// Oldest binaryen whose wasm-opt keeps Rust's current wasm output working. Binaryen 108
/// (Debian 12's) rewrites the externref table wasm-bindgen sets up, and the page then fails with
/// "WebAssembly.Table.set(): Argument 1 is invalid for table"; 132 works.
const MIN_BINARYEN: u32 = 120;

/// `$WASM_OPT` or `wasm-opt` on PATH, if recent enough.
fn wasm_opt() -> Result<PathBuf, String> {
    let path = std::env::var_os("WASM_OPT").map(PathBuf::from).or_else(|| which("wasm-opt"));
    let Some(path) = path else {
        return Err("wasm-opt not found (`npm install binaryen`, then WASM_OPT=…/node_modules/.bin/wasm-opt)".into());
    };
    let version = output(Command::new(&path).arg("--version")).unwrap_or_default();
    // "wasm-opt version 132 (version_132)"
    let n = version.split_whitespace().nth(2).and_then(|v| v.parse::<u32>().ok()).unwrap_or(0);
    if n < MIN_BINARYEN {
        return Err(format!(
            "{} is binaryen {n}, older than {MIN_BINARYEN}, which breaks wasm-bindgen's tables",
            path.display()
        ));
    }
    Ok(path)
}

/// The environment a nested cargo should not inherit from the `cargo run` that started us.
fn clean_env(cmd: &mut Command) -> &mut Command {
    for v in
        ["CARGO", "CARGO_MANIFEST_DIR", "CARGO_PKG_NAME", "RUSTUP_TOOLCHAIN", "RUSTC", "RUSTC_WRAPPER", "RUSTFLAGS"]
    {
        cmd.env_remove(v);
    }
    cmd
}

/// Builds `web/dist/` and returns its path.
pub fn build_web(root: &Path, args: &BuildArgs) -> anyhow::Result<PathBuf> {
    let started = Instant::now();
    let route = detect()?;
    let target_dir = args
        .target_dir
        .clone()
        .or_else(|| std::env::var_os("GRIDRT_WASM_TARGET_DIR").map(PathBuf::from))
        .unwrap_or_else(|| root.join("target/wasm"));
    println!("xtask: building the app for {TARGET} ({route:?}) in {}", target_dir.display());
    let mut cmd;
    match &route {
        Route::Rustup { cargo } => {
            cmd = Command::new(cargo);
            clean_env(&mut cmd);
            cmd.args(["build", "--release", "--target", TARGET, "-p", "gridrt"]);
        }
        Route::Debian { rustc, cargo, linker } => {
            cmd = Command::new(cargo);
            clean_env(&mut cmd);
            cmd.env("RUSTC", rustc)
                .env("RUSTC_BOOTSTRAP", "1")
                .env("CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER", linker)
                .args(["build", "--release", "--target", TARGET, "-p", "gridrt", "-Zbuild-std=std,panic_abort"]);
        }
    }
    cmd.env("CARGO_TARGET_DIR", &target_dir).current_dir(root);
    run(&mut cmd)?;
    let wasm = target_dir.join(TARGET).join("release/gridrt.wasm");
    anyhow::ensure!(wasm.is_file(), "the build produced no {}", wasm.display());

    let dist = root.join("web/dist");
    if dist.exists() {
        std::fs::remove_dir_all(&dist).with_context(|| format!("clearing {}", dist.display()))?;
    }
    std::fs::create_dir_all(&dist)?;
    let version = locked_wasm_bindgen(root)?;
    let bindgen = wasm_bindgen(&version)?;
    run(Command::new(&bindgen)
        .arg("--target")
        .arg("web")
        .arg("--no-typescript")
        .arg("--out-dir")
        .arg(&dist)
        .arg(&wasm))?;
    let out_wasm = dist.join("gridrt_bg.wasm");
    match (args.no_opt, wasm_opt()) {
        (false, Ok(opt)) => {
            // The features rustc enables by default for wasm32 (Rust ≥ 1.82).
            let tmp = dist.join("gridrt_bg.opt.wasm");
            let mut c = Command::new(opt);
            c.arg("-O2").args([
                "--enable-bulk-memory",
                "--enable-nontrapping-float-to-int",
                "--enable-sign-ext",
                "--enable-mutable-globals",
                "--enable-reference-types",
                "--enable-multivalue",
            ]);
            c.arg(&out_wasm).arg("-o").arg(&tmp);
            run(&mut c)?;
            std::fs::rename(&tmp, &out_wasm)?;
        }
        (false, Err(why)) => println!("xtask: {why}: the wasm stays unoptimised"),
        (true, _) => {}
    }
    // The page's static files (everything in web/ except dist/).
    for entry in std::fs::read_dir(root.join("web"))? {
        let entry = entry?;
        if entry.file_type()?.is_file() {
            std::fs::copy(entry.path(), dist.join(entry.file_name()))?;
        }
    }
    let (raw, gz) = sizes(&out_wasm)?;
    println!(
        "xtask: web/dist ready in {:.0} s: gridrt_bg.wasm {:.2} MB raw, {:.2} MB gzip",
        started.elapsed().as_secs_f64(),
        raw as f64 / 1e6,
        gz as f64 / 1e6
    );
    Ok(dist)
}

/// Raw and gzip (level 9) sizes of a file.
pub fn sizes(path: &Path) -> anyhow::Result<(u64, u64)> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    gz.write_all(&bytes)?;
    Ok((bytes.len() as u64, gz.finish()?.len() as u64))
}
