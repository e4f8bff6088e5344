//! The adversarial generators: sizes, determinism, and the property each scene exists for.

mod common;
use common::{assert_rejected, mesh_hash, scene, within_5_percent};
use raybench_geom::{Aabb, DVec3, Ray, Vec3};
use raybench_scenes::{primary_rays, random_rays};
use std::collections::{HashMap, HashSet};

const ADVERSARIAL: [&str; 6] = [
    "one-centroid",
    "coplanar",
    "offset",
    "zero-area-mixed",
    "single-triangle",
    "empty",
];

fn normal_f64(v: [Vec3; 3]) -> DVec3 {
    let [a, b, c] = v.map(|p| p.as_dvec3());
    (b - a).cross(c - a)
}

#[test]
fn default_sizes_and_requested_sizes() {
    let cases: [(&str, usize); 12] = [
        ("one-centroid", 1_000),
        ("one-centroid:triangles=1", 1),
        ("coplanar", 10_000),
        ("coplanar:triangles=7", 7),
        ("coplanar:triangles=3333", 3_333),
        ("offset", 20_000),
        ("offset:triangles=5000", 5_000),
        ("zero-area-mixed", 10_000),
        ("zero-area-mixed:triangles=77", 77),
        ("single-triangle", 1),
        ("single-triangle:size=1e-5", 1),
        ("empty", 0),
    ];
    for (spec, target) in cases {
        let s = scene(spec, 1);
        let made = s.mesh.len();
        assert!(
            within_5_percent(made, target),
            "{spec}: {made} triangles, wanted {target}"
        );
        assert_eq!(s.removed.total(), 0, "{spec}: nothing is removed");
        assert_eq!(s.name, spec.split(':').next().unwrap());
    }
}

#[test]
fn bad_parameters_are_rejected() {
    assert_rejected(&[
        ("offset:offset=-1", "must be between 0 and 10000000"),
        ("offset:offset=2e7", "must be between 0 and 10000000"),
        ("offset:offset=nan", "not a finite number"),
        (
            "zero-area-mixed:degenerate_fraction=1.5",
            "must be between 0 and 1",
        ),
        ("single-triangle:size=0", "must be between"),
        (
            "empty:triangles=5",
            "unknown parameter `triangles` for empty (known: view)",
        ),
        ("coplanar:triangles=0", "must be at least 1"),
    ]);
}

#[test]
fn deterministic_and_seeded_only_where_declared() {
    for name in ADVERSARIAL {
        let info = raybench_scenes::generators()
            .iter()
            .find(|g| g.name == name)
            .unwrap();
        let spec = match name {
            "one-centroid" | "single-triangle" | "empty" => name.to_string(),
            _ => format!("{name}:triangles=2000"),
        };
        let (a, b) = (scene(&spec, 5), scene(&spec, 5));
        assert_eq!(mesh_hash(&a), mesh_hash(&b), "{spec}");
        assert_eq!(a.view, b.view, "{spec}");
        let c = scene(&spec, 6);
        assert_eq!(
            mesh_hash(&a) != mesh_hash(&c),
            info.uses_seed,
            "{spec}: uses_seed = {} but the seed {} the mesh",
            info.uses_seed,
            if info.uses_seed {
                "does not change"
            } else {
                "changes"
            }
        );
    }
}

/// docs/validation.md, B5 and G8: every triangle's centroid is the origin, by either definition
/// builders use, exactly (not merely within an ulp: each axis holds +s, -s and 0), in sizes
/// spanning six octaves.
#[test]
fn one_centroid_shares_exactly_one_centroid() {
    for seed in [1, 2] {
        let s = scene("one-centroid", seed);
        assert_eq!(s.removed.degenerate_kept, 0);
        let mut areas = HashSet::new();
        for t in s.mesh.triangles() {
            let mean = (t.v0 + t.v1 + t.v2) / 3.0;
            let mean_other_order = (t.v2 + t.v0 + t.v1) / 3.0;
            let box_centre = t.bounds().center();
            for c in [mean, mean_other_order, box_centre] {
                assert_eq!(c, Vec3::ZERO, "{t:?}");
            }
            assert!(t.area() > 0.0, "{t:?}");
            areas.insert(t.area().to_bits());
        }
        assert!(areas.len() >= 3, "{} distinct areas", areas.len());
        let (smallest, largest) = s.mesh.triangles().fold((f64::MAX, 0.0f64), |(lo, hi), t| {
            (lo.min(t.area()), hi.max(t.area()))
        });
        assert!(largest / smallest > 100.0, "areas {smallest}..{largest}");
        // Orientations vary: many distinct normal directions.
        let normals: HashSet<_> = s
            .mesh
            .triangles()
            .map(|t| {
                let n = normal_f64([t.v0, t.v1, t.v2]).normalize();
                (n * 100.0).round().to_array().map(|c| c as i64)
            })
            .collect();
        assert!(normals.len() > 100, "{} normal directions", normals.len());
    }
}

/// docs/validation.md, G9, G11 and G16: every triangle is axis-aligned, every coordinate dyadic (a
/// multiple of 2^-20 within [-2, 2], so exactly on midpoint splits), many triangles lie exactly on
/// x = 0.5 and y = 0.25, and duplicates exist.
#[test]
fn coplanar_triangles_lie_exactly_on_dyadic_planes() {
    let n = 10_000;
    let s = scene("coplanar", 0);
    assert_eq!(s.removed.degenerate_kept, 0);
    let mut on_x = 0;
    let mut on_y = 0;
    let mut on_z = HashMap::new();
    let mut seen = HashMap::new();
    for t in s.mesh.triangles() {
        let v = [t.v0, t.v1, t.v2];
        let normal = normal_f64(v);
        let zeros = normal.to_array().iter().filter(|&&c| c == 0.0).count();
        assert_eq!(zeros, 2, "{t:?} is not axis-aligned (normal {normal})");
        for c in v.iter().flat_map(|p| p.to_array()) {
            let scaled = f64::from(c) * f64::from(1u32 << 20);
            assert!(
                scaled.fract() == 0.0 && c.abs() <= 2.0,
                "coordinate {c} is not dyadic"
            );
        }
        on_x += usize::from(v.iter().all(|p| p.x == 0.5));
        on_y += usize::from(v.iter().all(|p| p.y == 0.25));
        if v.iter().all(|p| p.z == v[0].z) {
            *on_z.entry(v[0].z.to_bits()).or_insert(0usize) += 1;
        }
        let mut key = v.map(|p| p.to_array().map(f32::to_bits));
        key.sort();
        *seen.entry(key).or_insert(0usize) += 1;
    }
    // 3/4 of the budget is split over five planes: 1500 each, plus duplicates of them.
    assert!(
        on_x >= 1_500 && on_y >= 1_500,
        "x = 0.5: {on_x}, y = 0.25: {on_y}"
    );
    for z in [-1.0f32, 0.0, 1.0] {
        assert!(
            on_z.get(&z.to_bits()).copied().unwrap_or(0) >= 1_500,
            "z = {z}: {on_z:?}"
        );
    }
    let duplicated: usize = seen.values().filter(|&&c| c > 1).map(|c| c - 1).sum();
    assert!(duplicated >= n / 8, "{duplicated} duplicates");
    let grazing = scene("coplanar:view=grazing", 0).view;
    assert!(grazing.is_usable());
    assert_eq!((grazing.camera.eye.y, grazing.camera.eye.z), (0.25, 0.0));
}

/// docs/validation.md, R15 and G15: the sphere's box centre is `offset` from the origin, and the
/// mesh is watertight.
#[test]
fn offset_sphere_sits_far_away_and_is_watertight() {
    for offset in [0.0, 1e4, 1e5, 1.5e5, 1e7] {
        let spec = format!("offset:triangles=3000,offset={offset}");
        let s = scene(&spec, 0);
        let b = s.mesh.bounds();
        let distance = b.center().as_dvec3().length();
        assert!(
            (distance - offset).abs() <= 1.0 + offset * 1e-6,
            "{spec}: centre at {distance}"
        );
        let e = b.extent();
        assert!(
            (e.max_element() - 2.0).abs() <= 2.0 * f32::EPSILON * (offset as f32 + 1.0) + 0.01,
            "{spec}: extent {e}"
        );
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for t in s.mesh.indices() {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{spec}: edge {a}->{b} used {count} times");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{spec}: edge {a}-{b} is a boundary"
            );
        }
        if offset <= 1.5e5 {
            assert_eq!(s.removed.degenerate_kept, 0, "{spec}");
        }
        let inside = scene(&format!("{spec},view=inside"), 0).view;
        assert!(
            inside.is_usable() && b.contains(inside.camera.eye),
            "{spec}"
        );
        assert!(!b.contains(s.view.camera.eye), "{spec}: default eye inside");
    }
}

/// docs/validation.md, B7 and G3: exactly round(fraction · n) triangles have zero area; the rest do
/// not.
#[test]
fn zero_area_mixed_has_the_requested_degenerates() {
    for (spec, expected) in [
        ("zero-area-mixed", 2_000),
        ("zero-area-mixed:degenerate_fraction=0", 0),
        ("zero-area-mixed:degenerate_fraction=1,triangles=600", 600),
        (
            "zero-area-mixed:degenerate_fraction=0.33,triangles=1000",
            330,
        ),
    ] {
        let s = scene(spec, 3);
        assert_eq!(s.removed.degenerate_kept, expected, "{spec}");
        let zero = s.mesh.triangles().filter(|t| t.area() == 0.0).count() as u64;
        assert_eq!(zero, expected, "{spec}");
    }
    // Degenerates are spread through the index order, not bunched at one end, and include
    // tobj point ([a, a, a]) and line ([a, b, b]) faces.
    let s = scene("zero-area-mixed", 3);
    let half = s.mesh.len() / 2;
    let first_half = s
        .mesh
        .triangles()
        .take(half)
        .filter(|t| t.area() == 0.0)
        .count();
    assert!(
        (800..=1_200).contains(&first_half),
        "{first_half} in the first half"
    );
    let idx = s.mesh.indices();
    assert!(idx.iter().any(|t| t[0] == t[1] && t[1] == t[2]));
    assert!(idx.iter().any(|t| t[0] != t[1] && t[1] == t[2]));
}

#[test]
fn single_triangle_is_one_real_triangle() {
    for spec in ["single-triangle", "single-triangle:size=1e5"] {
        let s = scene(spec, 0);
        assert_eq!(s.mesh.len(), 1, "{spec}");
        assert!(s.mesh.triangle(0).area() > 0.0, "{spec}");
    }
}

/// docs/validation.md, B18 and G1: no triangles, a usable view, and every ray workload can still be
/// made.
#[test]
fn empty_scene_has_a_usable_view_and_valid_rays() {
    let s = scene("empty", 0);
    assert!(s.mesh.is_empty());
    assert!(s.mesh.bounds().is_empty());
    assert!(s.view.is_usable(), "{:?}", s.view);
    assert_eq!(s.views.len(), 1);
    let bounds = s.mesh.bounds();
    let (rays, w, h) = primary_rays(&s.view, &bounds, 1_000);
    assert_eq!(rays.len(), (w * h) as usize);
    assert!(!rays.is_empty());
    let random = random_rays(&bounds, 1_000, 1);
    assert!(rays.iter().chain(&random).all(|r: &Ray| r.check().is_ok()));
}

/// Every non-empty default view has the eye outside the geometry and sends a good share of the
/// primary rays into its bounding box.
#[test]
fn default_views_look_at_the_geometry() {
    for spec in [
        "one-centroid",
        "coplanar",
        "offset",
        "offset:offset=1e7",
        "offset:offset=0",
        "zero-area-mixed",
        "single-triangle",
    ] {
        let s = scene(spec, 0);
        let bounds = s.mesh.bounds();
        assert!(s.view.is_usable(), "{spec}");
        assert!(!bounds.contains(s.view.camera.eye), "{spec}: eye inside");
        let (rays, _, _) = primary_rays(&s.view, &bounds, 2_000);
        let reaching = rays
            .iter()
            .filter(|r| bounds.intersect(r).is_some())
            .count();
        assert!(
            reaching * 10 > rays.len() * 3,
            "{spec}: only {reaching} of {} rays reach the box",
            rays.len()
        );
    }
    // The grazing view: every ray starts in the planes z = 0 and y = 0.25.
    let s = scene("coplanar:view=grazing", 0);
    let (rays, _, _) = primary_rays(&s.view, &Aabb::EMPTY, 500);
    assert!(
        rays.iter()
            .all(|r| r.origin().z == 0.0 && r.origin().y == 0.25)
    );
}
