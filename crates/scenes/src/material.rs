//! Surface properties used by the recursive `whitted` workload: how much light a surface
//! reflects and transmits, and its index of refraction.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Fraction of a ray's contribution carried by the mirror reflection (0 = none).
    pub reflectance: f32,
    /// Fraction carried by the refracted ray (0 = opaque).
    pub transmittance: f32,
    /// Index of refraction of the inside (the side the normal points away from).
    pub ior: f32,
}

impl Material {
    /// Every surface of a scene that says nothing else: a weak mirror, as in Whitted's
    /// images, so reflection chains end after a few bounces (0.2^3 < 0.01).
    pub const DEFAULT: Material = Material {
        reflectance: 0.2,
        transmittance: 0.0,
        ior: 1.0,
    };
    /// A strong mirror.
    pub const MIRROR: Material = Material {
        reflectance: 0.9,
        transmittance: 0.0,
        ior: 1.0,
    };
    /// Clear glass: mostly transmitted, some reflected.
    pub const GLASS: Material = Material {
        reflectance: 0.1,
        transmittance: 0.85,
        ior: 1.5,
    };
    /// Opaque and matte: ends every reflection chain.
    pub const MATTE: Material = Material {
        reflectance: 0.0,
        transmittance: 0.0,
        ior: 1.0,
    };
}

impl Default for Material {
    fn default() -> Self {
        Material::DEFAULT
    }
}
