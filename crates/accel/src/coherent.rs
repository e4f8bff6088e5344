//! The prepared form of a coherent batch for structures that trace it in packets of sixteen
//! rays ([`raybench_geom::packet::RayPackets`]): made by `prepare_coherent_rays`, found again
//! by `intersect_prepared`.

use crate::PreparedRays;
use raybench_geom::Ray;
use raybench_geom::packet::{RayBlock, RayPackets};

/// `rays` as packets, for [`crate::Accel::prepare_coherent_rays`].
pub fn prepare_packets(rays: &[Ray]) -> PreparedRays {
    PreparedRays::Foreign(Box::new(RayPackets::new(rays)))
}

/// The packets of rays `first .. first + len` when `prepared` came from [`prepare_packets`] and
/// `first` starts a packet; `None` otherwise (the caller walks ray by ray).
pub fn packet_blocks(prepared: &PreparedRays, first: usize, len: usize) -> Option<&[RayBlock]> {
    match prepared {
        PreparedRays::Foreign(any) => any.downcast_ref::<RayPackets>()?.range(first, len),
        PreparedRays::Native => None,
    }
}
