// The macrocell kernel's walk with the Amanatides-Woo walker: one walk of the fine cells that
// crosses empty macrocells as blocks, on the blocks' own walk, and re-enters the fine walk
// where the cell-by-cell walk would be. CPU port (same arithmetic, same visits and counts):
// `AmanatidesWoo::walk_blocks`, `LinearWalk::cross_blocks` and `enter_block` in
// crates/grid/src/traversal/amanatides_woo.rs, `MacrocellGrid::visit` in
// crates/grid/src/macrocell.rs.

// Called by `trace` in shared/closest_hit.wgsl.
fn walk(fine: GridRay) {
    var w = walker_init(fine, params.res);
    let log2 = countTrailingZeros(params.macro_edge);
    loop {
        if w.cur.done {
            return;
        }
        let idx = cell_index(w.cur.cell, params.res);
        let occupied = is_occupied(idx);
        if !occupied && macrocell_empty(w.cur.cell >> vec3<u32>(log2)) {
            visit_cell();
            if !walker_cross_blocks(&w, log2) {
                return;
            }
            continue;
        }
        walker_next(&w);
        visit_cell();
        if occupied {
            let r = refs_of(idx);
            if test_cell(r.x, r.y, w.out_t_exit) {
                return;
            }
        } else if done_at(w.out_t_exit) {
            return;
        }
    }
}

// From the current cell, whose macrocell (block of 2^log2 cells per edge) is empty: walks the
// macro grid, its walls being fine walls crossed at the fine walk's t, to the first occupied
// macrocell and sets the walker where the cell-by-cell walk enters it. Each empty macrocell
// entered after the current one is a visited cell. False when the walk ends first.
fn walker_cross_blocks(w: ptr<function, Walker>, log2: u32) -> bool {
    let step = (*w).cur.step;
    let o = (*w).g.o;
    let inv_d = (*w).g.inv_d;
    let res = vec3<i32>(macro_resolution());
    var block = (*w).cur.cell >> vec3<u32>(log2);
    var wall = vec3<i32>(0);
    var t_max = vec3<f32>(inf());
    for (var a = 0u; a < 3u; a++) {
        if step[a] != 0 {
            let lo = block[a] << log2;
            wall[a] = select(lo, min(lo + (1 << log2), (*w).cur.res[a]), step[a] > 0);
            t_max[a] = (f32(wall[a]) - o[a]) * inv_d[a];
        }
    }
    loop {
        let out = argmin3_of(t_max.x <= t_max.y, t_max.x <= t_max.z, t_max.y <= t_max.z);
        let t = t_max[out];
        if t != t || t > (*w).g.t1 {
            (*w).cur.done = true;
            return false;
        }
        block[out] += step[out];
        if block[out] < 0 || block[out] >= res[out] {
            (*w).cur.done = true;
            return false;
        }
        wall[out] = min(wall[out] + (step[out] << log2), (*w).cur.res[out]);
        t_max[out] = (f32(wall[out]) - o[out]) * inv_d[out];
        if !macrocell_empty(block) {
            for (var a = 0u; a < 3u; a++) {
                walker_enter_block(w, log2, a, block[a], out, t);
            }
            return true;
        }
        visit_cell();
    }
    return false;
}

// Axis `a`'s part of walker_cross_blocks: the cell, next wall and crossing on entering block
// `b` (its index on this axis) at `t` through axis `out`. On `out`, the block's first cell; on
// another axis, the walls whose (t, axis) is less are crossed, counted from the walker's next
// wall while it is still in block `b` on this axis, else from the block's first wall.
fn walker_enter_block(w: ptr<function, Walker>, log2: u32, a: u32, b: i32, out: u32, t: f32) {
    let step = (*w).cur.step[a];
    if step == 0 {
        return;
    }
    let o = (*w).g.o[a];
    let inv_d = (*w).g.inv_d[a];
    // Moving down, a block is entered from above, so never the grid's last, cut-short one; the
    // bound keeps the first cell in the grid regardless.
    var cell = select(min((b << log2) + (1 << log2) - 1, (*w).cur.res[a] - 1), b << log2, step > 0);
    var wall = cell + select(0, 1, step > 0);
    if a != out {
        if ((*w).cur.cell[a] >> log2) == b {
            cell = (*w).cur.cell[a];
            wall = i32((*w).wall[a]);
        }
        loop {
            let t_wall = (f32(wall) - o) * inv_d;
            if !(t_wall < t || (t_wall == t && a < out)) {
                break;
            }
            cell += step;
            wall += step;
        }
    }
    (*w).cur.cell[a] = cell;
    (*w).wall[a] = f32(wall);
    (*w).t_max[a] = (f32(wall) - o) * inv_d;
}
