//! `teapot-in-stadium`: being written (issue 3); registered so the table is complete.

use super::{GeneratorInfo, triangles};

pub(super) const TEAPOT_IN_STADIUM: GeneratorInfo = GeneratorInfo {
    name: "teapot-in-stadium",
    description: "(being written)",
    params: &[triangles("approximate triangle count", 10_000.0)],
    uses_seed: true,
    build: |_, _| Err("teapot-in-stadium is not written yet".into()),
};
