//! Workload rays: validity, the geometry each promises, and bit-exact determinism.
//!
//! Secondary rays need primary hits; these tests make them with a plain loop over the mesh
//! (raybench-scenes does not depend on the structures).

use raybench_geom::{Ray, TriangleTest};
use raybench_scenes::{
    SHADOW_T_MAX, Scene, SurfaceHit, Vec3, View, diffuse_rays, generate, primary_rays, random_rays,
    shadow_rays,
};

/// Closest hit by testing every triangle.
fn closest_hit(scene: &Scene, ray: &Ray) -> Option<SurfaceHit> {
    let mut best: Option<(f32, SurfaceHit)> = None;
    for (i, tri) in scene.mesh.triangles().enumerate() {
        let Some(h) = tri.intersect(ray, TriangleTest::MollerTrumbore) else {
            continue;
        };
        if best.is_none_or(|(t, _)| h.t < t) {
            let prim = i as u32;
            best = Some((
                h.t,
                SurfaceHit {
                    prim,
                    u: h.u,
                    v: h.v,
                },
            ));
        }
    }
    best.map(|(_, hit)| hit)
}

struct Traced {
    scene: Scene,
    primary: Vec<Ray>,
    hits: Vec<Option<SurfaceHit>>,
}

fn traced(spec: &str, n: usize) -> Traced {
    let scene = generate(spec, 3).unwrap();
    let (primary, _, _) = primary_rays(&scene.view, &scene.mesh.bounds(), n);
    let hits = primary.iter().map(|r| closest_hit(&scene, r)).collect();
    Traced {
        scene,
        primary,
        hits,
    }
}

fn bits(rays: &[Ray]) -> Vec<[u32; 8]> {
    rays.iter().map(Ray::to_bits).collect()
}

fn all_valid(rays: &[Ray]) -> bool {
    rays.iter().all(|r| r.check().is_ok())
}

#[test]
fn primary_rays_cover_the_image_and_the_centre_looks_at_the_target() {
    let scene = generate("sphere:triangles=200", 0).unwrap();
    let (rays, w, h) = primary_rays(&scene.view, &scene.mesh.bounds(), 20_000);
    assert_eq!(rays.len(), (w * h) as usize);
    assert!((rays.len() as f64 - 20_000.0).abs() < 200.0, "{w}x{h}");
    assert!(
        w % 2 == 1 && h % 2 == 1,
        "this test needs a middle pixel: {w}x{h}"
    );
    assert!(all_valid(&rays));
    let centre = rays[(h / 2 * w + w / 2) as usize];
    let cam = scene.view.camera;
    let to_target = (cam.target - cam.eye).normalize();
    assert!(
        centre.dir().normalize().dot(to_target) > 1.0 - 1e-6,
        "{:?}",
        centre.dir()
    );
    assert_eq!(centre.origin(), cam.eye);
    assert_eq!((centre.t_min(), centre.t_max()), (0.0, f32::INFINITY));
    // Row-major from the top-left: the first ray points up and left of the centre.
    let (first, cam_right) = (
        rays[0].dir().normalize(),
        to_target.cross(cam.up).normalize(),
    );
    assert!(first.dot(cam_right) < 0.0 && first.dot(cam.up) > 0.0);
}

#[test]
fn a_degenerate_view_falls_back_to_the_bounds() {
    let scene = generate("plane:quads=4", 0).unwrap();
    let mut view: View = scene.view;
    view.camera.eye = view.camera.target;
    let (rays, _, _) = primary_rays(&view, &scene.mesh.bounds(), 100);
    assert!(!rays.is_empty() && all_valid(&rays));
}

#[test]
fn random_rays_start_in_the_enlarged_bounds() {
    let scene = generate("soup:triangles=100", 0).unwrap();
    let bounds = scene.mesh.bounds();
    let region = bounds.enlarged(0.05);
    let rays = random_rays(&bounds, 10_000, 11);
    assert_eq!(rays.len(), 10_000);
    assert!(all_valid(&rays));
    assert!(rays.iter().all(|r| region.contains(r.origin())));
    assert!(
        rays.iter().any(|r| !bounds.contains(r.origin())),
        "the margin is used"
    );
    assert!(rays.iter().all(|r| (r.dir().length() - 1.0).abs() < 1e-5));
    // Uniform on the sphere: every octant gets about an eighth.
    let mut octants = [0usize; 8];
    for r in &rays {
        let d = r.dir();
        octants
            [(d.x > 0.0) as usize | ((d.y > 0.0) as usize) << 1 | ((d.z > 0.0) as usize) << 2] += 1;
    }
    assert!(
        octants.iter().all(|&c| (1_000..1_500).contains(&c)),
        "{octants:?}"
    );
}

/// The facing geometric normal of a hit, recomputed independently.
fn facing_normal(t: &Traced, i: usize) -> Vec3 {
    let hit = t.hits[i].unwrap();
    let n = t
        .scene
        .mesh
        .triangle(hit.prim as usize)
        .geometric_normal()
        .normalize();
    if n.dot(t.primary[i].dir()) > 0.0 {
        -n
    } else {
        n
    }
}

#[test]
fn shadow_rays_go_towards_the_light_and_stop_before_it() {
    let t = traced("sphere:triangles=2000", 3_000);
    let light = t.scene.view.light;
    let shadows = shadow_rays(&t.scene.mesh, light, &t.primary, &t.hits);
    let hit_count = t.hits.iter().flatten().count();
    assert!(hit_count > 500, "the sphere fills part of the frame");
    assert!(!shadows.is_empty() && shadows.len() <= hit_count);
    assert!(all_valid(&shadows));
    for r in &shadows {
        assert!(r.t_max() < 1.0 && r.t_max() == SHADOW_T_MAX);
        // In f64, so the check is about the interval, not f32 rounding of the end point.
        let (o, d) = (r.origin().as_dvec3(), r.dir().as_dvec3());
        let end = o + d * f64::from(r.t_max());
        let light = light.as_dvec3();
        assert!(end.distance(o) < light.distance(o), "ends before the light");
        assert!(
            (o + d - light).length() < 1e-5 * light.length(),
            "aims at the light"
        );
    }
    // A convex mesh never shadows its own lit side: no shadow ray may hit anything, which also
    // shows the origin offset keeps rays off their own triangle.
    let blocked = shadows
        .iter()
        .filter(|r| closest_hit(&t.scene, r).is_some())
        .count();
    assert_eq!(blocked, 0, "of {} shadow rays", shadows.len());
}

#[test]
fn hits_facing_away_from_the_light_get_no_shadow_ray() {
    let t = traced("plane:quads=4,tilt_deg=0", 400);
    // Light below the plane, camera above: every lit point faces away.
    let below = Vec3::new(0.0, -3.0, 0.0);
    assert!(t.hits.iter().flatten().count() > 100);
    assert!(shadow_rays(&t.scene.mesh, below, &t.primary, &t.hits).is_empty());
}

#[test]
fn diffuse_rays_leave_on_the_facing_side() {
    let t = traced("sphere:triangles=2000", 3_000);
    let diffuse = diffuse_rays(&t.scene.mesh, &t.primary, &t.hits, 5);
    let hit_index: Vec<usize> = (0..t.hits.len()).filter(|&i| t.hits[i].is_some()).collect();
    assert_eq!(diffuse.len(), hit_index.len());
    assert!(all_valid(&diffuse));
    let mut mean_cos = 0.0;
    for (r, &i) in diffuse.iter().zip(&hit_index) {
        let n = facing_normal(&t, i);
        let cos = r.dir().normalize().dot(n);
        assert!(cos > 0.0, "ray {i} goes into the surface: cos = {cos}");
        // The origin is on the facing side of the triangle's plane.
        let v0 = t.scene.mesh.triangle(t.hits[i].unwrap().prim as usize).v0;
        assert!(
            (r.origin() - v0).dot(n) > 0.0,
            "ray {i} starts behind its surface"
        );
        assert_eq!(r.t_max(), f32::INFINITY);
        mean_cos += cos as f64;
    }
    // Leaving a convex mesh outwards, nothing can be hit (and the ray misses its own triangle).
    let blocked = diffuse
        .iter()
        .filter(|r| closest_hit(&t.scene, r).is_some())
        .count();
    assert_eq!(blocked, 0, "of {} diffuse rays", diffuse.len());
    // Cosine-weighted: E[cos θ] = 2/3 (uniform over the hemisphere would give 1/2).
    mean_cos /= diffuse.len() as f64;
    assert!((mean_cos - 2.0 / 3.0).abs() < 0.03, "mean cos {mean_cos}");
}

#[test]
fn same_seed_same_bits_different_seed_different_rays() {
    let t = traced("soup:triangles=300", 1_000);
    let bounds = t.scene.mesh.bounds();
    let again = traced("soup:triangles=300", 1_000);
    assert_eq!(bits(&t.primary), bits(&again.primary));
    assert_eq!(t.hits, again.hits);
    assert_eq!(
        bits(&random_rays(&bounds, 500, 1)),
        bits(&random_rays(&bounds, 500, 1))
    );
    assert_ne!(
        bits(&random_rays(&bounds, 500, 1)),
        bits(&random_rays(&bounds, 500, 2))
    );
    let diffuse = |seed| bits(&diffuse_rays(&t.scene.mesh, &t.primary, &t.hits, seed));
    assert!(!diffuse(1).is_empty());
    assert_eq!(diffuse(1), diffuse(1));
    assert_ne!(diffuse(1), diffuse(2));
    let shadow = || {
        bits(&shadow_rays(
            &t.scene.mesh,
            t.scene.view.light,
            &t.primary,
            &t.hits,
        ))
    };
    assert_eq!(shadow(), shadow());
}

#[test]
fn a_diffuse_ray_depends_only_on_its_own_hit() {
    let t = traced("sphere:triangles=500", 500);
    let all = diffuse_rays(&t.scene.mesh, &t.primary, &t.hits, 8);
    // Drop every other hit: the remaining rays are unchanged.
    let thinned: Vec<_> = t
        .hits
        .iter()
        .enumerate()
        .map(|(i, h)| h.filter(|_| i % 2 == 0))
        .collect();
    let some = diffuse_rays(&t.scene.mesh, &t.primary, &thinned, 8);
    let kept: Vec<Ray> = (0..t.hits.len())
        .filter(|&i| t.hits[i].is_some())
        .zip(&all)
        .filter(|(i, _)| i % 2 == 0)
        .map(|(_, r)| *r)
        .collect();
    assert_eq!(bits(&some), bits(&kept));
}

#[test]
fn empty_inputs_give_no_rays() {
    let scene = generate("plane:quads=1", 0).unwrap();
    assert!(
        primary_rays(&scene.view, &scene.mesh.bounds(), 0)
            .0
            .is_empty()
    );
    assert!(random_rays(&scene.mesh.bounds(), 0, 0).is_empty());
    assert!(shadow_rays(&scene.mesh, Vec3::Y, &[], &[]).is_empty());
    let empty = raybench_geom::Aabb::EMPTY;
    assert!(all_valid(&random_rays(&empty, 10, 0)));
}
