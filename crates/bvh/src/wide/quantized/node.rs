//! The quantized 8-wide node and the rounding that keeps its boxes conservative.
//!
//! Per axis the node stores an origin `o` (f32) and a power-of-two step `s = 2^e` (`e` an
//! `i8`); a child's plane is an unsigned integer `q` of 8 or 16 bits ([`Plane`]) and decodes
//! to `o + q * s`. The product `q * s` of at most 16 bits and a power of two is exact, so the decoded plane is one correctly rounded addition:
//! the same bits whether computed by an FMA, a multiply and an add, in SIMD or in scalar code,
//! under any rounding of intermediate products. Quantizing then searches for the bytes whose
//! decoded planes enclose the float box (min rounded down, max up) with that very arithmetic,
//! instead of trusting a division, so containment holds by construction and the validator can
//! re-check it exactly.
//!
//! The width trades bytes for fit: 8-bit planes make a 128-byte node, but a child grows by up
//! to a 255th of its node's extent per side, and a flat leaf box (a wall's triangles) gains a
//! thickness, so a ray leaving that wall (shadow, diffuse) enters the leaf it starts on,
//! which the float box's zero thickness lets it skip. 16-bit planes make a 192-byte node
//! (three lines instead of four) and grow boxes 257 times less.

use crate::node::ChildRef;
use crate::wide::{NodeFormat, WideNode};
use raybench_geom::{Aabb, Vec3};
use std::fmt::Debug;

/// Children per quantized node.
pub const QWIDTH: usize = 8;

mod sealed {
    /// Only `u8` and `u16` are planes: the AVX2 decode reads rows of 8 or 16 bytes.
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
}

/// A quantized plane: `u8` or `u16`.
pub trait Plane:
    sealed::Sealed + Copy + Default + PartialEq + Debug + Send + Sync + 'static
{
    /// The largest value: the grid has `TOP` steps.
    const TOP: u32;
    /// The node format this plane width is.
    const FORMAT: NodeFormat;
    fn get(self) -> u32;
    /// `q <= TOP`.
    fn new(q: u32) -> Self;
}

impl Plane for u8 {
    const TOP: u32 = u8::MAX as u32;
    const FORMAT: NodeFormat = NodeFormat::Quantized;
    fn get(self) -> u32 {
        self as u32
    }
    fn new(q: u32) -> u8 {
        q as u8
    }
}

impl Plane for u16 {
    const TOP: u32 = u16::MAX as u32;
    const FORMAT: NodeFormat = NodeFormat::Quantized16;
    fn get(self) -> u32 {
        self as u32
    }
    fn new(q: u32) -> u16 {
        q as u16
    }
}

/// One quantized node of up to 8 children. With 8-bit planes, 128 bytes: the first cache line
/// holds everything the box test reads (the planes, origins, steps and the child count), the
/// second the child references, read only for the children a ray enters. With 16-bit planes,
/// 192 bytes: the box test reads 112.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct QNode<P: Plane> {
    /// `[axis][0 = min, 1 = max][slot]`: the planes as steps above the origin.
    pub q: [[[P; QWIDTH]; 2]; 3],
    /// Per axis, the plane that byte 0 decodes to.
    pub origin: [f32; 3],
    /// Per axis, the step's exponent: a byte `q` decodes to `origin + q * 2^exp`.
    pub exp: [i8; 3],
    /// Slots in use, packed from slot 0; the others hold no child.
    pub count: u8,
    pub child: [ChildRef; QWIDTH],
}

const _: () = assert!(std::mem::size_of::<QNode<u8>>() == 128);
const _: () = assert!(std::mem::size_of::<QNode<u16>>() == 192);

/// The smallest exponent: `2^-126` is the smallest normal f32, so every step and every
/// nonzero product `q * s` is normal.
const MIN_EXP: i32 = -126;
/// The largest exponent whose `65535 * 2^e` is still finite.
const MAX_EXP: i32 = 111;

/// The f32 `2^e` for `MIN_EXP <= e <= MAX_EXP`, built from its bits.
#[inline(always)]
pub fn step(e: i8) -> f32 {
    f32::from_bits(((e as i32 + 127) as u32) << 23)
}

/// The plane byte `q` decodes to: `origin + q * step`, one rounding (the product is exact).
#[inline(always)]
pub fn decode(origin: f32, step: f32, q: u32) -> f32 {
    origin + q as f32 * step
}

/// Whether `x` survives flush-to-zero and denormals-are-zero unchanged (zero or normal), so
/// the kernels see the same plane under any MXCSR state.
fn ftz_safe(x: f32) -> bool {
    x == 0.0 || x.is_normal()
}

/// How one axis of a node is quantized: the origin and exponent that cover `[lo, hi]` (the
/// union of the children, finite, `lo <= hi`) with planes 0 to `top`.
pub fn axis_frame(lo: f32, hi: f32, top: u32) -> (f32, i8) {
    // A subnormal origin would change under denormals-are-zero: take the normal or zero
    // value just below it.
    let origin = if ftz_safe(lo) {
        lo
    } else if lo > 0.0 {
        0.0
    } else {
        -f32::MIN_POSITIVE
    };
    // The smallest step with `top` steps reaching `hi`, found by the decode itself; the
    // estimate from the extent (in f64, so it cannot overflow) starts the search close.
    let extent = (hi as f64 - origin as f64) / top as f64;
    let mut e = if extent > 0.0 {
        (extent.log2().floor() as i32).clamp(MIN_EXP, MAX_EXP)
    } else {
        MIN_EXP
    };
    while e > MIN_EXP && decode(origin, step((e - 1) as i8), top) >= hi {
        e -= 1;
    }
    while e < MAX_EXP
        && (decode(origin, step(e as i8), top) < hi
            || !ftz_safe(decode(origin, step(e as i8), top)))
    {
        e += 1;
    }
    (origin, e as i8)
}

/// The smallest `q` in `lo..=hi` for which `pred` holds, `hi + 1` if none; `pred` must be
/// false then true along `q` (decoding is monotonic in `q`), so a binary search finds it in
/// 16 steps at most even where thousands of 16-bit values decode alike.
fn first(mut lo: u32, mut hi: u32, pred: impl Fn(u32) -> bool) -> u32 {
    hi += 1;
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// A plane value whose plane is the highest at or below `x` and unchanged by flush-to-zero (0
/// always qualifies: it decodes to the origin, at or below every child). Where a step is
/// smaller than the rounding of the addition, several values decode alike; of those, the
/// lowest, so that a flat child never gets its min above its max.
pub fn round_down(origin: f32, e: i8, x: f32, top: u32) -> u32 {
    let s = step(e);
    let at = |q: u32| decode(origin, s, q);
    let mut q = first(0, top, |q| at(q) > x).saturating_sub(1);
    // Subnormal planes span less than two steps (a step is at least the smallest normal).
    while q > 0 && !ftz_safe(at(q)) {
        q -= 1;
    }
    first(0, q, |k| at(k) >= at(q))
}

/// A plane value whose plane is the lowest at or above `x` and unchanged by flush-to-zero
/// (`top` qualifies by the choice of the exponent); of several values decoding alike, the
/// highest.
pub fn round_up(origin: f32, e: i8, x: f32, top: u32) -> u32 {
    let s = step(e);
    let at = |q: u32| decode(origin, s, q);
    let mut q = first(0, top, |q| at(q) >= x);
    while q < top && !ftz_safe(at(q)) {
        q += 1;
    }
    first(q, top, |k| at(k) > at(q)) - 1
}

impl<P: Plane> QNode<P> {
    /// The quantized form of a float wide node: the same children in the same slots, each box
    /// rounded outward on the grid of the node's own bounds.
    pub fn quantize(n: &WideNode<QWIDTH>) -> QNode<P> {
        let count = n.children();
        let bounds = (0..count).fold(Aabb::default(), |b, i| b.union(&n.child_bounds(i)));
        let mut node = QNode {
            q: [[[P::default(); QWIDTH]; 2]; 3],
            origin: [0.0; 3],
            exp: [MIN_EXP as i8; 3],
            count: count as u8,
            child: n.child,
        };
        if count == 0 {
            return node;
        }
        for axis in 0..3 {
            let (o, e) = axis_frame(bounds.min[axis], bounds.max[axis], P::TOP);
            node.origin[axis] = o;
            node.exp[axis] = e;
            for i in 0..count {
                node.q[axis][0][i] = P::new(round_down(o, e, n.planes[axis][0][i], P::TOP));
                node.q[axis][1][i] = P::new(round_up(o, e, n.planes[axis][1][i], P::TOP));
            }
        }
        node
    }

    pub fn children(&self) -> usize {
        self.count as usize
    }

    /// The mask of the slots in use.
    #[inline(always)]
    pub fn used_mask(&self) -> u32 {
        (1u32 << self.count) - 1
    }

    /// The decoded box of slot `i` (what the kernels test).
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let at = |axis: usize, side: usize| {
            decode(
                self.origin[axis],
                step(self.exp[axis]),
                self.q[axis][side][i].get(),
            )
        };
        Aabb::new(
            Vec3::new(at(0, 0), at(1, 0), at(2, 0)),
            Vec3::new(at(0, 1), at(1, 1), at(2, 1)),
        )
    }

    /// The node decoded to floats in the float node's layout, unused slots empty: the
    /// portable kernels' decode, and the reference the SIMD decodes must match bit for bit.
    pub fn decode_scalar(&self) -> WideNode<QWIDTH> {
        let mut planes = [[[f32::INFINITY; QWIDTH], [f32::NEG_INFINITY; QWIDTH]]; 3];
        for (axis, p) in planes.iter_mut().enumerate() {
            let (o, s) = (self.origin[axis], step(self.exp[axis]));
            for (row, bytes) in p.iter_mut().zip(&self.q[axis]) {
                for (plane, &q) in row.iter_mut().zip(bytes).take(self.children()) {
                    *plane = decode(o, s, q.get());
                }
            }
        }
        WideNode {
            planes,
            child: self.child,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Float nodes whose children stress the rounding: a huge extent, a child equal to its
    /// parent, flat children, a tiny child far from the origin, boxes at ±1e30, subnormal
    /// and signed-zero planes.
    pub(crate) fn sample_floats() -> Vec<WideNode<QWIDTH>> {
        let b = |lo: [f32; 3], hi: [f32; 3]| Aabb::new(Vec3::from(lo), Vec3::from(hi));
        let cases: Vec<Vec<Aabb>> = vec![
            // The project's scene limit on both sides, and a unit box inside.
            vec![
                b([-1.8e18; 3], [1.8e18; 3]),
                b([0.0; 3], [1.0; 3]),
                b([1.7e18, -3.0, 5.0], [1.8e18, -2.0, 5.0]),
            ],
            // A child equal to the union, and flat children on every axis.
            vec![
                b([-1.0, 2.0, 3.0], [4.0, 5.0, 6.0]),
                b([0.5, 2.0, 3.0], [0.5, 5.0, 6.0]),
                b([-1.0, 3.25, 3.0], [4.0, 3.25, 6.0]),
                b([-1.0, 2.0, 4.1], [4.0, 5.0, 4.1]),
            ],
            // Every child the same flat point: a zero extent on all axes.
            vec![b([7.0, -7.0, 0.0], [7.0, -7.0, 0.0]); 3],
            // Tiny boxes far from zero: the rounding at 1e6, where an f32 step is 0.0625.
            vec![
                b(
                    [1.0e6, 1.0e6, -1.0e6],
                    [1.0e6 + 0.125, 1.0e6 + 0.0625, -1.0e6 + 0.5],
                ),
                b(
                    [1.0e6 + 3.0, 1.0e6, -1.0e6],
                    [1.0e6 + 3.0625, 1.0e6 + 2.0, -1.0e6],
                ),
            ],
            // ±1e30 and small boxes beside them.
            vec![
                b([-1.0e30; 3], [-1.0e30 + 1.0e23; 3]),
                b([1.0e30; 3], [1.0e30; 3]),
                b([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
            ],
            // Subnormal and signed-zero planes, and a box straddling zero by one ulp.
            vec![
                b([-1.0e-40, 1.0e-42, -0.0], [1.0e-40, 2.0e-40, 0.0]),
                b([-1.0e-45, 0.0, -0.0], [1.0e-45, 1.0e-39, 0.0]),
                b([0.0, -1.0e-38, -1.0e-38], [1.0e-38, 0.0, 2.0e-38]),
            ],
            // Eight children spread over 0..1000 with fractional planes.
            (0..8)
                .map(|i| {
                    let x = i as f32 * 123.456 + 0.1;
                    b([x, x * 0.5, -x], [x + 7.77, x * 0.5 + 0.01, -x + 300.3])
                })
                .collect(),
        ];
        cases
            .into_iter()
            .map(|boxes| {
                let mut n = WideNode::<QWIDTH>::empty();
                for (i, bx) in boxes.iter().enumerate() {
                    n.set_child(
                        i,
                        bx,
                        ChildRef {
                            index: i as u32,
                            count: 1,
                        },
                    );
                }
                n
            })
            .collect()
    }

    pub(crate) fn sample_nodes<P: Plane>() -> Vec<QNode<P>> {
        sample_floats().iter().map(QNode::quantize).collect()
    }

    /// Every decoded box holds its float box, and is a tight rounding: the next distinct
    /// plane inward on any side (where there is one) would cut into the float box.
    fn hold_and_tight<P: Plane>() {
        for f in sample_floats() {
            let q = QNode::<P>::quantize(&f);
            assert_eq!(q.children(), f.children());
            assert_eq!(q.child, f.child);
            for i in 0..q.children() {
                let (fb, qb) = (f.child_bounds(i), q.child_bounds(i));
                assert!(
                    qb.contains_box(&fb),
                    "slot {i}: {qb:?} does not hold {fb:?}"
                );
                for axis in 0..3 {
                    let (o, s) = (q.origin[axis], step(q.exp[axis]));
                    let (lo, hi) = (q.q[axis][0][i].get(), q.q[axis][1][i].get());
                    let fits = |x: f32| x == 0.0 || x.is_normal();
                    assert!(lo <= hi, "slot {i} axis {axis}: planes {lo} > {hi}");
                    let up = (lo..=P::TOP)
                        .map(|b| decode(o, s, b))
                        .find(|&p| p > qb.min[axis]);
                    if let Some(p) = up.filter(|&p| fits(p)) {
                        assert!(p > fb.min[axis], "min {axis} not tight");
                    }
                    let down = (0..=hi)
                        .rev()
                        .map(|b| decode(o, s, b))
                        .find(|&p| p < qb.max[axis]);
                    if let Some(p) = down.filter(|&p| fits(p)) {
                        assert!(p < fb.max[axis], "max {axis} not tight");
                    }
                }
            }
        }
    }

    #[test]
    fn decoded_boxes_hold_the_float_boxes() {
        hold_and_tight::<u8>();
        hold_and_tight::<u16>();
    }

    /// The grid is as fine as the node allows: a child equal to the node decodes exactly,
    /// and a node of `TOP` unit steps on an integer grid is lossless.
    fn exact_cases<P: Plane>() {
        let nodes = sample_floats();
        let (f, q) = (&nodes[1], QNode::<P>::quantize(&nodes[1]));
        assert_eq!(q.child_bounds(0), f.child_bounds(0));
        let mut n = WideNode::<QWIDTH>::empty();
        let b = |lo: f32, hi: f32| Aabb::new(Vec3::splat(lo), Vec3::splat(hi));
        let leaf = ChildRef { index: 0, count: 1 };
        n.set_child(0, &b(0.0, P::TOP as f32), leaf);
        n.set_child(1, &b(17.0, 18.0), leaf);
        let q = QNode::<P>::quantize(&n);
        assert_eq!(q.exp, [0; 3]);
        assert_eq!(q.child_bounds(1), b(17.0, 18.0));
    }

    #[test]
    fn a_child_equal_to_the_node_and_an_integer_grid_decode_exactly() {
        exact_cases::<u8>();
        exact_cases::<u16>();
    }

    /// Every frame and plane survives flush-to-zero: the kernels see the same boxes under
    /// any MXCSR state.
    fn zero_or_normal<P: Plane>() {
        for q in sample_nodes::<P>() {
            for axis in 0..3 {
                let o = q.origin[axis];
                assert!(o == 0.0 || o.is_normal(), "origin {o}");
                assert!(step(q.exp[axis]).is_normal());
                for i in 0..q.children() {
                    for side in 0..2 {
                        let p = decode(o, step(q.exp[axis]), q.q[axis][side][i].get());
                        assert!(p == 0.0 || p.is_normal(), "plane {p}");
                    }
                }
            }
        }
    }

    #[test]
    fn frames_and_planes_are_zero_or_normal() {
        zero_or_normal::<u8>();
        zero_or_normal::<u16>();
    }
}
