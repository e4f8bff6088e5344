//! `terrain`: being written (issue 3); registered so the table is complete.

use super::{GeneratorInfo, triangles};

pub(super) const TERRAIN: GeneratorInfo = GeneratorInfo {
    name: "terrain",
    description: "(being written)",
    params: &[triangles("approximate triangle count", 10_000.0)],
    uses_seed: true,
    build: |_, _| Err("terrain is not written yet".into()),
};
