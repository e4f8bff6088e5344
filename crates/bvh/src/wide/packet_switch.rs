//! Whether a packet of a coherent batch is walked as a packet or its rays one by one
//! ([`Switch`]), and the loop over a batch's packets that asks it ([`each_packet`]): shared by
//! the sixteen-lane AVX-512 walk (`packets.rs`) and the eight-lane AVX2 walk (`packets8.rs`),
//! which decide alike from what their walks shared.

use super::avx2;
use crate::wide::BvhWide;
use raybench_geom::Ray;
use raybench_geom::packet::{PACKET, RayBlock, each_block};

/// Traces `blocks` (the packets of `rays`, the batch from ray `first` on) into `out`, a
/// block at a time: ray by ray through `single` where the [`Switch`] says so, else through
/// `packet`, which walks one block in packets of `LANES` rays and reports what its walk shared.
#[inline(always)]
pub(super) fn each_packet<const LANES: usize, const W: usize, T>(
    bvh: &BvhWide<W>,
    blocks: &[RayBlock],
    rays: &[Ray],
    first: usize,
    out: &mut [T],
    mut single: impl FnMut(avx2::Avx2Nodes, &[Ray], &mut [T]),
    mut packet: impl FnMut(&RayBlock, &mut [T], &mut Usage),
) {
    let mut switch = Switch::new(bvh, first, LANES);
    for (block, rays, out) in each_block(blocks, rays, out) {
        if let Some(k) = switch.ray_by_ray() {
            single(k, rays, out);
            continue;
        }
        let mut usage = Usage::default();
        packet(block, out, &mut usage);
        switch.walked(usage);
    }
}

/// Packets a window holds: the harness's chunk of 256 rays on several threads, so a window's
/// packets are decided alike whether the batch comes in one call or in chunks.
const WINDOW: usize = 256 / PACKET;

/// What a packet's walk shared among its rays: the nodes and `Tri4`s it visited, and the lanes
/// active at each visit, summed.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Usage {
    nodes: u32,
    node_lanes: u32,
    tri4s: u32,
    tri4_lanes: u32,
}

impl Usage {
    #[inline(always)]
    pub(super) fn node(&mut self, lanes: u16) {
        self.nodes += 1;
        self.node_lanes += lanes.count_ones();
    }

    #[inline(always)]
    pub(super) fn tri4s(&mut self, count: u32, lanes: u16) {
        self.tri4s += count;
        self.tri4_lanes += count * lanes.count_ones();
    }
}

/// Whether the next packet of a batch is walked as a packet or ray by ray
/// ([`PacketFloors`](crate::PacketFloors)): each window's first packet is walked as one, and
/// each packet so walked decides for the next. A packet's cost is per visit, whatever its
/// lanes; the rays' own walks cost per lane. So where few lanes share the nodes and few the
/// `Tri4`s (triangles smaller than the rays' spacing, rays spread by the surfaces they left),
/// the rays go faster alone. The floors are counted in rays of a sixteen-lane packet; a walk of
/// narrower packets, whose visits cost less, scales them to its width.
struct Switch {
    floors: crate::PacketFloors,
    /// The single-ray kernel, when some packets may be traced ray by ray.
    single: Option<avx2::Avx2Nodes>,
    /// The next packet's index in the whole batch.
    next: usize,
    packets: bool,
}

impl Switch {
    fn new<const W: usize>(bvh: &BvhWide<W>, first: usize, lanes: usize) -> Switch {
        let floors = bvh.params.packet_floors;
        let scale = lanes as f32 / PACKET as f32;
        Switch {
            floors: crate::PacketFloors {
                node: floors.node * scale,
                tri4: floors.tri4 * scale,
            },
            single: bvh.avx2.filter(|_| floors.node > 0.0 && floors.tri4 > 0.0),
            next: first / PACKET,
            packets: true,
        }
    }

    /// The single-ray kernel when the next packet is to be traced ray by ray.
    #[inline(always)]
    fn ray_by_ray(&mut self) -> Option<avx2::Avx2Nodes> {
        if self.next.is_multiple_of(WINDOW) {
            self.packets = true;
        }
        self.next += 1;
        self.single.filter(|_| !self.packets)
    }

    #[inline(always)]
    fn walked(&mut self, u: Usage) {
        self.packets = u.node_lanes as f32 >= self.floors.node * u.nodes as f32
            || u.tri4_lanes as f32 >= self.floors.tri4 * u.tri4s as f32;
    }
}
