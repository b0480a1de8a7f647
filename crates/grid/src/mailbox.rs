//! Mailboxing (Amanatides & Woo 1987): skip a triangle already tested by this ray.
//!
//! A triangle spanning several cells would otherwise be tested once per cell. The classic
//! mailbox stores a ray id per triangle, which needs shared mutable state and does not fit a
//! GPU thread; this is the per-ray hashed variant: a small direct-mapped table of recently
//! tested triangle ids. A collision only evicts an entry (the triangle may be tested again),
//! so it never skips a triangle that was not tested.
//!
//! Skipping is safe because the closest-hit loop keeps every tested triangle's hit as a
//! candidate, even when it lies beyond the current cell (see [`crate::trace::closest_hit`]).

/// Entries in the table (a power of two).
pub const MAILBOX_SIZE: usize = 16;

/// A table of `N` entries (a power of two): [`MAILBOX_SIZE`] for one ray, more for a packet of
/// rays ([`crate::coherent`]).
#[derive(Clone, Debug)]
pub struct Mailbox<const N: usize = MAILBOX_SIZE> {
    ids: [u32; N],
}

impl<const N: usize> Default for Mailbox<N> {
    fn default() -> Self {
        const { assert!(N.is_power_of_two()) };
        Mailbox { ids: [u32::MAX; N] }
    }
}

impl<const N: usize> Mailbox<N> {
    /// True if `tri` was already tested; otherwise records it and returns false.
    #[inline]
    pub fn check_and_insert(&mut self, tri: u32) -> bool {
        if self.contains(tri) {
            return true;
        }
        self.insert(tri);
        false
    }

    /// Whether `tri` was tested already.
    #[inline]
    pub fn contains(&self, tri: u32) -> bool {
        self.ids[tri as usize & (N - 1)] == tri
    }

    /// Records `tri` as tested.
    #[inline]
    pub fn insert(&mut self, tri: u32) {
        self.ids[tri as usize & (N - 1)] = tri;
    }
}
