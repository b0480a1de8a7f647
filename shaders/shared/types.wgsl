// Data layouts shared by every kernel.
// Keep in sync with crates/gpu/src/layout.rs (each struct is mirrored there; a test checks the
// sizes and member offsets with naga).

// One ray: origin.xyz + tmin, dir.xyz + tmax (the ray file's record). Mirrors `GpuRay`.
struct Ray {
    origin_tmin: vec4<f32>,
    dir_tmax: vec4<f32>,
}

// Closest hit: t, triangle (0xFFFFFFFF = miss), barycentrics u, v. Mirrors `GpuHit`.
struct Hit {
    t: f32,
    triangle: u32,
    u: f32,
    v: f32,
}

// Per-ray counters. Mirrors `GpuRayStats`.
struct RayStats {
    cells: u32,
    tests: u32,
}

// A triangle's vertices, packed `a.xyz b.x | b.yz c.xy | c.z` in three vec4 (48 bytes; the 9
// coordinates lead, so a kernel reads 9 components, not 12). Keep in sync with
// crates/gpu/src/upload.rs `pack_triangle`.
struct Vertices {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
}

// The vertices from a triangle's first two vec4 and the x of its third.
fn unpack_triangle(p: vec4<f32>, q: vec4<f32>, r: f32) -> Vertices {
    return Vertices(p.xyz, vec3<f32>(p.w, q.x, q.y), vec3<f32>(q.z, q.w, r));
}

// Per-dispatch parameters of a trace kernel. Mirrors `GridParams`.
struct Params {
    // xyz: grid box minimum (world units).
    grid_min: vec4<f32>,
    // xyz: 1 / cell size.
    inv_cell: vec4<f32>,
    // Resolution of the flat / fine / top grid.
    res: vec3<u32>,
    // Rays in this dispatch.
    ray_count: u32,
    // 1: skip triangles already tested by this ray (the mailbox).
    mailbox: u32,
    // Fine cells per macrocell edge (the macrocell kernel).
    macro_edge: u32,
    // Index of this dispatch's first ray in the whole ray set.
    first_ray: u32,
    // Pixels per row of the image the rays form (the packet kernels).
    image_width: u32,
    // What the search looks for: QUERY_CLOSEST or QUERY_ANY (occlusion).
    query: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Params.query (Rust: layout.rs QUERY_CLOSEST, QUERY_ANY).
const QUERY_CLOSEST: u32 = 0u;
const QUERY_ANY: u32 = 1u;

