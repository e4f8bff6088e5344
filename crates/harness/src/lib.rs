//! raybench-harness: runs suites of scenes × structures × workloads, times builds and traces,
//! checks every answer against a reference, and writes `report.json`.
//!
//! Four rooms: [`cli`] (one module per `raybench` subcommand), [`pipeline`] (the measurement
//! machinery: workers, scenes, workloads, timing, checking, dumps), [`report`] (the schema of
//! each report kind, reading and writing it, and the diff of two reports) and [`output`] (what
//! is shown to people: tables, the results page, charts, pictures and the HTML page).
#![forbid(unsafe_code)]

pub mod atomic;
pub mod cli;
pub mod env;
pub mod interrupt;
pub mod memory;
pub mod outdir;
pub mod output;
#[cfg(feature = "peers")]
pub mod peers;
pub mod pipeline;
pub mod registry;
pub mod report;

pub use registry::Registry;
