//! What gridrt's test suites read from their environment, in one place for every test crate:
//! the shared-scene folder (`../shared/scenes` beside the repository) and how large the
//! exactness matrices are.
//!
//! - `GRIDRT_REQUIRE_SHARED_SCENES=1` (set by `.ci/run`): a missing or empty shared-scene folder
//!   fails the test instead of skipping it.
//! - `GRIDRT_FULL_MATRICES=1` (set by `.ci/run`): the exactness matrices trace their full ray
//!   sets; without it they trace a fixed sample of each (every scene, structure, traversal,
//!   insertion and mailbox setting still runs), so a newcomer's `cargo test` stays short.
//! - `GRIDRT_THREE_DIR` (default `~/.cache/gridrt/three-0.170.0`): a folder holding
//!   `node_modules/three`, the independent glTF posing reference; `GRIDRT_REQUIRE_THREE=1` (set by
//!   `.ci/run`, which installs it) fails the posing comparison when it or `node` is missing.

use std::path::{Path, PathBuf};

/// True when `name` is set to `1`.
fn flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v == "1")
}

/// Whether the full exactness matrices run (`GRIDRT_FULL_MATRICES=1`).
pub fn full_matrices() -> bool {
    flag("GRIDRT_FULL_MATRICES")
}

/// Rays per scene in an exactness matrix: `full` in full mode, else a tenth of it (at least
/// 1000).
pub fn matrix_rays(full: usize) -> usize {
    if full_matrices() { full } else { (full / 10).max(1000).min(full) }
}

/// The folder holding `node_modules/three` (three.js, the scene crate's independent posing
/// reference), when it and `node` are there; `None` otherwise, which fails the calling test
/// under `GRIDRT_REQUIRE_THREE=1`.
pub fn three_js_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("GRIDRT_THREE_DIR").map(PathBuf::from).or_else(|| {
        let cache = std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
        Some(cache.join("gridrt").join("three-0.170.0"))
    });
    let node = std::process::Command::new("node").arg("--version").output().is_ok_and(|o| o.status.success());
    let found = dir.filter(|d| node && d.join("node_modules/three/package.json").is_file());
    if found.is_none() {
        assert!(
            !flag("GRIDRT_REQUIRE_THREE"),
            "GRIDRT_REQUIRE_THREE=1 but three.js or node is missing (GRIDRT_THREE_DIR, ~/.cache/gridrt/three-0.170.0)"
        );
        println!("three.js or node not installed: the check against three.js does not run");
    }
    found
}

/// The shared-scene folder, `../shared/scenes` beside the repository.
fn shared_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes")
}

/// The shared scenes whose file names end in one of `extensions`, in `subfolders` of the
/// shared folder (`""` is the folder itself), sorted. Empty when the folder is absent, unless
/// `GRIDRT_REQUIRE_SHARED_SCENES=1`, which makes that a failure.
pub fn shared_scenes_in(subfolders: &[&str], extensions: &[&str]) -> Vec<PathBuf> {
    let dir = shared_dir();
    let mut files: Vec<PathBuf> = subfolders
        .iter()
        .filter_map(|sub| std::fs::read_dir(dir.join(sub)).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| extensions.iter().any(|e| x == *e)))
        .collect();
    files.sort();
    if files.is_empty() {
        assert!(
            !flag("GRIDRT_REQUIRE_SHARED_SCENES"),
            "GRIDRT_REQUIRE_SHARED_SCENES=1 but {} holds no {extensions:?} scenes",
            dir.display()
        );
        println!("{} not present: the shared-scene checks have nothing to do", dir.display());
    }
    files
}

/// The static shared scenes (`.glb` files in the shared folder itself).
pub fn shared_scenes() -> Vec<PathBuf> {
    shared_scenes_in(&[""], &["glb"])
}
