//! Rays aimed at a closed mesh's interior edges and vertices from outside, each a segment that
//! an f64 test confirms crosses the mesh, so that a miss is a crack.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::{DVec3, Ray, TriangleMesh, Vec3};
use std::collections::HashMap;

/// Minimum |cos| between a ray and every triangle around its aimed point: steep enough that the
/// crossing is not a graze, loose enough to cover many directions.
const MIN_COS: f64 = 0.25;

/// The segment ends this far past the aimed point, in units of its distance from the origin.
const T_MAX: f32 = 1.25;

/// Stream tag of the ray generator (ASCII, as in `raybench_scenes`' streams).
const WATERTIGHT_STREAM: u64 = u64::from_be_bytes(*b"wt-rays_");

/// Rays aimed at a mesh's edges and vertices, every one confirmed in f64 to cross it.
#[derive(Clone, Debug, Default)]
pub struct AimedRays {
    pub rays: Vec<Ray>,
    /// Per ray: aimed at a vertex (else at a point on an edge).
    pub at_vertex: Vec<bool>,
    pub dropped: usize,
}

impl AimedRays {
    pub fn vertex_rays(&self) -> usize {
        self.at_vertex.iter().filter(|&&v| v).count()
    }

    pub fn edge_rays(&self) -> usize {
        self.rays.len() - self.vertex_rays()
    }
}

/// Interior edges and vertices of a mesh, with the triangles around each.
struct Topology {
    /// (vertex a, vertex b, the two triangles sharing the edge)
    edges: Vec<(u32, u32, [u32; 2])>,
    /// (vertex, every triangle around it), for vertices whose every edge is interior.
    vertices: Vec<(u32, Vec<u32>)>,
}

impl Topology {
    fn of(mesh: &TriangleMesh) -> Topology {
        let mut by_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut around: HashMap<u32, Vec<u32>> = HashMap::new();
        for (prim, t) in mesh.indices().iter().enumerate() {
            if mesh.triangle(prim).area() == 0.0 {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(prim as u32);
                around.entry(t[k]).or_default().push(prim as u32);
            }
        }
        let interior = |a: u32, b: u32| {
            by_edge
                .get(&(a.min(b), a.max(b)))
                .is_some_and(|p| p.len() == 2)
        };
        let mut edges: Vec<(u32, u32, [u32; 2])> = by_edge
            .iter()
            .filter(|(_, p)| p.len() == 2)
            .map(|(&(a, b), p)| (a, b, [p[0], p[1]]))
            .collect();
        edges.sort_unstable();
        let mut vertices: Vec<(u32, Vec<u32>)> = around
            .into_iter()
            .filter(|(v, prims)| {
                prims.iter().all(|&p| {
                    let t = mesh.indices()[p as usize];
                    t.iter().all(|&w| w == *v || interior(*v, w))
                })
            })
            .collect();
        vertices.sort_unstable();
        Topology { edges, vertices }
    }
}

fn unit_f64(rng: &mut Pcg64Mcg) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

fn below(rng: &mut Pcg64Mcg, n: usize) -> usize {
    ((unit_f64(rng) * n as f64) as usize).min(n - 1)
}

fn unit_vector(rng: &mut Pcg64Mcg) -> DVec3 {
    let z = 1.0 - 2.0 * unit_f64(rng);
    let phi = std::f64::consts::TAU * unit_f64(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn unit_normal(mesh: &TriangleMesh, prim: u32) -> DVec3 {
    let t = mesh.triangle(prim as usize);
    let [a, b, c] = [t.v0, t.v1, t.v2].map(Vec3::as_dvec3);
    (b - a).cross(c - a).normalize()
}

/// A direction into the front of every triangle in `prims` (|cos| ≥ [`MIN_COS`] to each):
/// against their mean normal, tilted at random; `None` if no try qualifies.
fn inward_direction(mesh: &TriangleMesh, prims: &[u32], rng: &mut Pcg64Mcg) -> Option<DVec3> {
    let normals: Vec<DVec3> = prims.iter().map(|&p| unit_normal(mesh, p)).collect();
    let mean = normals.iter().copied().sum::<DVec3>().normalize_or_zero();
    let qualifies = |d: DVec3| normals.iter().all(|n| n.dot(d) <= -MIN_COS);
    (0..8)
        .map(|_| (-mean + unit_vector(rng) * 0.6).normalize_or_zero())
        .chain([-mean])
        .find(|&d| d != DVec3::ZERO && qualifies(d))
}

/// The segment from outside through `target` (reached at t = 1), `length` long before it.
/// The origin is rounded to f32 first and the direction is then the f64 difference rounded
/// once, so the ray passes within about one f32 ulp *of the direction* of the exact target,
/// however far from the origin the mesh is (rounding the target itself to f32 would move it
/// by an ulp of its coordinates: at 1e5, more than a thin triangle is wide).
fn segment_through(target: DVec3, dir: DVec3, length: f64) -> Ray {
    let origin = (target - dir * length).as_vec3();
    Ray::new(origin, (target - origin.as_dvec3()).as_vec3(), 0.0, T_MAX)
}

/// True when an f64 test finds the ray crossing one of `prims` inside its segment.
fn confirmed(mesh: &TriangleMesh, prims: &[u32], ray: &Ray) -> bool {
    prims.iter().any(|&p| {
        mesh.triangle(p as usize)
            .plane_crossing_f64(ray)
            .is_some_and(|x| x.edge_distance >= 0.0 && x.t > 0.0 && x.t <= T_MAX as f64)
    })
}

/// `n` rays aimed at interior edges (two in three) and vertices (one in three) from outside;
/// ray `i` draws from its own seeded stream, so the set does not depend on the thread count.
pub fn aimed_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> AimedRays {
    let topo = Topology::of(mesh);
    let length = 0.25 * mesh.bounds().extent().as_dvec3().length();
    let mut out = AimedRays::default();
    if topo.edges.is_empty() || length == 0.0 {
        out.dropped = n;
        return out;
    }
    for i in 0..n {
        let mut rng = Pcg64Mcg::seed_from_u64(
            seed ^ WATERTIGHT_STREAM ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let at_vertex = i % 3 == 2 && !topo.vertices.is_empty();
        let position = |v: u32| mesh.positions()[v as usize].as_dvec3();
        let (target, prims): (DVec3, &[u32]) = if at_vertex {
            let (v, prims) = &topo.vertices[below(&mut rng, topo.vertices.len())];
            (position(*v), prims)
        } else {
            let (a, b, prims) = &topo.edges[below(&mut rng, topo.edges.len())];
            let (a, b) = (position(*a), position(*b));
            (a + (b - a) * unit_f64(&mut rng), &prims[..])
        };
        let ray =
            inward_direction(mesh, prims, &mut rng).map(|d| segment_through(target, d, length));
        match ray {
            Some(r) if r.check().is_ok() && confirmed(mesh, prims, &r) => {
                out.rays.push(r);
                out.at_vertex.push(at_vertex);
            }
            _ => out.dropped += 1,
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::watertight::{EMBREE_POSITION, case_mesh};
    use crate::report::watertight::Case;
    use std::sync::Arc;

    fn sphere(shift: [f64; 3]) -> Arc<TriangleMesh> {
        let case = Case {
            name: "t".into(),
            spec: "offset:triangles=500,radius=2,offset=0".into(),
            shift,
        };
        case_mesh(&case, 1).unwrap()
    }

    #[test]
    fn every_sphere_edge_and_vertex_is_interior() {
        let mesh = sphere([0.0; 3]);
        let topo = Topology::of(&mesh);
        // A closed mesh: edges = 3/2 · triangles, and Euler: V - E + F = 2.
        assert_eq!(topo.edges.len() * 2, mesh.len() * 3);
        assert_eq!(topo.vertices.len() + mesh.len() - topo.edges.len(), 2);
    }

    #[test]
    fn aimed_rays_pass_through_their_target_and_are_confirmed() {
        let mesh = sphere(EMBREE_POSITION);
        let a = aimed_rays(&mesh, 300, 5);
        assert_eq!(a.rays.len() + a.dropped, 300);
        assert!(a.rays.len() > 250, "{a:?}");
        assert!(
            a.vertex_rays() > 60 && a.edge_rays() > 150,
            "{} {}",
            a.vertex_rays(),
            a.edge_rays()
        );
        for r in &a.rays {
            // Origin outside the radius-2 sphere, the segment stopping well short of its far side.
            let centre = DVec3::from_array(EMBREE_POSITION);
            let d = (r.origin().as_dvec3() - centre).length();
            assert!(d > 2.0, "origin {d} from the centre");
            assert_eq!(r.t_max(), T_MAX);
        }
        // Seeded: the same rays again.
        assert_eq!(aimed_rays(&mesh, 300, 5).rays, a.rays);
        assert_ne!(aimed_rays(&mesh, 300, 6).rays, a.rays);
    }
}
