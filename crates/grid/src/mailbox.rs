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

#[derive(Clone, Debug)]
pub struct Mailbox {
    ids: [u32; MAILBOX_SIZE],
}

impl Default for Mailbox {
    fn default() -> Self {
        Mailbox { ids: [u32::MAX; MAILBOX_SIZE] }
    }
}

impl Mailbox {
    /// True if `tri` was already tested; otherwise records it and returns false.
    #[inline]
    pub fn check_and_insert(&mut self, tri: u32) -> bool {
        let slot = tri as usize & (MAILBOX_SIZE - 1);
        if self.ids[slot] == tri {
            return true;
        }
        self.ids[slot] = tri;
        false
    }
}
