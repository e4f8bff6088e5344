//! `hair`: being written (issue 3); registered so the table is complete.

use super::{GeneratorInfo, triangles};

pub(super) const HAIR: GeneratorInfo = GeneratorInfo {
    name: "hair",
    description: "(being written)",
    params: &[triangles("approximate triangle count", 10_000.0)],
    uses_seed: true,
    build: |_, _| Err("hair is not written yet".into()),
};
