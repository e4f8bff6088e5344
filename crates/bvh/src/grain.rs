//! How finely the builders cut their work into rayon tasks.
//!
//! A fixed grain sized for large meshes (thousands of triangles a task) leaves a small mesh
//! with two or three tasks of unequal size, so one thread finishes early and waits while the
//! other builds the rest: on a 6,000-triangle teapot the second of two threads did about a
//! third of the binary build. With more than one thread, each phase therefore takes as its
//! grain a share of its whole ([`TASKS_PER_THREAD`] tasks' worth for each thread), never more
//! than the grain large meshes use and never less than a floor below which a task's fork,
//! allocations and copies cost more than its work. One thread keeps the large grain: there
//! finer tasks balance nothing and cost about 5 % of a small mesh's build. The grain decides
//! only which thread builds what, never what is built, so the trees are the same whatever it is
//! (the tests build with one and two threads and with tiny and huge thresholds).

/// Tasks a phase is cut into for each thread, where its ceiling allows: enough for two
/// threads to balance unequal subtrees.
const TASKS_PER_THREAD: usize = 16;

/// The grain of a phase over `total` items (triangles, nodes or `Tri4`s) on the current rayon
/// pool: `ceiling` on one thread, else a [`TASKS_PER_THREAD`]th of each thread's share, at
/// least `floor` and at most `ceiling` (which wins when the two cross, so a caller's small
/// ceiling is always honoured).
pub(crate) fn grain(total: usize, floor: usize, ceiling: usize) -> usize {
    share(total, rayon::current_num_threads(), floor, ceiling)
}

fn share(total: usize, threads: usize, floor: usize, ceiling: usize) -> usize {
    if threads <= 1 {
        return ceiling;
    }
    (total / (TASKS_PER_THREAD * threads))
        .max(floor)
        .min(ceiling)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_wholes_take_the_floor_and_large_ones_the_ceiling() {
        assert_eq!(share(6_000, 2, 256, 4096), 256);
        assert_eq!(share(32_000, 2, 256, 4096), 1_000);
        assert_eq!(share(32_000, 4, 256, 4096), 500);
        assert_eq!(share(1_000_000, 2, 256, 4096), 4096);
        assert_eq!(share(0, 2, 256, 4096), 256);
        // A ceiling under the floor (a test's tiny threshold) is honoured.
        assert_eq!(share(1_000_000, 2, 256, 16), 16);
    }

    #[test]
    fn one_thread_keeps_the_ceiling() {
        assert_eq!(share(6_000, 1, 256, 4096), 4096);
        assert_eq!(share(6_000, 1, 256, 16), 16);
    }
}
