//! The per-pixel pictures of a report as PNG: traversal-cost heatmaps on one colour scale per
//! scene, shaded renders, and "disagrees with the reference" masks. No text is drawn into the
//! PNGs (that would need fonts); the HTML page labels them and the legend's numbers.

use crate::output::png::write_png;
use crate::pipeline::images::PrimaryImage;
use anyhow::{Result, anyhow};
use std::path::Path;

/// Viridis at nine stops (from matplotlib's table), interpolated linearly in between.
const VIRIDIS: [[f32; 3]; 9] = [
    [68.0, 1.0, 84.0],
    [71.0, 44.0, 122.0],
    [59.0, 81.0, 139.0],
    [44.0, 113.0, 142.0],
    [33.0, 144.0, 141.0],
    [39.0, 173.0, 129.0],
    [92.0, 200.0, 99.0],
    [170.0, 220.0, 50.0],
    [253.0, 231.0, 37.0],
];

/// Colour for `t` in `[0, 1]` (clamped).
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } as f32;
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    std::array::from_fn(|c| (VIRIDIS[i][c] * (1.0 - f) + VIRIDIS[i + 1][c] * f).round() as u8)
}

/// Heatmap pixels on a logarithmic scale: cost 0 is the bottom, `max` the top. Logarithmic
/// because one scale serves every structure of a scene, and brute force (N tests per pixel)
/// would otherwise flatten every tree into the bottom colour.
pub fn heatmap_pixels(img: &PrimaryImage, max: u16) -> Result<Option<Vec<[u8; 3]>>> {
    let Some(cost) = img.cost_values().map_err(|e| anyhow!(e))? else {
        return Ok(None);
    };
    Ok(Some(
        cost.iter().map(|&c| viridis(log_scale(c, max))).collect(),
    ))
}

/// `ln(1 + c) / ln(1 + max)`: 0 for no work, 1 at the scene's maximum.
pub fn log_scale(c: u16, max: u16) -> f64 {
    log_position(c.into(), max.into())
}

/// Where cost `c` sits on a logarithmic scale whose top is `max`: `ln(1 + c) / ln(1 + max)`.
pub fn log_position(c: u64, max: u64) -> f64 {
    (1.0 + c as f64).ln() / (1.0 + max.max(1) as f64).ln()
}

/// Heatmap pixels from costs already on a quantized logarithmic scale (`round(k·ln(1 + c))`),
/// `top` being the scene maximum's step: the same colours as [`log_scale`], from half the
/// memory of exact costs.
pub fn heat_rgb(steps: &[u16], top: u16) -> Vec<[u8; 3]> {
    let top = f64::from(top.max(1));
    steps.iter().map(|&q| viridis(f64::from(q) / top)).collect()
}

/// Miss: dark blue-grey background; hit: grey from the shade (1..=255).
pub fn render_rgb(shade: &[u8]) -> Vec<[u8; 3]> {
    shade
        .iter()
        .map(|&s| {
            if s == 0 {
                [34, 40, 49]
            } else {
                let v = 40 + (s as u32 * 215 / 255) as u8;
                [v, v, v]
            }
        })
        .collect()
}

/// Agreeing pixels as a dim version of the render, explained differences amber, mismatches red;
/// each disagreeing pixel also gets a half-tone halo [`HALO`] pixels wide per 640 of width, so
/// that a single one can be found in a picture shown smaller than its file. The pixel itself
/// keeps the full colour.
pub fn mask_rgb(shade: &[u8], levels: &[u8], width: usize) -> Vec<[u8; 3]> {
    let colour = |d: u8| if d == 1 { [255, 191, 0] } else { [230, 20, 20] };
    let mut out: Vec<[u8; 3]> = shade
        .iter()
        .zip(levels)
        .map(|(&s, &d)| match d {
            0 => {
                let v = 20 + (s as u32 * 60 / 255) as u8;
                [v, v, v]
            }
            d => colour(d),
        })
        .collect();
    let width = width.max(1);
    let height = levels.len() / width;
    let r = (HALO * width).div_ceil(640);
    for (i, &d) in levels.iter().enumerate().filter(|(_, d)| **d > 0) {
        let (x, y) = (i % width, i / width);
        for yy in y.saturating_sub(r)..(y + r + 1).min(height) {
            for xx in x.saturating_sub(r)..(x + r + 1).min(width) {
                let j = yy * width + xx;
                if levels[j] == 0 {
                    let [a, b, c] = colour(d);
                    let [p, q, s] = out[j];
                    out[j] = [a / 2 + p / 2, b / 2 + q / 2, c / 2 + s / 2];
                }
            }
        }
    }
    out
}

/// Halo radius of a disagreeing pixel in a 640-wide mask.
pub const HALO: usize = 4;

pub fn shade_pixels(img: &PrimaryImage) -> Result<Vec<[u8; 3]>> {
    Ok(render_rgb(&img.shade_values().map_err(|e| anyhow!(e))?))
}

pub fn disagree_pixels(img: &PrimaryImage) -> Result<Vec<[u8; 3]>> {
    let shade = img.shade_values().map_err(|e| anyhow!(e))?;
    let d = img.disagree_values().map_err(|e| anyhow!(e))?;
    Ok(mask_rgb(&shade, &d, img.width as usize))
}

/// The largest cost of any structure's image of a scene: one colour scale per scene.
pub fn shared_max(images: &[&PrimaryImage]) -> u16 {
    images
        .iter()
        .filter_map(|i| i.cost_values().ok().flatten())
        .flat_map(|c| c.into_iter())
        .max()
        .unwrap_or(1)
        .max(1)
}

pub fn write(pixels: &[[u8; 3]], img: &PrimaryImage, out: &Path) -> Result<()> {
    write_png(pixels, img.width, img.height, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_runs_from_dark_purple_to_yellow() {
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        let mid = viridis(0.5);
        assert_eq!(mid, [33, 144, 141]);
    }
}
