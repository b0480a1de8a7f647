//! The trace kernels and the walkers they are composed with, as types: which WGSL file and
//! entry point traces a structure (one kernel per structure; multi-resolution and two-level
//! grids share the hierarchy kernel), and which walker file (`shaders/shared/walker_*.wgsl`)
//! stands for `{TRAVERSAL}` in its includes.

use gridrt_grid::{GridKind, Traversal};

/// A trace kernel: `shaders/<file>`, whose entry point is [`Kernel::ENTRY`] (in
/// `shaders/shared/closest_hit.wgsl`, calling the file's `walk`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kernel {
    Flat,
    Macrocell,
    /// Multi-resolution and two-level grids (one layout, one kernel).
    Hierarchy,
    Proximity,
}

impl Kernel {
    /// Every trace kernel's entry point.
    pub const ENTRY: &'static str = "trace";
    /// Every packet kernel's entry point (`shaders/shared/coherent.wgsl`).
    pub const PACKET_ENTRY: &'static str = "trace_packets";
    /// Rays per packet edge of the packet kernels (`PACKET_EDGE`: 8×8 workgroups).
    pub const PACKET_EDGE: u32 = 8;
    /// The kernel that traces a structure of `kind`.
    pub fn for_kind(kind: GridKind) -> Kernel {
        match kind {
            GridKind::Flat => Kernel::Flat,
            GridKind::Macrocell => Kernel::Macrocell,
            GridKind::Multires | GridKind::TwoLevel => Kernel::Hierarchy,
            GridKind::Proximity => Kernel::Proximity,
        }
    }

    /// The packet kernel's file under `shaders/` (coherent grid traversal of an image's rays in
    /// 8×8 tiles), for the structures that have one.
    pub fn packet_file(self) -> Option<&'static str> {
        match self {
            Kernel::Flat => Some("coherent_flat.wgsl"),
            Kernel::Macrocell => Some("coherent_macrocell.wgsl"),
            Kernel::Hierarchy | Kernel::Proximity => None,
        }
    }

    /// The WGSL file under `shaders/`.
    pub fn file(self) -> &'static str {
        match self {
            Kernel::Flat => "flat.wgsl",
            Kernel::Macrocell => "macrocell.wgsl",
            Kernel::Hierarchy => "hierarchy.wgsl",
            Kernel::Proximity => "proximity.wgsl",
        }
    }
}

/// A GPU walker: `shaders/shared/walker_<name>.wgsl`, the port of the CPU traversal of the
/// same [`Traversal`] (naive Bresenham has none: it is incomplete by design).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GpuWalker {
    #[default]
    AmanatidesWoo,
    ClearyWyvill,
    Liu,
}

impl GpuWalker {
    pub const ALL: [GpuWalker; 3] = [GpuWalker::AmanatidesWoo, GpuWalker::ClearyWyvill, GpuWalker::Liu];

    /// The walker porting `traversal`; `None` for naive Bresenham, which has none.
    pub fn for_traversal(traversal: Traversal) -> Option<GpuWalker> {
        match traversal {
            Traversal::AmanatidesWoo => Some(GpuWalker::AmanatidesWoo),
            Traversal::ClearyWyvill => Some(GpuWalker::ClearyWyvill),
            Traversal::Liu => Some(GpuWalker::Liu),
            Traversal::Bresenham => None,
        }
    }

    /// The CPU traversal this walker ports.
    pub fn traversal(self) -> Traversal {
        match self {
            GpuWalker::AmanatidesWoo => Traversal::AmanatidesWoo,
            GpuWalker::ClearyWyvill => Traversal::ClearyWyvill,
            GpuWalker::Liu => Traversal::Liu,
        }
    }

    /// What `{TRAVERSAL}` becomes in an include: the traversal's short name (`aw`, `cw`, `liu`).
    pub fn name(self) -> &'static str {
        self.traversal().short_name()
    }
}

impl std::fmt::Display for GpuWalker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
