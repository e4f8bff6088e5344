mod common;
use common::assert_rejected;
use raybench_scenes::{SceneSource, generate, generators, primary_rays};
use std::collections::HashMap;

#[test]
fn bad_parameters_are_clear_errors() {
    let cases = [
        ("sphere:triangles=0", "triangles = 0: must be at least 1"),
        ("soup:triangles=-5", "triangles = -5: must be at least 1"),
        ("soup:triangles=NaN", "triangles = NaN: not a finite number"),
        ("soup:triangles=inf", "not a finite number"),
        ("soup:triangles=2e9", "more than the limit 50000000"),
        ("soup:triangles=10.5", "must be a whole number"),
        ("soup:triangles=many", "triangles = `many` is not a number"),
        ("plane:quads=0", "quads = 0: must be at least 1"),
        ("plane:quads=100000", "more than the limit 5000"),
        ("plane:tilt_deg=-1", "must be between 0 and 80"),
        ("sphere:radius=0", "must be between"),
        (
            "cube",
            "unknown generator `cube` (known: sphere, soup, plane",
        ),
        (
            "sphere:colour=red",
            "unknown parameter `colour` for sphere (known: triangles, radius, view)",
        ),
        ("sphere:triangles", "`triangles` is not key=value"),
        (
            "sphere:triangles=10,triangles=20",
            "`triangles` is given twice",
        ),
    ];
    assert_rejected(&cases);
}

#[test]
fn defaults_and_sizes() {
    let sphere = generate("sphere", 0).unwrap();
    assert!(
        (19_000..=21_000).contains(&sphere.mesh.len()),
        "{}",
        sphere.mesh.len()
    );
    assert_eq!(generate("soup", 0).unwrap().mesh.len(), 10_000);
    assert_eq!(
        generate("soup:triangles=5000", 0).unwrap().mesh.len(),
        5_000
    );
    assert_eq!(generate("plane", 0).unwrap().mesh.len(), 2 * 64 * 64);
    assert_eq!(generate("plane:quads=3", 0).unwrap().mesh.len(), 18);
    let big = generate("sphere:triangles=100000", 0).unwrap().mesh.len();
    assert!((99_000..=101_000).contains(&big), "{big}");
    assert_eq!(
        generate(" Sphere : triangles = 8 ", 0).unwrap().mesh.len(),
        8
    );
}

#[test]
fn sources_record_every_parameter() {
    let scene = generate("plane:quads=8", 42).unwrap();
    let json = serde_json::to_value(&scene.source).unwrap();
    assert_eq!(
        json,
        serde_json::json!({"procedural": {"generator": "plane", "params": {"quads": 8, "tilt_deg": 10.0}, "seed": 42}})
    );
    let back: SceneSource = serde_json::from_value(json).unwrap();
    assert_eq!(back, scene.source);
}

/// Every undirected edge of the sphere belongs to exactly two triangles, used once in each
/// direction (consistent orientation), and no triangle is degenerate.
#[test]
fn sphere_is_watertight() {
    for spec in ["sphere:triangles=8", "sphere:triangles=300", "sphere"] {
        let scene = generate(spec, 0).unwrap();
        assert_eq!(scene.removed.degenerate_kept, 0, "{spec}");
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for t in scene.mesh.indices() {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(
                count, 1,
                "{spec}: edge {a}->{b} used {count} times in one direction"
            );
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{spec}: edge {a}-{b} is a boundary"
            );
        }
    }
}

#[test]
fn generators_are_deterministic_and_soup_follows_the_seed() {
    for spec in [
        "sphere:triangles=500",
        "soup:triangles=500",
        "plane:quads=10",
    ] {
        let (a, b) = (generate(spec, 9).unwrap(), generate(spec, 9).unwrap());
        assert_eq!(a.mesh, b.mesh, "{spec}");
    }
    let (a, b) = (
        generate("soup:triangles=500", 1).unwrap(),
        generate("soup:triangles=500", 2).unwrap(),
    );
    assert_ne!(a.mesh.positions(), b.mesh.positions());
}

#[test]
fn soup_edges_have_the_documented_lengths() {
    let scene = generate("soup:triangles=2000", 5).unwrap();
    for t in scene.mesh.triangles() {
        for (p, q) in [(t.v0, t.v1), (t.v1, t.v2), (t.v2, t.v0)] {
            let len = p.distance(q);
            // 0.02–0.1 for an equilateral corner set; the ±0.3 rad jitter stretches it to
            // 0.0157–0.1126.
            assert!((0.015..=0.113).contains(&len), "edge length {len}");
        }
    }
}

#[test]
fn default_views_see_the_object() {
    for spec in ["sphere", "soup", "plane"] {
        let scene = generate(spec, 0).unwrap();
        let bounds = scene.mesh.bounds();
        assert!(
            !bounds.contains(scene.view.camera.eye),
            "{spec}: eye inside the object"
        );
        let (rays, _, _) = primary_rays(&scene.view, &bounds, 2_000);
        let hitting_box = rays
            .iter()
            .filter(|r| bounds.intersect(r).is_some())
            .count();
        assert!(
            hitting_box * 10 > rays.len() * 3,
            "{spec}: only {hitting_box} of {} rays reach the box",
            rays.len()
        );
    }
}

#[test]
fn generator_list_describes_every_parameter() {
    let names: Vec<_> = generators().iter().map(|g| g.name).collect();
    for expected in [
        "sphere",
        "soup",
        "plane",
        "teapot",
        "teapot-in-stadium",
        "grass",
        "terrain",
        "hair",
        "city",
    ] {
        assert!(
            names.contains(&expected),
            "{expected} missing from {names:?}"
        );
    }
    for g in generators() {
        assert!(!g.description.is_empty());
        for p in g.params {
            assert!(p.describe().contains("default"), "{}:{}", g.name, p.key);
            // Every listed key is accepted at its default value.
            let spec = format!("{}:{}={}", g.name, p.key, p.default);
            assert!(
                raybench_scenes::generators()
                    .iter()
                    .any(|x| x.name == g.name)
            );
            if let Err(e) = generate(&spec, 0) {
                assert!(!e.to_string().contains("unknown parameter"), "{spec}: {e}");
            }
        }
    }
}
