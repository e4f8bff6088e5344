use raybench_geom::Aabb;

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
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node {
    /// `[child][min or max][axis]`: indexable by a ray's per-axis sign, so the slab test picks
    /// its near and far planes without a branch.
    pub bounds: [[[f32; 3]; 2]; 2],
    pub child: [ChildRef; 2],
}

const _: () = assert!(std::mem::size_of::<Node>() == 64);

impl Node {
    pub fn child_bounds(&self, i: usize) -> Aabb {
        Aabb::new(self.bounds[i][0].into(), self.bounds[i][1].into())
    }
}

pub(crate) fn corners(b: &Aabb) -> [[f32; 3]; 2] {
    [b.min.to_array(), b.max.to_array()]
}
