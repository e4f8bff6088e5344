//! SVG drawn beside plotters' output: what plotters cannot write. Rotated tick labels that do
//! not overlap, `<title>` elements (a browser shows them on hover, so an abbreviated label can
//! still carry the full scene name), and legends outside the plot area. Coordinates are the
//! SVG's own pixels (plotters' backend coordinates), so the pieces line up with the chart.

use super::palette::hex;
use plotters::style::RGBColor;
use std::fmt::Write as _;

/// Font size, in SVG pixels, of every overlay text.
pub const FONT: f64 = 11.0;

/// Average advance of one character of a sans-serif font at `FONT`, for layout estimates
/// (the SVG names no font, so the real width depends on the viewer's; digits are 0.556 em in
/// Helvetica, Arial and Liberation Sans, and most lower-case letters narrower).
pub const CHAR_W: f64 = 0.56 * FONT;

pub fn text_width(s: &str) -> f64 {
    s.chars().count() as f64 * CHAR_W
}

/// XML-escapes text for an SVG text node or attribute.
pub fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// How a text is placed around its anchor point.
#[derive(Clone, Copy, Debug)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    fn svg(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// SVG fragments to draw on top of a chart, and grid lines to draw under everything.
#[derive(Debug, Default)]
pub struct Overlay {
    svg: String,
    under: String,
}

impl Overlay {
    /// A text whose baseline is centred vertically on `y` (the anchor is at its middle
    /// height), turned by `rotate` degrees about its anchor, with an optional hover title.
    pub fn text(
        &mut self,
        (x, y): (f64, f64),
        text: &str,
        anchor: Anchor,
        rotate: f64,
        title: Option<&str>,
    ) {
        let transform = if rotate == 0.0 {
            String::new()
        } else {
            format!(" transform=\"rotate({rotate:.0} {x:.1} {y:.1})\"")
        };
        let title = title.map_or(String::new(), |t| format!("<title>{}</title>", xml(t)));
        let _ = writeln!(
            self.svg,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" dy=\"0.35em\" text-anchor=\"{}\" font-family=\"sans-serif\" \
             font-size=\"{FONT}\" fill=\"#000000\"{transform}>{title}{}</text>",
            anchor.svg(),
            xml(text)
        );
    }

    /// A bold label on a white halo, readable over the lines it sits on.
    pub fn callout(&mut self, (x, y): (f64, f64), text: &str, title: &str) {
        let _ = writeln!(
            self.svg,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" dy=\"0.35em\" text-anchor=\"start\" \
             font-family=\"sans-serif\" font-size=\"{}\" font-weight=\"bold\" fill=\"#000000\" \
             stroke=\"#ffffff\" stroke-width=\"4\" paint-order=\"stroke\"><title>{}</title>{}</text>",
            FONT + 1.0,
            xml(title),
            xml(text)
        );
    }

    /// A line segment; `dash` is an SVG `stroke-dasharray` ("8 4").
    pub fn line(
        &mut self,
        (x0, y0): (f64, f64),
        (x1, y1): (f64, f64),
        color: RGBColor,
        width: f64,
        dash: Option<&str>,
    ) {
        let dash = dash.map_or(String::new(), |d| format!(" stroke-dasharray=\"{d}\""));
        let _ = writeln!(
            self.svg,
            "<line x1=\"{x0:.1}\" y1=\"{y0:.1}\" x2=\"{x1:.1}\" y2=\"{y1:.1}\" stroke=\"{}\" \
             stroke-width=\"{width}\"{dash}/>",
            hex(color)
        );
    }

    pub fn filled_rect(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), color: RGBColor) {
        let _ = writeln!(
            self.svg,
            "<rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{}\"/>",
            x1 - x0,
            y1 - y0,
            hex(color)
        );
    }

    pub fn circle(&mut self, (x, y): (f64, f64), r: f64, color: RGBColor) {
        let _ = writeln!(
            self.svg,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"{}\"/>",
            hex(color)
        );
    }

    /// An unfilled circle, to point a spot out.
    pub fn ring(&mut self, (x, y): (f64, f64), r: f64, color: RGBColor) {
        let _ = writeln!(
            self.svg,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"none\" stroke=\"{}\" \
             stroke-width=\"1.5\"/>",
            hex(color)
        );
    }

    /// An invisible rectangle that shows `title` when hovered.
    pub fn hover_rect(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), title: &str) {
        let _ = writeln!(
            self.svg,
            "<rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"#ffffff\" \
             fill-opacity=\"0\"><title>{}</title></rect>",
            (x1 - x0).max(0.0),
            (y1 - y0).max(0.0),
            xml(title)
        );
    }

    /// An invisible disc that shows `title` when hovered (a measured point's value).
    pub fn hover_circle(&mut self, (x, y): (f64, f64), r: f64, title: &str) {
        let _ = writeln!(
            self.svg,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"#ffffff\" fill-opacity=\"0\">\
             <title>{}</title></circle>",
            xml(title)
        );
    }

    /// A light grid line, drawn under the data.
    pub fn grid_line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) {
        let _ = writeln!(
            self.under,
            "<line x1=\"{x0:.1}\" y1=\"{y0:.1}\" x2=\"{x1:.1}\" y2=\"{y1:.1}\" stroke=\"#000000\" \
             stroke-opacity=\"0.12\" stroke-width=\"1\"/>"
        );
    }

    /// A y axis's ticks: at each (pixel row, label) a grid line across the plot from `left` to
    /// `right`, a tick mark and the label left of the axis.
    pub fn y_axis(&mut self, ticks: &[(f64, String)], left: f64, right: f64) {
        for (y, label) in ticks {
            self.grid_line((left, *y), (right, *y));
            self.line((left - 5.0, *y), (left, *y), RGBColor(0, 0, 0), 1.0, None);
            self.text((left - 8.0, *y), label, Anchor::End, 0.0, None);
        }
    }

    /// `svg` (a complete document from plotters) with the grid lines drawn first, over the
    /// background only, and the rest of the overlay last, on top.
    pub fn apply(self, mut svg: String) -> String {
        match svg.rfind("</svg>") {
            Some(end) => svg.insert_str(end, &self.svg),
            None => svg.push_str(&self.svg),
        }
        // plotters opens with the `<svg>` tag and the background `<rect …/>`, a line each.
        let after_background = svg
            .match_indices('\n')
            .nth(1)
            .map_or(svg.len(), |(i, _)| i + 1);
        svg.insert_str(after_background, &self.under);
        svg
    }
}

/// Where tick labels under an axis go, and how they are turned so that none overlaps another.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelLayout {
    /// Degrees (0, -35 or -90).
    pub rotate: f64,
    /// Show every `step`-th label (1 unless even upright-turned labels would collide).
    pub step: usize,
}

impl LabelLayout {
    /// The layout for labels of which the widest is `widest` pixels, at least `spacing` pixels
    /// apart: level if they fit side by side, else turned by 35°, else upright, else thinned.
    pub fn for_labels(widest: f64, spacing: f64) -> LabelLayout {
        let gap = 6.0;
        let (rotate, need) = if widest + gap <= spacing {
            (0.0, 0.0)
        } else if FONT / 35f64.to_radians().sin() + gap <= spacing {
            (-35.0, 0.0)
        } else {
            (-90.0, FONT + 2.0)
        };
        let step = if need > 0.0 && spacing > 0.0 {
            (need / spacing).ceil().max(1.0) as usize
        } else {
            1
        };
        LabelLayout { rotate, step }
    }

    /// Height the labels take below the axis, for labels up to `widest` pixels wide.
    pub fn height(&self, widest: f64) -> f64 {
        let a = self.rotate.abs().to_radians();
        widest * a.sin() + FONT * a.cos() + 8.0
    }

    /// Draws `label` for a tick at `x` under an axis at `y`.
    pub fn draw(&self, o: &mut Overlay, (x, y): (f64, f64), label: &str, title: Option<&str>) {
        if self.rotate == 0.0 {
            o.text((x, y + 10.0), label, Anchor::Middle, 0.0, title);
        } else {
            o.text((x, y + 8.0), label, Anchor::End, self.rotate, title);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_turn_only_when_they_would_touch() {
        assert_eq!(LabelLayout::for_labels(60.0, 100.0).rotate, 0.0);
        assert_eq!(LabelLayout::for_labels(120.0, 100.0).rotate, -35.0);
        let crowded = LabelLayout::for_labels(120.0, 10.0);
        assert_eq!(crowded.rotate, -90.0);
        assert_eq!(
            crowded.step, 2,
            "13 px of upright text need every other 10 px slot"
        );
        assert_eq!(LabelLayout::for_labels(120.0, 30.0).step, 1);
    }

    #[test]
    fn the_overlay_lands_inside_the_document_and_escapes_text() {
        let mut o = Overlay::default();
        o.text((1.0, 2.0), "a<b", Anchor::Start, -35.0, Some("x & y"));
        o.grid_line((0.0, 1.0), (2.0, 1.0));
        let svg = o.apply("<svg>\n<rect/>\n<line/>\n</svg>\n".into());
        assert!(svg.ends_with("</svg>\n"), "{svg}");
        let grid = svg.find("stroke-opacity").unwrap();
        assert!(svg.find("<rect/>").unwrap() < grid && grid < svg.find("<line/>").unwrap());
        assert!(
            svg.contains("<title>x &amp; y</title>a&lt;b</text>"),
            "{svg}"
        );
        assert!(svg.contains("rotate(-35 1.0 2.0)"), "{svg}");
    }
}
