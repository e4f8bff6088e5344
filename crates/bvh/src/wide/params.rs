//! The knobs of a wide BVH.

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
    /// AVX2 when the CPU has it, never AVX-512's registers: the same arithmetic as `Auto`,
    /// for comparing the two batch loops; packets (`coherent_packets`) of eight rays.
    Avx2,
    /// 4-lane SSE: one pass per axis and four children, one `Tri4` (four triangles) a pass
    /// (the x86-64 baseline; portable code elsewhere).
    Sse,
}

/// How a wide node stores its children's boxes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NodeFormat {
    /// Six f32 planes per child: 8 wide, 256 bytes a node ([`Bvh8`](super::Bvh8)).
    #[default]
    Float,
    /// One byte per plane on a per-node grid, rounded outward: 8 wide, 128 bytes a node
    /// ([`Bvh8Compressed`](super::Bvh8Compressed), the registry's `bvh8-compressed`).
    Quantized,
    /// Two bytes per plane, the same rounding: 8 wide, 192 bytes a node
    /// ([`Bvh8Compressed16`](super::Bvh8Compressed16), the registry's `bvh8-compressed16`).
    Quantized16,
}

/// How the binary tree's nodes are grouped into wide nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Collapse {
    /// Each wide node opens its largest child until it is full (`collapse.rs`).
    Greedy,
    /// Each wide node's children chosen for the least SAH cost of the whole wide tree, by
    /// dynamic programming over the binary tree (`optimal.rs`).
    #[default]
    Optimal,
}

/// Knobs of a wide BVH: the binary tree it is collapsed from, the node width and the node
/// test.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WideParams {
    pub binary: BvhParams,
    /// Children per node: 8 ([`Bvh8`](super::Bvh8)) or 4 ([`Bvh4`](super::Bvh4)); a tree is
    /// built only with its own.
    pub width: u32,
    /// The kernels: with AVX2, 8-wide nodes take one 8-lane pass per axis (4-wide ones keep
    /// one 4-lane pass) and leaves are tested two `Tri4`s a pass.
    pub node_simd: NodeSimd,
    /// How binary nodes are grouped into wide nodes.
    pub collapse: Collapse,
    /// Split leaves of more than one `Tri4` into the slots a node would leave empty (see
    /// `collapse.rs`); off, the wide tree has exactly the binary tree's leaves.
    pub fill_slots: bool,
    /// Batches prepared as coherent (`Accel::prepare_coherent_rays`: the primary and shadow
    /// rays) are traced for closest or any hit sixteen rays at a time, one per AVX-512 lane
    /// (`packets.rs`), when the CPU has AVX-512F, else eight at a time, one per AVX2 lane
    /// (`packets8.rs`; also with `NodeSimd::Avx2`); every other batch, and every batch
    /// without AVX2, ray by ray. The registry's `bvh8-packets`.
    pub coherent_packets: bool,
    /// With `coherent_packets`: when a packet is worth walking as one (else its rays are traced
    /// ray by ray). Off by default: every packet is walked as one.
    pub packet_floors: PacketFloors,
    /// The node format; each tree type is built only with its own.
    pub node_format: NodeFormat,
}

/// When the packet walk hands packets to the single-ray walk. A batch is taken in windows of
/// sixteen packets (256 rays, the harness's chunk on several threads, so the decisions are the
/// same on any number of threads). Each window's first packet is walked as a packet; each
/// packet walked as one decides for the next: it stays a packet while its walk carried, on
/// average, at least `node` rays per node visited or at least `tri4` rays per `Tri4` tested;
/// else the window's remaining packets go ray by ray. Zero in either field walks every packet
/// as one, and so does a tree without the AVX2 kernels (`node_simd = sse`): packets are handed
/// to the AVX2 single-ray loops. The floors count rays of a sixteen-lane packet; the eight-lane
/// walk (AVX2 without AVX-512F) scales them to its width, so [`PacketFloors::MEASURED`] walks
/// every packet there (a floor of one ray a `Tri4` always holds).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PacketFloors {
    pub node: f32,
    pub tri4: f32,
}

impl PacketFloors {
    /// Every packet walked as one.
    pub const OFF: PacketFloors = PacketFloors {
        node: 0.0,
        tri4: 0.0,
    };
    /// The registry's packet entries: measured over generated and real scenes (see
    /// docs/experiments.md, "packets handed to the single-ray walk by window").
    pub const MEASURED: PacketFloors = PacketFloors {
        node: 6.0,
        tri4: 2.0,
    };
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

impl WideParams {
    /// The 8-wide defaults over a binary tree built with spatial splits (`bvh8-sbvh`).
    pub fn sbvh() -> WideParams {
        let mut p = WideParams::for_width(8);
        p.binary.spatial_splits = Some(crate::SpatialSplits::default());
        // The Split BVH keeps the exact bounds: with the box's bounds its SAH cost rose on
        // some scenes (the tilted plane of the held-out suite by 6 %; docs/experiments.md,
        // "centroid bounds from the children's boxes").
        p.binary.centroids_from_boxes = None;
        p
    }
}

impl Default for WideParams {
    fn default() -> Self {
        WideParams {
            binary: BvhParams {
                // Twice bvh-binned's 32: measured, see docs/experiments.md, "64 bins".
                bins: 64,
                // Measured: see docs/experiments.md, "one bin per 4 triangles".
                triangles_per_bin: 4,
                // A leaf costs the `Tri4`s it fills.
                leaf_block: 4,
                // A triangle slot costs 0.15 of a wide node test, a `Tri4` 0.6: measured, see
                // docs/experiments.md, "0.15 per triangle slot".
                intersection_cost: 0.15,
                // Two `Tri4`s, one AVX2 leaf pass: measured, see docs/experiments.md, "leaves of
                // at most 8 triangles instead of 16 (with slots filled)".
                max_leaf_size: 8,
                // One pass fewer per node of 256 triangles or more, for trees whose SAH cost
                // moves by a few tenths of a per cent: measured, see docs/experiments.md,
                // "centroid bounds from the children's boxes".
                centroids_from_boxes: Some(256),
                ..BvhParams::binned()
            },
            width: 8,
            node_simd: NodeSimd::Auto,
            // Measured: see docs/experiments.md, "SAH-optimal collapse".
            collapse: Collapse::Optimal,
            fill_slots: true,
            coherent_packets: false,
            packet_floors: PacketFloors::OFF,
            node_format: NodeFormat::Float,
        }
    }
}
