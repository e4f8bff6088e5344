//! The flattened node: 20 bytes, the split point stored so traversal and validation use the
//! very f32 values the build split at.

use raybench_geom::Vec3;
use std::ops::Range;

/// Deepest tree the traversal stack is sized for. A pop of an interior node pushes at most four
/// children, so the stack never holds more than three waiting siblings per level plus one.
pub const MAX_DEPTH_LIMIT: u32 = 32;
pub(crate) const STACK: usize = 3 * MAX_DEPTH_LIMIT as usize + 2;

const LEAF: u32 = 1 << 31;

/// An interior node (centre point, first child, mask of present octants) or a leaf (a range
/// of the reference array). Octant bit `a` (0 = x, 1 = y, 2 = z) set means the upper half on
/// axis `a`; the present children of a node are contiguous, in octant order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    /// The split point (interior nodes): `lo * 0.5 + hi * 0.5` of the node's box, in f32.
    pub mid: [f32; 3],
    first: u32,
    bits: u32,
}

impl Node {
    pub(crate) fn leaf(first_ref: u32, count: u32) -> Node {
        assert!(count < LEAF, "leaf of {count} references");
        Node {
            mid: [0.0; 3],
            first: first_ref,
            bits: LEAF | count,
        }
    }

    pub(crate) fn interior(mid: Vec3, first_child: u32, mask: u8) -> Node {
        Node {
            mid: mid.to_array(),
            first: first_child,
            bits: mask as u32,
        }
    }

    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.bits & LEAF != 0
    }

    /// The leaf's slice of the reference array.
    #[inline(always)]
    pub fn refs(&self) -> Range<usize> {
        let first = self.first as usize;
        first..first + (self.bits & !LEAF) as usize
    }

    /// Present octants (interior nodes).
    #[inline(always)]
    pub fn mask(&self) -> u32 {
        self.bits & 0xff
    }

    /// Index of the first child (interior nodes).
    #[inline(always)]
    pub fn first_child(&self) -> u32 {
        self.first
    }

    /// The node index of octant `o`, if present.
    #[inline(always)]
    pub fn child(&self, o: u32) -> Option<u32> {
        let m = self.mask();
        (m & (1 << o) != 0).then(|| self.first + (m & ((1 << o) - 1)).count_ones())
    }

    #[cfg(test)]
    pub(crate) fn set_mask(&mut self, mask: u8) {
        self.bits = mask as u32;
    }
}

/// The split point of the box `[lo, hi]`, exactly as build, traversal and validation compute it.
#[inline(always)]
pub fn mid(lo: Vec3, hi: Vec3) -> Vec3 {
    lo * 0.5 + hi * 0.5
}

/// The box of octant `o` of `[lo, hi]` split at `mid`.
#[inline(always)]
pub fn child_box(lo: Vec3, hi: Vec3, mid: Vec3, o: u32) -> (Vec3, Vec3) {
    let mut clo = lo;
    let mut chi = hi;
    for a in 0..3 {
        if o & (1 << a) != 0 {
            clo[a] = mid[a];
        } else {
            chi[a] = mid[a];
        }
    }
    (clo, chi)
}
