//! The lattice scene and its rays, for space-partitioning structures: the cube [0, 4]³, whose
//! grid cells of side 0.5 and octree or k-d split planes at dyadic positions fall on multiples
//! of 0.5, with triangles lying exactly on such planes and rays along them.

use crate::Validator;
use crate::cases::Case;
use crate::check::check_case;
use crate::rays::{centred_direction, seeded_rng, unit_f32};
use raybench_accel::Accel;
use raybench_accel::classify::VerdictCounts;
use raybench_geom::{Ray, Triangle, TriangleMesh, Vec3};
use std::sync::Arc;

/// The scene [`crate::lattice_rays`] is made for: bounds exactly [0, 4]³, so grid cells of side
/// 0.5 and octree or k-d split planes at dyadic positions fall on multiples of 0.5; triangles
/// lying exactly on such planes (z = 2, x = 1, y = 3: docs/validation.md, G11), a seeded soup,
/// and a big slanted triangle whose hits lie beyond the current cell (docs/validation.md, B11).
pub fn lattice_scene() -> Arc<TriangleMesh> {
    let mut tris = vec![
        Triangle::new(
            Vec3::ZERO,
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
        ),
        Triangle::new(
            Vec3::splat(4.0),
            Vec3::new(3.9, 4.0, 4.0),
            Vec3::new(4.0, 3.9, 4.0),
        ),
        Triangle::new(
            Vec3::new(0.5, 0.5, 2.0),
            Vec3::new(3.5, 0.5, 2.0),
            Vec3::new(0.5, 3.5, 2.0),
        ),
        Triangle::new(
            Vec3::new(1.0, 0.5, 0.5),
            Vec3::new(1.0, 3.0, 0.5),
            Vec3::new(1.0, 0.5, 3.0),
        ),
        Triangle::new(
            Vec3::new(2.5, 3.0, 0.5),
            Vec3::new(3.5, 3.0, 0.5),
            Vec3::new(2.5, 3.0, 3.5),
        ),
        Triangle::new(
            Vec3::new(0.2, 0.3, 3.9),
            Vec3::new(3.9, 0.2, 0.1),
            Vec3::new(2.0, 3.9, 2.0),
        ),
    ];
    let mut rng = seeded_rng(0x5eed_6001);
    let mut f = move || unit_f32(&mut rng);
    for _ in 0..400 {
        let c = Vec3::new(f(), f(), f()) * 3.6 + 0.2;
        let mut v = || c + (Vec3::new(f(), f(), f()) - 0.5) * 0.3;
        tris.push(Triangle::new(v(), v(), v()));
    }
    Arc::new(TriangleMesh::from_triangles(&tris).unwrap().0)
}

/// Rays for space-partitioning structures over the cube [0, 4]³ cut at multiples of 0.5 (grid
/// cells, octants, split planes): along cell planes and edges and through cell corners,
/// axis-parallel with ±0 components, starting outside, inside, on planes and at vertices —
/// where an off-by-one in a cell walk or a strict comparison loses a hit.
pub fn lattice_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    let lines: Vec<f32> = (0..=8).map(|k| k as f32 * 0.5).collect();
    let signs = [(1.0f32, 0.0f32), (-1.0, -0.0)];
    for &a in &lines {
        for &b in &lines {
            for (s, z) in signs {
                // Along the z axis on the cell edge x = a, y = b: from outside and from inside.
                rays.push(Ray::infinite(
                    Vec3::new(a, b, 2.0 - 3.0 * s),
                    Vec3::new(z, -z, s),
                ));
                rays.push(Ray::infinite(Vec3::new(a, b, 2.25), Vec3::new(z, z, s)));
                // Along x on y = a, z = b, and along y on z = a, x = b.
                rays.push(Ray::infinite(
                    Vec3::new(2.0 - 3.0 * s, a, b),
                    Vec3::new(s, z, z),
                ));
                rays.push(Ray::infinite(Vec3::new(b, 1.75, a), Vec3::new(-z, s, z)));
            }
            // In the plane x = a (d.x = ±0), oblique in y and z, through cell corners.
            rays.push(Ray::infinite(
                Vec3::new(a, -1.0, b - 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ));
            rays.push(Ray::infinite(
                Vec3::new(a, 5.0, b + 1.0),
                Vec3::new(-0.0, -1.0, -1.0),
            ));
            // Diagonals through grid vertices, from inside with t_min > 0.
            rays.push(Ray::new(
                Vec3::new(a, b, 0.0),
                Vec3::new(1.0, 1.0, 1.0),
                0.25,
                100.0,
            ));
            rays.push(Ray::new(
                Vec3::new(a, b, 4.0),
                Vec3::new(-1.0, 1.0, -1.0),
                0.0,
                3.0,
            ));
        }
    }
    // From every grid vertex (origin exactly on three planes) in seeded directions.
    let mut rng = seeded_rng(LATTICE_RAYS_SEED);
    for &x in lines.iter().step_by(2) {
        for &y in lines.iter().step_by(2) {
            for &z in lines.iter().step_by(2) {
                let d = centred_direction(&mut rng);
                rays.push(Ray::infinite(Vec3::new(x, y, z), d));
                rays.push(Ray::infinite(Vec3::new(x, y, z), -d));
            }
        }
    }
    rays
}

/// Seed of the lattice rays' seeded part (the rays from every grid vertex).
const LATTICE_RAYS_SEED: u64 = 0x5eed_6002;

/// The lattice case (the [`lattice_scene`] and its [`lattice_rays`]) against brute force, as
/// case `name`: no mismatch, and more than 300 exact answers.
pub fn check_lattice<A: Accel>(
    name: &str,
    params: &A::Params,
    validate: Validator<'_, A>,
) -> VerdictCounts {
    let case = Case {
        name: name.into(),
        seed: LATTICE_RAYS_SEED,
        mesh: lattice_scene(),
        rays: lattice_rays(),
    };
    let counts = check_case::<A>(&case, params, validate).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(counts.mismatch, 0);
    assert!(counts.exact > 300, "{counts:?}");
    counts
}
