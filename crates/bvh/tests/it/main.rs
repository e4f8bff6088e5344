//! The bvh crate's integration tests in one binary, a module per file: the walks, generic over
//! the node width and kernel, are compiled once for all of them instead of once per binary.

mod conformance;
mod packet_floors;
mod packets8;
mod packets_any_hit;
mod packets_frustum;
mod quantized;
mod reinsert;
mod sbvh;

/// Runs `f` in a rayon pool of `threads` workers, as the builds under test would run in an
/// application's pool: the tests that a tree does not depend on the thread count use it.
fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}
