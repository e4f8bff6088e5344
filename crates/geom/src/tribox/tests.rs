//! The overlap test against exact clipping (seeded, degenerate), touching cases one f32 step
//! apart, NaN, scale invariance, far from the origin, and the conservative margin.

use super::*;
use glam::Vec3;

use crate::rng::SplitMix64 as Rng;

fn t(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
    Triangle::new(a.into(), b.into(), c.into())
}

fn unit() -> (DVec3, DVec3) {
    (DVec3::ZERO, DVec3::ONE)
}

fn ov(tri: &Triangle, (lo, hi): (DVec3, DVec3)) -> bool {
    TriBox::new(tri).overlaps(lo, hi)
}

/// Sutherland–Hodgman in f64: clips the triangle (as a polygon, degenerate ones included)
/// against the six half-spaces of the closed box; a non-empty result means overlap.
fn clip_nonempty(tri: &Triangle, lo: DVec3, hi: DVec3) -> bool {
    let mut poly: Vec<DVec3> = [tri.v0, tri.v1, tri.v2]
        .iter()
        .map(|p| p.as_dvec3())
        .collect();
    for axis in 0..3 {
        for (bound, keep_above) in [(lo[axis], true), (hi[axis], false)] {
            let inside = |p: DVec3| {
                if keep_above {
                    p[axis] >= bound
                } else {
                    p[axis] <= bound
                }
            };
            let mut out = Vec::with_capacity(poly.len() + 2);
            for i in 0..poly.len() {
                let a = poly[i];
                let b = poly[(i + 1) % poly.len()];
                match (inside(a), inside(b)) {
                    (true, true) => out.push(b),
                    (true, false) => out.push(cross_at(a, b, axis, bound)),
                    (false, true) => {
                        out.push(cross_at(a, b, axis, bound));
                        out.push(b);
                    }
                    (false, false) => {}
                }
            }
            poly = out;
            if poly.is_empty() {
                return false;
            }
        }
    }
    true
}

/// The point of segment a→b on the plane `p[axis] == bound`, snapped onto the plane.
fn cross_at(a: DVec3, b: DVec3, axis: usize, bound: f64) -> DVec3 {
    let s = (bound - a[axis]) / (b[axis] - a[axis]);
    let mut p = a + (b - a) * s;
    p[axis] = bound;
    p
}

fn grow(lo: DVec3, hi: DVec3, f: f64) -> (DVec3, DVec3) {
    let pad = (hi - lo) * f + DVec3::splat(f);
    (lo - pad, hi + pad)
}

/// Random boxes and triangles of mixed sizes around them: SAT agrees with clipping, up to
/// an ε band (clipping itself rounds): overlap ⇒ the ε-enlarged box clips non-empty, and no
/// overlap ⇒ the ε-shrunk box clips empty. Also the sampled points of the triangle inside
/// the box imply overlap.
#[test]
fn agrees_with_clipping_on_seeded_random_cases() {
    let mut rng = Rng::new(0x5eed_7b0c);
    let (mut hits, mut misses) = (0, 0);
    for case in 0..100_000 {
        let lo = rng.unit_vec() * 2.0 - 1.0;
        let hi = lo + rng.unit_vec() * 0.8 + 0.01;
        let size = [0.05f32, 0.3, 1.5][case % 3];
        // Centred around the box, from well inside to well outside it.
        let c = lo + (hi - lo) * (rng.unit_vec() * 2.0 - 0.5) + (rng.unit_vec() - 0.5) * size;
        let tri = Triangle::new(
            c + (rng.unit_vec() - 0.5) * size,
            c + (rng.unit_vec() - 0.5) * size,
            c + (rng.unit_vec() - 0.5) * size,
        );
        let (blo, bhi) = (lo.as_dvec3(), hi.as_dvec3());
        let sat = ov(&tri, (blo, bhi));
        let (glo, ghi) = grow(blo, bhi, 1e-9);
        let (slo, shi) = grow(blo, bhi, -1e-9);
        if sat {
            hits += 1;
            assert!(clip_nonempty(&tri, glo, ghi), "case {case}: {tri:?}");
        } else {
            misses += 1;
            assert!(!clip_nonempty(&tri, slo, shi), "case {case}: {tri:?}");
            for i in 0..=8 {
                for j in 0..=8 - i {
                    let p = tri.point_at(i as f32 / 8.0, j as f32 / 8.0).as_dvec3();
                    assert!(
                        !(p.cmpge(blo).all() && p.cmple(bhi).all()),
                        "case {case}: sample {p} inside the box but no overlap"
                    );
                }
            }
        }
    }
    // Both answers are well represented.
    assert!(hits > 10_000 && misses > 10_000, "{hits} / {misses}");
}

#[test]
fn agrees_with_clipping_on_degenerate_triangles() {
    let mut rng = Rng::new(0x5eed_de9e);
    let (mut hits, mut misses) = (0, 0);
    for case in 0..50_000 {
        let (blo, bhi) = unit();
        let a = rng.unit_vec() * 3.0 - 1.0;
        let b = rng.unit_vec() * 3.0 - 1.0;
        let tri = match case % 3 {
            0 => Triangle::new(a, a, a),                 // point
            1 => Triangle::new(a, b, b),                 // segment (repeated vertex)
            _ => Triangle::new(a, b, a * 0.5 + b * 0.5), // collinear, midpoint third
        };
        let sat = ov(&tri, (blo, bhi));
        let (glo, ghi) = grow(blo, bhi, 1e-9);
        let (slo, shi) = grow(blo, bhi, -1e-9);
        if sat {
            hits += 1;
            assert!(clip_nonempty(&tri, glo, ghi), "case {case}: {tri:?}");
        } else {
            misses += 1;
            assert!(!clip_nonempty(&tri, slo, shi), "case {case}: {tri:?}");
        }
    }
    assert!(hits > 5_000 && misses > 5_000, "{hits} / {misses}");
}

/// One f32 step: 2^-23 at 1.0 (coordinates below are in [0.5, 4), so it is exact there).
const STEP: f32 = 1.0 / (1u32 << 21) as f32;

/// A triangle as a function of how far it is moved off the box.
type MovedTriangle = Box<dyn Fn(f32) -> Triangle>;

#[test]
fn touching_counts_and_one_step_away_does_not() {
    let b = unit();
    // (touching triangle, the same moved STEP away)
    let cases: Vec<(&str, MovedTriangle)> = vec![
        (
            "vertex on a face",
            Box::new(|s| t([1.0 + s, 0.5, 0.5], [2.0, 0.25, 0.5], [2.0, 0.75, 0.75])),
        ),
        (
            "edge along a face",
            Box::new(|s| t([1.0 + s, 0.25, 0.5], [1.0 + s, 0.75, 0.5], [2.0, 0.5, 0.5])),
        ),
        (
            "triangle in a face's plane",
            Box::new(|s| {
                t(
                    [1.0 + s, 0.25, 0.25],
                    [1.0 + s, 0.75, 0.25],
                    [1.0 + s, 0.5, 3.0],
                )
            }),
        ),
        (
            "vertex on a box corner",
            Box::new(|s| {
                let c = 1.0 + s;
                t([c, c, c], [2.0, 3.0, 2.0], [3.0, 2.0, 3.0])
            }),
        ),
        (
            // The line x + y = 2 (+s) in z = 0.5 touches the box edge x = y = 1 at one point;
            // the triangle lies beyond it. Only an edge-cross axis separates the moved one.
            "edge across a box edge",
            Box::new(|s| t([2.0 + s, 0.0, 0.5], [0.0, 2.0 + s, 0.5], [2.0, 2.0, 0.5])),
        ),
        (
            // Plane x + y + z = 3 (+s) through the corner (1,1,1): only the normal separates.
            "plane through a box corner",
            Box::new(|s| {
                let k = 3.0 + s;
                t([k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k])
            }),
        ),
        (
            "segment touching an edge",
            Box::new(|s| {
                t(
                    [2.0 + s, 0.0, 0.5],
                    [0.0, 2.0 + s, 0.5],
                    [0.0, 2.0 + s, 0.5],
                )
            }),
        ),
        (
            "point on a corner",
            Box::new(|s| {
                let c = 1.0 + s;
                t([c, c, c], [c, c, c], [c, c, c])
            }),
        ),
    ];
    for (name, make) in &cases {
        // 4 STEPs: the smallest distance still exact after the sums above (e.g. 2 + s).
        assert!(ov(&make(0.0), b), "{name}: touching must count as overlap");
        assert!(
            !ov(&make(4.0 * STEP), b),
            "{name}: {} away must not",
            4.0 * STEP
        );
        assert!(
            ov(&make(-4.0 * STEP), b),
            "{name}: {} inside must",
            4.0 * STEP
        );
    }
}

#[test]
fn inside_containing_and_crossing() {
    let b = unit();
    // Wholly inside; a huge triangle containing the box's cross-section; a long needle
    // through the box with every vertex outside.
    assert!(ov(&t([0.2, 0.2, 0.2], [0.8, 0.2, 0.3], [0.3, 0.7, 0.6]), b));
    assert!(ov(
        &t(
            [-100.0, -100.0, 0.5],
            [100.0, -100.0, 0.5],
            [0.0, 100.0, 0.5]
        ),
        b
    ));
    assert!(ov(
        &t([-5.0, 0.5, 0.5], [5.0, 0.5, 0.5], [5.0, 0.5, 0.50001]),
        b
    ));
    // The same needle just above the box.
    assert!(!ov(
        &t([-5.0, 1.5, 0.5], [5.0, 1.5, 0.5], [5.0, 1.5, 0.50001]),
        b
    ));
    // A flat (zero-thickness) box is still a box.
    let flat = (DVec3::new(0.0, 0.0, 0.5), DVec3::new(1.0, 1.0, 0.5));
    assert!(ov(
        &t([0.5, 0.5, 0.0], [0.6, 0.5, 1.0], [0.5, 0.6, 1.0]),
        flat
    ));
    assert!(!ov(
        &t([0.5, 0.5, 0.6], [0.6, 0.5, 1.0], [0.5, 0.6, 1.0]),
        flat
    ));
    // A point box.
    let point = (DVec3::splat(0.25), DVec3::splat(0.25));
    assert!(ov(
        &t([0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.5, 0.0, 0.0]),
        point
    ));
    assert!(!ov(
        &t([0.0, 0.0, 0.0], [0.5, 0.5, 0.6], [0.5, 0.0, 0.0]),
        point
    ));
}

#[test]
fn nan_overlaps_nothing() {
    let nan = t([f32::NAN, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.6, 0.5]);
    assert!(!ov(&nan, unit()));
    assert!(!ov(&nan, (DVec3::splat(-1e30), DVec3::splat(1e30))));
}

/// Scaling everything by a power of two is exact, so the answers must not change, at
/// 2^-60 (1e-18, near the bottom of the normal f32 range once multiplied) and 2^60 (1e18,
/// near Embree's limit).
#[test]
fn scale_invariant_from_tiny_to_huge() {
    let mut rng = Rng::new(0x5eed_5ca1);
    for case in 0..20_000 {
        let lo = rng.unit_vec() * 2.0 - 1.0;
        let hi = lo + rng.unit_vec() * 0.5;
        let c = rng.unit_vec() * 2.0 - 1.0;
        let tri = Triangle::new(
            c + (rng.unit_vec() - 0.5) * 0.7,
            c + (rng.unit_vec() - 0.5) * 0.7,
            c + (rng.unit_vec() - 0.5) * 0.7,
        );
        let base = ov(&tri, (lo.as_dvec3(), hi.as_dvec3()));
        for k in [-60i32, 60] {
            let s = 2f32.powi(k);
            let scaled = Triangle::new(tri.v0 * s, tri.v1 * s, tri.v2 * s);
            assert_eq!(
                ov(&scaled, ((lo * s).as_dvec3(), (hi * s).as_dvec3())),
                base,
                "case {case} at 2^{k}"
            );
        }
    }
}

#[test]
fn far_from_origin_touching_is_exact() {
    // At 1e5 an f32 step is 2^-7: a triangle one step off the face is separated.
    let lo = DVec3::splat(100_000.0);
    let hi = DVec3::splat(100_001.0);
    let x = 100_001.0f32;
    let step = 1.0 / 128.0;
    let at = |s: f32| {
        t(
            [x + s, 1e5 + 0.5, 1e5 + 0.5],
            [x + 1.0, 1e5, 1e5],
            [x + 1.0, 1e5 + 1.0, 1e5 + 1.0],
        )
    };
    assert!(ov(&at(0.0), (lo, hi)));
    assert!(!ov(&at(step), (lo, hi)));
}

#[test]
fn conservative_box_grows_by_the_relative_margin() {
    let (lo, hi) = conservative_box(DVec3::new(-2.0, 0.0, 1.0), DVec3::new(4.0, 1.0, 1.0));
    let m = 4.0 * MARGIN_REL;
    assert_eq!(lo, DVec3::new(-2.0 - m, -m, 1.0 - m));
    assert_eq!(hi, DVec3::new(4.0 + m, 1.0 + m, 1.0 + m));
    // A child's enlarged box stays inside its parent's.
    let (plo, phi) = conservative_box(DVec3::splat(-8.0), DVec3::splat(8.0));
    let (clo, chi) = conservative_box(DVec3::splat(0.0), DVec3::splat(8.0));
    assert!(clo.cmpge(plo).all() && chi.cmple(phi).all());
}

/// For a triangle inside the box's slab on one axis, the 3 edge axes along it decide.
#[test]
fn edges_along_an_axis_decide_within_a_slab() {
    let mut rng = Rng::new(0x5eed_2d2d);
    let mut both = [0usize; 2];
    for case in 0..30_000 {
        let axis = case % 3;
        let lo = rng.unit_vec() * 2.0 - 1.0;
        let hi = lo + rng.unit_vec() * 0.6 + 0.01;
        let c = lo + (hi - lo) * (rng.unit_vec() * 2.0 - 0.5);
        let mut v = [0; 3].map(|_| c + (rng.unit_vec() - 0.5) * 0.8);
        for p in &mut v {
            p[axis] = lo[axis] + (hi[axis] - lo[axis]) * rng.unit();
        }
        let tb = TriBox::new(&Triangle::new(v[0], v[1], v[2]));
        let (blo, bhi) = (lo.as_dvec3(), hi.as_dvec3());
        let full = tb.overlaps(blo, bhi);
        assert_eq!(
            tb.bounds_overlap(blo, bhi) && tb.edges_overlap_along(blo, bhi, axis),
            full,
            "case {case}"
        );
        both[full as usize] += 1;
    }
    assert!(both[0] > 3000 && both[1] > 3000, "{both:?}");
}

#[test]
fn aabb_form_matches() {
    let tri = t([0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [0.5, 2.0, 0.5]);
    assert!(tri_box_overlap(&tri, &Aabb::new(Vec3::ZERO, Vec3::ONE)));
    assert!(!tri_box_overlap(
        &tri,
        &Aabb::new(Vec3::splat(1.5), Vec3::splat(2.0))
    ));
}
