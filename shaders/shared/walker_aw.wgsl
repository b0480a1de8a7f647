//!include shared/walker_common.wgsl
// Amanatides-Woo 3DDDA in floating point: per axis the t of the next wall crossing, computed
// from the integer wall index (no drift, no FMA contraction).
// CPU port (same names, same arithmetic): crates/grid/src/traversal/amanatides_woo.rs.

struct Walker {
    done: bool,
    g: GridRay,
    res: vec3<i32>,
    cell: vec3<i32>,
    step: vec3<i32>,
    wall: vec3<f32>,
    t_max: vec3<f32>,
    // Output of walker_next.
    out_cell: vec3<i32>,
    out_t_exit: f32,
}

fn argmin3f(v: vec3<f32>) -> u32 {
    if v.x <= v.y && v.x <= v.z {
        return 0u;
    }
    if v.y <= v.z {
        return 1u;
    }
    return 2u;
}

fn walker_init(g: GridRay, res_u: vec3<u32>) -> Walker {
    var w: Walker;
    w.done = false;
    w.g = g;
    w.res = vec3<i32>(res_u);
    let c = cell_at(g, g.t0, res_u);
    w.cell = c;
    w.t_max = vec3<f32>(inf());
    for (var a = 0u; a < 3u; a++) {
        w.step[a] = sign_step(g.d[a]);
        if g.d[a] != 0.0 {
            w.wall[a] = select(f32(c[a]), f32(c[a]) + 1.0, g.d[a] > 0.0);
            w.t_max[a] = (w.wall[a] - g.o[a]) * g.inv_d[a];
        }
    }
    return w;
}

// Advances to the next cell: sets out_cell / out_t_exit and returns true, or false when done.
fn walker_next(w: ptr<function, Walker>) -> bool {
    if (*w).done {
        return false;
    }
    let a = argmin3f((*w).t_max);
    let t = (*w).t_max[a];
    (*w).out_cell = (*w).cell;
    (*w).out_t_exit = min(t, (*w).g.t1);
    if t != t || t > (*w).g.t1 {
        (*w).done = true;
    } else {
        (*w).cell[a] += (*w).step[a];
        if (*w).cell[a] < 0 || (*w).cell[a] >= (*w).res[a] {
            (*w).done = true;
        }
        (*w).wall[a] += f32((*w).step[a]);
        (*w).t_max[a] = ((*w).wall[a] - (*w).g.o[a]) * (*w).g.inv_d[a];
    }
    return true;
}
