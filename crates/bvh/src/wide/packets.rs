//! Packets of sixteen coherent rays walked through a wide BVH together, one ray per
//! AVX-512 lane: for camera rays in scanline order, which enter the same nodes and leaves.
//!
//! A single-ray walk is a chain of dependent steps: each node's test waits for the child the test
//! before it chose (about 45 cycles a step on the bunny's primary rays: docs/experiments.md,
//! "Profiles behind the tables"). A packet turns that chain into independent work: at each node,
//! every child's box is tested against all sixteen rays (one broadcast plane against sixteen
//! origins), and at each leaf every triangle against all sixteen. The visits are shared, so the
//! per-ray cost is the packet's cost divided by how many rays needed it: low for a packet whose
//! rays hit one surface, high where they scatter (silhouettes, triangles smaller than the spacing
//! of the rays), since a test costs the same for one lane as for sixteen. This is the classic
//! packet traversal of Wald, Slusallek, Benthin and Wagner (2001), on a BVH as in Wald, Boulos and
//! Shirley (2007, "Ray tracing deformable scenes using dynamic bounding volume hierarchies"),
//! without their frustum culling. Trade-off, measured over the default suite's primary rays
//! (docs/results/): 1.5–2.8× the single-ray walk on scenes of large triangles (Sponza, the teapots,
//! Sibenik), nothing or up to a quarter lost where triangles are smaller than the rays' spacing
//! (the stadium from afar, San Francisco). Handing sparse subtrees or leaves back to the single-ray
//! walk, as Embree's hybrid traversal does, did not measurably help (docs/experiments.md, "Packets
//! for coherent rays").
//!
//! Exactness: every lane computes what the single-ray walk computes for its ray, operation for
//! operation — the slab test with the near planes chosen by the direction's signs
//! ([`super::avx2`]), Möller–Trumbore as in [`raybench_geom::Tri4::test`] (no fused
//! multiply-add) — so each ray's hit, `t`, `u` and `v` are the single-ray walk's, bit for bit.
//! Only the order in which triangles are met differs, so on an exact tie (two triangles at
//! the same `t`) the reported triangle may be the other one, as between any two structures.
//! The near planes are per packet, so a packet whose rays point into different octants is
//! walked once per octant present, each time with only that octant's lanes active (Embree's
//! stream mode sorts rays by octant for the same reason).
//!
//! A subtree pushed for later keeps the smallest entry distance among its rays and is skipped
//! when that is beyond every active ray's closest hit so far.

use crate::node::ChildRef;
use crate::simd::F4;
use crate::wide::{BvhWide, STACK};
use raybench_accel::Hit;
use raybench_geom::Ray;
use raybench_geom::{NO_PRIM, Tri4};
use std::arch::x86_64::*;

/// Rays in a packet: one per AVX-512 lane.
pub(crate) const PACKET: usize = 16;

/// Proof that this CPU runs AVX-512F (the only way to reach the packet code).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512Packets(());

impl Avx512Packets {
    pub(crate) fn detect() -> Option<Avx512Packets> {
        std::arch::is_x86_feature_detected!("avx512f").then_some(Avx512Packets(()))
    }
}

/// Up to sixteen rays in structure-of-arrays form.
struct Packet {
    origin: [__m512; 3],
    dir: [__m512; 3],
    inv: [__m512; 3],
    t_min: __m512,
}

/// Each lane's closest hit so far.
struct Best {
    t: __m512,
    u: __m512,
    v: __m512,
    prim: __m512i,
}

/// Rays `16 k ..` of a coherent batch in structure-of-arrays form, made outside timing by
/// `prepare_coherent_rays`: rows `origin x, y, z`, `dir x, y, z`, `inv_dir x, y, z`, `t_min`,
/// `t_max`, one lane per ray (lanes past the batch's end are copies of its last ray, never
/// reported).
#[derive(Clone, Debug)]
#[repr(C, align(64))]
pub(crate) struct RayBlock {
    rows: [[f32; PACKET]; 11],
}

/// A coherent batch as blocks of [`PACKET`] rays.
#[derive(Clone, Debug)]
pub(crate) struct RayPackets {
    blocks: Vec<RayBlock>,
    len: usize,
}

impl RayPackets {
    pub(crate) fn new(rays: &[Ray]) -> RayPackets {
        let blocks = rays
            .chunks(PACKET)
            .map(|chunk| {
                let mut rows = [[0.0f32; PACKET]; 11];
                for lane in 0..PACKET {
                    let ray = &chunk[lane.min(chunk.len() - 1)];
                    let (o, d, inv) = (ray.origin(), ray.dir(), ray.inv_dir());
                    for a in 0..3 {
                        rows[a][lane] = o[a];
                        rows[3 + a][lane] = d[a];
                        rows[6 + a][lane] = inv[a];
                    }
                    rows[9][lane] = ray.t_min();
                    rows[10][lane] = ray.t_max();
                }
                RayBlock { rows }
            })
            .collect();
        RayPackets {
            blocks,
            len: rays.len(),
        }
    }

    /// The blocks of rays `first .. first + len`, when `first` starts a block (the harness's
    /// chunks are multiples of [`PACKET`]); `None` otherwise, and the caller walks ray by ray.
    pub(crate) fn range(&self, first: usize, len: usize) -> Option<&[RayBlock]> {
        let end = first.checked_add(len)?;
        (first.is_multiple_of(PACKET) && end <= self.len)
            .then(|| &self.blocks[first / PACKET..end.div_ceil(PACKET)])
    }
}

/// A block loaded into a packet, with its closest-hit windows' far ends as the best hits so
/// far.
#[target_feature(enable = "avx512f")]
fn load_packet(block: &RayBlock) -> (Packet, Best) {
    // SAFETY: each row is 16 initialised f32s, 64-byte aligned (the block is aligned to 64
    // and every row is 64 bytes long).
    let load = |row: usize| unsafe { _mm512_load_ps(block.rows[row].as_ptr()) };
    let packet = Packet {
        origin: [load(0), load(1), load(2)],
        dir: [load(3), load(4), load(5)],
        inv: [load(6), load(7), load(8)],
        t_min: load(9),
    };
    let best = Best {
        t: load(10),
        u: _mm512_setzero_ps(),
        v: _mm512_setzero_ps(),
        prim: _mm512_set1_epi32(NO_PRIM as i32),
    };
    (packet, best)
}

/// A subtree still to visit: its reference, the smallest entry distance among the lanes that
/// entered its box, and those lanes.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    r: ChildRef,
    t_entry: f32,
    lanes: u16,
}

type PacketStack = [Entry; STACK];

/// Traces a coherent batch (closest hit), one packet per block; `out` gets the first
/// `out.len()` rays of `blocks`.
pub(crate) fn intersect_coherent<const W: usize>(
    _k: Avx512Packets,
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
) {
    let mut stack: Box<PacketStack> = Box::new([Entry::default(); STACK]);
    // SAFETY: an `Avx512Packets` exists only after `detect` saw AVX-512F on this CPU.
    unsafe { intersect_packets(bvh, blocks, out, &mut stack) }
}

#[target_feature(enable = "avx512f")]
fn intersect_packets<const W: usize>(
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    out: &mut [Option<Hit>],
    stack: &mut PacketStack,
) {
    for (block, out) in blocks.iter().zip(out.chunks_mut(PACKET)) {
        let (packet, mut best) = load_packet(block);
        if !bvh.tri4s().is_empty() {
            // Bit `a` of a lane's octant: axis `a` points down (`-0` too: its inverse is -inf).
            let zero = _mm512_setzero_ps();
            let down = packet
                .inv
                .map(|inv| _mm512_cmp_ps_mask::<_CMP_LT_OQ>(inv, zero));
            let mut left: u16 = if out.len() >= PACKET {
                u16::MAX
            } else {
                (1 << out.len()) - 1
            };
            while left != 0 {
                let lane = left.trailing_zeros();
                let octant = (0..3).fold(0u8, |o, a| o | (((down[a] >> lane) & 1) as u8) << a);
                let lanes = (0..3).fold(left, |m, a| {
                    m & if octant >> a & 1 == 1 {
                        down[a]
                    } else {
                        !down[a]
                    }
                });
                walk(bvh, &packet, lanes, octant, &mut best, stack);
                left &= !lanes;
            }
        }
        store_hits(&best, out);
    }
}

/// Each lane's hit as the single-ray walk reports it.
#[target_feature(enable = "avx512f")]
fn store_hits(best: &Best, out: &mut [Option<Hit>]) {
    let mut t = [0.0f32; PACKET];
    let mut u = [0.0f32; PACKET];
    let mut v = [0.0f32; PACKET];
    let mut prim = [0u32; PACKET];
    // SAFETY: each destination is 16 writable 4-byte values; `storeu` has no alignment
    // requirement.
    unsafe {
        _mm512_storeu_ps(t.as_mut_ptr(), best.t);
        _mm512_storeu_ps(u.as_mut_ptr(), best.u);
        _mm512_storeu_ps(v.as_mut_ptr(), best.v);
        _mm512_storeu_si512(prim.as_mut_ptr().cast(), best.prim);
    }
    for (lane, o) in out.iter_mut().enumerate() {
        *o = (prim[lane] != NO_PRIM).then_some(Hit {
            t: t[lane],
            prim: prim[lane],
            u: u[lane],
            v: v[lane],
        });
    }
}

/// The walk of the `active` lanes, whose directions all lie in `octant`. Each subtree is
/// walked with the lanes that entered its box, so every ray meets exactly the boxes and
/// triangles its single-ray walk would test (not those of a neighbour's leaf, where a ray
/// grazing a box it missed by rounding could find a hit its own walk never tests).
#[target_feature(enable = "avx512f")]
fn walk<const W: usize>(
    bvh: &BvhWide<W>,
    p: &Packet,
    active: u16,
    octant: u8,
    best: &mut Best,
    stack: &mut PacketStack,
) {
    let near = [0, 1, 2].map(|a| (octant >> a & 1) as usize);
    let mut farthest = _mm512_mask_reduce_max_ps(active, best.t);
    let mut sp = 0;
    let mut r = bvh.root();
    let mut lanes = active;
    'walk: loop {
        if r.is_leaf() {
            leaf(bvh, r, p, lanes, best);
            farthest = _mm512_mask_reduce_max_ps(active, best.t);
        } else {
            let n = &bvh.nodes()[r.index as usize];
            let base = sp;
            for slot in 0..W {
                let child = n.child[slot];
                if child == ChildRef::default() {
                    break;
                }
                let mut t0 = p.t_min;
                let mut t1 = best.t;
                for (a, &near) in near.iter().enumerate() {
                    let lo = _mm512_set1_ps(n.planes[a][near][slot]);
                    let hi = _mm512_set1_ps(n.planes[a][1 - near][slot]);
                    t0 = _mm512_max_ps(_mm512_mul_ps(_mm512_sub_ps(lo, p.origin[a]), p.inv[a]), t0);
                    t1 = _mm512_min_ps(_mm512_mul_ps(_mm512_sub_ps(hi, p.origin[a]), p.inv[a]), t1);
                }
                let entered = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(lanes, t0, t1);
                if entered != 0 {
                    let e = Entry {
                        r: child,
                        t_entry: _mm512_mask_reduce_min_ps(entered, t0),
                        lanes: entered,
                    };
                    push_sorted(stack, base, &mut sp, e);
                }
            }
            if sp > base {
                sp -= 1;
                (r, lanes) = (stack[sp].r, stack[sp].lanes);
                continue 'walk;
            }
        }
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            let e = stack[sp];
            if e.t_entry <= farthest {
                (r, lanes) = (e.r, e.lanes);
                continue 'walk;
            }
        }
    }
}

/// Pushes `e` onto `stack[base..*sp]`, kept in decreasing entry distance so the nearest is on
/// top (a later slot goes below earlier ones at the same distance).
#[inline(always)]
fn push_sorted(stack: &mut PacketStack, base: usize, sp: &mut usize, e: Entry) {
    let mut j = *sp;
    while j > base && stack[j - 1].t_entry <= e.t_entry {
        stack[j] = stack[j - 1];
        j -= 1;
    }
    stack[j] = e;
    *sp += 1;
}

/// `a × b` lane-wise in glam's order, as [`raybench_geom::Tri4::test`].
#[target_feature(enable = "avx512f")]
#[inline]
fn cross(a: &[__m512; 3], b: &[__m512; 3]) -> [__m512; 3] {
    [
        _mm512_sub_ps(_mm512_mul_ps(a[1], b[2]), _mm512_mul_ps(b[1], a[2])),
        _mm512_sub_ps(_mm512_mul_ps(a[2], b[0]), _mm512_mul_ps(b[2], a[0])),
        _mm512_sub_ps(_mm512_mul_ps(a[0], b[1]), _mm512_mul_ps(b[0], a[1])),
    ]
}

/// `a · b` lane-wise in glam's order, `(ax bx + ay by) + az bz`.
#[target_feature(enable = "avx512f")]
#[inline]
fn dot(a: &[__m512; 3], b: &[__m512; 3]) -> __m512 {
    _mm512_add_ps(
        _mm512_add_ps(_mm512_mul_ps(a[0], b[0]), _mm512_mul_ps(a[1], b[1])),
        _mm512_mul_ps(a[2], b[2]),
    )
}

/// `x` negated in the lanes where `by` has its sign bit set (`-0` counts as negative).
#[target_feature(enable = "avx512f")]
#[inline]
fn flip(x: __m512, by: __m512) -> __m512 {
    let sign = _mm512_and_si512(_mm512_castps_si512(by), _mm512_set1_epi32(i32::MIN));
    _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(x), sign))
}

/// Every triangle of leaf `r` against the `active` lanes, one triangle a pass.
#[target_feature(enable = "avx512f")]
fn leaf<const W: usize>(bvh: &BvhWide<W>, r: ChildRef, p: &Packet, active: u16, best: &mut Best) {
    let first = r.index as usize;
    let tri4s = &bvh.tri4s()[first..first + (r.count as usize).div_ceil(4)];
    for tri4 in tri4s {
        // The four normals `e2 × e1` in one 4-lane pass (the same operations as the 16-lane
        // `cross`, so the same bits), broadcast per triangle below.
        let ng4 = normals(tri4);
        for lane in 0..4 {
            let id = tri4.ids[lane];
            if id == NO_PRIM {
                break;
            }
            let at = |v: &[[f32; 4]; 3]| [0, 1, 2].map(|a| _mm512_set1_ps(v[a][lane]));
            let (v0, e1, e2, ng) = (at(&tri4.v0), at(&tri4.e1), at(&tri4.e2), at(&ng4));
            let c = [0, 1, 2].map(|a| _mm512_sub_ps(v0[a], p.origin[a]));
            let rr = cross(&c, &p.dir);
            let den = dot(&ng, &p.dir);
            let abs_den = _mm512_abs_ps(den);
            let u = flip(dot(&rr, &e2), den);
            let v = flip(dot(&rr, &e1), den);
            let zero = _mm512_setzero_ps();
            let mut hit = _mm512_mask_cmp_ps_mask::<_CMP_NEQ_UQ>(active, den, zero);
            hit = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(hit, u, zero);
            hit = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(hit, v, zero);
            hit = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(hit, _mm512_add_ps(u, v), abs_den);
            if hit == 0 {
                continue;
            }
            let t = flip(dot(&ng, &c), den);
            hit = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(hit, _mm512_mul_ps(abs_den, p.t_min), t);
            hit = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(hit, t, _mm512_mul_ps(abs_den, best.t));
            if hit == 0 {
                continue;
            }
            let inv = _mm512_div_ps(_mm512_set1_ps(1.0), abs_den);
            best.t = _mm512_mask_mov_ps(best.t, hit, _mm512_mul_ps(t, inv));
            best.u = _mm512_mask_mov_ps(best.u, hit, _mm512_mul_ps(u, inv));
            best.v = _mm512_mask_mov_ps(best.v, hit, _mm512_mul_ps(v, inv));
            best.prim = _mm512_mask_mov_epi32(best.prim, hit, _mm512_set1_epi32(id as i32));
        }
    }
}

/// `e2 × e1` of a `Tri4`'s four triangles, per axis, in glam's order.
#[inline(always)]
fn normals(t: &Tri4) -> [[f32; 4]; 3] {
    let (e1, e2) = (t.e1.map(|r| F4::load(&r)), t.e2.map(|r| F4::load(&r)));
    [
        e2[1].mul(e1[2]).sub(e1[1].mul(e2[2])).to_array(),
        e2[2].mul(e1[0]).sub(e1[2].mul(e2[0])).to_array(),
        e2[0].mul(e1[1]).sub(e1[0].mul(e2[1])).to_array(),
    ]
}
