// The macrocell kernel's walk for the Cleary-Wyvill and Liu walkers: the macro grid's walk,
// descending into each occupied macrocell's fine cells (the CPU's `MacrocellGrid::trace` for
// walkers other than Amanatides-Woo). Included through shared/macrocell_cw.wgsl and
// shared/macrocell_liu.wgsl.

// The fine cells of the occupied macrocell `m`, over [t_enter, t_exit]; true when done.
fn walk_block(fine: GridRay, m: vec3<i32>, t_enter: f32, t_exit: f32) -> bool {
    let a = params.macro_edge;
    let lo = m * i32(a);
    var sub = fine;
    sub.o = fine.o - vec3<f32>(lo);
    sub.t0 = t_enter;
    sub.t1 = t_exit;
    // A macrocell the grid's end cuts short has fewer fine cells (MacrocellGrid::block_res).
    var fw = walker_init(sub, min(vec3<u32>(a), params.res - vec3<u32>(lo)));
    loop {
        if !walker_next(&fw) {
            return false;
        }
        visit_cell();
        let idx = cell_index(lo + fw.out_cell, params.res);
        if is_occupied(idx) {
            let r = refs_of(idx);
            if test_cell(r.x, r.y, fw.out_t_exit) {
                return true;
            }
        } else if done_at(fw.out_t_exit) {
            return true;
        }
    }
    return false;
}

// The macro grid's walk, descending into occupied macrocells (called by `trace` in
// shared/closest_hit.wgsl).
fn walk(fine: GridRay) {
    let af = f32(params.macro_edge);
    let macro_res = macro_resolution();
    // Exact: A is a power of two.
    var mg = fine;
    mg.o = fine.o / af;
    mg.d = fine.d / af;
    mg.inv_d = fine.inv_d * af;
    var mw = walker_init(mg, macro_res);
    var t_enter = fine.t0;
    loop {
        if !walker_next(&mw) {
            return;
        }
        visit_cell();
        if (!macrocell_empty(mw.out_cell) && walk_block(fine, mw.out_cell, t_enter, mw.out_t_exit)) || done_at(mw.out_t_exit) {
            return;
        }
        t_enter = mw.out_t_exit;
    }
}
