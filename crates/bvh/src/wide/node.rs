//! The wide node: `W` children's boxes stored plane by plane, for one SIMD load per plane.

use crate::node::ChildRef;
use raybench_geom::{Aabb, Vec3};

/// One wide node of `W` children (4, 8 or 16): child boxes per axis as `[min or max][slot]`,
/// so one SIMD load fetches a plane of four, eight or sixteen children; unused slots hold an
/// empty box (`min = +inf`, `max = -inf`) that no ray enters. 16 wide: 512 bytes, eight cache
/// lines; 8 wide: 256 bytes, four; 4 wide: 128 bytes, two.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode<const W: usize> {
    /// `[axis][0 = min, 1 = max][slot]`.
    pub planes: [[[f32; W]; 2]; 3],
    pub child: [ChildRef; W],
}

const _: () = assert!(std::mem::size_of::<WideNode<16>>() == 512);
const _: () = assert!(std::mem::size_of::<WideNode<8>>() == 256);
const _: () = assert!(std::mem::size_of::<WideNode<4>>() == 128);

impl<const W: usize> WideNode<W> {
    pub(super) fn empty() -> WideNode<W> {
        WideNode {
            planes: [[[f32::INFINITY; W], [f32::NEG_INFINITY; W]]; 3],
            child: [ChildRef::default(); W],
        }
    }

    pub fn child_bounds(&self, i: usize) -> Aabb {
        let at = |axis: usize, side: usize| self.planes[axis][side][i];
        Aabb::new(
            Vec3::new(at(0, 0), at(1, 0), at(2, 0)),
            Vec3::new(at(0, 1), at(1, 1), at(2, 1)),
        )
    }

    pub(super) fn set_child(&mut self, i: usize, b: &Aabb, r: ChildRef) {
        for axis in 0..3 {
            self.planes[axis][0][i] = b.min[axis];
            self.planes[axis][1][i] = b.max[axis];
        }
        self.child[i] = r;
    }

    /// Slots in use: children are packed from slot 0.
    pub fn children(&self) -> usize {
        (0..W)
            .take_while(|&i| self.planes[0][0][i] <= self.planes[0][1][i])
            .count()
    }
}

/// The four lanes `4 * q ..` of a plane row, for one SSE load.
#[inline(always)]
pub(crate) fn quad<const W: usize>(row: &[f32; W], q: usize) -> &[f32; 4] {
    &row.as_chunks::<4>().0[q]
}
