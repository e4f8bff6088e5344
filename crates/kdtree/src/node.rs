//! The flattened node: 8 bytes, the classic layout (Pharr, Jakob and Humphreys, pbrt §4.4;
//! Wald's thesis 2004 §7.3).

/// Deepest tree the builders make (a node at this depth is a leaf whatever it holds), so the
/// traversal stack, one entry per level, can never overflow. The default depth limit
/// `8 + 1.3 log2 N` reaches 50 only at N = 2^32 triangles.
pub const MAX_DEPTH: usize = 64;

/// Largest child index or leaf reference count the 30 bits of [`Node::flags`] hold.
pub const MAX_PACKED: u32 = (1 << 30) - 1;

/// The two low bits of [`Node::flags`] for a leaf; 0, 1, 2 are the split axis of an interior
/// node.
pub const LEAF: u32 = 3;

/// One node of the depth-first array, 8 bytes (eight to a cache line).
///
/// * Interior: `word` holds the split position's `f32` bits; `flags` holds the axis (0–2) in
///   its two low bits and the index of the child above the plane in the upper 30. The child
///   below the plane is always the next node (depth-first order), so it needs no index.
/// * Leaf: the two low bits of `flags` are 3 and the upper 30 hold the reference count;
///   `word` is the leaf's first entry in the one reference array.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C, align(8))]
pub struct Node {
    pub word: u32,
    pub flags: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 8);

impl Node {
    pub fn interior(axis: usize, split: f32, above: u32) -> Node {
        debug_assert!(axis < 3 && above <= MAX_PACKED);
        Node {
            word: split.to_bits(),
            flags: axis as u32 | (above << 2),
        }
    }

    pub fn leaf(first: u32, count: u32) -> Node {
        debug_assert!(count <= MAX_PACKED);
        Node {
            word: first,
            flags: LEAF | (count << 2),
        }
    }

    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.flags & 3 == LEAF
    }

    /// Split axis (interior nodes).
    #[inline(always)]
    pub fn axis(&self) -> usize {
        (self.flags & 3) as usize
    }

    /// Split position (interior nodes).
    #[inline(always)]
    pub fn split(&self) -> f32 {
        f32::from_bits(self.word)
    }

    /// Index of the child above the split plane (interior nodes); the one below is `self + 1`.
    #[inline(always)]
    pub fn above(&self) -> u32 {
        self.flags >> 2
    }

    /// First reference of a leaf.
    #[inline(always)]
    pub fn first(&self) -> u32 {
        self.word
    }

    /// Number of references of a leaf.
    #[inline(always)]
    pub fn count(&self) -> u32 {
        self.flags >> 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips() {
        let n = Node::interior(2, -1.5, MAX_PACKED);
        assert!(!n.is_leaf());
        assert_eq!((n.axis(), n.split(), n.above()), (2, -1.5, MAX_PACKED));
        let l = Node::leaf(123_456, MAX_PACKED);
        assert!(l.is_leaf());
        assert_eq!((l.first(), l.count()), (123_456, MAX_PACKED));
        let e = Node::leaf(0, 0);
        assert!(e.is_leaf() && e.count() == 0);
    }
}
