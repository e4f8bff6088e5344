//! SVG charts drawn with plotters. Text is emitted as SVG `<text>` (plotters' naive font), so no
//! font files are read at build or run time. Two shapes cover every chart: grouped bars (groups
//! on x, one bar per series) and lines on log–log axes.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

/// A categorical palette (Tableau 10), cycled.
const PALETTE: [RGBColor; 10] = [
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
];

pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// One named series of values, one per group (`None`: no bar).
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub values: Vec<Option<f64>>,
}

/// A grouped bar chart.
#[derive(Clone, Debug)]
pub struct Bars {
    pub title: String,
    pub y_desc: String,
    pub groups: Vec<String>,
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
}

fn plot_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e}")
}

/// Renders one chart to an SVG string.
pub fn bars_svg(chart: &Bars, width: u32, height: u32) -> Result<String> {
    panels_svg(std::slice::from_ref(chart), width, height, |a, c| {
        draw_bars(a, c)
    })
}

/// Several charts stacked vertically in one SVG (e.g. the three counters of a workload).
#[allow(clippy::redundant_closure)]
pub fn stacked_bars_svg(charts: &[Bars], width: u32, panel_height: u32) -> Result<String> {
    panels_svg(charts, width, panel_height, |a, c| draw_bars(a, c))
}

/// One SVG of `panel_height`-high panels stacked vertically, each drawn by `draw`. Callers pass
/// closures, not the generic draw functions themselves: those are instantiated for one
/// backend lifetime, and `draw` must accept any (clippy's `redundant_closure` is wrong here).
fn panels_svg<T>(
    charts: &[T],
    width: u32,
    panel_height: u32,
    draw: impl Fn(&DrawingArea<SVGBackend, Shift>, &T) -> Result<()>,
) -> Result<String> {
    let mut svg = String::new();
    {
        let height = panel_height * charts.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let panels = root.split_evenly((charts.len().max(1), 1));
        for (panel, chart) in panels.iter().zip(charts) {
            draw(panel, chart)?;
        }
        root.present().map_err(plot_err)?;
    }
    Ok(svg)
}

fn short(label: &str) -> String {
    let label = label.trim_end_matches(".obj");
    if label.chars().count() > 18 {
        format!("{}…", label.chars().take(17).collect::<String>())
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
/// x runs from -0.5 so that the integer ticks fall on group centres and carry their names.
fn draw_bars<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &Bars) -> Result<()> {
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
    let groups = c.groups.clone();
    let x_fmt = move |x: &f64| {
        let i = x.round();
        if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < groups.len() {
            short(&groups[i as usize])
        } else {
            String::new()
        }
    };
    let x_range = -0.5..(n as f64 - 0.5);
    if c.log_y {
        // Headroom above the tallest bar for the legend box; bars rise from below the lowest.
        let top = hi * 2.0 * (hi / lo * 4.0).max(4.0).powf(0.35);
        bars_on(
            area,
            c,
            x_range,
            ((lo / 2.0)..top).log_scale(),
            lo / 2.0,
            &x_fmt,
        )
    } else {
        bars_on(area, c, x_range, 0.0..(hi * 1.45).max(1e-9), 0.0, &x_fmt)
    }
}

/// Draws `c` with a linear or logarithmic y axis (`y_range`); bars start at `base`.
fn bars_on<DB, Y>(
    area: &DrawingArea<DB, Shift>,
    c: &Bars,
    x_range: std::ops::Range<f64>,
    y_range: Y,
    base: f64,
    x_fmt: &dyn Fn(&f64) -> String,
) -> Result<()>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let n = c.groups.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .caption(&c.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y_range)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n + 1)
        .x_label_formatter(x_fmt)
        .x_label_style(("sans-serif", 11))
        .y_desc(c.y_desc.as_str())
        .y_label_formatter(&|y| format_value(*y))
        .draw()
        .map_err(plot_err)?;
    let width = 0.8 / c.series.len().max(1) as f64;
    for (s, series) in c.series.iter().enumerate() {
        let col = color(s);
        let rects = bar_rects(series, s, width, base);
        chart
            .draw_series(rects.into_iter().map(|r| Rectangle::new(r, col.filled())))
            .map_err(plot_err)?
            .label(series.name.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], col.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(plot_err)?;
    Ok(())
}

type Rect = [(f64, f64); 2];

fn bar_rects(series: &Series, s: usize, width: f64, base: f64) -> Vec<Rect> {
    series
        .values
        .iter()
        .enumerate()
        .filter_map(|(g, v)| {
            let v = (*v)?;
            (v.is_finite() && v > 0.0).then(|| {
                let x0 = g as f64 - 0.4 + s as f64 * width;
                [(x0, base), (x0 + width * 0.9, on_axis(v))]
            })
        })
        .collect()
}

/// Short numbers for axis labels: 0.001, 0.25, 12, 3.4k, 2.1M.
pub fn format_value(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 1e6 {
        format!("{:.3}M", v / 1e6)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else if a >= 1e3 {
        format!("{:.3}k", v / 1e3)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else if a >= 1.0 {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.2e}")
    }
}

/// A line chart on log–log axes: measured series (solid, with points) and reference curves
/// (dashed grey, labelled in the legend).
#[derive(Clone, Debug)]
pub struct LogLog {
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub series: Vec<(String, Vec<(f64, f64)>)>,
    pub references: Vec<(String, Vec<(f64, f64)>)>,
}

impl LogLog {
    pub fn has_data(&self) -> bool {
        self.series
            .iter()
            .any(|(_, p)| p.iter().any(|&(x, y)| ok(x) && ok(y)))
    }
}

fn ok(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

#[allow(clippy::redundant_closure)]
pub fn loglog_svg(charts: &[LogLog], width: u32, panel_height: u32) -> Result<String> {
    panels_svg(charts, width, panel_height, |a, c| draw_loglog(a, c))
}

fn draw_loglog<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &LogLog) -> Result<()> {
    let points: Vec<(f64, f64)> = c
        .series
        .iter()
        .chain(&c.references)
        .flat_map(|(_, p)| p.iter().copied())
        .filter(|&(x, y)| ok(x) && ok(y))
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = points.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    );
    if points.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
    }
    let (x0, x1, y0, y1) = (on_axis(x0), on_axis(x1), on_axis(y0), on_axis(y1));
    let mut chart = ChartBuilder::on(area)
        .caption(&c.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(
            ((x0 / 1.5)..(x1 * 1.5)).log_scale(),
            ((y0 / 2.0)..(y1 * 2.0)).log_scale(),
        )
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(c.x_desc.as_str())
        .y_desc(c.y_desc.as_str())
        .x_label_formatter(&|x| format_value(*x))
        .y_label_formatter(&|y| format_value(*y))
        .draw()
        .map_err(plot_err)?;
    for (i, (name, pts)) in c.series.iter().enumerate() {
        let col = color(i);
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .filter(|&&(x, y)| ok(x) && ok(y))
            .map(|&(x, y)| (on_axis(x), on_axis(y)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))
            .map_err(plot_err)?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], col.stroke_width(2)));
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, col.filled())))
            .map_err(plot_err)?;
    }
    for (i, (name, pts)) in c.references.iter().enumerate() {
        let grey = RGBColor(120 + 25 * (i as u8 % 4), 120, 120);
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .filter(|&&(x, y)| ok(x) && ok(y))
            .map(|&(x, y)| (on_axis(x), on_axis(y)))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(pts, 6, 4, grey.stroke_width(1)))
            .map_err(plot_err)?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 14, y)], grey.stroke_width(1))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(plot_err)?;
    Ok(())
}
