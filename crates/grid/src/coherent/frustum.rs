//! The packet's frustum, slice by slice: the axis the packet walks along, each ray's line in
//! grid space, and the rectangle of cells the packet's rays cross in a slice.
//!
//! On the walk axis `a`, ray i's position on another axis is the line
//! `c_i + slope_i · (s − s_ref)` of the plane coordinate `s`. Over the active rays the
//! intercepts and slopes are bounded by intervals, so a slice's rectangle costs a few
//! operations however many rays are active (the intervals are recomputed only when a ray leaves).
//! `s_ref` is the plane where the rays are closest together: the camera's eye for camera rays,
//! the light for shadow rays towards it, so the bounds there are tight. The lines are computed
//! in f64 from the f32 grid-space rays the single-ray walkers use, so the rectangle holds each
//! ray's cells exactly; [`SLICE_MARGIN_CELLS`] widens it further (smaller than the insertion
//! margin, so a triangle a ray meets lies in a cell the packet visits).

use glam::UVec3;
use gridrt_scene::Ray;

use crate::geometry::GridGeometry;
use crate::ray::PreparedRay;

/// Slices [`SliceWalk::coherent_enough`] samples at most (plus one).
pub const COHERENCE_SAMPLES: u32 = 16;

/// Widening of each slice rectangle and each ray's slice range, in cells.
pub const SLICE_MARGIN_CELLS: f64 = 1.0 / 512.0;

/// One ray of a packet.
#[derive(Clone, Copy, Debug)]
pub struct Lane {
    /// None for rays no triangle can be hit by or that miss the grid: they stay misses.
    pub ray: Option<PreparedRay>,
    /// Grid-space origin and direction (as the single-ray walkers see them), in f64.
    o: [f64; 3],
    d: [f64; 3],
    /// The segment clipped to the grid.
    t0: f32,
    t1: f32,
    /// Slopes of the line on the two other axes (per cell along the walk axis).
    slope: [f64; 2],
    /// The ray parameter at plane `s` of the walk axis is `t_at_0 + s · t_per_cell`.
    t_at_0: f64,
    t_per_cell: f64,
    /// First and last step (see [`SliceWalk::slice`]) of the ray's slices.
    pub first: u32,
    pub last: u32,
}

impl Lane {
    /// A ray that misses the grid or that no triangle can be hit by (the walk-axis fields are
    /// set once the axis is chosen).
    const INVALID: Lane = Lane {
        ray: None,
        o: [0.0; 3],
        d: [1.0, 0.0, 0.0],
        t0: 0.0,
        t1: 0.0,
        slope: [0.0; 2],
        t_at_0: 0.0,
        t_per_cell: 0.0,
        first: 0,
        last: 0,
    };

    /// The ray's `t` in its walk's units (those of the lane's line; [`PreparedRay::walk_t`]).
    #[inline]
    fn walk_t(&self, t: f32) -> f32 {
        self.ray.map_or(t, |r| r.walk_t(t))
    }

    /// Whether the walk has reached the ray's first slice at step `j`.
    #[inline]
    pub fn started(&self, j: u32) -> bool {
        j >= self.first
    }
}

/// `v.floor()` without the libm call of baseline x86-64 (|v| < 2^63; beyond, saturated).
#[inline]
fn floor(v: f64) -> f64 {
    let i = v as i64 as f64;
    if i > v { i - 1.0 } else { i }
}

/// Bounds over the active rays of their lines' intercepts and slopes on the two other axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bounds {
    pub(crate) c_lo: [f64; 2],
    pub(crate) c_hi: [f64; 2],
    pub(crate) slope_lo: [f64; 2],
    pub(crate) slope_hi: [f64; 2],
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        c_lo: [f64::INFINITY; 2],
        c_hi: [f64::NEG_INFINITY; 2],
        slope_lo: [f64::INFINITY; 2],
        slope_hi: [f64::NEG_INFINITY; 2],
    };

    /// The bounds over the `active` lanes started by step `j` of their lines on the two axes
    /// other than `a`, with intercepts at plane `s_ref`.
    fn of(a: usize, s_ref: f64, lanes: &[Lane], active: &[u32], j: u32) -> Bounds {
        Bounds::over(a, s_ref, lanes, active.iter().copied().filter(|&i| lanes[i as usize].first <= j))
    }

    /// The bounds over the lines of `lanes[i]` for each `i` of `which`.
    fn over(a: usize, s_ref: f64, lanes: &[Lane], which: impl Iterator<Item = u32>) -> Bounds {
        let others = [(a + 1) % 3, (a + 2) % 3];
        let mut b = Bounds::EMPTY;
        for i in which {
            b.add(others, a, s_ref, &lanes[i as usize]);
        }
        b
    }

    /// The bounds widened to lane `l`'s line.
    #[inline]
    fn add(&mut self, others: [usize; 2], a: usize, s_ref: f64, l: &Lane) {
        let ds = s_ref - l.o[a];
        for (k, &u) in others.iter().enumerate() {
            let slope = l.slope[k];
            let c = l.o[u] + slope * ds;
            self.c_lo[k] = self.c_lo[k].min(c);
            self.c_hi[k] = self.c_hi[k].max(c);
            self.slope_lo[k] = self.slope_lo[k].min(slope);
            self.slope_hi[k] = self.slope_hi[k].max(slope);
        }
    }
}

/// A slice's box of cells and the region of grid space the active rays cross in it.
#[derive(Clone, Copy, Debug)]
pub struct SliceRect {
    pub lo: UVec3,
    pub hi: UVec3,
    /// Per axis, the lowest and highest grid coordinate of the region.
    pub span: [(f64, f64); 3],
    /// The walk axis, the reference plane and the lines' bounds, for the region of a thinner
    /// slab ([`SliceRect::span_between`]).
    frustum: (usize, f64, Bounds),
}

/// A triangle's bounding box in grid space, computed as insertion computes it and widened by
/// the insertion margin: per axis the lowest and highest grid coordinate a ray meeting the
/// triangle can have there.
#[derive(Clone, Copy, Debug)]
pub struct TriangleBox {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl TriangleBox {
    #[inline]
    pub fn of(geom: &GridGeometry, tri: &[glam::Vec3; 3]) -> TriangleBox {
        let g = tri.map(|p| (p - geom.min) * geom.inv_cell);
        let (lo, hi) = (g[0].min(g[1]).min(g[2]), g[0].max(g[1]).max(g[2]));
        let m = crate::geometry::INSERT_MARGIN_CELLS;
        TriangleBox { lo: lo.to_array().map(|v| v as f64 - m), hi: hi.to_array().map(|v| v as f64 + m) }
    }
}

impl SliceRect {
    /// The axis the packet walks along.
    #[inline]
    pub fn walk_axis(&self) -> usize {
        self.frustum.0
    }

    /// The region the rays cross between planes `s0` and `s1` of the walk axis (grid
    /// coordinates, within the slice): [`SliceWalk::rect`]'s bounds at those planes, so a
    /// hierarchy's child grid is visited layer by layer, each layer only where the rays are.
    #[inline]
    pub fn span_between(&self, s0: f64, s1: f64) -> [(f64, f64); 3] {
        let (a, s_ref, b) = self.frustum;
        let mut span = self.span;
        span[a] = (s0.min(s1), s0.max(s1));
        for (n, u) in [(a + 1) % 3, (a + 2) % 3].into_iter().enumerate() {
            span[u] = line_span(&b, n, s_ref, s0, s1);
        }
        span
    }

    /// Whether no active ray can meet the triangle of box `b` inside this slice: the box misses
    /// the region. Such a triangle is left for the slices where its box meets the rays (it is in
    /// their cells too), and is not mailboxed here.
    #[inline]
    pub fn misses(&self, b: &TriangleBox) -> bool {
        (0..3).any(|k| b.hi[k] < self.span[k].0 || b.lo[k] > self.span[k].1)
    }
}

/// The cells `0..n` of one axis that the coordinates `lo..=hi` (in cells) touch: each end's
/// floor, clamped to the axis (truncation of a non-negative value); `None` when the interval
/// lies outside the axis or is NaN.
#[inline]
pub fn cells_of(lo: f64, hi: f64, n: u32) -> Option<(u32, u32)> {
    if hi < 0.0 || lo >= n as f64 || lo.is_nan() || hi.is_nan() {
        return None;
    }
    Some(((lo.max(0.0) as u32).min(n - 1), (hi.max(0.0) as u32).min(n - 1)))
}

/// On the `n`-th axis other than the walk axis, the lowest and highest coordinates the lines of
/// `b` (intercepts at plane `s_ref`) take between planes `near` and `far`, widened by
/// [`SLICE_MARGIN_CELLS`]: a line is linear in the plane, so its extremes are at the two planes.
#[inline]
fn line_span(b: &Bounds, n: usize, s_ref: f64, near: f64, far: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in [near, far] {
        let ds = s - s_ref;
        let (sl, sh) = if ds >= 0.0 { (b.slope_lo[n], b.slope_hi[n]) } else { (b.slope_hi[n], b.slope_lo[n]) };
        lo = lo.min(b.c_lo[n] + sl * ds);
        hi = hi.max(b.c_hi[n] + sh * ds);
    }
    (lo - SLICE_MARGIN_CELLS, hi + SLICE_MARGIN_CELLS)
}

/// The coordinates on one axis that lines with intercepts in `c` (at the reference plane) and
/// slopes in `slope` take where the walk axis is `ds` in `d` from the reference plane, widened
/// by [`SLICE_MARGIN_CELLS`]: `c + slope · ds` is extreme at the intervals' corners. Plain
/// comparisons (the values are finite, so no NaN arises) compile to single min and max
/// instructions when eight of these run in lanes.
#[inline(always)]
pub(crate) fn lines_interval(c: (f64, f64), slope: (f64, f64), d: (f64, f64)) -> (f64, f64) {
    let (min, max) = (|x: f64, y: f64| if x < y { x } else { y }, |x: f64, y: f64| if x > y { x } else { y });
    let (p, q, r, s) = (slope.0 * d.0, slope.0 * d.1, slope.1 * d.0, slope.1 * d.1);
    let m = SLICE_MARGIN_CELLS;
    (c.0 + min(min(p, q), min(r, s)) - m, c.1 + max(max(p, q), max(r, s)) + m)
}

/// Bounds of some lanes' lines (a chunk of a packet's gathered rays), as [`SliceWalk`] keeps
/// them for the whole packet.
#[derive(Clone, Copy, Debug)]
pub struct LineBounds(pub(crate) Bounds);

/// The walk of one packet: axis, direction, steps and the frustum of its active rays.
#[derive(Clone, Copy, Debug)]
pub struct SliceWalk {
    /// The axis the packet walks along (every ray moves along it with the same sign).
    pub axis: usize,
    pub positive: bool,
    /// Slices along the axis.
    pub slices: u32,
    first: u32,
    last: u32,
    /// The reference plane of the lines' intercepts.
    s_ref: f64,
    /// About the cells the rays cross one by one (the sum of their segments' lengths in cells,
    /// one axis after another).
    single_ray_cells: f64,
    bounds: Bounds,
    /// The first step at which a lane not yet in `bounds` starts (see [`SliceWalk::reach`]).
    next_start: u32,
}

/// The walk axis of a packet of `rays`: the dominant axis of the middle of the box of their
/// grid-space directions (as `coherent.wgsl` chooses it; rays with an empty interval or a
/// non-finite direction are left out), `None` when no ray is left. Only which slices the packet
/// walks depends on it, never a hit.
fn packet_axis(geom: &GridGeometry, rays: &[Ray]) -> Option<usize> {
    use glam::Vec3A;
    let inv = Vec3A::from(geom.inv_cell);
    let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    for r in rays {
        let d = Vec3A::from(r.d()) * inv;
        if d.is_finite() && r.tmin <= r.tmax {
            (lo, hi) = (lo.min(d), hi.max(d));
        }
    }
    let mid = (lo + hi).abs();
    mid.is_finite().then(|| crate::ray::argmax3(mid.to_array()))
}

impl SliceWalk {
    /// Prepares `rays` as `lanes` and chooses the walk axis ([`packet_axis`]), which every
    /// valid ray must cross with the same sign. `None` for an incoherent packet, or one with a
    /// ray of a scaled walk (trace its rays one by one). `active` receives the valid lanes.
    pub fn new(geom: &GridGeometry, rays: &[Ray], lanes: &mut Vec<Lane>, active: &mut Vec<u32>) -> Option<SliceWalk> {
        lanes.clear();
        active.clear();
        let axis = packet_axis(geom, rays)?;
        // The first valid ray's origin and end on the axis (the candidate reference planes) and
        // its sign there, which every valid ray must share.
        let mut first_ray: Option<(f64, Option<f64>, bool)> = None;
        for r in rays {
            let pr = PreparedRay::new(r);
            // A ray walked at a scale (a direction of 2^16 or more) is traced alone, where its
            // walk widens its segment and stops by its hits' rounded `t` (GridGeometry::clip,
            // ClosestHit::done_at): the packet is traced as single rays.
            if pr.is_some_and(|p| p.t_scale > 1.0) {
                return None;
            }
            let clipped = pr.and_then(|pr| geom.clip_unscaled(&pr, pr.tmin, pr.tmax).map(|g| (pr, g)));
            let lane = match clipped {
                Some((ray, g)) => {
                    let o = g.o.to_array().map(f64::from);
                    let d = g.d.to_array().map(f64::from);
                    first_ray.get_or_insert_with(|| {
                        let tmax = ray.walk_t(r.tmax);
                        (o[axis], tmax.is_finite().then(|| o[axis] + d[axis] * tmax as f64), d[axis] > 0.0)
                    });
                    Lane { ray: Some(ray), o, d, t0: g.t0, t1: g.t1, ..Lane::INVALID }
                }
                None => Lane::INVALID,
            };
            lanes.push(lane);
        }
        let positive = first_ray.is_none_or(|f| f.2);
        let res = geom.res[axis];
        let others = [(axis + 1) % 3, (axis + 2) % 3];
        let (mut first, mut last) = (u32::MAX, 0u32);
        let mut single_ray_cells = 0.0;
        // The lines' bounds at the first ray's origin, the first candidate reference plane.
        let mut at_origin = Bounds::EMPTY;
        let s0 = first_ray.map_or(0.0, |f| f.0);
        for (i, l) in lanes.iter_mut().enumerate() {
            if l.ray.is_none() {
                continue;
            }
            if !(l.d[axis] != 0.0 && (l.d[axis] > 0.0) == positive) {
                return None;
            }
            let (e, x) = (l.o[axis] + l.d[axis] * l.t0 as f64, l.o[axis] + l.d[axis] * l.t1 as f64);
            // Truncation is the floor of a non-negative value (and `f64::floor` is a libm call on
            // baseline x86-64).
            let slice = |v: f64| (v.max(0.0) as u32).min(res - 1);
            let step = |k: u32| if positive { k } else { res - 1 - k };
            let m = SLICE_MARGIN_CELLS;
            let (a, b) = if positive { (slice(e - m), slice(x + m)) } else { (slice(e + m), slice(x - m)) };
            (l.first, l.last) = (step(a), step(b));
            let len = (l.t1 - l.t0) as f64;
            single_ray_cells += 1.0 + l.d.iter().map(|d| (d * len).abs()).sum::<f64>();
            l.t_per_cell = 1.0 / l.d[axis];
            l.slope = others.map(|u| l.d[u] * l.t_per_cell);
            l.t_at_0 = -l.o[axis] * l.t_per_cell;
            first = first.min(l.first);
            last = last.max(l.last);
            at_origin.add(others, axis, s0, l);
            active.push(i as u32);
        }
        // The reference plane: the first ray's origin or its end, whichever the rays are
        // closer together at. (A common origin, as a camera tile's, has no spread: the end is
        // then not looked at.)
        let spread = |b: &Bounds| (b.c_hi[0] - b.c_lo[0]) + (b.c_hi[1] - b.c_lo[1]);
        let (s_ref, bounds) = match first_ray {
            None => (0.0, Bounds::EMPTY),
            Some((s0, Some(s1), _)) if spread(&at_origin) != 0.0 => {
                let at_end = Bounds::of(axis, s1, lanes, active, u32::MAX);
                if spread(&at_end) < spread(&at_origin) { (s1, at_end) } else { (s0, at_origin) }
            }
            Some((s0, ..)) => (s0, at_origin),
        };
        Some(SliceWalk { axis, positive, slices: res, first, last, s_ref, single_ray_cells, bounds, next_start: first })
    }

    /// The bounds of the lines of `lanes[i]` for each `i` of `which`.
    pub fn line_bounds(&self, lanes: &[Lane], which: impl Iterator<Item = u32>) -> LineBounds {
        LineBounds(Bounds::over(self.axis, self.s_ref, lanes, which))
    }

    /// The walk axis' coordinate of the plane the lines' intercepts are taken at.
    #[inline]
    pub fn reference_plane(&self) -> f64 {
        self.s_ref
    }

    /// Whether walking the rays as a packet visits fewer cells than `ratio` times the cells
    /// they cross one by one: the frustum of rays that start or end far apart (shadow rays
    /// from different depths, tiles over silhouettes) can cover many more cells than the rays.
    /// The frustum's cells are estimated from at most [`COHERENCE_SAMPLES`] evenly spaced
    /// slices (a rectangle's sides change linearly from slice to slice): the walk computes the
    /// rectangles of the slices it reaches, and most packets end long before the last slice.
    /// The choice only decides how the rays are traced, never their hits.
    pub fn coherent_enough(&self, res: UVec3, ratio: f64) -> bool {
        let budget = ratio * self.single_ray_cells;
        let steps = self.steps();
        if steps.is_empty() {
            return true;
        }
        let stride = (steps.end() - steps.start()) / COHERENCE_SAMPLES + 1;
        let mut cells = 0.0;
        for j in steps.step_by(stride as usize) {
            if let Some(r) = self.rect(j, res) {
                let n = (r.hi - r.lo + UVec3::ONE).as_dvec3();
                cells += n.x * n.y * n.z * stride as f64;
                if cells > budget {
                    return false;
                }
            }
        }
        true
    }

    /// Recomputes the frustum's bounds over the `active` lanes that have started by step `j`.
    pub fn update(&mut self, lanes: &[Lane], active: &[u32], j: u32) {
        self.bounds = Bounds::of(self.axis, self.s_ref, lanes, active, j);
    }

    /// Starts the walk with an empty frustum: the lanes join it as the walk reaches them
    /// ([`SliceWalk::reach`]). Before its first slice a lane's line is of no use and would widen
    /// the rectangles (shadow rays start at different depths).
    pub fn begin(&mut self) {
        self.bounds = Bounds::EMPTY;
        self.next_start = self.first;
    }

    /// Widens the frustum to the `active` lanes whose first step is `j` or earlier and not yet
    /// in it (a lane ends only after it started, so the lanes not started are all active).
    #[inline]
    pub fn reach(&mut self, j: u32, lanes: &[Lane], active: &[u32]) {
        if j < self.next_start {
            return;
        }
        let a = self.axis;
        let mut later = u32::MAX;
        for &i in active {
            let lane = &lanes[i as usize];
            if lane.first > j {
                later = later.min(lane.first);
            } else if lane.first >= self.next_start {
                self.bounds.add([(a + 1) % 3, (a + 2) % 3], a, self.s_ref, lane);
            }
        }
        self.next_start = later;
    }

    /// The walk's steps (empty when no ray is valid).
    pub fn steps(&self) -> std::ops::RangeInclusive<u32> {
        // Empty when no ray is valid (first = u32::MAX > last = 0).
        self.first..=self.last
    }

    /// The slice index of step `j`.
    #[inline]
    pub fn slice(&self, j: u32) -> u32 {
        if self.positive { j } else { self.slices - 1 - j }
    }

    /// The slice's near and far planes (grid coordinates along the axis) at step `j`.
    #[inline]
    fn planes(&self, j: u32) -> (f64, f64) {
        let k = self.slice(j) as f64;
        if self.positive { (k, k + 1.0) } else { (k + 1.0, k) }
    }

    /// The box of cells the active rays' lines cross in step `j`'s slice (widened by the
    /// margin, clamped to the grid) and the region itself: per axis, the grid coordinates the
    /// lines span in the slice (on the walk axis, the slab); `None` when it lies outside the
    /// grid.
    #[inline]
    pub fn rect(&self, j: u32, res: UVec3) -> Option<SliceRect> {
        let a = self.axis;
        let (near, far) = self.planes(j);
        let b = &self.bounds;
        let mut l = UVec3::ZERO;
        let mut h = UVec3::ZERO;
        let mut span = [(0.0, 0.0); 3];
        let k = self.slice(j);
        (l[a], h[a]) = (k, k);
        span[a] = (k as f64, k as f64 + 1.0);
        for (n, u) in [(a + 1) % 3, (a + 2) % 3].into_iter().enumerate() {
            let (lo, hi) = line_span(b, n, self.s_ref, near, far);
            (l[u], h[u]) = cells_of(lo, hi, res[u])?;
            span[u] = (lo, hi);
        }
        Some(SliceRect { lo: l, hi: h, span, frustum: (a, self.s_ref, *b) })
    }

    /// A step no later than the first at which [`SliceWalk::ends_ray`] is true for `lane` with
    /// its best hit at `best_t` (one slice early, to stay clear of rounding).
    #[inline]
    pub fn earliest_end(&self, lane: &Lane, best_t: f32) -> u32 {
        let best_t = lane.walk_t(best_t);
        if !best_t.is_finite() {
            return lane.last;
        }
        let a = self.axis;
        let s = lane.o[a] + lane.d[a] * best_t as f64;
        let k = floor(s) - 1.0;
        let step = if self.positive { k } else { self.slices as f64 - 1.0 - (k + 2.0) };
        (step.max(0.0) as u32).min(lane.last)
    }

    /// Whether `lane` leaves the packet after step `j`: its best hit (at `best_t`) lies before
    /// the slice's far plane, or the slice was its last. Rays that have not started stay.
    #[inline]
    pub fn ends_ray(&self, j: u32, lane: &Lane, best_t: f32) -> bool {
        if !lane.started(j) {
            return false;
        }
        if j >= lane.last {
            return true;
        }
        let t_far = lane.t_at_0 + self.planes(j).1 * lane.t_per_cell;
        (lane.walk_t(best_t) as f64) < t_far
    }
}
