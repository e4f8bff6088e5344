//! raybench-harness: runs suites of scenes × structures × workloads, times builds and traces,
//! validates every ray against a reference, and writes `report.json`.
#![forbid(unsafe_code)]

pub mod agreement;
pub mod atomic;
pub mod cli;
pub mod compare;
pub mod dump;
pub mod env;
pub mod images;
pub mod measure;
pub mod registry;
pub mod render;
pub mod replay;
pub mod report;
pub mod run;
pub mod scene_cmd;
pub mod summary;
pub mod validate;
pub mod verify;
pub mod watertight;
