use serde::{Deserialize, Serialize};
use std::ops::AddAssign;

/// Where a traversal reports its work. The timed path uses [`NoCount`] (zero-sized, every
/// method a no-op that the optimiser removes); the counted path uses [`Counters`].
pub trait CounterSink {
    fn node(&mut self);
    fn leaf(&mut self);
    fn prim_tests(&mut self, n: u64);
    fn cell(&mut self);
    fn mailbox_skip(&mut self);
    fn jump(&mut self);
}

/// The non-counting sink.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoCount;

impl CounterSink for NoCount {
    #[inline(always)]
    fn node(&mut self) {}
    #[inline(always)]
    fn leaf(&mut self) {}
    #[inline(always)]
    fn prim_tests(&mut self, _n: u64) {}
    #[inline(always)]
    fn cell(&mut self) {}
    #[inline(always)]
    fn mailbox_skip(&mut self) {}
    #[inline(always)]
    fn jump(&mut self) {}
}

/// Algorithmic work of one or more queries: deterministic, so an exact regression signal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    /// Interior nodes visited (a wide node counts once).
    pub nodes: u64,
    /// Leaves visited.
    pub leaves: u64,
    /// Ray–triangle tests performed.
    pub prim_tests: u64,
    /// Grid cells stepped through.
    pub cells: u64,
    /// Triangle tests skipped because the mailbox had seen the triangle.
    pub mailbox_skips: u64,
    /// Jumps over blocks of empty cells (`grid-skip`); the cells jumped over are not in
    /// `cells`. Absent in reports written before it existed: 0.
    #[serde(default)]
    pub jumps: u64,
}

impl CounterSink for Counters {
    #[inline(always)]
    fn node(&mut self) {
        self.nodes += 1;
    }
    #[inline(always)]
    fn leaf(&mut self) {
        self.leaves += 1;
    }
    #[inline(always)]
    fn prim_tests(&mut self, n: u64) {
        self.prim_tests += n;
    }
    #[inline(always)]
    fn cell(&mut self) {
        self.cells += 1;
    }
    #[inline(always)]
    fn mailbox_skip(&mut self) {
        self.mailbox_skips += 1;
    }
    #[inline(always)]
    fn jump(&mut self) {
        self.jumps += 1;
    }
}

impl AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.nodes += o.nodes;
        self.leaves += o.leaves;
        self.prim_tests += o.prim_tests;
        self.cells += o.cells;
        self.mailbox_skips += o.mailbox_skips;
        self.jumps += o.jumps;
    }
}
