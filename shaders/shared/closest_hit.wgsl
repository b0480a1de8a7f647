//!include shared/bindings.wgsl
//!include shared/ray.wgsl
//!include shared/triangle.wgsl
//!include shared/walker_{TRAVERSAL}.wgsl
// The closest-hit rule, written once for every trace kernel (CPU port:
// crates/grid/src/trace/closest_hit.rs), and the kernels' one entry point, `trace`: it prepares
// the ray and clips it to the grid, calls the structure's `walk` (defined by the kernel file
// that includes this one), and writes the hit and counters. `walk` visits the structure's cells
// in order of increasing t, hands each leaf's references to `test_cell` and returns when it says
// the search is done (the best hit lies before the cell's exit; for an occlusion query,
// params.query == QUERY_ANY, as soon as there is a hit).

// One invocation's search: its ray, best hit so far (by t, then triangle index), counters and
// mailbox. Private (per-invocation) so every kernel and walker shares them without passing them.
var<private> ray: PreparedRay;
// The ray in the grid space of the flat / top grid, clipped to its box.
var<private> top_ray: GridRay;
var<private> best: Hit;
var<private> stats: RayStats;
var<private> mailbox: array<u32, 16>;

// Starts the search of ray `i`: false when `i` is past the dispatch, the ray can hit nothing or
// misses the grid's box (then there is nothing to walk; `end_ray` still writes the miss).
fn begin_ray(i: u32) -> bool {
    best = miss();
    stats = RayStats(0u, 0u);
    mailbox = empty_mailbox();
    if i >= params.ray_count {
        return false;
    }
    ray = prepare_ray(rays[i]);
    if !ray.valid {
        return false;
    }
    // In the walk's units (PreparedRay.t_scale), a scaled walk's segment widened by an ulp on
    // each side, as on the CPU (GridGeometry::clip).
    var tmin = ray.tmin;
    var tmax = ray.tmax;
    if ray.t_scale > 1.0 {
        tmin = -next_up_f32(-tmin);
        tmax = next_up_f32(tmax);
    }
    top_ray = clip_ray((ray.org - params.grid_min.xyz) * params.inv_cell.xyz,
                       (ray.dir * (1.0 / ray.t_scale)) * params.inv_cell.xyz, params.res,
                       tmin * ray.t_scale, tmax * ray.t_scale);
    return !ray_is_empty(top_ray);
}

// Writes ray `i`'s hit and counters (nothing past the dispatch).
fn end_ray(i: u32) {
    if i < params.ray_count {
        hits[i] = best;
        ray_stats[i] = stats;
    }
}

// Counts one visited cell (a leaf, an internal cell or a skipped block).
fn visit_cell() {
    stats.cells += 1u;
}

// Tests refs[first .. end], a leaf the ray leaves at `t_exit` (skipping mailboxed triangles);
// true when the search is done.
fn test_cell(first: u32, end: u32, t_exit: f32) -> bool {
    let use_mailbox = params.mailbox != 0u;
    for (var k = first; k < end; k++) {
        test_triangle(refs[k], use_mailbox);
    }
    // An occlusion query is done at its first hit (checked per cell: a check per triangle
    // cost the closest-hit kernels more than it saved the shadow rays on lavapipe).
    return done_at(t_exit) || (params.query == QUERY_ANY && best.t < inf());
}

// True when the best hit lies before `t_exit` (the end of a cell or block just crossed, in the
// walk's units), compared in the ray's units as hits are rounded (CPU: ClosestHit::done_at).
fn done_at(t_exit: f32) -> bool {
    return best.t < t_exit * (1.0 / ray.t_scale);
}

// The next f32 above `x` (x not NaN; +inf stays): a scaled walk's segment widening.
fn next_up_f32(x: f32) -> f32 {
    let b = bitcast<u32>(x);
    if b == 0x7f800000u {
        return x;
    }
    if (b & 0x7fffffffu) == 0u {
        return bitcast<f32>(1u);
    }
    if (b >> 31u) == 0u {
        return bitcast<f32>(b + 1u);
    }
    return bitcast<f32>(b - 1u);
}

// Tests one referenced triangle, updating the best hit, the counters and the mailbox.
fn test_triangle(tri: u32, use_mailbox: bool) {
    if use_mailbox {
        let slot = tri & (MAILBOX_SIZE - 1u);
        if mailbox[slot] == tri {
            return;
        }
        mailbox[slot] = tri;
    }
    stats.tests += 1u;
    let h = intersect_triangle(ray, tri);
    if h.hit && closer(h.t, tri, best) {
        best = Hit(h.t, tri, h.u, h.v);
    }
}

fn cell_index(c: vec3<i32>, res: vec3<u32>) -> u32 {
    let u = vec3<u32>(c);
    return u.x + res.x * (u.y + res.y * u.z);
}

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if begin_ray(gid.x) {
        walk(top_ray);
    }
    end_ray(gid.x);
}
