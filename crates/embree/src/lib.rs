//! raybench-embree: Intel Embree 3 behind raybench's [`Accel`](raybench_accel::Accel) trait.
//!
//! * [`Device`]: one `RTCDevice` per explicit config string, shared through
//!   [`Device::shared`], with an error callback and a memory monitor; [`Device::info`] gives
//!   the [`EmbreeInfo`] a report records.
//! * [`EmbreeScene`]: a committed scene over one triangle mesh, built with [`EmbreeParams`]
//!   (presets `low`, `medium`, `high`, `robust`).
//! * [`fpu`]: the calling thread's FTZ/DAZ state, which the harness sets alike on every worker.
//!
//! Every Embree handle has exactly one owner and is released on drop; every `unsafe` block
//! says why it is sound. Debian's Embree aborts the process on invalid rays, so no ray reaches
//! it without passing `Ray::check`.

mod device;
mod error;
pub mod fpu;
mod info;
mod packet16;
mod params;
mod point;
mod rays;
mod scene;

pub use device::Device;
pub use error::{EmbreeError, InvalidRay};
pub use info::{EmbreeInfo, ISA_CAPPED, ISA_FROM_CONFIG, ISA_INFERRED, infer_isa};
pub use params::{EmbreeParams, Quality};
pub use raybench_embree_sys as sys;
pub use rays::PreparedEmbreeRays;
pub use scene::EmbreeScene;
