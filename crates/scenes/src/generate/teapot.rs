//! `teapot`: being written (issue 3); registered so the table is complete.

use super::{GeneratorInfo, triangles};

pub(super) const TEAPOT: GeneratorInfo = GeneratorInfo {
    name: "teapot",
    description: "(being written)",
    params: &[triangles("approximate triangle count", 10_000.0)],
    uses_seed: true,
    build: |_, _| Err("teapot is not written yet".into()),
};
