//! Adversarial scenes: being written (issue 3); registered so the table is complete.

use super::{GeneratorInfo, triangles};

macro_rules! pending {
    ($c:ident, $n:literal) => {
        pub(super) const $c: GeneratorInfo = GeneratorInfo {
            name: $n,
            description: "(being written)",
            params: &[triangles("approximate triangle count", 1000.0)],
            uses_seed: true,
            build: |_, _| Err(concat!($n, " is not written yet").into()),
        };
    };
}
pending!(ONE_CENTROID, "one-centroid");
pending!(COPLANAR, "coplanar");
pending!(OFFSET, "offset");
pending!(ZERO_AREA_MIXED, "zero-area-mixed");
pending!(SINGLE_TRIANGLE, "single-triangle");
pending!(EMPTY, "empty");
