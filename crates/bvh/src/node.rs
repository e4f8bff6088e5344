use raybench_geom::Aabb;

/// Deepest tree the builder makes: a node at this depth becomes a leaf whatever its size, so
/// the traversal stack (one entry per level) can never overflow.
pub const MAX_DEPTH: usize = 64;

/// One node of the flattened tree, 32 bytes: the box, and either the index of the second child
/// (`count == 0`; the first child is the next node) or a leaf's first triangle and count.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Node {
    pub min: [f32; 3],
    /// Interior: index of the second child. Leaf: offset of the first triangle.
    pub index: u32,
    pub max: [f32; 3],
    /// Triangles in the leaf; 0 for an interior node.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    pub fn leaf(bounds: &Aabb, first: u32, count: u32) -> Node {
        Node {
            min: bounds.min.to_array(),
            index: first,
            max: bounds.max.to_array(),
            count,
        }
    }

    pub fn interior(bounds: &Aabb, second_child: u32) -> Node {
        Node {
            min: bounds.min.to_array(),
            index: second_child,
            max: bounds.max.to_array(),
            count: 0,
        }
    }

    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }
}
