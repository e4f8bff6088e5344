//! Where a subtree is best reinserted, and what a given move gains in the tree as it is now.
//!
//! Gains are in (half) surface area summed over interior nodes. A move keeps every leaf and
//! the number of interior nodes, so the builder's SAH cost falls by exactly the traversal cost
//! times the gain over the root's area: the leaf terms do not change.
//!
//! Moving `x` out deletes its parent `p` (whose box no longer counts) and shrinks the
//! ancestors of `p` below the lowest one that still contains the destination; putting it next
//! to `c` adds a node of box `c ∪ x` and grows every node between that ancestor and `c`.

use super::tree::{Kind, NONE, Tree};
use crate::build::Box3;

/// Moving `from` next to `to` lowers the interior area by `gain`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Move {
    pub from: u32,
    pub to: u32,
    pub gain: f64,
}

/// The best destination for `x` (not the root) by branch and bound, or `None` when no move
/// lowers the area. `stack` is scratch space.
///
/// Walks up from `x`'s parent; at each ancestor, every destination in the subtree on the
/// other side is priced with what the removal has saved up to there. Descending into a node
/// costs the growth of its box by `x`; a subtree is skipped when even a new node no larger
/// than `x` could not beat the best gain found.
pub(super) fn best_move(t: &Tree, x: u32, stack: &mut Vec<(f64, u32)>) -> Option<Move> {
    let xb = t.bounds[x as usize];
    let x_area = xb.half_area();
    let p = t.parent[x as usize];
    let mut best = Move {
        from: x,
        to: NONE,
        gain: 0.0,
    };
    let mut saved = t.area(p);
    // What is left of the current ancestor's box once `x` is gone.
    let mut rest = t.bounds[t.sibling(x) as usize];
    search_below(t, &xb, x_area, t.sibling(x), saved, &mut best, stack);
    let mut at = p;
    while t.parent[at as usize] != NONE {
        if at != p {
            saved += t.area(at) - rest.half_area();
        }
        let other = t.sibling(at);
        search_below(t, &xb, x_area, other, saved, &mut best, stack);
        rest = rest.union(&t.bounds[other as usize]);
        at = t.parent[at as usize];
    }
    (best.to != NONE).then_some(best)
}

/// Prices every destination in the subtree of `top`, entered with `saved` area already
/// gained, updating `best`.
fn search_below(
    t: &Tree,
    xb: &Box3,
    x_area: f64,
    top: u32,
    saved: f64,
    best: &mut Move,
    stack: &mut Vec<(f64, u32)>,
) {
    stack.clear();
    stack.push((saved, top));
    while let Some((g, c)) = stack.pop() {
        if g - x_area <= best.gain {
            continue;
        }
        let own = t.bounds[c as usize];
        let here = g - own.union(xb).half_area();
        if here > best.gain {
            *best = Move {
                from: best.from,
                to: c,
                gain: here,
            };
        }
        if let Kind::Interior([a, b]) = t.kind[c as usize] {
            // Below `c`, its box grows to `c ∪ x`: the new node is paid at the leaf level.
            let down = here + own.half_area();
            if down - x_area > best.gain {
                stack.push((down, b));
                stack.push((down, a));
            }
        }
    }
}

/// Marks of `x`'s ancestors, reused across moves (an epoch number instead of clearing).
pub(super) struct Marks {
    epoch: u32,
    mark: Vec<u32>,
    /// For a marked node, its distance above `x`.
    level: Vec<u32>,
}

impl Marks {
    pub(super) fn new(nodes: usize) -> Marks {
        Marks {
            epoch: 0,
            mark: vec![0; nodes],
            level: vec![0; nodes],
        }
    }
}

/// What moving `x` next to `c` gains in the tree as it is, and whether the move is legal:
/// `None` when `c` is `x`, inside `x`'s subtree or one of its ancestors, or when the move
/// would put a leaf deeper than `max_leaf_depth`.
pub(super) fn exact_gain(
    t: &Tree,
    x: u32,
    c: u32,
    max_leaf_depth: u32,
    marks: &mut Marks,
) -> Option<f64> {
    let p = t.parent[x as usize];
    if p == NONE || c == x {
        return None;
    }
    marks.epoch += 1;
    let mut depth_x = 0;
    let mut n = p;
    while n != NONE {
        depth_x += 1;
        marks.mark[n as usize] = marks.epoch;
        marks.level[n as usize] = depth_x;
        n = t.parent[n as usize];
    }
    // Up from `c` to the lowest common ancestor, growing every node on the way by `x`.
    let xb = t.bounds[x as usize];
    let mut grow = 0.0;
    let mut steps = 0;
    let mut n = c;
    while marks.mark[n as usize] != marks.epoch {
        if n == x {
            return None;
        }
        if n != c {
            grow += t.bounds[n as usize].union(&xb).half_area() - t.area(n);
        }
        steps += 1;
        n = t.parent[n as usize];
    }
    let lca = n;
    if steps == 0 {
        return None;
    }
    let depth_c = depth_x - marks.level[lca as usize] + steps;
    let deepest = depth_c + 1 + t.height[x as usize].max(t.height[c as usize]);
    if deepest > max_leaf_depth {
        return None;
    }
    // Up from `p` to the common ancestor: `p` goes, the nodes between shrink.
    let mut saved = t.area(p);
    let mut rest = t.bounds[t.sibling(x) as usize];
    let mut at = p;
    while at != lca {
        let up = t.parent[at as usize];
        if up != lca {
            rest = rest.union(&t.bounds[t.sibling(at) as usize]);
            saved += t.area(up) - rest.half_area();
        }
        at = up;
    }
    Some(saved - t.bounds[c as usize].union(&xb).half_area() - grow)
}
