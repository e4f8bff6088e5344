use raybench_geom::{Aabb, Vec3};

/// Deepest tree the builder makes: a node at this depth becomes a leaf whatever its size, so
/// the traversal stack (one entry per level) can never overflow.
pub const MAX_DEPTH: usize = 64;

/// A reference to a subtree: an interior node (`count == 0`, `index` into the node array) or a
/// leaf (`count` triangles from `index` in the triangle array).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChildRef {
    pub index: u32,
    pub count: u32,
}

impl ChildRef {
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// One interior node, 64 bytes and 64-byte aligned (one cache line): the boxes of both children
/// and where each child is. Keeping the children's boxes in the parent means one fetch serves
/// both box tests; a child node is only fetched when the ray descends into it.
///
/// The boxes are stored per axis as `[min of child 0, min of child 1, max of child 0, max of
/// child 1]`, so one 4-lane SIMD operation per axis computes all four slab distances of both
/// children (see `traverse`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// `[axis][lane]`, lanes `min0, min1, max0, max1`.
    pub planes: [[f32; 4]; 3],
    pub child: [ChildRef; 2],
}

const _: () = assert!(std::mem::size_of::<Node>() == 64);

impl Node {
    pub fn new(bounds: [&Aabb; 2], child: [ChildRef; 2]) -> Node {
        let mut node = Node {
            planes: [[0.0; 4]; 3],
            child,
        };
        node.set_child_bounds(0, bounds[0]);
        node.set_child_bounds(1, bounds[1]);
        node
    }

    pub fn child_bounds(&self, i: usize) -> Aabb {
        let p = &self.planes;
        Aabb::new(
            Vec3::new(p[0][i], p[1][i], p[2][i]),
            Vec3::new(p[0][2 + i], p[1][2 + i], p[2][2 + i]),
        )
    }

    pub fn set_child_bounds(&mut self, i: usize, b: &Aabb) {
        for axis in 0..3 {
            self.planes[axis][i] = b.min[axis];
            self.planes[axis][2 + i] = b.max[axis];
        }
    }
}
