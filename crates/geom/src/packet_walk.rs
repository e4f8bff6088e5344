//! Which packet walk a structure runs for coherent batches: sixteen rays a packet on AVX-512F
//! ([`packet`](crate::packet)), eight on AVX2 ([`packet8`](crate::packet8)). The wide BVH and
//! the k-d tree both pick their walk with it, so they pick alike on every CPU.

use crate::packet::{Avx512Packets, PACKET};
use crate::packet8::{Avx2Packets, LANES};

/// A packet walk this CPU runs, with the proof of its instruction set.
#[derive(Clone, Copy, Debug)]
pub enum PacketWalk {
    Avx512(Avx512Packets),
    Avx2(Avx2Packets),
}

impl PacketWalk {
    /// The widest walk this CPU runs; eight lanes when `sixteen` is false, so a CPU with
    /// AVX-512 can run (and test) the AVX2 walk too. `None` without AVX2.
    pub fn detect(sixteen: bool) -> Option<PacketWalk> {
        sixteen
            .then(Avx512Packets::detect)
            .flatten()
            .map(PacketWalk::Avx512)
            .or_else(|| Avx2Packets::detect().map(PacketWalk::Avx2))
    }

    /// The rays of one packet.
    pub fn lanes(self) -> usize {
        match self {
            PacketWalk::Avx512(_) => PACKET,
            PacketWalk::Avx2(_) => LANES,
        }
    }
}
