//! Line charts: measured series (solid, a marker at each measured point, a vertical bar from
//! the fastest to the slowest run where the report has them) and reference curves (black,
//! each with its own dash pattern), on a logarithmic y axis and a linear or logarithmic x axis.
//! The legend sits right of the plot; x ticks are either plotters' own or given (the swept
//! values), then drawn turned when they would overlap, each with its full name on hover.

use super::charts::{panels_svg, plot_err};
use super::legend::{self, Entry, LEGEND_W, Swatch};
use super::overlay::{LabelLayout, Overlay, text_width};
use super::ticks::{axis_ticks, tick_label};
use anyhow::Result;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

/// One measured point.
#[derive(Clone, Debug)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    /// The lowest and highest of the timed runs, drawn as an error bar.
    pub range: Option<(f64, f64)>,
    /// Shown on hover: what was measured where.
    pub title: String,
}

/// One structure's measurements.
#[derive(Clone, Debug)]
pub struct Line {
    /// The legend's text (a structure name, maybe with its fitted exponent).
    pub label: String,
    pub color: RGBColor,
    /// 0: dots; 1, 2, …: crosses, triangles, squares (structures past the palette's length).
    pub marker: usize,
    pub points: Vec<Point>,
}

/// A theory curve.
#[derive(Clone, Debug)]
pub struct Reference {
    pub label: String,
    /// Dash and gap lengths in pixels.
    pub dash: (u32, u32),
    pub points: Vec<(f64, f64)>,
}

/// A point to point out: a ring at `(x, y)`, a dotted drop to the x axis and a label (the
/// break-even chart's crossings, "2.9k rays").
#[derive(Clone, Debug)]
pub struct Mark {
    pub x: f64,
    pub y: f64,
    pub label: String,
    /// Shown on hover: what the mark means.
    pub title: String,
}

/// An x tick at a given value.
#[derive(Clone, Debug)]
pub struct Tick {
    pub x: f64,
    pub label: String,
    pub title: Option<String>,
}

#[derive(Clone, Debug)]
pub struct LineChart {
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub log_x: bool,
    /// Ticks at these values; empty: plotters' own, labelled with [`tick_label`].
    pub ticks: Vec<Tick>,
    pub lines: Vec<Line>,
    pub references: Vec<Reference>,
    pub marks: Vec<Mark>,
}

fn ok(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

impl LineChart {
    pub fn has_data(&self) -> bool {
        self.lines
            .iter()
            .any(|l| l.points.iter().any(|p| p.x.is_finite() && ok(p.y)))
    }

    fn usable_x(&self, x: f64) -> bool {
        if self.log_x { ok(x) } else { x.is_finite() }
    }
}

/// Each chart a panel `panel_height` high, stacked in one SVG.
#[allow(clippy::redundant_closure)]
pub fn lines_svg(charts: &[LineChart], width: u32, panel_height: u32) -> Result<String> {
    panels_svg(charts, width, panel_height, |a, c, o| draw(a, c, o))
}

/// Ends of an axis holding `values`, with `pad` of room (a factor on a log axis, a fraction of
/// the span on a linear one). Values past ±1e30 are clamped: an axis needs finite ends.
fn extent(values: impl Iterator<Item = f64>, log: bool, pad: f64) -> (f64, f64) {
    let (lo, hi) = values
        .map(|v| v.clamp(-1e30, 1e30))
        .filter(|&v| !log || v >= 1e-30)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo > hi {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / pad, hi * pad)
    } else {
        let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
        (lo - span * pad, hi + span * pad)
    }
}

/// Two lines measured the same at every point: the later one hides the earlier, so the legend
/// says so (two structures whose counted walks are identical, say).
fn same_points(a: &Line, b: &Line) -> bool {
    let pts = |l: &Line| {
        l.points
            .iter()
            .filter(|p| ok(p.y))
            .map(|p| (p.x, p.y))
            .collect::<Vec<_>>()
    };
    let (pa, pb) = (pts(a), pts(b));
    !pa.is_empty() && pa == pb
}

fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: &LineChart,
    o: &mut Overlay,
) -> Result<()> {
    let (w, h) = area.dim_in_pixel();
    let (plot, side) = area.split_horizontally(w.saturating_sub(LEGEND_W));
    let xs = c
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.x))
        .chain(
            c.references
                .iter()
                .flat_map(|r| r.points.iter().map(|p| p.0)),
        )
        .chain(c.ticks.iter().map(|t| t.x))
        .filter(|&x| c.usable_x(x));
    let (x0, x1) = extent(xs, c.log_x, if c.log_x { 1.3 } else { 0.05 });
    let ys = c
        .lines
        .iter()
        .flat_map(|l| &l.points)
        .filter(|p| c.usable_x(p.x))
        .flat_map(|p| {
            let (lo, hi) = p.range.unwrap_or((p.y, p.y));
            [p.y, lo, hi]
        })
        .chain(
            c.references
                .iter()
                .flat_map(|r| r.points.iter().map(|p| p.1)),
        )
        .filter(|&y| ok(y));
    let (y0, y1) = extent(ys, true, 1.6);

    // Where the given ticks fall, as a fraction of the axis, decides how their labels turn.
    let plot_w = (w.saturating_sub(LEGEND_W) as f64 - 80.0 - 24.0).max(50.0);
    let frac = |x: f64| {
        if c.log_x {
            (x.ln() - x0.ln()) / (x1.ln() - x0.ln())
        } else {
            (x - x0) / (x1 - x0)
        }
    };
    let mut fracs: Vec<f64> = c.ticks.iter().map(|t| frac(t.x)).collect();
    fracs.sort_by(f64::total_cmp);
    // Two scenes at one x (a generator that rounds two sizes alike) share a tick position.
    let spacing = fracs
        .windows(2)
        .map(|p| (p[1] - p[0]) * plot_w)
        .filter(|d| *d > 0.5)
        .fold(plot_w, f64::min);
    let widest = c
        .ticks
        .iter()
        .map(|t| text_width(&t.label))
        .fold(0.0, f64::max);
    let layout = LabelLayout::for_labels(widest, spacing);
    let label_h = if c.ticks.is_empty() {
        30.0
    } else {
        layout.height(widest)
    };

    let y_range = (y0..y1).log_scale();
    if c.log_x {
        draw_on(
            &plot,
            c,
            o,
            ((x0..x1).log_scale(), y_range),
            label_h,
            layout,
        )?;
    } else {
        draw_on(&plot, c, o, (x0..x1, y_range), label_h, layout)?;
    }
    let (sx, sy) = side.get_base_pixel();
    // A line with nothing to draw (no cells stepped by a tree) stays out of the legend.
    let drawn: Vec<&Line> = c
        .lines
        .iter()
        .filter(|l| l.points.iter().any(|p| c.usable_x(p.x) && ok(p.y)))
        .collect();
    let entries: Vec<Entry> = drawn
        .iter()
        .enumerate()
        .map(|(i, l)| Entry {
            label: match drawn[..i].iter().find(|e| same_points(e, l)) {
                Some(e) => format!("{} (= {})", l.label, e.label),
                None => l.label.clone(),
            },
            swatch: Swatch::Line {
                color: l.color,
                dash: None,
                dot: true,
            },
        })
        .chain(c.references.iter().map(|r| Entry {
            label: r.label.clone(),
            swatch: Swatch::Line {
                color: BLACK,
                dash: Some(format!("{} {}", r.dash.0, r.dash.1)),
                dot: false,
            },
        }))
        .collect();
    legend::draw_beside(o, (sx, sy), h, &entries);
    Ok(())
}

fn draw_on<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    c: &LineChart,
    o: &mut Overlay,
    (x_range, y_range): (X, Y),
    label_h: f64,
    layout: LabelLayout,
) -> Result<()>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&c.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(label_h as u32 + 22)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y_range)
        .map_err(plot_err)?;
    let own_ticks = c.ticks.is_empty();
    let x_fmt = move |x: &f64| {
        if own_ticks {
            tick_label(*x)
        } else {
            String::new()
        }
    };
    let mut mesh = chart.configure_mesh();
    if !own_ticks {
        mesh.disable_x_mesh()
            .x_labels(0)
            .set_tick_mark_size(LabelAreaPosition::Bottom, 0);
    }
    mesh.light_line_style(TRANSPARENT)
        .disable_y_mesh()
        .y_labels(0)
        .set_tick_mark_size(LabelAreaPosition::Left, 0)
        // The ticks are drawn with the overlay; plotters' log axis labels a decade anyway.
        .y_label_formatter(&|_| String::new())
        .x_desc(c.x_desc.as_str())
        .y_desc(c.y_desc.as_str())
        .x_label_formatter(&x_fmt)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(plot_err)?;
    let (y_lo, y_hi) = {
        let r = chart.y_range();
        (r.start, r.end)
    };
    let x_lo = chart.x_range().start;
    let (left, right) = {
        let (xs, _) = chart.plotting_area().get_pixel_range();
        (xs.start as f64, xs.end as f64)
    };
    let y_ticks: Vec<(f64, String)> = axis_ticks(y_lo, y_hi, true)
        .into_iter()
        .map(|y| (chart.backend_coord(&(x_lo, y)).1 as f64, tick_label(y)))
        .collect();
    o.y_axis(&y_ticks, left, right);
    let usable = |x: f64| c.usable_x(x);
    for t in c.ticks.iter().filter(|t| usable(t.x)) {
        let top = chart.backend_coord(&(t.x, y_hi));
        let bottom = chart.backend_coord(&(t.x, y_lo));
        o.grid_line(
            (top.0 as f64, top.1 as f64),
            (bottom.0 as f64, bottom.1 as f64),
        );
    }
    for r in &c.references {
        let pts: Vec<(f64, f64)> = r
            .points
            .iter()
            .copied()
            .filter(|&(x, y)| usable(x) && ok(y))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(
                pts,
                r.dash.0,
                r.dash.1,
                BLACK.stroke_width(1),
            ))
            .map_err(plot_err)?;
    }
    for l in &c.lines {
        let pts: Vec<&Point> = l.points.iter().filter(|p| usable(p.x) && ok(p.y)).collect();
        let style = l.color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.x, p.y)), style))
            .map_err(plot_err)?;
        for p in &pts {
            if let Some((lo, hi)) = p.range.filter(|&(lo, hi)| ok(lo) && ok(hi) && hi > lo) {
                let bar = l.color.stroke_width(1);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(p.x, lo), (p.x, hi)],
                        bar,
                    )))
                    .map_err(plot_err)?;
                for end in [lo, hi] {
                    chart
                        .draw_series(std::iter::once(
                            EmptyElement::at((p.x, end))
                                + PathElement::new(vec![(-4, 0), (4, 0)], bar),
                        ))
                        .map_err(plot_err)?;
                }
            }
            let at = (p.x, p.y);
            let filled = l.color.filled();
            match l.marker {
                0 => chart.draw_series(std::iter::once(Circle::new(at, 3, filled))),
                1 => chart.draw_series(std::iter::once(Cross::new(at, 4, style))),
                2 => chart.draw_series(std::iter::once(TriangleMarker::new(at, 4, filled))),
                _ => chart.draw_series(std::iter::once(
                    EmptyElement::at(at) + Rectangle::new([(-3, -3), (3, 3)], filled),
                )),
            }
            .map_err(plot_err)?;
            let (px, py) = chart.backend_coord(&at);
            o.hover_circle((px as f64, py as f64), 6.0, &p.title);
        }
    }
    for (i, m) in c
        .marks
        .iter()
        .filter(|m| usable(m.x) && ok(m.y))
        .enumerate()
    {
        let (px, py) = chart.backend_coord(&(m.x, m.y));
        let (_, bottom) = chart.backend_coord(&(m.x, y_lo));
        let (px, py, bottom) = (px as f64, py as f64, bottom as f64);
        o.line((px, py), (px, bottom), BLACK, 1.0, Some("2 3"));
        o.ring((px, py), 6.0, BLACK);
        // Above the point, on a halo over the lines; a second mark's label goes below its
        // point so that two crossings close together keep their labels apart.
        let dy = if i % 2 == 0 { -16.0 } else { 16.0 };
        o.callout((px + 6.0, py + dy), &m.label, &m.title);
        o.hover_circle((px, py), 8.0, &m.title);
    }
    let visible: Vec<&Tick> = c.ticks.iter().filter(|t| usable(t.x)).collect();
    for t in visible.iter().step_by(layout.step) {
        let (px, py) = chart.backend_coord(&(t.x, y_lo));
        let (px, py) = (px as f64, py as f64);
        o.line((px, py), (px, py + 5.0), BLACK, 1.0, None);
        layout.draw(o, (px, py), &t.label, t.title.as_deref());
    }
    Ok(())
}
