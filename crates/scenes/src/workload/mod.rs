//! Workloads. Each is a pure function of its inputs and seed.
//!
//! [`Workload`] names every workload a run can ask for: five ray workloads (this module) and two
//! closest-point workloads ([`crate::points`]), so the CLI, suite manifests and reports take
//! one list. Code that only makes sense for rays asks [`Workload::is_point_query`] first.
//!
//! Ray workloads: primary and random rays come from the view and the bounds ([`primary`]);
//! shadow and diffuse rays start at the surfaces the primary rays hit ([`secondary`]); Whitted
//! rays recurse from those hits by reflection and refraction ([`whitted`]).

mod primary;
mod secondary;
mod whitted;

pub use primary::{primary_rays, primary_rays_sized, random_rays};
pub use secondary::{
    SHADOW_T_MAX, SurfaceHit, SurfacePoint, diffuse_rays, shadow_rays, surface_point,
};
pub use whitted::{WhittedParams, whitted_children};

use crate::SceneError;
use crate::points::PointWorkload;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// What a batch of queries asks of a structure: rays, or closest points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Workload {
    Primary,
    Random,
    Shadow,
    Diffuse,
    Whitted,
    /// Closest point, points near the surface ([`PointWorkload::Near`]).
    #[serde(rename = "points-near")]
    PointsNear,
    /// Closest point, points in the enlarged box ([`PointWorkload::Volume`]).
    #[serde(rename = "points-volume")]
    PointsVolume,
}

impl Workload {
    /// The ray workloads.
    pub const RAYS: [Workload; 5] = [
        Workload::Primary,
        Workload::Random,
        Workload::Shadow,
        Workload::Diffuse,
        Workload::Whitted,
    ];

    /// The closest-point workloads.
    pub const POINTS: [Workload; 2] = [Workload::PointsNear, Workload::PointsVolume];

    /// Every workload: the rays, then the points.
    pub const ALL: [Workload; 7] = [
        Workload::Primary,
        Workload::Random,
        Workload::Shadow,
        Workload::Diffuse,
        Workload::Whitted,
        Workload::PointsNear,
        Workload::PointsVolume,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            Workload::Primary => "primary",
            Workload::Random => "random",
            Workload::Shadow => "shadow",
            Workload::Diffuse => "diffuse",
            Workload::Whitted => "whitted",
            Workload::PointsNear => PointWorkload::Near.name(),
            Workload::PointsVolume => PointWorkload::Volume.name(),
        }
    }

    /// The closest-point workload this is, if it is one.
    pub fn point_workload(&self) -> Option<PointWorkload> {
        match self {
            Workload::PointsNear => Some(PointWorkload::Near),
            Workload::PointsVolume => Some(PointWorkload::Volume),
            _ => None,
        }
    }

    /// True for closest-point workloads (points, not rays).
    pub fn is_point_query(&self) -> bool {
        self.point_workload().is_some()
    }

    /// True when the query is "is anything in the way" (`occluded`), not the closest hit.
    pub fn any_hit(&self) -> bool {
        matches!(self, Workload::Shadow)
    }

    /// True when consecutive rays are coherent: the batch is prepared with
    /// `Accel::prepare_coherent_rays`, so structures may trace it in packets. Camera rays in
    /// scanline order are; so are shadow rays, which start at those rays' hits in the same
    /// order and all end at one light (a pixel that gives no shadow ray only closes the gap
    /// between its neighbours).
    pub fn coherent(&self) -> bool {
        matches!(self, Workload::Primary | Workload::Shadow)
    }

    /// True when the rays start at the primary rays' hits.
    pub fn from_hits(&self) -> bool {
        matches!(
            self,
            Workload::Shadow | Workload::Diffuse | Workload::Whitted
        )
    }

    pub fn description(&self) -> &'static str {
        match self {
            Workload::Primary => {
                "camera rays through pixel centres: coherent, closest hit (ray casting)"
            }
            Workload::Random => {
                "origins uniform in the scene box enlarged by 5% per side, directions uniform on the sphere: incoherent, closest hit"
            }
            Workload::Shadow => {
                "from each primary hit that faces the light towards the light, ending just before it, in pixel order: coherent, any hit (occlusion)"
            }
            Workload::Diffuse => {
                "from each primary hit, cosine-weighted over the facing hemisphere: incoherent, closest hit (path tracing bounce)"
            }
            Workload::Whitted => {
                "Whitted's recursion from primary hits: mirror reflections, and refractions through transparent materials, until a maximum depth or a minimum contribution: closest hit"
            }
            Workload::PointsNear | Workload::PointsVolume => {
                self.point_workload().map_or("", |p| p.description())
            }
        }
    }
}

impl fmt::Display for Workload {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Workload {
    type Err = SceneError;

    /// Case-insensitive workload name.
    fn from_str(s: &str) -> Result<Workload, SceneError> {
        Workload::ALL
            .into_iter()
            .find(|w| w.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| SceneError::UnknownWorkload { name: s.to_owned() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workload_names_round_trip() {
        for w in Workload::ALL {
            assert_eq!(w.name().parse::<Workload>().unwrap(), w);
            assert_eq!(w.name().to_uppercase().parse::<Workload>().unwrap(), w);
            assert_eq!(
                serde_json::to_string(&w).unwrap(),
                format!("\"{}\"", w.name())
            );
        }
        let err = "glossy".parse::<Workload>().unwrap_err().to_string();
        assert!(err.contains("glossy") && err.contains("diffuse"), "{err}");
        let points: Vec<Workload> = Workload::ALL
            .into_iter()
            .filter(Workload::is_point_query)
            .collect();
        assert_eq!(points, Workload::POINTS);
        assert!(Workload::RAYS.iter().all(|w| w.point_workload().is_none()));
        assert_eq!(
            Workload::PointsVolume.point_workload(),
            Some(PointWorkload::Volume)
        );
    }
}
