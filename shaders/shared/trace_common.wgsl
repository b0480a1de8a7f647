//!include shared/bindings.wgsl
//!include shared/ray.wgsl
//!include shared/triangle.wgsl
//!include shared/walker_{TRAVERSAL}.wgsl
// What every trace kernel does around its structure walk: read the ray, prepare it, place it
// in the grid, write hit and stats.

// The ray in the grid space of the top / flat grid (GridGeometry::clip).
fn grid_ray(pr: PreparedRay) -> GridRay {
    let res = params.res.xyz;
    return clip_ray((pr.org - params.grid_min.xyz) * params.inv_cell.xyz, pr.dir * params.inv_cell.xyz, res, pr.tmin, pr.tmax);
}

fn cell_index(c: vec3<i32>, res: vec3<u32>) -> u32 {
    let u = vec3<u32>(c);
    return u.x + res.x * (u.y + res.y * u.z);
}

fn write_result(i: u32, best: Hit, stats: RayStats) {
    hits[i] = best;
    ray_stats[i] = stats;
}
