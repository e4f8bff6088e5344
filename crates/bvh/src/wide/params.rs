//! The knobs of a wide BVH.

use super::MAX_WIDTH;
use crate::BvhParams;
use serde::Serialize;

/// Which instructions test a wide node and its leaves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NodeSimd {
    /// AVX2 when the CPU has it (run-time detection), SSE otherwise; the batch loops with
    /// AVX-512VL's 32 registers when the CPU has AVX-512F and VL too.
    #[default]
    Auto,
    /// AVX2 when the CPU has it, never AVX-512 (the kernels as they were before `Auto` used
    /// AVX-512's registers, for comparison).
    Avx2,
    /// 4-lane SSE: one pass per axis and four children, one `Tri4` (four triangles) a pass
    /// (the x86-64 baseline; portable code elsewhere).
    Sse,
}

/// Knobs of a wide BVH: the binary tree it is collapsed from, the node width and the node
/// test.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WideParams {
    pub binary: BvhParams,
    /// Children per node: 8 ([`Bvh8`]) or 4 ([`Bvh4`]); a tree is built only with its own.
    pub width: u32,
    /// The kernels: with AVX2, 8-wide nodes take one 8-lane pass per axis (4-wide ones keep
    /// one 4-lane pass) and leaves are tested two `Tri4`s a pass.
    pub node_simd: NodeSimd,
    /// Split leaves of more than one `Tri4` into the slots a node would leave empty (see
    /// [`collapse`]); off, the wide tree has exactly the binary tree's leaves.
    pub fill_slots: bool,
    /// Batches prepared as coherent (`Accel::prepare_coherent_rays`: the primary rays) are
    /// traced for closest hit sixteen rays at a time, one per AVX-512 lane ([`super::packets`]),
    /// when the CPU has AVX-512F; every other batch, and every batch without AVX-512, ray by
    /// ray. The registry's `bvh8-packets`.
    pub coherent_packets: bool,
}

impl WideParams {
    /// The defaults for nodes of `width` children.
    pub fn for_width(width: u32) -> WideParams {
        WideParams {
            width,
            ..WideParams::default()
        }
    }
}

impl Default for WideParams {
    fn default() -> Self {
        WideParams {
            // 0.15 per triangle slot: a packet of four costs 0.6 of a wide node test. Embree's
            // BVH8 builder prices a packet like one node test (0.25 here), which was 2–7 %
            // faster than 1 and 8; since the AVX2 leaf test takes two packets a pass, larger
            // leaves pay. Over the 17 scenes of the default suite, against 0.25 (geometric
            // means of best-of-6 passes interleaved in one process, this VM, 2026-11-21):
            // 0.15 primary +3.2 %, random +3.4 %, shadow +2.4 %; 0.125 +2.2–2.9 / +2.6–2.9 /
            // +1.0–1.4 % (two sweeps); 0.1 and 0.18 less; a leaf cap of 12 nothing. Below 0.15
            // the SAH cost with the shared constants (which price every triangle alike)
            // exceeds bvh-binned's on the bunny and the dragon (0.125: 33.4 against 31.3;
            // 0.15: 30.5).
            //
            // Leaves of at most 8 triangles (two packets, one AVX2 leaf pass): with 16, the
            // SAH could stop early where triangles overlap, and on soup and hair the tree's
            // SAH cost with the shared constants came out above bvh-binned's (553.0 against
            // 454.1, 9,658.5 against 9,032.7), which issue 8 rules out. With 8 the 8-wide tree
            // is below bvh-binned on all 17 default scenes (soup 401.9, hair 8,688.9; the
            // bunny 22.5 → 18.7). The price, over the 17 scenes against 16 (best of 6 passes
            // interleaved with embree-medium, this VM, 2026-11-22): primary −1.4 % single-ray
            // and −0.4 % in packets, random −3.0 %, shadow −2.5 %.
            //
            // 64 bins, not bvh-binned's 32: over the 17 default scenes, best of 10 passes
            // interleaved in one process (this VM, 2026-11-21), primary +2.1 % and +1.6 %,
            // random +0.9 % and -0.8 %, shadow +1.8 % and -0.4 % in two sweeps; the steady
            // part is the teapot in the stadium's close-up, +14-17 % on primary rays (its
            // 219,956 centroids spread over the stadium leave the teapot in one bin of 32 for
            // more levels). 128 and 256 bins gained no more.
            //
            // One bin per 4 triangles in a node (bvh-binned keeps one per triangle): the sweep
            // over the boundaries costs per bin, the binning per triangle, and below 256
            // triangles the bins were most of a small node's work. Over the 17 default scenes
            // against one per triangle (best of 6 passes interleaved with embree-medium, two
            // sweeps with the roles swapped, this VM, 2026-11-22): primary −0.4 %, random
            // −0.5 %, shadow −1.0 %, about the noise; one per 8 lost 1.5–2.1 %. The build ran
            // 24 % fewer instructions on the bunny (callgrind; one per 8: 28 %). The SAH cost
            // with the shared constants fell on 13 of the 16 meshes, stayed on the plane and
            // rose on Sibenik (32.14 → 32.24) and hair (8,688.9 → 8,835.1), both still below
            // bvh-binned (47.15, 9,032.7).
            binary: BvhParams {
                bins: 64,
                triangles_per_bin: 4,
                leaf_block: 4,
                intersection_cost: 0.15,
                max_leaf_size: 8,
                ..BvhParams::binned()
            },
            width: MAX_WIDTH as u32,
            node_simd: NodeSimd::Auto,
            fill_slots: true,
            coherent_packets: false,
        }
    }
}
