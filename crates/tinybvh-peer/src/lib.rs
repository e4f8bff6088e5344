//! raybench-tinybvh-peer: the tinybvh C++ library (Jacco Bikker, MIT, version 1.6.8 as bundled
//! by the `tinybvh-rs` 0.1.0-beta.3 crate, MIT) wrapped as raybench [`Accel`] peers. Two
//! layouts: the binary "Wald" BVH (32-byte nodes, scalar traversal, Möller–Trumbore per
//! triangle), built with binned SAH or SBVH ([`TinyBvh`]), and BVH8_CPU (Wald and Bikker's
//! 8-wide layout for AVX2: one node tests eight child boxes, leaves hold four triangles tested
//! four-wide; `TinyBvh8`), converted from the binned BVH through tinybvh's MBVH8. Everything
//! goes through tinybvh-rs's public API. Trade-off: tinybvh is compiled by tinybvh-rs's build
//! script with `-march=native`, so its speed and its very availability follow the build
//! machine ([`CXX_MARCH`]); BVH8_CPU's traversal is exposed by tinybvh-rs only when Rust itself
//! is compiled with AVX2 (`-C target-cpu=native`). Caveats, each answered here rather than
//! hidden: tinybvh has no any-hit query for these layouts (emulated with closest hit), no
//! `t_min` (see `ray`), no closest-point query, an absolute determinant threshold (|det| <
//! 1e-6 is a miss in the Wald layout's test), and it counts no work raybench can read.
//!
//! This crate holds the `unsafe` the harness (`forbid(unsafe_code)`) cannot: keeping the vertex
//! array beside the BVH that borrows it, declaring the wrappers `Send + Sync`, and nothing else.
//!
//! [`Accel`]: raybench_accel::Accel

mod accel_bvh8;
mod accel_wald;
mod build_mode;
mod ray;
mod validate;
mod wald;

pub use accel_bvh8::{BVH8_AVAILABLE, BVH8_UNAVAILABLE_REASON};
#[cfg(target_feature = "avx2")]
pub use accel_bvh8::{TinyBvh8, TinyBvh8Params};
pub use accel_wald::{TinyBvh, TinyBvhParams};
pub use build_mode::BuildMode;

/// What `-march=native` resolved to for the C++ compiler on the build machine (`c++ -march=native
/// -Q --help=target`): the ISA tinybvh was compiled for. g++ 12 reports Zen 4 as `znver3`, so
/// its C++ uses AVX2 and FMA but no AVX-512.
pub const CXX_MARCH: &str = env!("TINYBVH_CXX_MARCH");
