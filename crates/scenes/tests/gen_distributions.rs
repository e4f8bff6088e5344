//! The distribution generators (`terrain`, `grass`, `hair`, `city`): sizes, determinism,
//! shape, the distribution property each one exists for, and views that see the geometry.

mod common;
use common::{assert_rejected, mesh_hash, scene};
use raybench_geom::{Aabb, Ray, Triangle, Vec3};
use raybench_scenes::{Scene, primary_rays};
use std::collections::HashMap;

fn assert_near_target(spec: &str, target: usize) {
    let n = scene(spec, 1).mesh.len();
    let error = (n as f64 - target as f64).abs() / target as f64;
    assert!(
        error <= 0.05,
        "{spec}: {n} triangles, {:.1} % off {target}",
        error * 100.0
    );
}

#[test]
fn triangle_counts_are_within_five_percent_of_the_target() {
    for name in ["terrain", "hair", "city"] {
        for target in [1_000, 2_345, 10_000, 100_000] {
            assert_near_target(&format!("{name}:triangles={target}"), target);
        }
    }
    // Defaults.
    assert_near_target("terrain", 100_000);
    assert_near_target("hair", 50_000);
    assert_near_target("city", 100_000);
    assert_eq!(scene("hair:triangles=777", 1).mesh.len(), 777);
    // Tiny budgets still make something.
    assert_eq!(scene("terrain:triangles=1", 1).mesh.len(), 2);
    assert_eq!(scene("city:triangles=1", 1).mesh.len(), 12);
}

/// Blades for the given density on the given field (the documented rule).
fn blades(density: f64, field: f64) -> usize {
    (density * field * field).round() as usize
}

#[test]
fn grass_grows_linearly_with_density_from_1k_to_4m() {
    // The ground is the same at every density; each blade adds 2·segments - 1 triangles.
    let mut ground = None;
    for density in [0.7, 1.0, 10.0, 200.0, 1000.0, 5700.0] {
        let n = scene(&format!("grass:density={density}"), 1).mesh.len();
        let g = n - 7 * blades(density, 10.0);
        assert_eq!(*ground.get_or_insert(g), g, "density {density}: {n}");
        if density == 0.7 {
            assert!((900..=1_100).contains(&n), "{n}");
        }
        if density == 5700.0 {
            assert!((3_900_000..=4_100_000).contains(&n), "{n}");
        }
    }
    // 16 × 16 ground quads on the default field; the default scene is 140,512 triangles.
    assert_eq!(ground, Some(512));
    assert_eq!(scene("grass", 1).mesh.len(), 140_512);
    // Segments: 2 → 3 triangles per blade, 8 → 15.
    assert_eq!(
        scene("grass:density=10,segments=2", 1).mesh.len(),
        512 + 3 * 1000
    );
    assert_eq!(
        scene("grass:density=10,segments=8", 1).mesh.len(),
        512 + 15 * 1000
    );
}

#[test]
fn same_seed_same_geometry_other_seed_other_geometry() {
    for spec in [
        "terrain:triangles=5000",
        "grass:density=10",
        "hair:triangles=3000",
        "city:triangles=5000",
    ] {
        let a = mesh_hash(&scene(spec, 7));
        assert_eq!(a, mesh_hash(&scene(spec, 7)), "{spec}");
        assert_ne!(a, mesh_hash(&scene(spec, 8)), "{spec}: the seed is ignored");
    }
}

#[test]
fn no_zero_area_triangles() {
    for spec in [
        "terrain:triangles=5000",
        "terrain:triangles=5000,height=0",
        "terrain:triangles=20000,octaves=12,roughness=1,height=2",
        "grass:density=10,segments=2",
        "grass:density=10,segments=8",
        "hair:triangles=5000,length=0.02",
        "city:triangles=20000",
        "city:triangles=5000,max_height=0.25",
    ] {
        let s = scene(spec, 3);
        assert_eq!(s.removed.degenerate_kept, 0, "{spec}");
        let smallest = s
            .mesh
            .triangles()
            .map(|t| t.area())
            .fold(f64::MAX, f64::min);
        assert!(smallest > 0.0, "{spec}: smallest area {smallest}");
    }
}

#[test]
fn bounding_boxes_have_the_expected_extents() {
    // Terrain: exactly [-1, 1] in x and z; heights within ±height·width and not flat.
    let b = scene("terrain:triangles=10000", 2).mesh.bounds();
    assert_eq!((b.min.x, b.max.x, b.min.z, b.max.z), (-1.0, 1.0, -1.0, 1.0));
    assert!(b.min.y >= -0.3 && b.max.y <= 0.3, "{b:?}");
    assert!(b.max.y - b.min.y > 0.1, "terrain is nearly flat: {b:?}");
    let b = scene("terrain:triangles=10000,height=0", 2).mesh.bounds();
    assert_eq!((b.min.y, b.max.y), (0.0, 0.0));
    let b = scene("terrain:triangles=10000,height=1", 2).mesh.bounds();
    assert!(
        b.min.y >= -2.0 && b.max.y <= 2.0 && b.max.y - b.min.y > 0.6,
        "{b:?}"
    );

    // Grass: the ground (the first 512 triangles) spans the field exactly and undulates by at
    // most 2 % of it; blades are at most 0.45 tall and lean out over the edge by less than that.
    let s = scene("grass:density=20", 2);
    let ground = (0..512).fold(Aabb::EMPTY, |b, i| b.union(&s.mesh.triangle(i).bounds()));
    assert_eq!(
        (ground.min.x, ground.max.x, ground.min.z, ground.max.z),
        (-5.0, 5.0, -5.0, 5.0)
    );
    assert!(ground.min.y >= -0.2 && ground.max.y <= 0.2, "{ground:?}");
    let b = s.mesh.bounds();
    assert!(b.min.is_finite() && b.max.is_finite());
    assert!(b.min.x >= -5.45 && b.max.x <= 5.45 && b.min.z >= -5.45 && b.max.z <= 5.45);
    assert!(b.min.y >= -0.2 && b.max.y <= 0.2 + 0.45, "{b:?}");
    assert!(b.max.y > 0.3, "no blade stands up: {b:?}");

    // Hair: inside the unit cube, and spanning nearly all of it.
    let b = scene("hair:triangles=10000,length=1", 2).mesh.bounds();
    assert!(
        b.min.min_element() > 0.0 && b.max.max_element() < 1.0,
        "{b:?}"
    );
    assert!(b.extent().min_element() > 0.98, "{b:?}");

    // City: ground at y = 0, a square centred on the origin; no building above max_height.
    for (spec, max_height) in [("city:triangles=10000", 8.0), ("city:max_height=2.5", 2.5)] {
        let b = scene(spec, 2).mesh.bounds();
        assert_eq!(b.min.y, 0.0, "{spec}");
        assert!(
            b.max.y <= max_height && b.max.y >= 0.5 * max_height,
            "{spec}: {b:?}"
        );
        assert_eq!(b.min.x, -b.max.x, "{spec}");
        assert_eq!((b.min.x, b.max.x), (b.min.z, b.max.z), "{spec}");
    }
}

/// Where a vertical ray down through `(x, z)` meets the first `ground` triangles.
fn ground_height(mesh: &raybench_geom::TriangleMesh, ground: usize, x: f32, z: f32) -> f32 {
    let ray = Ray::infinite(Vec3::new(x, 1e3, z), Vec3::NEG_Y);
    (0..ground)
        .find_map(|i| mesh.triangle(i).intersect_moller(&ray))
        .map(|hit| 1e3 - hit.t)
        .unwrap_or_else(|| panic!("no ground under ({x}, {z})"))
}

/// The lowest vertex of every blade (2·segments - 1 triangles each, after the ground).
fn blade_roots(s: &Scene, density: f64, field: f64, segments: usize) -> (usize, Vec<Vec3>) {
    let per_blade = 2 * segments - 1;
    let count = blades(density, field);
    let ground = s.mesh.len() - count * per_blade;
    let roots = (0..count)
        .map(|b| {
            (ground + b * per_blade..ground + (b + 1) * per_blade)
                .flat_map(|i| {
                    let t = s.mesh.triangle(i);
                    [t.v0, t.v1, t.v2]
                })
                .min_by(|p, q| p.y.total_cmp(&q.y))
                .unwrap()
        })
        .collect();
    (ground, roots)
}

#[test]
fn grass_blades_stand_on_the_ground() {
    for (density, field, segments) in [(10.0, 10.0, 4), (50.0, 3.0, 2), (2.0, 40.0, 8)] {
        let spec = format!("grass:density={density},field={field},segments={segments}");
        let s = scene(&spec, 4);
        let (ground, roots) = blade_roots(&s, density, field, segments);
        for root in roots {
            let h = ground_height(&s.mesh, ground, root.x, root.z);
            assert!(
                (root.y - h).abs() <= 1e-4 * field as f32,
                "{spec}: blade root {root} is {} off the ground",
                root.y - h
            );
        }
    }
}

#[test]
fn grass_blades_fill_the_field_uniformly() {
    let s = scene("grass:density=20", 5);
    let (_, roots) = blade_roots(&s, 20.0, 10.0, 4);
    let mut cells = [0usize; 16];
    for r in &roots {
        let cell = |v: f32| (((v + 5.0) / 10.0 * 4.0) as usize).min(3);
        cells[cell(r.z) * 4 + cell(r.x)] += 1;
    }
    let mean = roots.len() as f64 / 16.0;
    for (i, &c) in cells.iter().enumerate() {
        assert!(
            c as f64 >= 0.5 * mean,
            "cell {i} has {c}, mean {mean}: {cells:?}"
        );
    }
    // Every blade leans at most 1 radian, so its tip is higher than its root.
    assert!(roots.iter().all(|r| r.y < 0.2));
}

/// Normal axis (0, 1, 2) when the triangle is axis-aligned (two normal components exactly 0).
fn aligned_axis(t: &Triangle) -> Option<usize> {
    let n = t.geometric_normal();
    let zeros = n.to_array().iter().filter(|&&c| c == 0.0).count();
    (zeros == 2).then(|| n.abs().max_position())
}

#[test]
fn city_faces_are_axis_aligned_and_share_planes() {
    for spec in ["city:triangles=10000", "city"] {
        let s = scene(spec, 6);
        let n = s.mesh.len();
        let mut planes: HashMap<(usize, u32), usize> = HashMap::new();
        let mut aligned = 0;
        for t in s.mesh.triangles() {
            if let Some(axis) = aligned_axis(&t) {
                aligned += 1;
                // Exactly coplanar: all three vertices on the plane.
                assert!(t.v0[axis] == t.v1[axis] && t.v1[axis] == t.v2[axis]);
                *planes.entry((axis, t.v0[axis].to_bits())).or_default() += 1;
            }
        }
        assert!(
            aligned * 100 >= n * 99,
            "{spec}: {aligned} of {n} axis-aligned"
        );
        // A box face is two triangles; a plane with more holds faces of several buildings.
        let shared: usize = planes.values().filter(|&&c| c > 2).sum();
        assert!(
            shared * 10 >= n * 8,
            "{spec}: {shared} of {n} on shared planes"
        );
        assert!(
            planes.len() * 20 <= n,
            "{spec}: {} distinct planes for {n} triangles",
            planes.len()
        );
        // Exactly coincident wall quads (terraces of equal height): some, not rare.
        let mut quads: HashMap<[u32; 9], usize> = HashMap::new();
        for t in s.mesh.triangles() {
            let mut v = [t.v0, t.v1, t.v2].map(|p| p.to_array().map(f32::to_bits));
            v.sort_unstable();
            *quads.entry(v.concat().try_into().unwrap()).or_default() += 1;
        }
        let coincident: usize = quads.values().filter(|&&c| c > 1).sum();
        assert!(
            coincident * 20 >= n,
            "{spec}: only {coincident} coincident triangles"
        );
    }
}

fn mean_aspect(s: &Scene) -> f64 {
    let total: f64 = s
        .mesh
        .triangles()
        .map(|t| {
            let longest = [t.v1 - t.v0, t.v2 - t.v1, t.v0 - t.v2]
                .iter()
                .map(|e| f64::from(e.length()))
                .fold(0.0, f64::max);
            // Shortest altitude = 2·area / longest edge.
            longest * longest / (2.0 * t.area())
        })
        .sum();
    total / s.mesh.len() as f64
}

/// Mean over triangles of how many other triangles' bounding boxes overlap its own.
fn mean_box_overlaps(s: &Scene) -> f64 {
    let boxes: Vec<Aabb> = s.mesh.triangles().map(|t| t.bounds()).collect();
    let overlap = |a: &Aabb, b: &Aabb| (a.min.cmple(b.max) & b.min.cmple(a.max)).all();
    let mut pairs = 0u64;
    for (i, a) in boxes.iter().enumerate() {
        pairs += boxes[i + 1..].iter().filter(|b| overlap(a, b)).count() as u64;
    }
    2.0 * pairs as f64 / boxes.len() as f64
}

#[test]
fn hair_is_thin_and_overlapping() {
    let hair = scene("hair:triangles=2000", 7);
    let soup = scene("soup:triangles=2000", 7);
    let (hair_aspect, soup_aspect) = (mean_aspect(&hair), mean_aspect(&soup));
    assert!(hair_aspect > 50.0, "hair aspect {hair_aspect}");
    assert!(soup_aspect < 10.0, "soup aspect {soup_aspect}");
    let (hair_overlaps, soup_overlaps) = (mean_box_overlaps(&hair), mean_box_overlaps(&soup));
    // Each strand's box overlaps a good share of all others' (~10 % at the default length),
    // against a handful for the soup.
    assert!(hair_overlaps > 100.0, "hair overlaps {hair_overlaps}");
    assert!(
        hair_overlaps > 20.0 * soup_overlaps,
        "hair {hair_overlaps} vs soup {soup_overlaps}"
    );
    // Longer strands overlap more.
    let short = mean_box_overlaps(&scene("hair:triangles=2000,length=0.2", 7));
    assert!(short < 0.5 * hair_overlaps, "{short} vs {hair_overlaps}");
}

#[test]
fn terrain_octaves_and_roughness_add_detail() {
    // Mean absolute second difference of the heights along a grid row: fine detail.
    let detail = |spec: &str| {
        let s = scene(spec, 9);
        let p = s.mesh.positions();
        let row = 201; // 2·200² triangles: 201 vertices per row.
        let mut total = 0.0f64;
        let mut count = 0;
        for r in 0..row {
            for c in 1..row - 1 {
                let y = |k: usize| f64::from(p[r * row + k].y);
                total += (y(c - 1) - 2.0 * y(c) + y(c + 1)).abs();
                count += 1;
            }
        }
        total / count as f64
    };
    let smooth = detail("terrain:triangles=80000,octaves=1");
    let default = detail("terrain:triangles=80000");
    let rough = detail("terrain:triangles=80000,roughness=0.8");
    assert!(default > 3.0 * smooth, "{smooth} {default}");
    assert!(rough > 2.0 * default, "{default} {rough}");
}

/// Fraction of the scene's primary rays that reach its bounding box.
fn box_coverage(s: &Scene, rays: &[Ray]) -> f64 {
    let bounds = s.mesh.bounds();
    let hit = rays
        .iter()
        .filter(|r| bounds.intersect(r).is_some())
        .count();
    hit as f64 / rays.len() as f64
}

/// Fraction of rays that hit any triangle (brute force).
fn hit_coverage(s: &Scene, rays: &[Ray]) -> f64 {
    let tris: Vec<Triangle> = s.mesh.triangles().collect();
    let hit = rays
        .iter()
        .filter(|r| tris.iter().any(|t| t.intersect_moller(r).is_some()))
        .count();
    hit as f64 / rays.len() as f64
}

#[test]
fn default_views_are_filled_with_geometry() {
    for spec in [
        "terrain",
        "terrain:triangles=1000",
        "terrain:height=1",
        "terrain:height=0",
        "grass:density=20",
        "grass:field=100,density=1",
        "hair",
        "hair:length=0.1",
        "city:triangles=1000",
        "city:triangles=10000",
        "city",
        "city:triangles=1000000",
        "city:triangles=2000,max_height=64",
    ] {
        let s = scene(spec, 1);
        let bounds = s.mesh.bounds();
        assert!(
            !bounds.contains(s.view.camera.eye),
            "{spec}: eye inside the scene's box"
        );
        let (rays, _, _) = primary_rays(&s.view, &bounds, 10_000);
        let coverage = box_coverage(&s, &rays);
        assert!(
            coverage >= 0.9,
            "{spec}: {coverage:.3} of rays reach the box"
        );
    }
    // Small instances: brute force says most rays hit a triangle.
    for spec in [
        "terrain:triangles=2000",
        "terrain:triangles=2000,height=1",
        "grass:density=4",
        "hair:triangles=5000",
        "city:triangles=2000",
        "city:triangles=2000,max_height=20",
    ] {
        let s = scene(spec, 1);
        let (rays, _, _) = primary_rays(&s.view, &s.mesh.bounds(), 10_000);
        let coverage = hit_coverage(&s, &rays);
        assert!(coverage >= 0.5, "{spec}: only {coverage:.3} of rays hit");
    }
}

#[test]
fn bad_parameters_are_clear_errors() {
    let cases = [
        ("terrain:triangles=0", "triangles = 0: must be at least 1"),
        ("terrain:triangles=1e9", "more than the limit 50000000"),
        ("terrain:octaves=0", "octaves = 0: must be at least 1"),
        ("terrain:octaves=13", "octaves = 13: more than the limit 12"),
        ("terrain:octaves=2.5", "must be a whole number"),
        (
            "terrain:roughness=1.5",
            "roughness = 1.5: must be between 0 and 1",
        ),
        (
            "terrain:height=-0.1",
            "height = -0.1: must be between 0 and 2",
        ),
        ("terrain:height=nan", "not a finite number"),
        (
            "grass:density=0",
            "density = 0: must be between 0.1 and 100000",
        ),
        ("grass:field=0", "field = 0: must be between 0.5 and 1000"),
        ("grass:segments=1", "segments = 1: must be at least 2"),
        ("grass:segments=9", "more than the limit 8"),
        (
            "grass:triangles=1000",
            "unknown parameter `triangles` for grass (known: density, field, segments, view)",
        ),
        ("grass:density=0.1,field=1", "makes no blades"),
        (
            "grass:density=100000,field=100",
            "makes 1000000000 blades, 7000051200 triangles: more than the limit 50000000",
        ),
        ("hair:triangles=-1", "must be at least 1"),
        ("hair:length=0", "length = 0: must be between 0.02 and 1"),
        ("hair:length=2", "must be between 0.02 and 1"),
        ("city:triangles=60000000", "more than the limit 50000000"),
        (
            "city:max_height=0",
            "max_height = 0: must be between 0.25 and 64",
        ),
        ("city:max_height=100", "must be between 0.25 and 64"),
    ];
    assert_rejected(&cases);
}
