//! `gridrt rays SCENE --kind …`: ray files.

use anyhow::Context;
use glam::Vec3;
use gridrt_scene::Camera;
use gridrt_scene::rays::{camera_rays, inside_rays, random_rays, write_rays};

use crate::cli::{RayKind, RaysArgs};
use crate::lab::views;

pub fn run(args: RaysArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let bounds = mesh.bounds();
    anyhow::ensure!(args.count > 0, "--count must be positive");
    let rays = match args.kind {
        RayKind::Random => random_rays(&bounds, args.count, args.seed),
        RayKind::Camera => camera_rays(&Camera::fit(&bounds, 4.0 / 3.0), args.count),
        RayKind::Framed | RayKind::Interior => {
            let tris = mesh.triangles();
            let probe = views::probe_grid(&tris)?;
            let cam = if args.kind == RayKind::Framed {
                views::framed_camera(&tris, &bounds, &probe, 4.0 / 3.0)
            } else {
                views::interior_camera(&tris, &bounds, &probe)
            };
            camera_rays(&cam, args.count)
        }
        RayKind::Inside => {
            let origin = match &args.origin {
                Some(s) => parse_vec3(s)?,
                None => bounds.center(),
            };
            inside_rays(&mesh, origin, args.count, args.seed)
        }
    };
    write_rays(&args.output, &rays).with_context(|| format!("writing {}", args.output.display()))?;
    println!("{} {:?} rays for {} -> {}", rays.len(), args.kind, report.source, args.output.display());
    Ok(())
}

fn parse_vec3(s: &str) -> anyhow::Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("bad point \"{s}\""))?;
    anyhow::ensure!(v.len() == 3 && v.iter().all(|x| x.is_finite()), "expected x,y,z, got \"{s}\"");
    Ok(Vec3::new(v[0], v[1], v[2]))
}
