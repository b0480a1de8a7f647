//!include shared/ray.wgsl
// What the three cell walkers share. Each walker lives in its own file with the same interface
// (`Walker` holding a `Cursor`, `walker_init`, `walker_advance`) and only its own state, and a
// kernel is composed with the one its pipeline walks (crates/gpu/src/shaders.rs, `{TRAVERSAL}`
// in an include): a small walker stays in registers, which matters most on the hierarchy stack
// (one walker per level).
// Naive Bresenham is CPU-only (it is incomplete by design).

// Advances to the next cell: sets out_cell / out_t_exit and returns true, or false when done.
// The walker file's `walker_advance` takes the step (the cursor is not done; out_cell holds the
// current cell). Rust: the exact walkers' `Iterator` (crates/grid/src/traversal/mod.rs).
fn walker_next(w: ptr<function, Walker>) -> bool {
    if (*w).cur.done {
        return false;
    }
    (*w).out_cell = (*w).cur.cell;
    return walker_advance(w);
}

// What the walkers share: the cell they are in, the grid's resolution, the step direction per
// axis and whether the walk has ended. Rust: `Cursor` in crates/grid/src/traversal/mod.rs.
struct Cursor {
    cell: vec3<i32>,
    res: vec3<i32>,
    step: vec3<i32>,
    done: bool,
}

// In the segment's first cell, stepping along the sign of the direction on each axis.
fn cursor_start(g: GridRay, res: vec3<u32>) -> Cursor {
    var c: Cursor;
    c.cell = cell_at(g, g.t0, res);
    c.res = vec3<i32>(res);
    for (var a = 0u; a < 3u; a++) {
        c.step[a] = sign_step(g.d[a]);
    }
    c.done = false;
    return c;
}

// One cell along axis `a`; the walk ends when that leaves the grid. By value: naga's SPIR-V
// writer cannot pass a pointer to a struct member (`&(*w).cur`) to a function.
fn cursor_cross(cur: Cursor, a: u32) -> Cursor {
    var c = cur;
    c.cell[a] += c.step[a];
    if c.cell[a] < 0 || c.cell[a] >= c.res[a] {
        c.done = true;
    }
    return c;
}

// The wall the walk crosses next on axis `a` (as f32: exact for any resolution up to 2^24).
fn cursor_wall(c: Cursor, a: u32) -> f32 {
    return f32(c.cell[a] + select(0, 1, c.step[a] > 0));
}

// The axis of the smallest of three values from their comparisons; ties go to the lower axis.
// The tie-break every walker shares with its Rust port (`argmin3`).
fn argmin3_of(x_le_y: bool, x_le_z: bool, y_le_z: bool) -> u32 {
    if x_le_y && x_le_z {
        return 0u;
    }
    if y_le_z {
        return 1u;
    }
    return 2u;
}

fn sign_step(x: f32) -> i32 {
    if x > 0.0 {
        return 1;
    }
    if x < 0.0 {
        return -1;
    }
    return 0;
}
