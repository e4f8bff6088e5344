use super::*;
use crate::WideParams;
use raybench_geom::Aabb;

/// Boxes of `n` small triangles scattered in the unit cube, from a fixed seed.
fn scattered(n: usize, seed: u64) -> Vec<Aabb> {
    let mut rng = raybench_geom::SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let lo = rng.unit_vec();
            Aabb::new(lo, lo + rng.unit_vec() * 0.05)
        })
        .collect()
}

fn refs_of(boxes: &[Aabb], scale: f32) -> Vec<PrimRef> {
    let scaled = |b: &Aabb| Aabb::new(b.min * scale, b.max * scale);
    (0..boxes.len())
        .map(|i| PrimRef::new(&scaled(&boxes[i]), i as u32))
        .collect()
}

/// The premise of [`leaf_beats_any_split`], which lets the builder skip binning: with the
/// wide tree's knobs no split of up to four triangles is ever taken, by the binned or the
/// sweep builder, and five may be.
#[test]
fn a_leaf_no_dearer_than_a_node_step_is_never_split() {
    let wide = WideParams::default().binary;
    assert!(leaf_beats_any_split(&wide, 4));
    assert!(!leaf_beats_any_split(&wide, 5));
    assert!(!leaf_beats_any_split(&BvhParams::binned(), 2));
    for seed in 0..200 {
        for n in 2..=4 {
            let mut refs = refs_of(&scattered(n, seed), 1.0);
            let r = Ranged::of(&refs, PARALLEL_BINNING);
            let binned = binned_split(&mut refs, &r, &wide, &mut Scratch::new());
            assert!(binned.is_none(), "seed {seed}: {n} triangles split");
            assert!(sweep_split(&mut refs, &r, &wide).is_none());
        }
    }
}

/// The sweep runs in f32 on coordinates scaled by the node's largest extent, so the split
/// does not depend on the mesh's scale (powers of two scale exactly), from 2^-60 to near
/// the mesh limit of 1.8e18, where unscaled areas weighted by counts would overflow f32.
#[test]
fn the_binned_split_is_the_same_at_every_scale() {
    for (seed, n) in [(1, 40), (2, 300), (3, 5000)] {
        let boxes = scattered(n, seed);
        let split_at = |scale: f32| {
            let mut refs = refs_of(&boxes, scale);
            let r = Ranged::of(&refs, PARALLEL_BINNING);
            let p = WideParams::default().binary;
            let s = binned_split(&mut refs, &r, &p, &mut Scratch::new()).expect("splits");
            let left: Vec<u32> = refs[..s.mid].iter().map(PrimRef::id).collect();
            (s.mid, left)
        };
        let unit = split_at(1.0);
        assert!(0 < unit.0 && unit.0 < n);
        for scale in [2f32.powi(-60), 2f32.powi(59)] {
            assert_eq!(split_at(scale), unit, "seed {seed}, scale {scale:e}");
        }
    }
}

#[test]
fn a_node_gets_a_bin_per_triangles_per_bin() {
    let p = BvhParams {
        bins: 64,
        triangles_per_bin: 4,
        ..BvhParams::binned()
    };
    let bins: Vec<usize> = [2, 9, 40, 255, 256, 100_000]
        .iter()
        .map(|&n| bins_for(&p, n))
        .collect();
    assert_eq!(bins, [2, 2, 10, 63, 64, 64]);
    assert_eq!(bins_for(&BvhParams::binned(), 20), 20);
}

/// `centroids_from_boxes`: the bounds taken from a child's box hold every centroid of its
/// records (else the binner's clamp would pile them into the end bins), at every scale; below
/// the knob's size, and with it off, a child's bounds are exactly its centroids'.
#[test]
fn centroid_bounds_from_boxes_hold_every_centroid() {
    for (seed, n) in [(4, 300), (5, 5000), (6, 70_000)] {
        let boxes = scattered(n, seed);
        for scale in [2f32.powi(-60), 1.0, 2f32.powi(59)] {
            for knob in [Some(0), Some(256), None] {
                let mut refs = refs_of(&boxes, scale);
                let r = Ranged::of(&refs, PARALLEL_BINNING);
                let p = BvhParams {
                    centroids_from_boxes: knob,
                    ..WideParams::default().binary
                };
                let s = binned_split(&mut refs, &r, &p, &mut Scratch::new()).expect("splits");
                for (side, range) in [(s.left, &refs[..s.mid]), (s.right, &refs[s.mid..])] {
                    let exact = Box3::centroids_of(range, PARALLEL_BINNING);
                    let held = exact.lo.cmpge(side.centroids.lo).all()
                        && exact.hi.cmple(side.centroids.hi).all();
                    assert!(
                        held,
                        "seed {seed}, scale {scale:e}, {knob:?}: a centroid outside"
                    );
                    if knob.is_none_or(|m| range.len() < m as usize) {
                        assert_eq!((exact.lo, exact.hi), (side.centroids.lo, side.centroids.hi));
                    }
                }
            }
        }
    }
}
