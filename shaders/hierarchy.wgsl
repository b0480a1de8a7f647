// Closest hit through a hierarchy of grids: the one kernel of multi-resolution grids (Jevans &
// Wyvill) and two-level grids (Kalojanov, Billeter & Slusallek), which share the layout. A stack
// of walkers, one per level.
// CPU port: crates/grid/src/hierarchy.rs (`Hierarchy::trace`).
//!include shared/closest_hit.wgsl

// Mirrors GpuNode: xyz = resolution, w = index of the node's first cell.
struct Node {
    res_first: vec4<u32>,
}

// Per cell (and one more at the end): where its entries start in `refs`, CHILD_BIT set for a
// child grid, whose one entry is the child node's index; a leaf's entries end where the next
// cell's start. Mirrors Hierarchy::cells.
@group(0) @binding(6) var<storage, read> cells: array<u32>;
@group(0) @binding(7) var<storage, read> nodes: array<Node>;

const CHILD_BIT: u32 = 0x80000000u;
// Levels, top included (crates/grid/src/hierarchy.rs MAX_DEPTH, keep in sync): the builders
// stop at depth MAX_DEPTH - 1, so at most MAX_DEPTH - 1 parents are saved.
const MAX_DEPTH: u32 = 8u;

// A parent level, saved on descent and restored on return.
struct Frame {
    w: Walker,
    node: Node,
    t_enter: f32,
}

// The saved parents live in seven named variables, not an array<Frame, 7>: a dynamically
// indexed private array is per-lane scratch memory, which lavapipe reads and writes lane by
// lane (a Walker is ~30 scalars), while a switch over named variables compiles to masked
// register moves (the README's GPU section has the measured difference).
struct Stack {
    f0: Frame,
    f1: Frame,
    f2: Frame,
    f3: Frame,
    f4: Frame,
    f5: Frame,
    f6: Frame,
}

fn stack_store(s: ptr<function, Stack>, depth: u32, f: Frame) {
    switch depth {
        case 0u: { (*s).f0 = f; }
        case 1u: { (*s).f1 = f; }
        case 2u: { (*s).f2 = f; }
        case 3u: { (*s).f3 = f; }
        case 4u: { (*s).f4 = f; }
        case 5u: { (*s).f5 = f; }
        default: { (*s).f6 = f; }
    }
}

fn stack_load(s: ptr<function, Stack>, depth: u32) -> Frame {
    switch depth {
        case 0u: { return (*s).f0; }
        case 1u: { return (*s).f1; }
        case 2u: { return (*s).f2; }
        case 3u: { return (*s).f3; }
        case 4u: { return (*s).f4; }
        case 5u: { return (*s).f5; }
        default: { return (*s).f6; }
    }
}

// The hierarchy's walk: a walker per level, descending into child grids (called by `trace` in
// shared/closest_hit.wgsl).
fn walk(top: GridRay) {
    // Parents of the current level; the current walker lives in `w` (copied only on descent
    // and return).
    var stack: Stack;
    // The current node, kept in registers (and in the saved frames): read from `nodes` once per
    // descent, not per cell (each storage read is costly on software adapters).
    var node = nodes[0];
    var w = walker_init(top, node.res_first.xyz);
    var t_enter = top.t0;
    var depth = 0u;
    loop {
        if !walker_next(&w) {
            if depth == 0u {
                return;
            }
            depth -= 1u;
            let f = stack_load(&stack, depth);
            w = f.w;
            node = f.node;
            t_enter = f.t_enter;
            continue;
        }
        visit_cell();
        let c = w.out_cell;
        let t_exit = w.out_t_exit;
        let i = node.res_first.w + cell_index(c, node.res_first.xyz);
        let entry = cells[i];
        let start = entry & ~CHILD_BIT;
        let te = t_enter;
        t_enter = t_exit;
        if (entry & CHILD_BIT) != 0u {
            if depth + 1u < MAX_DEPTH {
                stack_store(&stack, depth, Frame(w, node, t_enter));
                depth += 1u;
                node = nodes[refs[start]];
                let child_res = node.res_first.xyz;
                let r = child_ray(w.g, c, child_res, te, t_exit);
                w = walker_init(r, child_res);
                t_enter = r.t0;
            }
            continue;
        }
        if test_cell(start, cells[i + 1u] & ~CHILD_BIT, t_exit) {
            return;
        }
    }
}
