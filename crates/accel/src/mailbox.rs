/// A per-ray record of the triangles already tested, for structures that reference a triangle
/// from several cells or leaves (k-d tree, grid, octree): a direct-mapped table of `N` triangle
/// ids on the stack, indexed by the low bits of the id. Nothing is allocated per ray and the
/// structure stays shareable across threads. A collision only evicts, so the worst case is a
/// repeated test, never a missed one — provided the structure keeps the closest hit across
/// cells, so that a skipped triangle's hit (if any) is already accounted for.
#[derive(Clone, Copy, Debug)]
pub struct Mailbox<const N: usize>([u32; N]);

impl<const N: usize> Mailbox<N> {
    const POWER_OF_TWO: () = assert!(N.is_power_of_two(), "mailbox size must be a power of two");

    #[inline(always)]
    pub fn new() -> Mailbox<N> {
        let () = Self::POWER_OF_TWO;
        Mailbox([u32::MAX; N])
    }

    /// True when `prim` was tested already (skip it); otherwise records it.
    #[inline(always)]
    pub fn seen(&mut self, prim: u32) -> bool {
        let slot = &mut self.0[prim as usize & (N - 1)];
        if *slot == prim {
            true
        } else {
            *slot = prim;
            false
        }
    }
}

impl<const N: usize> Default for Mailbox<N> {
    fn default() -> Self {
        Mailbox::new()
    }
}

#[cfg(test)]
mod tests {
    use super::Mailbox;

    #[test]
    fn remembers_until_evicted_by_a_colliding_id() {
        let mut m = Mailbox::<8>::new();
        assert!(!m.seen(3));
        assert!(m.seen(3));
        assert!(!m.seen(11), "11 shares slot 3 and evicts it");
        assert!(!m.seen(3), "evicted: tested again, never skipped wrongly");
        assert!(!m.seen(u32::MAX - 1));
        assert!(m.seen(u32::MAX - 1));
    }
}
