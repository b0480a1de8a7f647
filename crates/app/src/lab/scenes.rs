//! The scenes benchmarks and experiments run on: a manifest's (by default ../shared/scenes,
//! picked by kind) or procedural stand-ins, and the mixed ray sets they are measured with.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use glam::Vec3;
use gridrt_scene::procedural::{self, SceneKind};
use gridrt_scene::rays::{camera_rays, random_rays};
use gridrt_scene::{Aabb, Camera};

use crate::cli::ExperimentArgs;

/// A scene of a benchmark or an experiment: name, kind, triangles, bounds.
pub struct LabScene {
    pub name: String,
    pub kind: String,
    pub tris: Vec<[Vec3; 3]>,
    pub bounds: Aabb,
}

/// The shared scenes' folder when it exists next to the workspace or the current directory.
pub fn default_scenes() -> Option<PathBuf> {
    [PathBuf::from("../shared/scenes"), PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes"))]
        .into_iter()
        .find(|p| p.join("manifest.json").is_file())
}

/// Every scene of `dir`'s manifest.json, or every .glb/.gltf in `dir` without one, by triangle
/// count (`quick`: the two smallest). Scenes without triangles are skipped, with a note.
pub fn every_scene(dir: &Path, quick: bool) -> anyhow::Result<Vec<LabScene>> {
    let manifest: Vec<serde_json::Value> = match std::fs::read_to_string(dir.join("manifest.json")) {
        Ok(text) => serde_json::from_str(&text).map_err(|e| anyhow::anyhow!("{}/manifest.json: {e}", dir.display()))?,
        Err(_) => Vec::new(),
    };
    let mut files: Vec<(String, String)> = manifest
        .iter()
        .filter_map(|e| Some((e["file"].as_str()?.to_string(), e["kind"].as_str().unwrap_or("unknown").to_string())))
        .collect();
    if files.is_empty() {
        let found = gltf_files(dir).map_err(|e| anyhow::anyhow!("reading {}: {e}", dir.display()))?;
        files.extend(
            found.iter().filter_map(|p| Some((p.file_name()?.to_string_lossy().into_owned(), "unknown".into()))),
        );
    }
    files.sort();
    let mut scenes = Vec::new();
    for (file, kind) in files {
        let (mesh, _) = gridrt_scene::gltf_load::load_path(&dir.join(&file))?;
        let tris = mesh.triangles();
        if tris.is_empty() {
            eprintln!("skipping {file}: no triangles");
            continue;
        }
        scenes.push(LabScene { name: file, kind, bounds: mesh.bounds(), tris });
    }
    scenes.sort_by_key(|s| s.tris.len());
    if quick {
        scenes.truncate(2);
    }
    anyhow::ensure!(!scenes.is_empty(), "no scenes with triangles in {}", dir.display());
    Ok(scenes)
}

/// The .glb/.gltf files directly in `dir`, sorted by path.
pub fn gltf_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.extension().is_some_and(|e| e == "glb" || e == "gltf") {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

pub fn from_manifest(dir: &Path, quick: bool) -> anyhow::Result<Vec<LabScene>> {
    let text = std::fs::read_to_string(dir.join("manifest.json"))
        .with_context(|| format!("reading {}/manifest.json", dir.display()))?;
    let entries: Vec<serde_json::Value> = serde_json::from_str(&text).context("parsing manifest.json")?;
    let mut picked = Vec::new();
    for (kind, count) in [("scanned", 2), ("architectural", 1), ("particles", 1), ("slivers", 1)] {
        let mut of_kind: Vec<&serde_json::Value> = entries.iter().filter(|e| e["kind"] == kind).collect();
        // The largest ones (quick runs: the smallest, to stay quick).
        of_kind.sort_by_key(|e| e["triangles"].as_u64().unwrap_or(0));
        if !quick {
            of_kind.reverse();
        }
        for e in of_kind.into_iter().take(if quick { 1 } else { count }) {
            let file = e["file"].as_str().context("a manifest entry without a file")?;
            let (mesh, _) = gridrt_scene::gltf_load::load_path(&dir.join(file))?;
            picked.push(LabScene {
                name: file.into(),
                kind: kind.into(),
                tris: mesh.triangles(),
                bounds: mesh.bounds(),
            });
        }
    }
    anyhow::ensure!(
        !picked.is_empty(),
        "{}/manifest.json names no scanned/architectural/particles/slivers scene",
        dir.display()
    );
    Ok(picked)
}

pub fn procedural_scenes(quick: bool) -> Vec<LabScene> {
    let s = |k: SceneKind, size: u32, kind: &str| {
        let g = procedural::generate(k, size, 1);
        LabScene {
            name: format!("{} (procedural)", k.name()),
            kind: kind.into(),
            tris: g.mesh.triangles(),
            bounds: g.mesh.bounds(),
        }
    };
    if quick {
        return vec![s(SceneKind::Sphereflake, 1, "scanned-like"), s(SceneKind::Particles, 5_000, "particles")];
    }
    vec![
        s(SceneKind::Sphereflake, 2, "scanned-like"),
        s(SceneKind::Mountain, 8, "scanned-like"),
        s(SceneKind::TeapotInStadium, 2, "architectural-like"),
        s(SceneKind::Particles, 50_000, "particles"),
        s(SceneKind::Slivers, 20_000, "slivers"),
    ]
}

/// The scenes an experiment runs on: `--scenes`' manifest (default ../shared/scenes), or the
/// procedural stand-ins without one or with `--procedural`.
pub fn pick_scenes(args: &ExperimentArgs) -> anyhow::Result<Vec<LabScene>> {
    let dir = if args.procedural { None } else { args.scenes.clone().or_else(default_scenes) };
    Ok(match dir {
        Some(dir) => from_manifest(&dir, args.quick)?,
        None => procedural_scenes(args.quick),
    })
}

/// The rays of a scene's measurements: half primary (from the auto camera), half random.
pub fn mixed_rays(bounds: &Aabb, count: usize, seed: u64) -> Vec<gridrt_scene::Ray> {
    let mut rays = camera_rays(&Camera::fit(bounds, 4.0 / 3.0), count / 2);
    rays.extend(random_rays(bounds, count - rays.len(), seed));
    rays
}
