//! The memory limit of our builds on this machine. Each of our builders estimates the memory it
//! needs before allocating and refuses past its `memory_limit_bytes` with "scene too large"
//! (an error in the report), where running out would get the process killed by the kernel and
//! lose the report. A fixed limit protects only a machine that has it: a grid over 200,000
//! copies of one triangle or a k-d tree over a million triangles sharing one centroid plans on
//! 8 GiB, which a CI runner or a laptop may not hold. So the built-in structures take the least
//! of their own limit and half of this machine's memory (its cgroup's limit where lower): the
//! rule the CLI's `--rays` and `--points` bounds follow, leaving the other half for the scene,
//! the rays and the scene's other structures, all alive at once in a run. Embree's entries take
//! the same limit through their device's memory monitor (`registry.rs`, `embree`).

use super::BuildContext;
use raybench_bvh::{BvhParams, WideParams};
use raybench_grid::{Grid2Params, GridParams, SkipGridParams};
use raybench_kdtree::KdParams;
use raybench_octree::OctreeParams;
use std::sync::OnceLock;

/// Half of this machine's memory (or of its cgroup's limit, where lower), at most the 8 GiB
/// every builder defaults to. Read once per process: the machine's memory does not change
/// during a run, and every build asks.
pub fn for_this_machine() -> u64 {
    static LIMIT: OnceLock<u64> = OnceLock::new();
    *LIMIT.get_or_init(|| (crate::memory::physical() / 2).min(BvhParams::MEMORY_LIMIT))
}

/// Parameters with a memory limit that a [`BuildContext`] may lower.
pub(super) trait MemoryLimited {
    /// These parameters with a limit no higher than `bytes`.
    fn at_most(self, bytes: u64) -> Self;
}

/// A registered structure's parameters with the run's memory limit applied.
pub(super) fn limited<P: MemoryLimited>(
    params: impl Fn(&BuildContext) -> P + Send + Sync,
) -> impl Fn(&BuildContext) -> P + Send + Sync {
    move |ctx| params(ctx).at_most(ctx.memory_limit_bytes)
}

/// Implements [`MemoryLimited`] for parameter types, each with the path to its limit's field.
macro_rules! memory_limited {
    ($($ty:ty => $($field:ident).+;)*) => {$(
        impl MemoryLimited for $ty {
            fn at_most(mut self, bytes: u64) -> Self {
                self.$($field).+ = self.$($field).+.min(bytes);
                self
            }
        }
    )*};
}

memory_limited! {
    BvhParams => memory_limit_bytes;
    WideParams => binary.memory_limit_bytes;
    KdParams => memory_limit_bytes;
    GridParams => memory_limit_bytes;
    SkipGridParams => grid.memory_limit_bytes;
    Grid2Params => memory_limit_bytes;
    OctreeParams => memory_limit_bytes;
}
