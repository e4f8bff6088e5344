//! The measurement machinery the measuring commands share: the worker pool, the scenes, the
//! workloads and the reference's answers, timing, checking every answer, the per-pixel
//! pictures and the hit dumps; then one module per command that measures (`run`, `verify`,
//! `watertight`, `replay`).

pub mod check;
pub mod dump;
pub mod images;
pub mod measure;
pub mod picture;
pub mod picture_set;
pub mod replay;
mod rounds;
pub mod run;
pub mod scenes;
pub mod verify;
pub mod watertight;
pub mod workers;
pub mod workloads;
