//! Per-pixel pictures of the primary workload, kept in `report.json` so that `raybench report`
//! draws everything from the report alone: traversal cost (nodes + leaves + triangle tests +
//! cells per pixel, from the counted pass), a shaded render of the structure's own hits, and
//! where it disagrees with the reference.
//!
//! Stored downsampled to at most [`MAX_WIDTH`] pixels across (box filter: mean cost, mean
//! shade, worst disagreement), each plane as base64 of little-endian bytes, row-major from the
//! top-left: `cost` u16 (saturating), `shade` u8 (0 = miss, 1..=255 = lit hit), `disagree` u8
//! (0 agrees, 1 an explained difference — tie, boundary, edge-ambiguous — 2 a mismatch).

use raybench_accel::Hit;
use raybench_geom::{Ray, TriangleMesh};
use serde::{Deserialize, Serialize};

/// Widest stored image: 160 × 120 is 19,200 pixels, about 100 KB of base64 per structure.
pub const MAX_WIDTH: u32 = 160;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrimaryImage {
    pub width: u32,
    pub height: u32,
    /// Pixels of the traced image per stored pixel, per axis.
    pub downsample: u32,
    /// Base64 of u16 LE per pixel; absent for structures that cannot count (Embree).
    pub cost: Option<String>,
    pub shade: String,
    pub disagree: String,
}

/// What one traced pixel contributes.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelInput {
    pub cost: Option<u32>,
    pub shade: u8,
    pub disagree: u8,
}

/// Shade of a hit as seen along the ray: |cos| between the geometric normal and the ray,
/// mapped to 1..=255 so that 0 means "miss".
pub fn shade(mesh: &TriangleMesh, ray: &Ray, hit: Option<&Hit>) -> u8 {
    let Some(h) = hit else { return 0 };
    let n = mesh
        .triangle(h.prim as usize)
        .geometric_normal()
        .normalize_or_zero();
    let d = ray.dir().normalize_or_zero();
    1 + (n.dot(d).abs() * 254.0).round() as u8
}

impl PrimaryImage {
    /// Downsamples a `width × height` image of traced pixels (row-major from the top-left).
    pub fn new(width: u32, height: u32, pixels: &[PixelInput]) -> PrimaryImage {
        assert_eq!(
            pixels.len(),
            width as usize * height as usize,
            "one input per pixel"
        );
        let f = width.div_ceil(MAX_WIDTH).max(1);
        let (w, h) = (width.div_ceil(f), height.div_ceil(f));
        let counted = pixels.iter().all(|p| p.cost.is_some());
        let (mut cost, mut shade, mut disagree) = (Vec::new(), Vec::new(), Vec::new());
        for by in 0..h {
            for bx in 0..w {
                let (mut c, mut s, mut d, mut n) = (0u64, 0u64, 0u8, 0u64);
                for y in by * f..((by + 1) * f).min(height) {
                    for x in bx * f..((bx + 1) * f).min(width) {
                        let p = &pixels[(y * width + x) as usize];
                        c += p.cost.unwrap_or(0) as u64;
                        s += p.shade as u64;
                        d = d.max(p.disagree);
                        n += 1;
                    }
                }
                let n = n.max(1);
                cost.extend_from_slice(&((c / n).min(u16::MAX as u64) as u16).to_le_bytes());
                shade.push((s / n) as u8);
                disagree.push(d);
            }
        }
        PrimaryImage {
            width: w,
            height: h,
            downsample: f,
            cost: counted.then(|| base64_encode(&cost)),
            shade: base64_encode(&shade),
            disagree: base64_encode(&disagree),
        }
    }

    /// Width × height, in `usize` so a report's sizes cannot overflow it.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The decoded cost plane, checked against the image size.
    pub fn cost_values(&self) -> Result<Option<Vec<u16>>, String> {
        let Some(text) = &self.cost else {
            return Ok(None);
        };
        let bytes = base64_decode(text)?;
        if bytes.len() != 2 * self.pixels() {
            return Err(format!(
                "cost plane has {} bytes for {} pixels",
                bytes.len(),
                self.pixels()
            ));
        }
        Ok(Some(
            bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect(),
        ))
    }

    pub fn shade_values(&self) -> Result<Vec<u8>, String> {
        self.plane(&self.shade, "shade")
    }

    pub fn disagree_values(&self) -> Result<Vec<u8>, String> {
        self.plane(&self.disagree, "disagree")
    }

    fn plane(&self, text: &str, what: &str) -> Result<Vec<u8>, String> {
        let bytes = base64_decode(text)?;
        if bytes.len() != self.pixels() {
            return Err(format!(
                "{what} plane has {} bytes for {} pixels",
                bytes.len(),
                self.pixels()
            ));
        }
        Ok(bytes)
    }
}

const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 (RFC 4648) with `=` padding.
pub fn base64_encode(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

pub fn base64_decode(text: &str) -> Result<Vec<u8>, String> {
    let bytes = text.as_bytes();
    if !bytes.len().is_multiple_of(4) {
        return Err(format!(
            "base64 length {} is not a multiple of 4",
            bytes.len()
        ));
    }
    let value = |c: u8| -> Result<u32, String> {
        ALPHABET
            .iter()
            .position(|&a| a == c)
            .map(|p| p as u32)
            .ok_or_else(|| format!("invalid base64 character {}", (c as char).escape_default()))
    };
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3);
    for (k, quad) in bytes.chunks(4).enumerate() {
        let last = k == bytes.len() / 4 - 1;
        let pad = quad.iter().rev().take_while(|&&c| c == b'=').count();
        if pad > 2 || (pad > 0 && !last) {
            return Err("misplaced base64 padding".into());
        }
        let mut n = 0u32;
        for &c in &quad[..4 - pad] {
            n = n << 6 | value(c)?;
        }
        n <<= 6 * pad as u32;
        let got = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&got[..3 - pad]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_and_matches_rfc_4648() {
        assert_eq!(base64_encode(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64_encode(b"fooba"), "Zm9vYmE=");
        assert_eq!(base64_encode(b"foob"), "Zm9vYg==");
        for n in 0..40u8 {
            let data: Vec<u8> = (0..n).map(|i| i.wrapping_mul(37) ^ 0xa5).collect();
            assert_eq!(base64_decode(&base64_encode(&data)).unwrap(), data);
        }
        assert!(base64_decode("Zm9").is_err());
        assert!(base64_decode("Zm=v").is_err());
        assert!(base64_decode("Zm9*").is_err());
    }

    #[test]
    fn downsampling_averages_cost_and_keeps_the_worst_disagreement() {
        // 320 × 2 pixels → factor 2 → 160 × 1.
        let mut pixels = vec![PixelInput::default(); 640];
        for (i, p) in pixels.iter_mut().enumerate() {
            p.cost = Some(i as u32 % 2 * 10); // 0, 10, 0, 10, …
            p.shade = 100;
        }
        pixels[1].disagree = 2;
        let img = PrimaryImage::new(320, 2, &pixels);
        assert_eq!((img.width, img.height, img.downsample), (160, 1, 2));
        let cost = img.cost_values().unwrap().unwrap();
        assert!(cost.iter().all(|&c| c == 5), "{cost:?}");
        let d = img.disagree_values().unwrap();
        assert_eq!((d[0], d[1]), (2, 0));
        assert!(img.shade_values().unwrap().iter().all(|&s| s == 100));
    }

    #[test]
    fn uncounted_structures_have_no_cost_plane() {
        let pixels = vec![PixelInput::default(); 6];
        let img = PrimaryImage::new(3, 2, &pixels);
        assert_eq!((img.width, img.height, img.downsample), (3, 2, 1));
        assert_eq!(img.cost_values().unwrap(), None);
    }
}
