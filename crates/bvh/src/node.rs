use raybench_geom::Aabb;

/// Deepest tree the builder makes: a node at this depth becomes a leaf whatever its size, so
/// the traversal stack (one entry per level) can never overflow.
pub const MAX_DEPTH: usize = 64;

/// One node of the flattened tree, 32 bytes: the box, and either the index of the second child
/// (`count == 0`; the first child is the next node) or a leaf's first triangle and count.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Node {
    /// `[min, max]`: indexable by a ray's per-axis sign, so the slab test picks its near and
    /// far planes without a branch.
    pub bounds: [[f32; 3]; 2],
    /// Interior: index of the second child. Leaf: offset of the first triangle.
    pub index: u32,
    /// Triangles in the leaf; 0 for an interior node.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    pub fn leaf(bounds: &Aabb, first: u32, count: u32) -> Node {
        Node {
            bounds: [bounds.min.to_array(), bounds.max.to_array()],
            index: first,
            count,
        }
    }

    pub fn interior(bounds: &Aabb, second_child: u32) -> Node {
        Node {
            bounds: [bounds.min.to_array(), bounds.max.to_array()],
            index: second_child,
            count: 0,
        }
    }

    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.bounds[0].into(), self.bounds[1].into())
    }
}
