//! The `teapot` and `teapot-in-stadium` generators: sizes, determinism, bounds, closedness of
//! the teapot, and what their views see (traced by brute force).

mod common;
use common::{assert_rejected, mesh_hash, scene, within_5_percent};
use raybench_geom::{Aabb, MollerTriangle, Ray};
use raybench_scenes::{Material, Scene, Vec3, View, primary_rays};
use std::collections::HashMap;

/// Columns per patch for a target (see generate/teapot/mod.rs, `Tessellation`): `round(sqrt(target
/// / 64))`.
fn teapot_columns(target: f64) -> usize {
    ((target / 64.0).sqrt().round() as usize).max(1)
}

/// Triangles of the stadium (material 0) and of the teapot (material 1): the stadium's come
/// first.
fn split(s: &Scene) -> (usize, usize) {
    assert_eq!(s.triangle_materials.len(), s.mesh.len());
    let stadium = s.triangle_materials.iter().filter(|&&m| m == 0).count();
    assert!(s.triangle_materials[..stadium].iter().all(|&m| m == 0));
    assert!(s.triangle_materials[stadium..].iter().all(|&m| m == 1));
    (stadium, s.mesh.len() - stadium)
}

fn bounds_of(s: &Scene, triangles: std::ops::Range<usize>) -> Aabb {
    Aabb::from_points(
        s.mesh.indices()[triangles]
            .iter()
            .flat_map(|t| t.map(|i| s.mesh.positions()[i as usize])),
    )
}

/// Brute-force closest hit, with the ray's interval shrunk to the best hit so far.
fn closest(tris: &[MollerTriangle], ray: &Ray) -> Option<usize> {
    let mut best: Option<(f32, usize)> = None;
    for (i, t) in tris.iter().enumerate() {
        let r = best.map_or(*ray, |(t_best, _)| ray.with_t_max(t_best));
        if let Some(h) = t.intersect(&r) {
            best = Some((h.t, i));
        }
    }
    best.map(|(_, i)| i)
}

/// Fractions of 20,000 primary rays whose closest hit is a triangle `>= first_teapot`, and any
/// other triangle.
fn hit_fractions(s: &Scene, view: &View, first_teapot: usize) -> (f64, f64) {
    let tris: Vec<MollerTriangle> = s
        .mesh
        .triangles()
        .map(|t| MollerTriangle::new(&t))
        .collect();
    let (rays, _, _) = primary_rays(view, &s.mesh.bounds(), 20_000);
    let (mut teapot, mut other) = (0usize, 0usize);
    for r in &rays {
        match closest(&tris, r) {
            Some(i) if i >= first_teapot => teapot += 1,
            Some(_) => other += 1,
            None => {}
        }
    }
    let n = rays.len() as f64;
    (teapot as f64 / n, other as f64 / n)
}

/// The largest |x| or |y| of the points projected into the view's image, in units of its
/// half-extent (4:3 image): at most 1 when every point is in the picture.
fn image_extent(view: &View, points: impl Iterator<Item = Vec3>) -> f32 {
    let c = view.camera;
    let forward = (c.target - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let tan_y = (c.fov_y_deg.to_radians() * 0.5).tan();
    points.fold(0.0f32, |m, p| {
        let q = p - c.eye;
        let depth = q.dot(forward);
        assert!(depth > 0.0, "{p} is behind the camera");
        let x = q.dot(right) / depth / (tan_y * 4.0 / 3.0);
        let y = q.dot(up) / depth / tan_y;
        m.max(x.abs()).max(y.abs())
    })
}

const SMALL_STADIUM: &str = "teapot-in-stadium:stadium_triangles=2000,teapot_triangles=2000";

#[test]
fn teapot_counts_are_within_5_percent() {
    for target in [200usize, 1_000, 6_000, 50_000] {
        let s = scene(&format!("teapot:triangles={target}"), 1);
        let n = s.mesh.len();
        assert!(within_5_percent(n, target), "{target}: {n}");
        assert_eq!(s.removed.total(), 0, "{target}");
        // The collapsed first rows of the 4 lid-top and 4 bottom patches: one zero-area
        // triangle per column in each.
        let columns = teapot_columns(target as f64);
        assert_eq!(s.removed.degenerate_kept as usize, 8 * columns, "{target}");
    }
    // The default, and the smallest mesh (one quad per patch).
    assert!(within_5_percent(scene("teapot", 1).mesh.len(), 6_000));
    assert_eq!(scene("teapot:triangles=1", 1).mesh.len(), 64);
}

#[test]
fn teapot_is_glass_one_unit_wide_and_on_the_ground() {
    let s = scene("teapot", 7);
    assert_eq!(s.materials, [Material::GLASS]);
    assert!(s.triangle_materials.is_empty());
    assert_eq!(s.material(0), Material::GLASS);
    let b = s.mesh.bounds();
    let e = b.extent();
    assert!((e.x - 1.0).abs() < 1e-6, "{b:?}");
    // Newell's proportions: 3.15 high and 4 deep for about 6.4 from handle to spout.
    assert!((0.47..0.51).contains(&e.y), "{b:?}");
    assert!((0.6..0.64).contains(&e.z), "{b:?}");
    assert_eq!(b.min.y, 0.0);
    assert!(
        b.center().x.abs() < 1e-6 && b.center().z.abs() < 1e-6,
        "{b:?}"
    );
    // The spout points to +x, its tip level with the rim; the handle to -x, lower.
    let by_x = |a: &&Vec3, b: &&Vec3| a.x.total_cmp(&b.x);
    let spout_tip = s.mesh.positions().iter().max_by(by_x).unwrap();
    let handle = s.mesh.positions().iter().min_by(by_x).unwrap();
    assert!((0.33..0.42).contains(&spout_tip.y), "{spout_tip}");
    assert!((0.15..0.37).contains(&handle.y), "{handle}");
}

/// Apart from the zero-area triangles at the lid's apex and the base's centre, every edge
/// belongs to one or two triangles, and exactly `16 · columns` to one: the rim's lip (4 patches
/// × columns), the lid's lower edge (4), both ends of the handle (2 + 2) and of the spout
/// (2 + 2). A crack between patches, or a wrong control-point index, would add more.
#[test]
fn teapot_is_closed_except_its_known_openings() {
    for target in [1_000usize, 6_000] {
        let s = scene(&format!("teapot:triangles={target}"), 1);
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        let mut degenerate = 0;
        for (i, t) in s.mesh.indices().iter().enumerate() {
            if s.mesh.triangle(i).area() == 0.0 {
                degenerate += 1;
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let columns = teapot_columns(target as f64);
        assert_eq!(degenerate, 8 * columns);
        let over = edges.values().filter(|&&n| n > 2).count();
        assert_eq!(over, 0, "{target}: edges shared by more than two triangles");
        let boundary = edges.values().filter(|&&n| n == 1).count();
        assert_eq!(boundary, 16 * columns, "{target}: boundary edges");
    }
}

#[test]
fn teapot_view_shows_the_whole_teapot_filling_the_frame() {
    let s = scene("teapot", 1);
    let extent = image_extent(&s.view, s.mesh.positions().iter().copied());
    assert!(
        (0.85..=1.0).contains(&extent),
        "teapot reaches {extent} of the image's half-extent"
    );
    let (teapot, _) = hit_fractions(&s, &s.view, 0);
    assert!(teapot >= 0.30, "{teapot}");
    let light = s.view.light;
    assert!(
        light.y > 1.0 && light.z > 0.5,
        "the light is above and in front: {light}"
    );
}

#[test]
fn stadium_counts_are_within_5_percent() {
    let cases = [
        (1_000, 64),
        (2_000, 2_000),
        (57_321, 3_333),
        (200_000, 20_000),
    ];
    for (stadium_target, teapot_target) in cases {
        let spec = format!(
            "teapot-in-stadium:stadium_triangles={stadium_target},teapot_triangles={teapot_target}"
        );
        let s = scene(&spec, 5);
        let (stadium, teapot) = split(&s);
        assert!(
            within_5_percent(stadium, stadium_target),
            "{spec}: {stadium}"
        );
        assert!(within_5_percent(teapot, teapot_target), "{spec}: {teapot}");
        assert_eq!(s.removed.total(), 0, "{spec}");
        assert_eq!(s.materials, [Material::DEFAULT, Material::GLASS]);
    }
    // Defaults: 200,000 + 20,000.
    let (stadium, teapot) = split(&scene("teapot-in-stadium", 1));
    assert!(within_5_percent(stadium, 200_000) && within_5_percent(teapot, 20_000));
}

#[test]
fn generators_are_deterministic_and_only_the_stadium_uses_the_seed() {
    let teapot = mesh_hash(&scene("teapot:triangles=3000", 1));
    assert_eq!(teapot, mesh_hash(&scene("teapot:triangles=3000", 1)));
    assert_eq!(teapot, mesh_hash(&scene("teapot:triangles=3000", 99)));
    assert_ne!(teapot, mesh_hash(&scene("teapot:triangles=3100", 1)));

    let a = scene(SMALL_STADIUM, 1);
    assert_eq!(mesh_hash(&a), mesh_hash(&scene(SMALL_STADIUM, 1)));
    let b = scene(SMALL_STADIUM, 2);
    assert_ne!(mesh_hash(&a), mesh_hash(&b));
    // The seed moves the stands (aisles, heights), not the triangle count or the teapot.
    assert_eq!(a.mesh.len(), b.mesh.len());
    let (stadium, _) = split(&a);
    let teapot_bits = |s: &Scene| {
        let b = bounds_of(s, stadium..s.mesh.len());
        (b.min.to_array(), b.max.to_array())
    };
    assert_eq!(teapot_bits(&a), teapot_bits(&b));
}

#[test]
fn stadium_and_teapot_bounds_are_sane() {
    for ratio in [1e-6f64, 3e-4, 0.01, 0.5] {
        let spec = format!("{SMALL_STADIUM},size_ratio={ratio}");
        let s = scene(&spec, 3);
        assert!(s.mesh.positions().iter().all(|p| p.is_finite()));
        let (stadium, _) = split(&s);
        let arena = bounds_of(&s, 0..stadium);
        assert!(
            arena.min.x >= -600.0 && arena.max.x <= 600.0,
            "{spec}: {arena:?}"
        );
        assert!(
            arena.min.z >= -600.0 && arena.max.z <= 600.0,
            "{spec}: {arena:?}"
        );
        assert!((arena.extent().x - 1000.0).abs() < 1.0, "{spec}: {arena:?}");
        assert!(
            arena.min.y == 0.0 && arena.max.y < 150.0,
            "{spec}: {arena:?}"
        );
        let whole = s.mesh.bounds();
        assert!(whole.min.abs().max_element() <= 1000.0 && whole.max.abs().max_element() <= 1000.0);

        let teapot = bounds_of(&s, stadium..s.mesh.len());
        let width = (ratio * 1000.0) as f32;
        let e = teapot.extent();
        assert!((e.x - width).abs() <= width * 1e-5, "{spec}: {teapot:?}");
        assert!((e.y / width - 0.49).abs() < 0.02, "{spec}: {teapot:?}");
        assert_eq!(teapot.min.y, 0.0, "{spec}: stands on the field");
        let c = teapot.center();
        assert!(
            c.x.abs() <= width * 1e-5 && c.z.abs() <= width * 1e-5,
            "{spec}: {teapot:?}"
        );
    }
}

#[test]
fn closeup_sees_mostly_the_teapot_and_stadium_view_the_stadium() {
    let s = scene(SMALL_STADIUM, 1);
    let names: Vec<&str> = s.views.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["closeup", "stadium"]);
    assert_eq!(s.view, s.views[0].view, "closeup is the default");
    let (stadium, _) = split(&s);

    let (teapot, behind) = hit_fractions(&s, &s.views[0].view, stadium);
    assert!(teapot >= 0.30, "closeup: {teapot} of rays hit the teapot");
    assert!(
        behind >= 0.10,
        "closeup: the stadium is visible behind ({behind})"
    );

    let wide = scene(&format!("{SMALL_STADIUM},view=stadium"), 1);
    assert_eq!(wide.view, s.views[1].view);
    let (teapot, arena) = hit_fractions(&wide, &wide.view, stadium);
    assert!(
        arena >= 0.5,
        "stadium view: {arena} of rays hit the stadium"
    );
    assert_eq!(teapot, 0.0, "the teapot is invisible at that scale");
    let extent = image_extent(
        &wide.view,
        wide.mesh.indices()[..stadium]
            .iter()
            .flat_map(|t| t.map(|i| wide.mesh.positions()[i as usize])),
    );
    assert!(
        extent <= 1.0,
        "the whole stadium is in the picture: {extent}"
    );

    // The floodlight is above the stadium and lights the teapot: nothing between them.
    let light = s.view.light;
    assert_eq!(light, wide.view.light);
    assert!(light.y > 100.0);
    let tris: Vec<MollerTriangle> = s
        .mesh
        .triangles()
        .map(|t| MollerTriangle::new(&t))
        .collect();
    let lid = Vec3::new(0.0, 0.5 * 0.3, 0.0);
    let to_light = Ray::new(lid, light - lid, 1e-3, 1.0);
    assert!(
        tris[..stadium]
            .iter()
            .all(|t| t.intersect(&to_light).is_none()),
        "the stadium shadows the teapot"
    );
}

#[test]
fn bad_parameters_are_clear_errors() {
    let cases = [
        ("teapot:triangles=0", "triangles = 0: must be at least 1"),
        (
            "teapot:size_ratio=0.1",
            "unknown parameter `size_ratio` for teapot",
        ),
        (
            "teapot-in-stadium:size_ratio=0",
            "size_ratio = 0: must be between",
        ),
        (
            "teapot-in-stadium:size_ratio=-0.5",
            "size_ratio = -0.5: must be between",
        ),
        (
            "teapot-in-stadium:size_ratio=0.6",
            "size_ratio = 0.6: must be between",
        ),
        (
            "teapot-in-stadium:size_ratio=NaN",
            "size_ratio = NaN: not a finite number",
        ),
        (
            "teapot-in-stadium:stadium_triangles=0",
            "stadium_triangles = 0: must be at least 1000",
        ),
        (
            "teapot-in-stadium:teapot_triangles=0",
            "teapot_triangles = 0: must be at least 64",
        ),
        (
            "teapot-in-stadium:stadium_triangles=45000000",
            "more than the limit 40000000",
        ),
        (
            "teapot-in-stadium:view=aerial",
            "unknown view `aerial` (known: closeup, stadium)",
        ),
    ];
    assert_rejected(&cases);
}
