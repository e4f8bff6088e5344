//! Legends drawn in a column to the right of the plot area, so they never cover data.

use super::overlay::{Anchor, CHAR_W, Overlay};
use plotters::style::RGBColor;

/// Width of the legend column, in pixels.
pub const LEGEND_W: u32 = 250;

/// What a legend entry shows before its text.
#[derive(Clone, Debug)]
pub enum Swatch {
    /// A filled square, for bars.
    Block(RGBColor),
    /// A line, solid or dashed (an SVG `stroke-dasharray`), with a dot for measured points.
    Line {
        color: RGBColor,
        dash: Option<String>,
        dot: bool,
    },
}

#[derive(Clone, Debug)]
pub struct Entry {
    pub label: String,
    pub swatch: Swatch,
}

/// Draws `entries` in the legend column of a chart panel of `panel_height` pixels whose side
/// area starts at `(sx, sy)`: below the title, clear of the bottom axis labels.
pub fn draw_beside(o: &mut Overlay, (sx, sy): (i32, i32), panel_height: u32, entries: &[Entry]) {
    draw(
        o,
        (sx as f64 + 8.0, sy as f64 + 40.0),
        panel_height as f64 - 60.0,
        entries,
    );
}

/// Draws `entries` top-down from `(x, y)` within `height` pixels: 16 pixels a row, closer when
/// that does not fit, and the rest summed up in one "… and n more" row below 11 pixels a row.
/// A label too long for the column is cut with "…" and keeps its full text as a hover title.
pub fn draw(o: &mut Overlay, (x, y): (f64, f64), height: f64, entries: &[Entry]) {
    if entries.is_empty() {
        return;
    }
    let row = (height / entries.len() as f64).clamp(11.0, 16.0);
    let fits = ((height / row).floor() as usize).max(1);
    let shown = if fits >= entries.len() {
        entries.len()
    } else {
        fits - 1
    };
    let max_chars = ((LEGEND_W as f64 - 36.0) / CHAR_W) as usize;
    for (i, e) in entries[..shown].iter().enumerate() {
        let cy = y + row * (i as f64 + 0.5);
        match &e.swatch {
            Swatch::Block(c) => o.filled_rect((x, cy - 5.0), (x + 10.0, cy + 5.0), *c),
            Swatch::Line { color, dash, dot } => {
                o.line((x - 4.0, cy), (x + 18.0, cy), *color, 2.0, dash.as_deref());
                if *dot {
                    o.circle((x + 7.0, cy), 3.0, *color);
                }
            }
        }
        let (text, title) = if e.label.chars().count() > max_chars {
            let cut: String = e.label.chars().take(max_chars - 1).collect();
            (format!("{cut}…"), Some(e.label.as_str()))
        } else {
            (e.label.clone(), None)
        };
        o.text((x + 24.0, cy), &text, Anchor::Start, 0.0, title);
    }
    if shown < entries.len() {
        let rest: Vec<&str> = entries[shown..].iter().map(|e| e.label.as_str()).collect();
        let cy = y + row * (shown as f64 + 0.5);
        o.text(
            (x + 24.0, cy),
            &format!("… and {} more", rest.len()),
            Anchor::Start,
            0.0,
            Some(&rest.join(", ")),
        );
    }
}
