//! The one traversal loop, for closest hit and any hit, ordered and unordered, counted and not.

use crate::simd::F4;
use crate::{Bvh, ChildRef, MAX_DEPTH, Node};
use raybench_accel::{CounterSink, Hit};
use raybench_geom::{MollerTriangle, Ray, TriHit};

/// What the slab test needs of a ray, with each axis's near/far plane choice made once.
struct SlabRay {
    /// Per axis, 1 when the direction's sign bit is set (so -0, whose inverse is -inf, counts
    /// as negative: docs/validation.md, B3): the index of the near plane in a box `[min, max]`, and
    /// `1 - near` the far one.
    near: [usize; 3],
    /// The same ray in SIMD lanes for [`SlabRay::enter_children`]: the origin splatted, and
    /// the inverse direction as `[inv, inv, -inv, -inv]`, so the far distances come out
    /// negated and one `max` per axis tightens entries and exits alike.
    origin4: [F4; 3],
    inv4: [F4; 3],
}

impl SlabRay {
    fn new(ray: &Ray) -> SlabRay {
        let inv = ray.inv_dir().to_array();
        let origin = ray.origin().to_array();
        SlabRay {
            near: inv.map(|x| x.is_sign_negative() as usize),
            origin4: origin.map(F4::splat),
            inv4: inv.map(|x| F4::new(x, x, -x, -x)),
        }
    }

    /// Both children of `n` at once, the same arithmetic as `Aabb::intersect` lane for lane:
    /// lanes `[entry 0, entry 1, -exit 0, -exit 1]` start at `[t_min, t_min, -t_max, -t_max]`
    /// and each axis raises them with its near (or negated far) plane distances; a NaN lane is
    /// ignored because `max_keep` keeps the accumulator. Returns a mask (bit `i`: child `i` is
    /// hit) and the lanes, whose first two are the entry distances.
    #[inline(always)]
    fn enter_children(&self, n: &Node, t_min: f32, t_max: f32) -> (u32, [f32; 4]) {
        let mut acc = F4::new(t_min, t_min, -t_max, -t_max);
        for a in 0..3 {
            let planes = F4::load(&n.planes[a]);
            // Near planes first: for a negative direction the max planes are met first.
            let planes = if self.near[a] == 1 {
                planes.swap_halves()
            } else {
                planes
            };
            acc = planes.sub(self.origin4[a]).mul(self.inv4[a]).max_keep(acc);
        }
        let mask = acc.le_mask(acc.swap_halves().neg()) & 0b11;
        (mask, acc.to_array())
    }
}

impl Bvh {
    /// Iterative depth-first walk with a fixed stack of (subtree, entry t) — one entry per
    /// level at most, and the builder caps the depth at [`MAX_DEPTH`], so it cannot overflow.
    /// `ORDERED`: visit the nearer child first and drop popped entries that start beyond the
    /// closest hit so far. `ANY_HIT`: return at the first hit.
    pub(crate) fn trace<const ANY_HIT: bool, const ORDERED: bool, C: CounterSink>(
        &self,
        ray: &Ray,
        c: &mut C,
    ) -> Option<Hit> {
        if self.triangles.is_empty() {
            return None;
        }
        let slab = SlabRay::new(ray);
        let t_min = ray.t_min();
        let mut best_t = ray.t_max();
        let mut best: Option<(usize, TriHit)> = None;
        self.root_bounds.intersect(ray)?;
        let mut stack = [(ChildRef::default(), 0f32); MAX_DEPTH];
        let mut sp = 0;
        let mut next = Some(self.root);
        'walk: loop {
            // Descend: interior nodes until both children are missed or a leaf is reached.
            while let Some(r) = next.take() {
                if r.is_leaf() {
                    if intersect_leaf::<ANY_HIT, C>(
                        &self.triangles,
                        r,
                        ray,
                        &mut best_t,
                        &mut best,
                        c,
                    ) {
                        break 'walk;
                    }
                    break;
                }
                c.node();
                let n = &self.nodes[r.index as usize];
                let (hit, t) = slab.enter_children(n, t_min, best_t);
                next = match hit {
                    0b11 => {
                        let (near, far, t_far) = if ORDERED && t[1] < t[0] {
                            (1, 0, t[0])
                        } else {
                            (0, 1, t[1])
                        };
                        stack[sp] = (n.child[far], t_far);
                        sp += 1;
                        Some(n.child[near])
                    }
                    0b01 => Some(n.child[0]),
                    0b10 => Some(n.child[1]),
                    _ => None,
                };
            }
            // Pop the next subtree worth visiting.
            loop {
                if sp == 0 {
                    break 'walk;
                }
                sp -= 1;
                let (r, t_entry) = stack[sp];
                if ORDERED && t_entry > best_t {
                    continue; // starts beyond the closest hit: nothing in it can be closer
                }
                next = Some(r);
                break;
            }
        }
        best.map(|(i, h)| Hit::from_tri_hit(self.prim_ids[i], h))
    }
}

/// Tests the triangles of leaf `r` against `ray` below `*best_t`, keeping the closest hit
/// (as an index into `triangles`); true when an any-hit query may stop. Shared by the binary
/// and the wide traversal.
#[inline(always)]
pub(crate) fn intersect_leaf<const ANY_HIT: bool, C: CounterSink>(
    triangles: &[MollerTriangle],
    r: ChildRef,
    ray: &Ray,
    best_t: &mut f32,
    best: &mut Option<(usize, TriHit)>,
    c: &mut C,
) -> bool {
    c.leaf();
    let first = r.index as usize;
    for (k, tri) in triangles[first..first + r.count as usize]
        .iter()
        .enumerate()
    {
        c.prim_tests(1);
        if let Some(h) = tri.intersect(&ray.with_t_max(*best_t)) {
            *best_t = h.t;
            *best = Some((first + k, h));
            if ANY_HIT {
                return true;
            }
        }
    }
    false
}
