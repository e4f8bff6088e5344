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
