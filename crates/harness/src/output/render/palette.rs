//! One colour per structure, the same in every chart of a report.
//!
//! A structure's colour is the palette entry at its position in the report's structure list
//! (`run.structures`, then any structure only the results name), so two reports of suites that
//! list their structures in the same order colour them alike. The palette is Tableau 10
//! followed by fourteen colours picked greedily, each as far (CIELAB ΔE) from every earlier one
//! and from black and white as a 15-step RGB grid allowed, lightness 25–80 so each stands out
//! on white. Black is kept for the reference curves (theory lines).

use super::names::structure_names;
use crate::report::run::Report;
use plotters::style::RGBColor;

pub const PALETTE: [RGBColor; 24] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 255),
    RGBColor(255, 30, 255),
    RGBColor(0, 75, 30),
    RGBColor(90, 0, 165),
    RGBColor(240, 180, 120),
    RGBColor(0, 225, 0),
    RGBColor(165, 210, 150),
    RGBColor(255, 0, 120),
    RGBColor(120, 0, 75),
    RGBColor(120, 105, 15),
    RGBColor(0, 105, 255),
    RGBColor(255, 135, 135),
    RGBColor(195, 0, 165),
    RGBColor(210, 180, 225),
];

/// The structures of one report and their colours.
#[derive(Clone, Debug)]
pub struct Palette {
    structures: Vec<String>,
}

impl Palette {
    pub fn for_report(report: &Report) -> Palette {
        let mut structures = report.run.structures.clone();
        for name in structure_names(report) {
            if !structures.contains(&name) {
                structures.push(name);
            }
        }
        Palette { structures }
    }

    /// The colour of `structure`. Past the palette's 24 colours they repeat (a later entry of
    /// the same colour is then told apart by its marker, see [`Palette::marker`]); a structure
    /// the report does not list gets grey.
    pub fn color(&self, structure: &str) -> RGBColor {
        match self.position(structure) {
            Some(i) => PALETTE[i % PALETTE.len()],
            None => RGBColor(90, 90, 90),
        }
    }

    /// Which marker a structure's measured points use: 0 (a dot) for the first 24 structures,
    /// then 1, 2, … for each further round through the palette.
    pub fn marker(&self, structure: &str) -> usize {
        self.position(structure).map_or(0, |i| i / PALETTE.len())
    }

    fn position(&self, structure: &str) -> Option<usize> {
        self.structures.iter().position(|s| s == structure)
    }
}

/// `#rrggbb`, as SVG attributes take it.
pub fn hex(c: RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lab(c: RGBColor) -> [f64; 3] {
        let lin = |v: u8| {
            let v = v as f64 / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (lin(c.0), lin(c.1), lin(c.2));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| {
            if t > 216.0 / 24389.0 {
                t.cbrt()
            } else {
                (24389.0 / 27.0 * t + 16.0) / 116.0
            }
        };
        [
            116.0 * f(y) - 16.0,
            500.0 * (f(x) - f(y)),
            200.0 * (f(y) - f(z)),
        ]
    }

    fn delta_e(a: RGBColor, b: RGBColor) -> f64 {
        let (a, b) = (lab(a), lab(b));
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    /// Tableau 10's closest pair is ΔE 27.7 apart; no added colour comes closer than that.
    #[test]
    fn every_two_palette_colours_are_clearly_apart() {
        for (i, &a) in PALETTE.iter().enumerate() {
            for &b in &PALETTE[i + 1..] {
                assert!(delta_e(a, b) > 27.0, "{a:?} and {b:?} look alike");
            }
            assert!(
                delta_e(a, RGBColor(255, 255, 255)) > 20.0,
                "{a:?} fades on white"
            );
            assert!(
                delta_e(a, RGBColor(0, 0, 0)) > 25.0,
                "{a:?} looks like a theory line"
            );
        }
    }

    #[test]
    fn hex_is_lower_case_rrggbb() {
        assert_eq!(hex(RGBColor(31, 119, 180)), "#1f77b4");
        assert_eq!(hex(RGBColor(0, 5, 255)), "#0005ff");
    }
}
