//! Reinsertion: a post-build optimizer of the binary tree (Bittner, Hapala and Havran 2013,
//! "Fast insertion-based optimization of bounding volume hierarchies"; in batches, as Meister
//! and Bittner 2018, "Parallel reinsertion for bounding volume hierarchy optimization"). Each
//! round takes the nodes with the largest boxes (the inefficiency measure of the 2018 paper:
//! a ray is most likely to enter them), finds for each one in parallel the place in the tree
//! where moving its subtree lowers the summed interior area most (branch and bound from the
//! node's old place, `search.rs`), and applies the moves in order of gain, one after another,
//! each re-priced in the tree as the earlier ones left it and applied only if it still gains
//! (where the 2018 paper locks the nodes a move touches instead). So the SAH cost never rises
//! and the result does not depend on the thread count: the search only reads the tree and the
//! moves are applied in a fixed order. Leaves are moved whole, never opened, so the leaf terms
//! of the SAH, priced as the builder prices them, stay as they are and every gain is a gain
//! in the builder's cost. Trade-off: each round costs a search per candidate that can visit a
//! good part of the tree, for a tree the collapse into wide nodes then regroups; the gain is
//! largest on trees a top-down builder got wrong near the root. Caveat: a move never opens a
//! leaf, so leaves the builder made too large stay too large.

mod search;
mod tree;

use super::Flat;
use crate::BvhParams;
use crate::node::MAX_DEPTH;
use rayon::prelude::*;
use search::{Marks, Move, best_move, exact_gain};
use serde::Serialize;
use std::collections::BTreeMap;
use tree::Tree;

/// The knobs of the optimizer (`BvhParams::reinsertion`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reinsertion {
    /// Candidates per round, as a fraction of the tree's nodes (interior and leaves), the
    /// largest boxes first.
    pub batch_fraction: f32,
    /// Rounds at most.
    pub max_rounds: u32,
    /// Stop when a round lowers the summed interior area by less than this fraction.
    pub min_round_gain: f32,
}

/// 1 % a round, at most 16 rounds, stop under 0.1 %: measured against 0.5, 2 and 5 % and
/// against 32 rounds without a stop on conference, Sponza, Sibenik, the sphere, hair and the
/// stadium (`cargo run --release -p raybench-harness --example reinsert`; docs/experiments.md,
/// "Tree optimization: reinsertion").
impl Default for Reinsertion {
    fn default() -> Self {
        Reinsertion {
            batch_fraction: 0.01,
            max_rounds: 16,
            min_round_gain: 0.001,
        }
    }
}

/// What the optimizer did, all deterministic: written into the build stats' `extra`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReinsertStats {
    /// The builder's SAH cost (its traversal and intersection costs, leaves by `leaf_block`)
    /// before and after.
    pub sah_before: f64,
    pub sah_after: f64,
    pub rounds: u32,
    pub moves: u64,
}

impl ReinsertStats {
    pub(crate) fn insert_into(&self, extra: &mut BTreeMap<String, f64>) {
        extra.insert("reinsert_sah_before".into(), self.sah_before);
        extra.insert("reinsert_sah_after".into(), self.sah_after);
        extra.insert("reinsert_rounds".into(), self.rounds as f64);
        extra.insert("reinsert_moves".into(), self.moves as f64);
    }
}

/// Leaf cost as the builder prices it: `intersection_cost` per slot of whole `leaf_block`s.
fn leaf_cost(p: &BvhParams, count: u32) -> f64 {
    let block = p.leaf_block.max(1);
    p.intersection_cost as f64 * (count.div_ceil(block) * block) as f64
}

/// Runs the optimizer `p.reinsertion` asks for on `flat` (anything a builder made, references
/// duplicated or not); `None` stats when it asks for none.
pub(crate) fn optimize(flat: Flat, p: &BvhParams) -> (Flat, Option<ReinsertStats>) {
    let Some(knobs) = p.reinsertion else {
        return (flat, None);
    };
    if flat.refs.is_empty() || flat.root.is_leaf() {
        return (flat, Some(ReinsertStats::default()));
    }
    let mut tree = Tree::from_flat(&flat);
    let sah = |t: &Tree| t.sah(p.traversal_cost as f64, |n| leaf_cost(p, n));
    let mut stats = ReinsertStats {
        sah_before: sah(&tree),
        ..ReinsertStats::default()
    };
    run(&mut tree, &knobs, &mut stats);
    stats.sah_after = sah(&tree);
    let mut out = tree.into_flat(&flat.refs);
    out.spatial = flat.spatial;
    (out, Some(stats))
}

fn interior_area(t: &Tree) -> f64 {
    (0..t.len() as u32)
        .filter(|&n| matches!(t.kind[n as usize], tree::Kind::Interior(_)))
        .map(|n| t.area(n))
        .sum()
}

fn run(tree: &mut Tree, knobs: &Reinsertion, stats: &mut ReinsertStats) {
    let batch = ((tree.len() as f64 * knobs.batch_fraction as f64).ceil() as usize)
        .clamp(1, tree.len() - 1);
    let mut marks = Marks::new(tree.len());
    // Nodes whose search found no better place: later rounds go on down the ranking instead
    // of searching them again (the tree around them changes little).
    let mut settled = vec![false; tree.len()];
    let mut area = interior_area(tree);
    let mut candidates: Vec<(f64, u32)> = Vec::with_capacity(tree.len());
    for _ in 0..knobs.max_rounds {
        choose(tree, &settled, batch, &mut candidates);
        if candidates.is_empty() {
            break;
        }
        stats.rounds += 1;
        let t: &Tree = tree;
        let found: Vec<Option<Move>> = candidates
            .par_iter()
            // Searches are short: a few per task keeps rayon's overhead small (not tuned).
            .with_min_len(16)
            .map_init(Vec::new, |stack, &(_, x)| best_move(t, x, stack))
            .collect();
        let mut moves = Vec::with_capacity(found.len());
        for (m, &(_, x)) in found.into_iter().zip(&candidates) {
            match m {
                Some(m) => moves.push(m),
                None => settled[x as usize] = true,
            }
        }
        moves.sort_unstable_by(|a, b| b.gain.total_cmp(&a.gain).then(a.from.cmp(&b.from)));
        let mut gained = 0.0;
        // Gains below this are rounding, not improvement.
        let floor = area * 1e-9;
        for m in moves {
            let max_leaf_depth = MAX_DEPTH as u32 - 1;
            if let Some(g) = exact_gain(tree, m.from, m.to, max_leaf_depth, &mut marks)
                && g > floor
            {
                tree.move_next_to(m.from, m.to);
                gained += g;
                stats.moves += 1;
            }
        }
        let before = area;
        area -= gained;
        if gained < knobs.min_round_gain as f64 * before {
            break;
        }
    }
}

/// The `batch` unsettled nodes with the largest boxes, the root excluded (ties by id).
fn choose(t: &Tree, settled: &[bool], batch: usize, out: &mut Vec<(f64, u32)>) {
    out.clear();
    out.extend(
        (0..t.len() as u32)
            .filter(|&n| n != t.root && !settled[n as usize])
            .map(|n| (t.area(n), n)),
    );
    let larger_first = |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
    if batch < out.len() {
        out.select_nth_unstable_by(batch, larger_first);
        out.truncate(batch);
    }
    out.sort_unstable_by(larger_first);
}

#[cfg(test)]
mod tests;
