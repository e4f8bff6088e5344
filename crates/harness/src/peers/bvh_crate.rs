//! `peer-bvh`: svenstaro's `bvh` crate (0.13, MIT), the default binary BVH of the Rust
//! ecosystem. Its builder (binned SAH over the shapes' boxes, single-threaded `Bvh::build` so
//! the tree does not depend on the thread count) sees one shape per triangle. A ray query with
//! `traverse_iterator` yields every shape whose box the ray's line crosses, unordered and with
//! no early exit; the crate's own `Ray::intersects_triangle` culls back faces, so each candidate
//! is finished with raybench's two-sided Möller–Trumbore instead. Closest point uses the
//! crate's `nearest_to` with raybench's exact point–triangle distance. Caveat: the crate's ray
//! ignores the query's `[t_min, t_max]` segment while walking, so every box along the whole
//! line is visited.

use super::{any_among, closest_among, moller_triangles, point_answer};
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::{Bvh, BvhNode};
use bvh::point_query::PointDistance;
use nalgebra::{Point3, Vector3};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory, PointHit};
use raybench_geom::{MollerTriangle, Ray, Triangle, TriangleMesh, Vec3, closest_point_on_triangle};
use serde::Serialize;
use std::sync::Arc;

/// No knobs: the crate's default build (`Bvh::build`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct BvhCrateParams {}

/// One triangle as the crate's builder sees it: its box, its mesh index, and the node index
/// the crate writes back.
#[derive(Debug)]
struct Shape {
    tri: Triangle,
    prim: usize,
    node: usize,
}

fn p3(v: Vec3) -> Point3<f32> {
    Point3::new(v.x, v.y, v.z)
}

impl Bounded<f32, 3> for Shape {
    fn aabb(&self) -> Aabb<f32, 3> {
        let t = &self.tri;
        Aabb::with_bounds(p3(t.v0.min(t.v1).min(t.v2)), p3(t.v0.max(t.v1).max(t.v2)))
    }
}

impl BHShape<f32, 3> for Shape {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

impl PointDistance<f32, 3> for Shape {
    fn distance_squared(&self, q: Point3<f32>) -> f32 {
        let q = Vec3::new(q.x, q.y, q.z);
        closest_point_on_triangle(q, &self.tri).distance_squared(q)
    }
}

#[derive(Debug)]
pub struct BvhCrate {
    mesh: Arc<TriangleMesh>,
    tris: Vec<MollerTriangle>,
    shapes: Vec<Shape>,
    bvh: Bvh<f32, 3>,
}

impl BvhCrate {
    fn crate_ray(ray: &Ray) -> bvh::ray::Ray<f32, 3> {
        let (o, d) = (ray.origin(), ray.dir());
        bvh::ray::Ray::new(p3(o), Vector3::new(d.x, d.y, d.z))
    }
}

impl Accel for BvhCrate {
    type Params = BvhCrateParams;

    fn build(mesh: Arc<TriangleMesh>, _params: &BvhCrateParams) -> Result<Self, BuildError> {
        let mut shapes: Vec<Shape> = mesh
            .triangles()
            .enumerate()
            .map(|(prim, tri)| Shape { tri, prim, node: 0 })
            .collect();
        let bvh = Bvh::build(&mut shapes);
        Ok(BvhCrate {
            tris: moller_triangles(&mesh),
            mesh,
            shapes,
            bvh,
        })
    }

    fn name(&self) -> &str {
        "peer-bvh"
    }

    raybench_accel::uncounted_queries!();

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let r = Self::crate_ray(ray);
        let it = self.bvh.traverse_iterator(&r, &self.shapes).map(|s| s.prim);
        closest_among(&self.tris, ray, it)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let r = Self::crate_ray(ray);
        let it = self.bvh.traverse_iterator(&r, &self.shapes).map(|s| s.prim);
        any_among(&self.tris, ray, it)
    }

    fn closest_point(&self, p: Vec3, max_radius: f32) -> Option<PointHit> {
        let found = self
            .bvh
            .nearest_to(p3(p), &self.shapes)
            .map(|(s, _)| s.prim);
        point_answer(&self.mesh, p, max_radius, found)
    }

    fn build_stats(&self) -> BuildStats {
        let leaves = self
            .bvh
            .nodes
            .iter()
            .filter(|n| matches!(n, BvhNode::Leaf { .. }))
            .count() as u64;
        BuildStats {
            nodes: self.bvh.nodes.len() as u64,
            leaves,
            refs: leaves,
            ..BuildStats::default()
        }
    }

    /// From the crate's own vectors: its node array, plus the shape array it indexes (one
    /// triangle, index and node slot each).
    fn memory(&self) -> Memory {
        Memory {
            nodes: (self.bvh.nodes.len() * size_of::<BvhNode<f32, 3>>()) as u64,
            indices: 0,
            primitives: (self.shapes.len() * size_of::<Shape>()) as u64,
        }
    }
}
