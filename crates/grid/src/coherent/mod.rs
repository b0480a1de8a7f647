//! Coherent grid traversal (Wald, Ize, Kensler, Knoll, Parker 2006; the survey's §2.2): a packet
//! of rays walks a grid slice by slice along one axis. In each slice the packet's rays span a
//! rectangle of cells ([`frustum`]); every occupied cell of it is visited once for the whole
//! packet and its triangles are tested against every active ray ([`packet_test`]). No packet is
//! split or merged; a ray leaves the packet when its best hit lies before the slice's far plane
//! or its segment ends, and the packet ends when no ray is left.
//!
//! Exactness: the rectangle holds each ray's own cells in that slice, widened by
//! [`frustum::SLICE_MARGIN_CELLS`] (more than the rounding of the f32 slice arithmetic and less
//! than the insertion margin), so every triangle a ray meets before its accepted hit is tested,
//! and the closest-hit rule (t, then index) is the single-ray one: hits are bit-identical to
//! single rays and to brute force. A packet-wide mailbox skips a triangle already tested: the
//! rays still active then were active when it was tested.
//!
//! A triangle whose bounding box (widened by the insertion margin) misses the region the rays
//! cross in a slice is skipped there and not mailboxed ([`frustum::SliceRect::misses`]): no
//! ray can meet it in that slice, and it is in the cells of every slice where one can.
//! A triangle tested is tested only against the chunks of eight rays some of whose lines pass
//! through its box over the box's whole depth: a spared chunk's rays miss it everywhere, so the
//! mailbox stays valid. Whether a packet checks its chunks follows how many the checks spared
//! in recent packets ([`CULL_WORTH`]).
//!
//! An occlusion query ([`Query::Any`]) ends a ray at its first hit instead, as for single rays.
//!
//! The hierarchies (multires, two-level) are walked on their top grid's slices; in a top cell
//! that is a child grid the packet visits the child's cells layer by layer along the walk axis,
//! each layer where the rays' region between its planes reaches (Ize et al.'s hierarchical CGT,
//! flattened into the top slice). The exactness argument holds one level down: every point a
//! ray crosses in the slice lies in the region, so the leaf holding it is visited.
//!
//! Packets whose rays do not share the sign of one axis (incoherent) are traced as single rays.
//! In a hierarchy, coherent packets are also traced as single rays while recent packets of the
//! image have tested far more triangles per ray than single rays do ([`WASTE_RATIO`]).
//! The rectangles are computed per ray, not from four corner rays, so any packet works: camera
//! tiles (common origin), shadow rays towards a point light (common end) or arbitrary rays.

pub mod frustum;
pub mod packet_test;

use glam::{UVec3, Vec3};
use gridrt_scene::{Hit, Ray};
use serde::Serialize;

use crate::flat::FlatGrid;
use crate::geometry::GridGeometry;
use crate::hierarchy::{Cell, Hierarchy};
use crate::macrocell::MacrocellGrid;
use crate::mailbox::Mailbox;
use crate::stats::{BatchStats, RayStats};
use crate::trace::Query;
use frustum::{Lane, SliceWalk};
use packet_test::PacketRays;

/// Edge of the default square packet, in pixels (8×8 = 64 rays).
pub const DEFAULT_TILE: u32 = 8;
/// Entries of the packet-wide mailbox (a power of two; a collision only re-tests a triangle).
pub const PACKET_MAILBOX_SIZE: usize = 256;

/// A packet walks slice by slice only when its frustum covers at most this many times the
/// cells its rays cross one by one (their whole segments: an occlusion query or an early hit
/// ends a single ray sooner, so the ratio is low); otherwise its rays are traced singly. The
/// README's packet levers (coherent grid traversal) have the measurements behind the value.
pub const COHERENCE_RATIO: f64 = 0.2;

/// A grid a packet can walk slice by slice: its geometry and the occupied cells of a slice.
pub trait SliceCells {
    fn geom(&self) -> &GridGeometry;
    /// Calls `f` with the references of every occupied cell of `rect`'s box of cells
    /// (`lo..=hi`, within the grid); a hierarchy's with those of every occupied leaf below it
    /// that the rays' region (`span`) reaches.
    fn for_each_occupied(&self, rect: &frustum::SliceRect, f: &mut impl FnMut(&[u32]));
    /// Whether coherent packets are watched for waste ([`WASTE_RATIO`]): a hierarchy's packet
    /// checks its rays' ends once per top slice, which can hold many layers of geometry behind
    /// the hits; a flat grid's checks every slice, and its probes would only cost.
    const WATCHES_WASTE: bool = false;
}

impl SliceCells for FlatGrid {
    fn geom(&self) -> &GridGeometry {
        &self.geom
    }

    #[inline]
    fn for_each_occupied(&self, rect: &frustum::SliceRect, f: &mut impl FnMut(&[u32])) {
        self.for_each_occupied_in(rect.lo, rect.hi, f);
    }
}

impl FlatGrid {
    /// [`SliceCells::for_each_occupied`] over the box of cells `lo..=hi`.
    #[inline]
    fn for_each_occupied_in(&self, lo: UVec3, hi: UVec3, f: &mut impl FnMut(&[u32])) {
        let res = self.geom.res;
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                let row = (res.x * (y + res.y * z)) as usize;
                for x in lo.x..=hi.x {
                    let i = row + x as usize;
                    if self.is_occupied(i) {
                        f(self.refs_of(i));
                    }
                }
            }
        }
    }
}

impl SliceCells for MacrocellGrid {
    fn geom(&self) -> &GridGeometry {
        &self.fine.geom
    }

    /// Empty macrocells of the box are skipped whole (one bit each).
    #[inline]
    fn for_each_occupied(&self, rect: &frustum::SliceRect, f: &mut impl FnMut(&[u32])) {
        let (lo, hi, a) = (rect.lo, rect.hi, self.a);
        let (mlo, mhi) = (lo / a, hi / a);
        for mz in mlo.z..=mhi.z {
            for my in mlo.y..=mhi.y {
                for mx in mlo.x..=mhi.x {
                    let m = UVec3::new(mx, my, mz);
                    if !self.occupied(m) {
                        continue;
                    }
                    let blo = (m * a).max(lo);
                    let bhi = (m * a + UVec3::splat(a - 1)).min(hi);
                    self.fine.for_each_occupied_in(blo, bhi, f);
                }
            }
        }
    }
}

impl SliceCells for Hierarchy {
    fn geom(&self) -> &GridGeometry {
        &self.geom
    }

    const WATCHES_WASTE: bool = true;

    /// Ize et al.'s hierarchical CGT, flattened: the packet walks the top grid's slices, and in
    /// a top cell that is a child grid it visits the child's cells the rays' region reaches
    /// (widened by the child's insertion margin), descending likewise to any depth.
    fn for_each_occupied(&self, rect: &frustum::SliceRect, f: &mut impl FnMut(&[u32])) {
        let top = &self.nodes[0];
        for z in rect.lo.z..=rect.hi.z {
            for y in rect.lo.y..=rect.hi.y {
                for x in rect.lo.x..=rect.hi.x {
                    let c = UVec3::new(x, y, z);
                    let i = top.first_cell as usize + crate::geometry::linear_index(c, top.res);
                    self.visit_region(i, c.as_dvec3().to_array(), [1.0; 3], rect, &rect.span, f);
                }
            }
        }
    }
}

impl Hierarchy {
    /// Cell `i`, whose box in top-grid coordinates starts at `base` and is `size` wide: its
    /// references if a non-empty leaf; if a child grid, those of its cells the rays' region
    /// reaches, layer by layer along the walk axis (each layer's region from `rect`'s frustum,
    /// within `span`), widened by the child's insertion margin, recursively.
    fn visit_region(
        &self,
        i: usize,
        base: [f64; 3],
        size: [f64; 3],
        rect: &frustum::SliceRect,
        span: &[(f64, f64); 3],
        f: &mut impl FnMut(&[u32]),
    ) {
        let a = match self.cell(i) {
            Cell::Leaf(r) if r.is_empty() => return,
            Cell::Leaf(r) => return f(&self.refs[r]),
            Cell::Child(a) => a,
        };
        let node = &self.nodes[a as usize];
        let margin = node.margin as f64;
        let cell: [f64; 3] = std::array::from_fn(|k| size[k] / node.res[k] as f64);
        // The child's cells within `span` on axis `k` (widened by the margin), None if none.
        let range = |span: &[(f64, f64); 3], k: usize| {
            let to_cells = |x: f64| (x - base[k]) / cell[k];
            frustum::cells_of(to_cells(span[k].0) - margin, to_cells(span[k].1) + margin, node.res[k])
        };
        let w = rect.walk_axis();
        let [u, v] = [(w + 1) % 3, (w + 2) % 3];
        let Some((wl, wh)) = range(span, w) else { return };
        for layer in wl..=wh {
            // The rays' region in this layer (its planes widened by the margin), within `span`.
            let s0 = base[w] + (layer as f64 - margin) * cell[w];
            let s1 = base[w] + (layer as f64 + 1.0 + margin) * cell[w];
            let mut sub = rect.span_between(s0, s1);
            for k in [u, v] {
                sub[k] = (sub[k].0.max(span[k].0), sub[k].1.min(span[k].1));
            }
            sub[w] = span[w];
            let (Some((ul, uh)), Some((vl, vh))) = (range(&sub, u), range(&sub, v)) else { continue };
            for cv in vl..=vh {
                for cu in ul..=uh {
                    let mut c = UVec3::ZERO;
                    (c[w], c[u], c[v]) = (layer, cu, cv);
                    let j = node.first_cell as usize + crate::geometry::linear_index(c, node.res);
                    let b = [0, 1, 2].map(|k| base[k] + c[k] as f64 * cell[k]);
                    self.visit_region(j, b, cell, rect, &sub, f);
                }
            }
        }
    }
}

/// Packet settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct PacketOptions {
    /// Packet edge in pixels: a packet is a `tile`×`tile` block of the image.
    pub tile: u32,
    /// The packet-wide mailbox.
    pub mailbox: bool,
}

impl Default for PacketOptions {
    fn default() -> Self {
        PacketOptions { tile: DEFAULT_TILE, mailbox: true }
    }
}

/// What the packets of a batch did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PacketStats {
    /// Packets walked slice by slice.
    pub packets: u64,
    /// Packets traced as single rays (incoherent: no axis whose sign all rays share, or a
    /// frustum that would visit more cells than the rays one by one; in a hierarchy also the
    /// packets its waste watch traces as single rays, [`WASTE_RATIO`]).
    pub single_ray_packets: u64,
}

impl PacketStats {
    pub fn merge(self, o: PacketStats) -> PacketStats {
        PacketStats {
            packets: self.packets + o.packets,
            single_ray_packets: self.single_ray_packets + o.single_ray_packets,
        }
    }
}

/// One thread's packet state, reused from packet to packet.
#[derive(Debug, Default)]
pub struct Packet {
    lanes: Vec<Lane>,
    best: Vec<Hit>,
    /// The running total of cells before each step (indexed by step).
    cells_before: Vec<u64>,
    /// Lanes still walking (indices into `lanes`).
    active: Vec<u32>,
    rays: PacketRays,
    mailbox: Mailbox<PACKET_MAILBOX_SIZE>,
    /// Triangle tests per ray of recent coherent packets walked as packets and as single rays
    /// (see [`WASTE_RATIO`]), and how many coherent packets this state has seen.
    waste: WasteTally,
    coherent_seen: u64,
    /// Chunks checked against triangles' boxes and chunks spared by it, over recent packets
    /// (see [`CULL_WORTH`]).
    cull_stats: packet_test::CullStats,
    /// Packets traced by this state.
    traced: u64,
}

/// A packet checks its chunks of eight rays against each triangle's box (sparing those that
/// pass away from it) while the checks spare at least this share of the chunks checked: a
/// check costs about one chunk's pre-filter, so it pays where triangles are small next to the
/// packet (LittlestTokyo, the scanned models) and not where they are large (the Cornell box).
/// Every [`CULL_PROBE`]-th packet checks anyway, so the share follows the scene.
pub const CULL_WORTH: f64 = 0.25;
/// See [`CULL_WORTH`].
pub const CULL_PROBE: u64 = 32;
/// In a grid that [`SliceCells::WATCHES_WASTE`] (the hierarchies), a coherent packet is traced
/// as single rays while the packets' rays each test more than this many times the triangles a
/// single ray tests (both measured on the recent packets of the same band of tiles): a
/// triangle's test against eight lanes costs about one single ray's test, so beyond eight times
/// the lanes' tests cost more, and twice that leaves room for the rest of a packet's savings.
/// On the 1M-triangle crowd a hierarchy's packets tested 70–80 times a single ray's triangles
/// (a top slice holds many layers of tubes behind the hits); on meshes 1.4–3.4 times.
pub const WASTE_RATIO: f64 = 16.0;
/// Every this many coherent packets of a grid that watches for waste, one is traced the other
/// way (as single rays while packets pay, as a packet while they do not), so that both tests
/// per ray stay measured.
pub const WASTE_PROBE: u64 = 64;
/// Beyond this many rays a waste tally's sums are halved, so they follow recent packets.
pub const WASTE_WINDOW: u64 = 1 << 14;
/// Chunks checked before the share spared decides (a thread's first packets always check).
pub const CULL_WARM_UP: u64 = 256;
/// Beyond this many chunks checked the counts are halved, so they follow recent packets.
pub const CULL_WINDOW: u64 = 1 << 14;

/// Triangle tests and rays, summed over recent packets (halved as they grow, so the sums follow
/// the image).
#[derive(Clone, Copy, Debug, Default)]
struct TestTally {
    tests: u64,
    rays: u64,
}

impl TestTally {
    fn add(&mut self, stats: &[RayStats]) {
        if self.rays > WASTE_WINDOW {
            *self = TestTally { tests: self.tests / 2, rays: self.rays / 2 };
        }
        self.tests += stats.iter().map(|s| s.tests as u64).sum::<u64>();
        self.rays += stats.len() as u64;
    }

    fn per_ray(&self) -> f64 {
        self.tests as f64 / self.rays.max(1) as f64
    }
}

/// Tests per ray of coherent packets walked as packets and as single rays ([`WASTE_RATIO`]).
#[derive(Clone, Copy, Debug, Default)]
struct WasteTally {
    packets: TestTally,
    singles: TestTally,
}

impl WasteTally {
    /// Whether packets have tested more than [`WASTE_RATIO`] times the single rays' triangles
    /// per ray (a single ray testing less than one counts as one).
    fn wasteful(&self) -> bool {
        self.packets.rays > 0
            && self.singles.rays > 0
            && self.packets.per_ray() > WASTE_RATIO * self.singles.per_ray().max(1.0)
    }
}

/// How a packet was traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketWalk {
    /// Slice by slice.
    Coherent,
    /// Incoherent: as single rays.
    SingleRays,
}

impl Packet {
    /// Closest hits (or any hits, by `query`) of `rays` in `grid` (built over `tris`) as one
    /// packet, written to `hits` and `stats` (each as long as `rays`). An incoherent packet calls
    /// `single` for each ray.
    #[allow(clippy::too_many_arguments)]
    pub fn trace<G: SliceCells>(
        &mut self,
        grid: &G,
        tris: &[[Vec3; 3]],
        rays: &[Ray],
        mailbox: bool,
        query: Query,
        (hits, stats): (&mut [Hit], &mut [RayStats]),
        single: impl Fn(&Ray) -> (Hit, RayStats),
    ) -> PacketWalk {
        assert!(rays.len() == hits.len() && rays.len() == stats.len(), "one hit and one stats record per ray");
        let walk = SliceWalk::new(grid.geom(), rays, &mut self.lanes, &mut self.active)
            .filter(|w| w.coherent_enough(grid.geom().res, COHERENCE_RATIO));
        let single_rays = |hits: &mut [Hit], stats: &mut [RayStats]| {
            for ((r, h), s) in rays.iter().zip(hits.iter_mut()).zip(stats.iter_mut()) {
                (*h, *s) = single(r);
            }
        };
        let Some(mut walk) = walk else {
            single_rays(hits, stats);
            return PacketWalk::SingleRays;
        };
        // A coherent packet as single rays when packets have been wasteful here, and every
        // WASTE_PROBE-th the other way (the first one of a state as single rays, to measure them).
        self.coherent_seen += 1;
        let probe = self.coherent_seen % WASTE_PROBE == 1;
        if G::WATCHES_WASTE && probe != self.waste.wasteful() {
            single_rays(hits, stats);
            self.waste.singles.add(stats);
            return PacketWalk::SingleRays;
        }
        self.best.clear();
        self.best.resize(rays.len(), Hit::MISS);
        self.mailbox = Mailbox::default();
        self.rays.gather(&self.lanes, &self.active);
        self.traced += 1;
        let packet_test::CullStats { checked, spared } = self.cull_stats;
        let cull = checked < CULL_WARM_UP
            || spared as f64 >= CULL_WORTH * checked as f64
            || self.traced.is_multiple_of(CULL_PROBE);
        if checked > CULL_WINDOW {
            self.cull_stats = packet_test::CullStats { checked: checked / 2, spared: spared / 2 };
        }
        // Each lane's stats from running totals: cells of the slices since its first, tests of
        // every triangle tested while it was active.
        let (mut cells, mut tests) = (0u64, 0u64);
        self.cells_before.clear();
        stats.fill(RayStats::default());
        let res = grid.geom().res;
        let lanes = &self.lanes;
        let record = |s: &mut RayStats, lane: &frustum::Lane, cells_before: &[u64], cells: u64, tests: u64| {
            let before = cells_before.get(lane.first as usize).copied().unwrap_or(cells);
            *s = RayStats {
                cells: (cells - before).min(u32::MAX as u64) as u32,
                tests: tests.min(u32::MAX as u64) as u32,
            };
        };
        let mut next_check = 0u32;
        // The frustum bounds the lanes the walk has reached only. Every active lane is still
        // tested against every triangle, so the packet's mailbox stays valid for lanes that
        // start later.
        walk.begin();
        for j in walk.steps() {
            walk.reach(j, lanes, &self.active);
            // cells_before[j]: the running total before step j.
            while self.cells_before.len() < j as usize {
                self.cells_before.push(cells);
            }
            self.cells_before.push(cells);
            let Some(rect) = walk.rect(j, res) else { continue };
            let (lo, hi) = (rect.lo, rect.hi);
            let n = (hi - lo + UVec3::ONE).as_u64vec3();
            cells += n.x * n.y * n.z;
            let (best, mb, rays_soa, cull_stats) =
                (&mut self.best, &mut self.mailbox, &mut self.rays, &mut self.cull_stats);
            let mut changed = false;
            let geom = grid.geom();
            grid.for_each_occupied(&rect, &mut |refs| {
                for &tri in refs {
                    // Tested already, or out of the rays' reach in this slice (then left for
                    // later slices: not mailboxed).
                    if mailbox && mb.contains(tri) {
                        continue;
                    }
                    let t = &tris[tri as usize];
                    let tb = frustum::TriangleBox::of(geom, t);
                    if rect.misses(&tb) {
                        continue;
                    }
                    if mailbox {
                        mb.insert(tri);
                    }
                    tests += 1;
                    if cull && !rays_soa.chunks_bounded() {
                        rays_soa.bound_chunks(lanes, &walk);
                    }
                    let test = packet_test::TriangleTest { tri: t, id: tri, cull: cull.then_some((&walk, &tb)) };
                    changed |= rays_soa.test(lanes, &test, best, cull_stats);
                }
            });
            // No ray can leave before `next_check` unless some ray's best hit changed.
            if !changed && j < next_check {
                continue;
            }
            let (best, cb, soa) = (&self.best, &self.cells_before, &mut self.rays);
            next_check = u32::MAX;
            let mut dead = 0;
            self.active.retain(|&i| {
                let lane = &lanes[i as usize];
                let t = best[i as usize].t;
                let ends = (query == Query::Any && best[i as usize].is_hit()) || walk.ends_ray(j, lane, t);
                if ends {
                    record(&mut stats[i as usize], lane, cb, cells, tests);
                    dead = soa.remove(i);
                } else {
                    next_check = next_check.min(walk.earliest_end(lane, t));
                }
                !ends
            });
            if self.active.is_empty() {
                break;
            }
            // Removed rays are skipped in place; a whole chunk's worth is worth a gather (the
            // frustum of the remaining rays shrinks with it).
            if dead >= packet_test::LANES {
                self.rays.gather(lanes, &self.active);
                walk.update(lanes, &self.active, j);
            }
        }
        for &i in &self.active {
            record(&mut stats[i as usize], &lanes[i as usize], &self.cells_before, cells, tests);
        }
        hits.copy_from_slice(&self.best);
        if G::WATCHES_WASTE {
            self.waste.packets.add(stats);
        }
        PacketWalk::Coherent
    }
}

/// Closest hits (or any hits, by `query`) of an image's rays (`rays` row-major, `width` per
/// row) in `tile`×`tile` packets, on all threads when `parallel` (and the `parallel` feature):
/// hits in the order of `rays`, batch and packet figures. `single` traces one ray of an
/// incoherent packet (with the same query).
#[allow(clippy::too_many_arguments)]
pub fn trace_image<G: SliceCells + Sync>(
    grid: &G,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    width: usize,
    opts: PacketOptions,
    query: Query,
    parallel: bool,
    single: impl Fn(&Ray) -> (Hit, RayStats) + Sync,
) -> (Vec<Hit>, BatchStats, PacketStats) {
    let width = width.max(1);
    let tile = opts.tile.max(1) as usize;
    assert!(rays.len().is_multiple_of(width), "an image's rays: a whole number of rows");
    let mut hits = vec![Hit::MISS; rays.len()];
    // One band of `tile` rows at a time, its packets left to right.
    let band = |(rays, hits): (&[Ray], &mut [Hit])| {
        let rows = rays.len() / width;
        let mut packet = Packet::default();
        let (mut pr, mut ph, mut ps) = (Vec::new(), Vec::new(), Vec::new());
        let (mut batch, mut pstats) = (BatchStats::default(), PacketStats::default());
        for x0 in (0..width).step_by(tile) {
            let x1 = (x0 + tile).min(width);
            pr.clear();
            for y in 0..rows {
                pr.extend_from_slice(&rays[y * width + x0..y * width + x1]);
            }
            ph.resize(pr.len(), Hit::MISS);
            ps.resize(pr.len(), RayStats::default());
            match packet.trace(grid, tris, &pr, opts.mailbox, query, (&mut ph, &mut ps), &single) {
                PacketWalk::Coherent => pstats.packets += 1,
                PacketWalk::SingleRays => pstats.single_ray_packets += 1,
            }
            for y in 0..rows {
                let w = x1 - x0;
                hits[y * width + x0..y * width + x1].copy_from_slice(&ph[y * w..(y + 1) * w]);
                for k in 0..w {
                    batch.add(ps[y * w + k], ph[y * w + k].is_hit());
                }
            }
        }
        (batch, pstats)
    };
    let chunk = width * tile;
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        let (batch, pstats) = rays
            .par_chunks(chunk)
            .zip(hits.par_chunks_mut(chunk))
            .map(band)
            .reduce(|| (BatchStats::default(), PacketStats::default()), |a, b| (a.0.merge(b.0), a.1.merge(b.1)));
        return (hits, batch, pstats);
    }
    let _ = parallel;
    let (batch, pstats) = rays
        .chunks(chunk)
        .zip(hits.chunks_mut(chunk))
        .map(band)
        .fold((BatchStats::default(), PacketStats::default()), |a, b| (a.0.merge(b.0), a.1.merge(b.1)));
    (hits, batch, pstats)
}
