//! `gridrt gen KIND`: procedural scenes as .glb.

use anyhow::Context;
use gridrt_scene::procedural::{self, SceneKind};

use crate::cli::{GenArgs, GenKind};

/// Largest crowd (tubes): about 1.1 billion triangles would not load anyway.
const MAX_CROWD_TUBES: u32 = 100_000;

pub fn run(args: GenArgs) -> anyhow::Result<()> {
    if args.kind == GenKind::Crowd {
        let tubes = args.size.unwrap_or(500);
        anyhow::ensure!(
            (1..=MAX_CROWD_TUBES).contains(&tubes),
            "--size {tubes} is out of range for crowd: 1..={MAX_CROWD_TUBES} (skinned tubes)"
        );
        let bytes = gridrt_scene::crowd::crowd_glb(tubes, args.seed);
        std::fs::write(&args.output, &bytes).with_context(|| format!("writing {}", args.output.display()))?;
        println!(
            "crowd: size {tubes} (skinned tubes; half as many rigid balls), {} triangles, animated -> {} ({} bytes)",
            gridrt_scene::crowd::crowd_triangles(tubes),
            args.output.display(),
            bytes.len()
        );
        return Ok(());
    }
    let kind = match args.kind {
        GenKind::Crowd => unreachable!("handled above"),
        GenKind::Mountain => SceneKind::Mountain,
        GenKind::Sphereflake => SceneKind::Sphereflake,
        GenKind::Particles => SceneKind::Particles,
        GenKind::Slivers => SceneKind::Slivers,
        GenKind::TeapotInStadium => SceneKind::TeapotInStadium,
    };
    let (meaning, default) = kind.size_help();
    let size = args.size.unwrap_or(default);
    let range = kind.size_range();
    anyhow::ensure!(
        range.contains(&size),
        "--size {size} is out of range for {}: {}..={} ({meaning})",
        kind.name(),
        range.start(),
        range.end()
    );
    let g = procedural::generate(kind, size, args.seed);
    let bytes = gridrt_scene::glb_write::to_glb(
        &g.mesh,
        &format!("gridrt gen {} --size {size} --seed {}", kind.name(), args.seed),
    );
    std::fs::write(&args.output, &bytes).with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "{}: size {size} ({meaning}), {} triangles, {} vertices -> {} ({} bytes)",
        kind.name(),
        g.mesh.triangle_count(),
        g.mesh.positions.len(),
        args.output.display(),
        bytes.len()
    );
    Ok(())
}
