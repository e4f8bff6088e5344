//! PNG files from RGB pixels, written atomically through plotters' bitmap backend (no text is
//! drawn, so no fonts are read).

use anyhow::{Context, Result, anyhow, bail};
use plotters::prelude::{BitMapBackend, DrawingBackend};
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

/// Writes RGB pixels (row-major from the top-left) as a PNG, atomically: a temporary `.png`
/// next to `out` (plotters picks the format from the extension), then a rename over `out`.
pub fn write_png(pixels: &[[u8; 3]], width: u32, height: u32, out: &Path) -> Result<()> {
    check_size(width, height)?;
    anyhow::ensure!(
        pixels.len() == width as usize * height as usize,
        "{} pixels for a {width}×{height} image",
        pixels.len()
    );
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "preview.png".into());
    let tmp = out.with_file_name(format!(".{name}.tmp-{}.png", std::process::id()));
    let result = (|| -> Result<()> {
        let flat: Vec<u8> = pixels.iter().flatten().copied().collect();
        let mut backend = BitMapBackend::new(&tmp, (width, height));
        backend
            .blit_bitmap((0, 0), (width, height), &flat)
            .map_err(|e| anyhow!("{}: {e}", tmp.display()))?;
        backend
            .present()
            .map_err(|e| anyhow!("{}: {e}", tmp.display()))?;
        drop(backend);
        std::fs::rename(&tmp, out)
            .with_context(|| format!("{} (renaming {} over it)", out.display(), tmp.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
