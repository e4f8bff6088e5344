//! SVG charts drawn with plotters. Text is emitted as SVG `<text>` (plotters' naive font, and
//! the `Overlay`'s own), so no font files are read at build or run time. Two shapes cover
//! every chart: grouped bars (groups on x, one bar per series), here, and lines
//! ([`super::lines`]). Both keep their legend in a column right of the plot and draw the
//! fastest and slowest timed run as an error bar where the report has them.

use super::legend::{self, Entry, LEGEND_W, Swatch};
use super::overlay::{LabelLayout, Overlay, text_width};
use super::ticks::{axis_ticks, tick_label};
use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

/// One named series of values, one per group (`None`: no bar).
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub color: RGBColor,
    pub values: Vec<Option<f64>>,
    /// Per group, the lowest and highest of the timed runs, drawn as an error bar over the
    /// bar (empty: none).
    pub ranges: Vec<Option<(f64, f64)>>,
}

/// A grouped bar chart.
#[derive(Clone, Debug)]
pub struct Bars {
    pub title: String,
    pub y_desc: String,
    /// The label under each group.
    pub groups: Vec<String>,
    /// Each group's full name, shown on hover (empty: the labels).
    pub group_titles: Vec<String>,
    pub series: Vec<Series>,
    pub log_y: bool,
}

impl Bars {
    /// True when there is at least one bar to draw.
    pub fn has_data(&self) -> bool {
        self.positive_values().next().is_some()
    }

    fn positive_values(&self) -> impl Iterator<Item = f64> + '_ {
        self.series
            .iter()
            .flat_map(|s| s.values.iter().flatten().copied())
            .filter(|v| v.is_finite() && *v > 0.0)
    }

    fn group_title(&self, g: usize) -> &str {
        self.group_titles.get(g).unwrap_or(&self.groups[g]).as_str()
    }
}

pub(super) fn plot_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e}")
}

/// Renders one chart to an SVG string.
pub fn bars_svg(chart: &Bars, width: u32, height: u32) -> Result<String> {
    panels_svg(std::slice::from_ref(chart), width, height, |a, c, o| {
        draw_bars(a, c, o)
    })
}

/// Several charts stacked vertically in one SVG (e.g. the three counters of a workload).
#[allow(clippy::redundant_closure)]
pub fn stacked_bars_svg(charts: &[Bars], width: u32, panel_height: u32) -> Result<String> {
    panels_svg(charts, width, panel_height, |a, c, o| draw_bars(a, c, o))
}

/// One SVG of `panel_height`-high panels stacked vertically, each drawn by `draw`, which may
/// add to one [`Overlay`] drawn over the whole. Callers pass closures, not the generic draw
/// functions themselves: those are instantiated for one backend lifetime, and `draw` must
/// accept any (clippy's `redundant_closure` is wrong here).
pub(super) fn panels_svg<T>(
    charts: &[T],
    width: u32,
    panel_height: u32,
    draw: impl Fn(&DrawingArea<SVGBackend, Shift>, &T, &mut Overlay) -> Result<()>,
) -> Result<String> {
    let mut svg = String::new();
    let mut overlay = Overlay::default();
    {
        let height = panel_height * charts.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let panels = root.split_evenly((charts.len().max(1), 1));
        for (panel, chart) in panels.iter().zip(charts) {
            draw(panel, chart, &mut overlay)?;
        }
        root.present().map_err(plot_err)?;
    }
    Ok(overlay.apply(svg))
}

/// Longest label drawn under a group; longer ones are cut with "…" (the full name stays in
/// the hover title).
const MAX_LABEL: usize = 28;

fn cut(label: &str) -> String {
    if label.chars().count() > MAX_LABEL {
        format!("{}…", label.chars().take(MAX_LABEL - 1).collect::<String>())
    } else {
        label.to_string()
    }
}

/// The extremes a chart's value axis spans. Any finite value may sit in a report (a speedup of
/// 5e-324 after a bad run, a build time of 1e-300), but an axis needs finite ends with room
/// around them: a log axis from 0 or to infinity has no end, and drawing its ticks would never
/// finish. Values beyond these are drawn at the edge of the axis.
const AXIS_MIN: f64 = 1e-30;
const AXIS_MAX: f64 = 1e30;

fn on_axis(v: f64) -> f64 {
    v.clamp(AXIS_MIN, AXIS_MAX)
}

/// Bars for group `g`, series `s` span `[g - 0.4, g + 0.4]` split evenly between the series;
/// x runs from -0.5 so that group `g` is centred on `g`.
fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: &Bars,
    o: &mut Overlay,
) -> Result<()> {
    let (w, h) = area.dim_in_pixel();
    let (plot, side) = area.split_horizontally(w.saturating_sub(LEGEND_W));
    let n = c.groups.len().max(1);
    let values: Vec<f64> = c.positive_values().collect();
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (lo, hi) = if values.is_empty() {
        (0.1, 1.0)
    } else {
        (on_axis(lo), on_axis(hi))
    };
    let labels: Vec<String> = c.groups.iter().map(|g| cut(g)).collect();
    let plot_w = (w.saturating_sub(LEGEND_W) as f64 - 80.0 - 24.0).max(50.0);
    let widest = labels.iter().map(|l| text_width(l)).fold(0.0, f64::max);
    let layout = LabelLayout::for_labels(widest, plot_w / n as f64);
    let x_range = -0.5..(n as f64 - 0.5);
    let geometry = (layout, labels.as_slice());
    if c.log_y {
        let (bottom, top) = (lo / 2.0, (hi * 2.0).min(AXIS_MAX * 2.0));
        bars_on(
            &plot,
            c,
            o,
            (x_range, (bottom..top).log_scale()),
            bottom,
            geometry,
        )?;
    } else {
        bars_on(
            &plot,
            c,
            o,
            (x_range, 0.0..(hi * 1.1).max(1e-9)),
            0.0,
            geometry,
        )?;
    }
    let (sx, sy) = side.get_base_pixel();
    let entries: Vec<Entry> = c
        .series
        .iter()
        .map(|s| Entry {
            label: s.name.clone(),
            swatch: Swatch::Block(s.color),
        })
        .collect();
    legend::draw_beside(o, (sx, sy), h, &entries);
    Ok(())
}

/// Draws `c` with a linear or logarithmic y axis (`y_range`); bars start at `base`.
fn bars_on<DB, Y>(
    area: &DrawingArea<DB, Shift>,
    c: &Bars,
    o: &mut Overlay,
    (x_range, y_range): (std::ops::Range<f64>, Y),
    base: f64,
    (layout, labels): (LabelLayout, &[String]),
) -> Result<()>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let widest = labels.iter().map(|l| text_width(l)).fold(0.0, f64::max);
    let mut chart = ChartBuilder::on(area)
        .caption(&c.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(layout.height(widest) as u32 + 4)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y_range)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .x_labels(0)
        .y_labels(0)
        .set_all_tick_mark_size(0)
        // The ticks are drawn with the overlay; plotters' log axis labels a decade anyway.
        .y_label_formatter(&|_| String::new())
        .y_desc(c.y_desc.as_str())
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(plot_err)?;
    let top = chart.y_range().end;
    let (left, right) = {
        let (xs, _) = chart.plotting_area().get_pixel_range();
        (xs.start as f64, xs.end as f64)
    };
    let y_ticks: Vec<(f64, String)> = axis_ticks(base, top, c.log_y)
        .into_iter()
        .map(|y| (chart.backend_coord(&(0.0, y)).1 as f64, tick_label(y)))
        .collect();
    o.y_axis(&y_ticks, left, right);
    // Hovering anywhere over a group names its scene; over a bar, also the value.
    for g in 0..c.groups.len() {
        let a = chart.backend_coord(&(g as f64 - 0.5, top));
        let b = chart.backend_coord(&(g as f64 + 0.5, base));
        o.hover_rect(
            (a.0 as f64, a.1 as f64),
            (b.0 as f64, b.1 as f64),
            c.group_title(g),
        );
    }
    let width = 0.8 / c.series.len().max(1) as f64;
    for (s, series) in c.series.iter().enumerate() {
        let col = series.color;
        for (g, rect) in bar_rects(series, s, width, base) {
            chart
                .draw_series(std::iter::once(Rectangle::new(rect, col.filled())))
                .map_err(plot_err)?;
            let a = chart.backend_coord(&rect[0]);
            let b = chart.backend_coord(&rect[1]);
            let value = series.values[g].unwrap_or_default();
            let range = series
                .ranges
                .get(g)
                .copied()
                .flatten()
                .filter(|&(lo, hi)| lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo);
            let spread = range.map_or(String::new(), |(lo, hi)| {
                format!(" (runs from {} to {})", tick_label(lo), tick_label(hi))
            });
            o.hover_rect(
                (a.0 as f64, b.1 as f64),
                (b.0 as f64, a.1 as f64),
                &format!(
                    "{}, {}: {} {}{spread}",
                    series.name,
                    c.group_title(g),
                    tick_label(value),
                    c.y_desc
                ),
            );
            if let Some((lo, hi)) = range {
                // Drawn in black over the bar: the bar's own colour would vanish into it.
                let x = (rect[0].0 + rect[1].0) / 2.0;
                let (px, top) = chart.backend_coord(&(x, on_axis(hi)));
                let (_, bottom) = chart.backend_coord(&(x, on_axis(lo)));
                let (px, top, bottom) = (px as f64, top as f64, bottom as f64);
                let half = ((b.0 - a.0) as f64 / 2.0).clamp(1.0, 4.0);
                o.line((px, top), (px, bottom), BLACK, 1.0, None);
                o.line((px - half, top), (px + half, top), BLACK, 1.0, None);
                o.line((px - half, bottom), (px + half, bottom), BLACK, 1.0, None);
            }
        }
    }
    for (g, label) in labels.iter().enumerate().step_by(layout.step) {
        let (px, py) = chart.backend_coord(&(g as f64, base));
        let (px, py) = (px as f64, py as f64);
        o.line((px, py), (px, py + 5.0), BLACK, 1.0, None);
        layout.draw(o, (px, py), label, Some(c.group_title(g)));
    }
    Ok(())
}

type Rect = [(f64, f64); 2];

/// The bars of series `s`, each with its group.
fn bar_rects(series: &Series, s: usize, width: f64, base: f64) -> Vec<(usize, Rect)> {
    series
        .values
        .iter()
        .enumerate()
        .filter_map(|(g, v)| {
            let v = (*v)?;
            (v.is_finite() && v > 0.0).then(|| {
                let x0 = g as f64 - 0.4 + s as f64 * width;
                (g, [(x0, base), (x0 + width * 0.9, on_axis(v))])
            })
        })
        .collect()
}
