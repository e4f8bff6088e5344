//! PNG files from RGB pixels, encoded by the `png` crate and written atomically (no text is
//! drawn, so no fonts are read).

use crate::atomic::write_atomic_with;
use anyhow::{Result, bail};
use std::path::Path;

/// Largest preview side, and largest pixel count (64 Mi pixels = 192 MiB of RGB).
pub const MAX_PREVIEW_SIDE: u32 = 16_384;
pub const MAX_PREVIEW_PIXELS: u64 = 1 << 26;

pub(crate) fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 || width > MAX_PREVIEW_SIDE || height > MAX_PREVIEW_SIDE {
        bail!("image size {width}×{height}: each side must be 1 to {MAX_PREVIEW_SIDE}");
    }
    if u64::from(width) * u64::from(height) > MAX_PREVIEW_PIXELS {
        bail!("image size {width}×{height}: more than {MAX_PREVIEW_PIXELS} pixels");
    }
    Ok(())
}

/// Writes RGB pixels (row-major from the top-left) as a PNG file, atomically
/// ([`crate::atomic`]).
pub fn write_png(pixels: &[[u8; 3]], width: u32, height: u32, out: &Path) -> Result<()> {
    check_size(width, height)?;
    anyhow::ensure!(
        pixels.len() == width as usize * height as usize,
        "{} pixels for a {width}×{height} image",
        pixels.len()
    );
    write_atomic_with(out, |w| {
        let mut encoder = png::Encoder::new(w, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(pixels.as_flattened())
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
}
