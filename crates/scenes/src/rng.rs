//! Seeded random streams and the few distributions raybench needs.
//!
//! Every stream is a `Pcg64Mcg` seeded with `seed_from_u64(seed ^ PURPOSE)`, one constant per
//! purpose, so adding a workload or a generator never shifts another one's numbers. Floats are
//! built from the top 24 bits of a `u32`, which gives every value in `[0, 1)` on a 2^-24 grid
//! and is identical on every platform.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::Vec3;
use raybench_geom::rng::{GOLDEN_GAMMA, mix64};
use std::f32::consts::TAU;

/// Stream tags: ASCII names, so a seed dump is self-explanatory.
pub(crate) const SOUP_STREAM: u64 = u64::from_be_bytes(*b"gen-soup");
pub(crate) const RANDOM_RAYS_STREAM: u64 = u64::from_be_bytes(*b"wl-randm");
pub(crate) const DIFFUSE_RAYS_STREAM: u64 = u64::from_be_bytes(*b"wl-diffu");

pub(crate) fn stream(seed: u64, purpose: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed ^ purpose)
}

/// An independent stream per item (e.g. per ray index), so item `i`'s numbers do not depend on
/// how many numbers earlier items drew. The index is spread by a SplitMix64 finaliser so that
/// neighbouring indices do not give neighbouring seeds.
pub(crate) fn item_stream(seed: u64, purpose: u64, index: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed ^ purpose ^ mix64(index.wrapping_add(GOLDEN_GAMMA)))
}

/// Uniform in `[0, 1)`: the largest value is `1 - 2^-24`.
pub(crate) fn unit_f32(rng: &mut Pcg64Mcg) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Uniform in `[lo, hi]`.
pub(crate) fn range_f32(rng: &mut Pcg64Mcg, lo: f32, hi: f32) -> f32 {
    (lo + (hi - lo) * unit_f32(rng)).clamp(lo, hi)
}

/// A direction uniform on the unit sphere (Archimedes: z uniform in [-1, 1], angle uniform).
pub(crate) fn uniform_sphere(rng: &mut Pcg64Mcg) -> Vec3 {
    let z = 1.0 - 2.0 * unit_f32(rng);
    let phi = TAU * unit_f32(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A cosine-weighted direction about the unit normal `n` (Malley's method: uniform on the disk,
/// lifted to the hemisphere). `1 - r²` is at least 2^-24, so the direction's height above the
/// surface is at least 2^-12, far above the rounding of the basis, and `dir · n > 0` always.
pub(crate) fn cosine_hemisphere(rng: &mut Pcg64Mcg, n: Vec3) -> Vec3 {
    let r2 = unit_f32(rng);
    let phi = TAU * unit_f32(rng);
    let r = r2.sqrt();
    let height = (1.0 - r2).sqrt();
    let (t, b) = orthonormal_basis(n);
    t * (r * phi.cos()) + b * (r * phi.sin()) + n * height
}

/// Two unit vectors completing the unit vector `n` to an orthonormal basis, without a branch
/// on a near-parallel axis (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
pub(crate) fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_f32_is_below_one() {
        let mut rng = stream(7, 0);
        assert!(
            (0..10_000)
                .map(|_| unit_f32(&mut rng))
                .all(|x| (0.0..1.0).contains(&x))
        );
    }

    #[test]
    fn basis_is_orthonormal_including_the_poles() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            for (u, v) in [(t, b), (t, n), (b, n)] {
                assert!(u.dot(v).abs() < 1e-6, "{n} {t} {b}");
            }
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn streams_differ_by_purpose_and_item() {
        let draw = |mut r: Pcg64Mcg| r.next_u64();
        assert_ne!(
            draw(stream(1, SOUP_STREAM)),
            draw(stream(1, RANDOM_RAYS_STREAM))
        );
        assert_ne!(
            draw(item_stream(1, DIFFUSE_RAYS_STREAM, 0)),
            draw(item_stream(1, DIFFUSE_RAYS_STREAM, 1))
        );
    }
}
