// The GPU grid build's parameters and its insertion rule, shared by its kernels.
// BuildParams mirrors crates/gpu/src/layout.rs `BuildParams`; `cell_range` is
// gridrt_grid::insert::box_cell_range and `grid_box_cells`, operation for operation (a
// subtraction, a product, then exact floor and fraction: WGSL rounds these as the CPU does).
//!include shared/types.wgsl

struct BuildParams {
    // xyz: grid box minimum (world units).
    grid_min: vec4<f32>,
    // xyz: 1 / cell size.
    inv_cell: vec4<f32>,
    res: vec3<u32>,
    triangle_count: u32,
    // Insertion margin, in cells.
    margin: f32,
    // Elements of the array a scan pass reads.
    count: u32,
    // Workgroups along x of a 2-D dispatch: kernels number their workgroups wid.x + wid.y * groups_x.
    groups_x: u32,
    // Fine cells per macrocell edge (build_occupancy).
    macro_edge: u32,
    // build_insert_exact: 0 counts each cell's triangles, 1 scatters their indices.
    scatter: u32,
}

struct CellRange {
    lo: vec3<u32>,
    hi: vec3<u32>,
}

// The cell of x − margin on an axis of n cells (x clamped to [0, n] first: truncation is floor
// and the fraction is exact).
fn cell_below(x: f32, n: u32, margin: f32) -> u32 {
    let c = clamp(x, 0.0, f32(n));
    let i = u32(c);
    let frac = c - f32(i);
    return min(select(i, i - 1u, frac < margin && i > 0u), n - 1u);
}

// The cell of x + margin.
fn cell_above(x: f32, n: u32, margin: f32) -> u32 {
    let c = clamp(x, 0.0, f32(n));
    let i = u32(c);
    let frac = c - f32(i);
    return min(select(i, i + 1u, frac >= 1.0 - margin), n - 1u);
}

// The cells within the margin of triangle `v`'s bounding box, clamped to the grid.
fn cell_range(v: Vertices, p: BuildParams) -> CellRange {
    let a = (v.a - p.grid_min.xyz) * p.inv_cell.xyz;
    let b = (v.b - p.grid_min.xyz) * p.inv_cell.xyz;
    let c = (v.c - p.grid_min.xyz) * p.inv_cell.xyz;
    let lo = min(min(a, b), c);
    let hi = max(max(a, b), c);
    return CellRange(
        vec3<u32>(cell_below(lo.x, p.res.x, p.margin), cell_below(lo.y, p.res.y, p.margin), cell_below(lo.z, p.res.z, p.margin)),
        vec3<u32>(cell_above(hi.x, p.res.x, p.margin), cell_above(hi.y, p.res.y, p.margin), cell_above(hi.z, p.res.z, p.margin)),
    );
}

// Cells in the range.
fn range_cells(r: CellRange) -> u32 {
    let e = r.hi - r.lo + vec3<u32>(1u);
    return e.x * e.y * e.z;
}

// The linear index of the range's k-th cell, x fastest (the CPU's insertion order).
fn range_cell(r: CellRange, k: u32, res: vec3<u32>) -> u32 {
    let e = r.hi - r.lo + vec3<u32>(1u);
    let c = r.lo + vec3<u32>(k % e.x, (k / e.x) % e.y, k / (e.x * e.y));
    return linear_cell(c, res);
}

// Linear cell index, x fastest (gridrt_grid::geometry::linear_index).
fn linear_cell(c: vec3<u32>, res: vec3<u32>) -> u32 {
    return c.x + res.x * (c.y + res.y * c.z);
}

// The workgroup's number in a 2-D dispatch.
fn group_index(wid: vec3<u32>, groups_x: u32) -> u32 {
    return wid.x + wid.y * groups_x;
}
