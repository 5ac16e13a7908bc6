//! The sweep's picture: error (log axis) against GPU time, every
//! combination a labelled point, the Pareto front connected and
//! highlighted. Drawn with `plotters` into an SVG string.
//!
//! Three things plotters does not do for us:
//!
//! - Any finite value has a place. The error axis is drawn linear in the
//!   error's base-10 exponent, and both axes' ticks are chosen here, a
//!   bounded number of them: plotters' own tick search never ends on a
//!   range that reaches infinity (an error of 1e305 with half a decade of
//!   room above it) or spans more decades than a float's ratio holds.
//! - Error 0 (the reference itself) has no place on a log axis. Such points
//!   are drawn on a floor one decade below the smallest non-zero error, on a
//!   line labelled as such, with their own marker. When every error is
//!   above 0 (a CPU reference) there is no floor, and the axis starts just
//!   below the smallest error instead of wasting a decade on an empty line.
//! - Labels are placed by hand: each goes to the first of a few spots around
//!   its point that stays inside the plot and clear of every marker and
//!   label placed so far (or, failing that, the spot with the least
//!   overlap). Sweeps put many points close together (e.g. two HDR formats
//!   at the same tessellation), and plotters would draw their labels on top
//!   of each other.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One point of the plot.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotPoint {
    /// GPU time, ms.
    pub x: f64,
    /// Error (0 allowed: drawn at the floor).
    pub y: f64,
    pub label: String,
    pub pareto: bool,
    /// The point is its own reference (error 0 by definition).
    pub reference: bool,
}

/// What to draw.
pub struct Plot<'a> {
    pub title: &'a str,
    /// A smaller line under the title.
    pub subtitle: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub points: &'a [PlotPoint],
}

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("nothing to plot: no points")]
    Empty,
    #[error(
        "cannot plot point '{label}' at ({x}, {y}): coordinates must be finite and not negative"
    )]
    BadPoint { label: String, x: f64, y: f64 },
    #[error("drawing the plot failed: {0}")]
    Draw(String),
}

const WIDTH: u32 = 1100;
const HEIGHT: u32 = 700;
const FONT: &str = "sans-serif";
const LABEL_SIZE: u32 = 13;
/// Average glyph width of a sans-serif font, as a share of its size; SVG
/// has no text metrics, so label boxes are estimated with this.
const GLYPH_WIDTH: f64 = 0.55;

/// The longest legend line (the legend's width is estimated from it).
const FRONT_LABEL: &str = "Pareto front (nothing else is both faster and more accurate)";

const FRONT: RGBColor = RGBColor(200, 40, 30);
const OTHER: RGBColor = RGBColor(120, 130, 150);
const FLOOR: RGBColor = RGBColor(170, 170, 170);

/// Renders `plot` as an SVG document.
pub fn error_vs_time_svg(plot: &Plot<'_>) -> Result<String, PlotError> {
    let points = plot.points;
    if points.is_empty() {
        return Err(PlotError::Empty);
    }
    if let Some(p) = points
        .iter()
        .find(|p| !(p.x.is_finite() && p.y.is_finite() && p.x >= 0.0 && p.y >= 0.0))
    {
        return Err(PlotError::BadPoint {
            label: p.label.clone(),
            x: p.x,
            y: p.y,
        });
    }

    let axes = Axes::of(points);
    let mut svg = String::new();
    draw(plot, &axes, &mut svg).map_err(|e| PlotError::Draw(e.to_string()))?;
    Ok(svg)
}

/// The plot's coordinates: x as given, y as its base-10 logarithm (the
/// error axis is drawn linear in the exponent), with their ranges and
/// ticks. Any finite, non-negative points give finite ranges and at most a
/// dozen ticks per axis, whatever their magnitude (1e-320 or 1e305 alike).
#[derive(Clone, Debug, PartialEq)]
struct Axes {
    /// The exponent errors of 0 are drawn at: a decade below the smallest
    /// non-zero error, rounded down to a whole decade.
    floor_exp: f64,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    x_ticks: Vec<f64>,
    /// Exponents (log10 of the error).
    y_ticks: Vec<f64>,
}

/// The most ticks an axis gets.
const MAX_TICKS: usize = 12;

impl Axes {
    /// The axes for `points` (finite and non-negative: checked by the
    /// caller).
    fn of(points: &[PlotPoint]) -> Axes {
        // log10 of the smallest non-zero error; denormals included, so it
        // is at least about -324.
        let min_exp = points
            .iter()
            .filter(|p| p.y > 0.0)
            .map(|p| p.y.log10())
            .fold(f64::INFINITY, f64::min);
        let floor_exp = if min_exp.is_finite() {
            min_exp.floor() - 1.0
        } else {
            -6.0
        };
        let exp_of = |p: &PlotPoint| if p.y > 0.0 { p.y.log10() } else { floor_exp };
        let y_max = points.iter().map(exp_of).fold(floor_exp, f64::max);
        let y_min = if points.iter().any(|p| p.y <= 0.0) {
            floor_exp
        } else {
            min_exp
        };
        // Half a decade of room below the lowest point and above the
        // highest (a factor of 3).
        let pad = 3f64.log10();
        let y = y_min - pad..y_max + pad;

        let (x_min, x_max) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.x), hi.max(p.x))
            });
        // A span too small for its magnitude (one point, or points equal
        // to the last digits) is widened to a fifth of the largest value.
        let span = if x_max - x_min > x_max * 1e-9 {
            x_max - x_min
        } else {
            x_max.max(1.0) * 0.2
        };
        // Extra room on the right for the labels of the slowest points;
        // the right end stays finite however large the times.
        let x_end = x_max + 0.25 * span;
        let x_end = if x_end.is_finite() { x_end } else { f64::MAX };
        let x = (x_min - 0.1 * span).max(0.0)..x_end;
        Axes {
            floor_exp,
            x_ticks: linear_ticks(x.start, x.end),
            y_ticks: decade_ticks(y.start, y.end),
            x,
            y,
        }
    }

    /// Where point `p` is drawn.
    fn at(&self, p: &PlotPoint) -> (f64, f64) {
        (
            p.x,
            if p.y > 0.0 {
                p.y.log10()
            } else {
                self.floor_exp
            },
        )
    }
}

/// Ticks at round multiples (1, 2 or 5 times a power of ten) inside
/// `lo..hi`, at most [`MAX_TICKS`]; the two ends when no such step fits
/// (a range too narrow or too wide for its magnitude).
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let rough = span / MAX_TICKS as f64;
    let power = 10f64.powf(rough.log10().floor());
    for step in [power, 2.0 * power, 5.0 * power, 10.0 * power] {
        if !(step.is_finite() && step > 0.0) {
            break;
        }
        let first = (lo / step).ceil();
        let last = (hi / step).floor();
        let count = last - first + 1.0;
        if count.is_finite() && count >= 1.0 && count <= MAX_TICKS as f64 {
            // At most MAX_TICKS steps: the loop is bounded by the check.
            return (0..count as usize)
                .map(|i| (first + i as f64) * step)
                .filter(|v| v.is_finite())
                .collect();
        }
    }
    vec![lo, hi]
}

/// Ticks at whole decades inside `lo..hi` (exponents), every k-th so at
/// most [`MAX_TICKS`]; with fewer than three decades, also 2 and 5 times
/// each decade.
fn decade_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let first = lo.ceil();
    let last = hi.floor();
    // The exponents of finite numbers lie within about ±330.
    let count = (last - first + 1.0).clamp(0.0, 1000.0) as usize;
    let every = count.div_ceil(MAX_TICKS).max(1);
    let mut ticks: Vec<f64> = (0..count)
        .step_by(every)
        .map(|i| first + i as f64)
        .collect();
    if count < 3 {
        let decades = (lo.floor() as i32)..=(hi.floor() as i32);
        ticks = decades
            .flat_map(|d| [1f64, 2.0, 5.0].map(|m| f64::from(d) + m.log10()))
            .filter(|v| (lo..=hi).contains(v))
            .collect();
    }
    ticks
}

/// A linear axis whose ticks are given (plotters' own are not searched
/// for: see the module docs).
struct Ticked {
    inner: plotters::coord::types::RangedCoordf64,
    ticks: Vec<f64>,
}

impl Ticked {
    fn new(range: std::ops::Range<f64>, ticks: &[f64]) -> Ticked {
        Ticked {
            inner: range.into(),
            ticks: ticks.to_vec(),
        }
    }
}

impl plotters::coord::ranged1d::Ranged for Ticked {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.max_num_points() == 0 {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
}

/// The label of the tick at exponent `v`: `1e-3`, `2e-3`, `5e-3`, ...
fn decade_label(v: f64) -> String {
    let exp = v.floor();
    let mantissa = 10f64.powf(v - exp).round();
    // 10^(v - exp) rounds to 10 just below a decade.
    if mantissa >= 10.0 {
        format!("1e{}", exp + 1.0)
    } else {
        format!("{mantissa}e{exp}")
    }
}

/// The label of the x tick `v`, with as many decimals as the ticks' step
/// needs and exponent notation for very large or small values.
fn x_label(v: f64, step: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e7).contains(&a) {
        format!("{v:.1e}")
    } else {
        let decimals = if step > 0.0 && step < 1.0 {
            ((-step.log10()).ceil() as usize).min(6)
        } else {
            0
        };
        format!("{v:.decimals$}")
    }
}

/// The SVG's whole drawing area.
type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;
/// The plot's chart on it, in time and error coordinates.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<Ticked, Ticked>>;

fn draw(plot: &Plot<'_>, axes: &Axes, svg: &mut String) -> Result<(), Box<dyn std::error::Error>> {
    let points = plot.points;
    let at = |p: &PlotPoint| axes.at(p);
    let root = SVGBackend::with_string(svg, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    root.draw(&Text::new(
        plot.title.to_string(),
        (24, 14),
        (FONT, 22).into_font().color(&BLACK),
    ))?;
    root.draw(&Text::new(
        plot.subtitle.to_string(),
        (24, 44),
        (FONT, 14).into_font().color(&RGBColor(80, 80, 80)),
    ))?;
    let (_, body) = root.split_vertically(70);

    let mut chart = ChartBuilder::on(&body)
        .margin_left(20)
        .margin_right(30)
        .margin_bottom(16)
        .x_label_area_size(52)
        .y_label_area_size(84)
        .build_cartesian_2d(
            Ticked::new(axes.x.clone(), &axes.x_ticks),
            Ticked::new(axes.y.clone(), &axes.y_ticks),
        )?;
    let x_step = match axes.x_ticks.as_slice() {
        [a, b, ..] => b - a,
        _ => 0.0,
    };
    chart
        .configure_mesh()
        .x_desc(plot.x_label)
        .y_desc(plot.y_label)
        .x_label_formatter(&|v| x_label(*v, x_step))
        .y_label_formatter(&|v| decade_label(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .light_line_style(WHITE)
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()?;
    draw_points(&mut chart, points, axes)?;

    // Labels, in pixels of the whole picture (chart coordinates map to the
    // same backend pixels).
    let pixel: Vec<(i32, i32)> = points.iter().map(|p| chart.backend_coord(&at(p))).collect();
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    let area = Rect {
        x0: xs.start,
        y0: ys.start,
        x1: xs.end,
        y1: ys.end,
    };
    draw_labels(&root, points, &pixel, &area)?;
    root.present()?;
    Ok(())
}

/// The floor line, the front, the other points, the reference's ring and
/// the legend.
fn draw_points<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    points: &[PlotPoint],
    axes: &Axes,
) -> Result<(), Box<dyn std::error::Error>> {
    let at = |p: &PlotPoint| axes.at(p);
    let floor = axes.floor_exp;
    // The floor line, only when something sits on it.
    let any_zero = points.iter().any(|p| p.y <= 0.0);
    let (x0, x1) = (axes.x.start, axes.x.end);
    if any_zero {
        chart.draw_series(LineSeries::new(
            [(x0, floor), (x1, floor)],
            FLOOR.stroke_width(1),
        ))?;
    }

    // The front, left to right; on it the error falls as time grows.
    let mut front: Vec<&PlotPoint> = points.iter().filter(|p| p.pareto).collect();
    front.sort_by(|a, b| a.x.total_cmp(&b.x));
    chart
        .draw_series(LineSeries::new(
            front.iter().map(|p| at(p)),
            FRONT.stroke_width(2),
        ))?
        .label(FRONT_LABEL)
        .legend(|(x, y)| PathElement::new([(x, y), (x + 24, y)], FRONT.stroke_width(2)));
    chart
        .draw_series(
            points
                .iter()
                .filter(|p| !p.pareto)
                .map(|p| Circle::new(at(p), 4, OTHER.filled())),
        )?
        .label("other combinations")
        .legend(|(x, y)| Circle::new((x + 12, y), 4, OTHER.filled()));
    chart.draw_series(front.iter().map(|p| Circle::new(at(p), 5, FRONT.filled())))?;
    if points.iter().any(|p| p.reference) {
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| p.reference)
                    .map(|p| Circle::new(at(p), 9, BLACK.stroke_width(2))),
            )?
            .label(format!(
                "reference: error 0, drawn at {} (grey line)",
                decade_label(floor)
            ))
            .legend(|(x, y)| Circle::new((x + 12, y), 7, BLACK.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(200, 200, 200))
        .draw()?;
    Ok(())
}

/// Every point's label, placed where it overlaps the least with the
/// markers (at `pixel`), the legend and the labels placed before it.
fn draw_labels(
    root: &Area<'_>,
    points: &[PlotPoint],
    pixel: &[(i32, i32)],
    area: &Rect,
) -> Result<(), Box<dyn std::error::Error>> {
    // Markers are obstacles too; the reference's ring is larger.
    let mut taken: Vec<Rect> = points
        .iter()
        .zip(pixel)
        .map(|(p, &(x, y))| {
            let r = if p.reference { 11 } else { 6 };
            Rect {
                x0: x - r,
                y0: y - r,
                x1: x + r,
                y1: y + r,
            }
        })
        .collect();
    // The legend box, roughly: upper right corner of the plot, as wide as
    // its longest line plus the marker.
    let legend_w = (FRONT_LABEL.len() as f64 * 14.0 * GLYPH_WIDTH) as i32 + 60;
    taken.push(Rect {
        x0: area.x1 - legend_w,
        y0: area.y0,
        x1: area.x1,
        y1: area.y0 + 80,
    });
    let style = (FONT, LABEL_SIZE).into_font().color(&BLACK);
    let reference_style = (FONT, LABEL_SIZE)
        .into_font()
        .style(FontStyle::Bold)
        .color(&BLACK);
    // The front's labels first: they matter most, so they get the best spots.
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by_key(|&i| !points[i].pareto);
    for i in order {
        let p = &points[i];
        let text = if p.reference {
            format!("{} (reference)", p.label)
        } else {
            p.label.clone()
        };
        let spot = place(&text, pixel[i], area, &taken);
        taken.push(spot.rect);
        // A label pushed away from its point gets a thin leader line, so
        // it is clear which of two close points it belongs to.
        let (px, py) = pixel[i];
        let near = (
            px.clamp(spot.rect.x0, spot.rect.x1),
            py.clamp(spot.rect.y0, spot.rect.y1),
        );
        if (near.0 - px).pow(2) + (near.1 - py).pow(2) > 14 * 14 {
            root.draw(&PathElement::new([(px, py), near], FLOOR.stroke_width(1)))?;
        }
        let style = if p.reference {
            &reference_style
        } else {
            &style
        };
        let style = style.pos(Pos::new(spot.align.into(), VPos::Top));
        root.draw(&Text::new(text, spot.anchor, style))?;
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    fn overlap(&self, o: &Rect) -> i64 {
        let w = (self.x1.min(o.x1) - self.x0.max(o.x0)).max(0);
        let h = (self.y1.min(o.y1) - self.y0.max(o.y0)).max(0);
        i64::from(w) * i64::from(h)
    }

    fn inside(&self, o: &Rect) -> bool {
        self.x0 >= o.x0 && self.y0 >= o.y0 && self.x1 <= o.x1 && self.y1 <= o.y1
    }
}

/// Where a label goes: the text's anchor and alignment, and the box it is
/// estimated to cover.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Label {
    anchor: (i32, i32),
    align: Align,
    rect: Rect,
}

/// Horizontal text alignment at the anchor (plotters' `HPos` has no
/// `PartialEq`/`Debug`, which the tests want).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Align {
    Left,
    Right,
    Center,
}

impl From<Align> for HPos {
    fn from(a: Align) -> HPos {
        match a {
            Align::Left => HPos::Left,
            Align::Right => HPos::Right,
            Align::Center => HPos::Center,
        }
    }
}

/// The spot for `text` next to the point at `(x, y)`: the first candidate
/// that is inside `area` and overlaps nothing in `taken`, else the inside
/// candidate with the least overlap, else the first one. The text is
/// anchored at the side facing the point (right-aligned when left of it,
/// centred above or below it), so it sits next to its point even where
/// the width estimate is off.
fn place(text: &str, (x, y): (i32, i32), area: &Rect, taken: &[Rect]) -> Label {
    let w = (text.chars().count() as f64 * f64::from(LABEL_SIZE) * GLYPH_WIDTH).ceil() as i32;
    let h = LABEL_SIZE as i32 + 2;
    let gap = 9;
    // Right, left, above, below, then the diagonals and further out.
    let (l, r, c) = (Align::Left, Align::Right, Align::Center);
    let candidates = [
        (gap, -h / 2, l),
        (-gap, -h / 2, r),
        (0, -gap - h, c),
        (0, gap, c),
        (gap, -gap - h, l),
        (gap, gap, l),
        (-gap, -gap - h, r),
        (-gap, gap, r),
        (gap, -2 * h - gap, l),
        (gap, h + gap, l),
        (-gap, -2 * h - gap, r),
        (-gap, h + gap, r),
    ];
    let labels: Vec<Label> = candidates
        .iter()
        .map(|&(dx, dy, align)| {
            let (ax, ay) = (x + dx, y + dy);
            let x0 = match align {
                Align::Left => ax,
                Align::Right => ax - w,
                Align::Center => ax - w / 2,
            };
            Label {
                anchor: (ax, ay),
                align,
                rect: Rect {
                    x0,
                    y0: ay,
                    x1: x0 + w,
                    y1: ay + h,
                },
            }
        })
        .collect();
    let cost = |r: &Rect| taken.iter().map(|t| r.overlap(t)).sum::<i64>();
    labels
        .iter()
        .filter(|l| l.rect.inside(area))
        .min_by_key(|l| cost(&l.rect))
        .or(labels.first())
        .copied()
        .unwrap_or(Label {
            anchor: (x, y),
            align: Align::Left,
            rect: Rect {
                x0: x,
                y0: y,
                x1: x,
                y1: y,
            },
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64, label: &str, pareto: bool) -> PlotPoint {
        PlotPoint {
            x,
            y,
            label: label.into(),
            pareto,
            reference: y == 0.0,
        }
    }

    fn plot(points: &[PlotPoint]) -> Result<String, PlotError> {
        error_vs_time_svg(&Plot {
            title: "t",
            subtitle: "s",
            x_label: "ms",
            y_label: "rmse",
            points,
        })
    }

    #[test]
    fn svg_has_every_label_and_the_floor() {
        let svg = plot(&[
            point(1.0, 0.3, "coarse", true),
            point(2.0, 0.5, "slow & bad", false),
            point(3.0, 0.002, "fine", true),
            point(4.0, 0.0, "best", true),
        ])
        .unwrap();
        assert!(svg.starts_with("<svg"));
        for label in ["coarse", "slow &amp; bad", "fine", "best (reference)"] {
            assert!(svg.contains(label), "{label} missing");
        }
        // Smallest non-zero error 2e-3 -> floor 1e-4.
        assert!(svg.contains("drawn at 1e-4"), "{svg}");
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        assert!(matches!(plot(&[]), Err(PlotError::Empty)));
        let err = plot(&[point(f64::NAN, 1.0, "nan", true)]).unwrap_err();
        assert!(err.to_string().contains("'nan'"), "{err}");
        assert!(plot(&[point(1.0, -1.0, "neg", true)]).is_err());
        // All errors above 0: no floor line, no reference in the legend.
        let svg = plot(&[point(1.0, 0.3, "a", true), point(2.0, 0.02, "b", true)]).unwrap();
        assert!(!svg.contains("drawn at") && !svg.contains("(reference)"));
        // One point, or all at error 0, still has axes to draw.
        plot(&[point(2.0, 0.0, "only", true)]).unwrap();
        plot(&[point(2.0, 0.1, "a", true), point(2.0, 0.1, "b", true)]).unwrap();
    }

    /// Plots `points` on another thread: `None` if it has not finished
    /// within a minute (plotters' tick search looped forever on huge
    /// values), instead of hanging the test run.
    fn plot_in_time(points: Vec<PlotPoint>) -> Option<Result<String, PlotError>> {
        let (send, receive) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = send.send(plot(&points));
        });
        receive
            .recv_timeout(std::time::Duration::from_secs(60))
            .ok()
    }

    #[test]
    fn any_finite_values_plot_with_bounded_axes() {
        let cases: [&[(f64, f64)]; 8] = [
            &[(1.0, 1e305), (2.0, 0.5)],
            &[(1.0, f64::MAX), (2.0, 0.0)],
            &[(1.0, 5e-324), (2.0, f64::MAX)],
            &[(1.0, 1e-300), (3.0, 1e300)],
            &[(1e308, 0.1), (f64::MAX, 0.2)],
            &[(0.0, 0.1), (f64::MAX, 0.0)],
            &[(5e-324, 0.1), (1e-300, 0.2)],
            &[(1e300, 1e300), (1e300, 1e300)],
        ];
        for case in cases {
            let points: Vec<PlotPoint> = case
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| point(x, y, &format!("p{i}"), i == 0))
                .collect();
            let axes = Axes::of(&points);
            for r in [&axes.x, &axes.y] {
                assert!(
                    r.start.is_finite() && r.end.is_finite() && r.start < r.end,
                    "{case:?}: {axes:?}"
                );
            }
            for ticks in [&axes.x_ticks, &axes.y_ticks] {
                assert!(
                    !ticks.is_empty() && ticks.len() <= MAX_TICKS,
                    "{case:?}: {axes:?}"
                );
                assert!(ticks.iter().all(|t| t.is_finite()), "{case:?}: {axes:?}");
            }
            let svg = plot_in_time(points)
                .unwrap_or_else(|| panic!("{case:?}: the plot did not finish"))
                .unwrap_or_else(|e| panic!("{case:?}: {e}"));
            assert!(svg.contains("p0") && svg.contains("p1"), "{case:?}");
        }
    }

    #[test]
    fn ticks_are_round_and_labelled_by_their_decade() {
        assert_eq!(
            linear_ticks(0.0, 10.0),
            [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]
        );
        assert_eq!(linear_ticks(0.5, 3.1), [0.5, 1.0, 1.5, 2.0, 2.5, 3.0]);
        assert_eq!(decade_ticks(-4.5, 0.5), [-4.0, -3.0, -2.0, -1.0, 0.0]);
        // Under three decades, 2 and 5 times each decade too.
        let t = decade_ticks(-1.2, 0.2);
        let labels: Vec<String> = t.iter().map(|&v| decade_label(v)).collect();
        assert_eq!(labels, ["1e-1", "2e-1", "5e-1", "1e0"]);
        // 600 decades: every 50th, at most a dozen.
        let t = decade_ticks(-300.0, 300.0);
        assert!(t.len() <= MAX_TICKS && t.first() == Some(&-300.0), "{t:?}");
        assert_eq!(decade_label(-4.0), "1e-4");
        assert_eq!(x_label(2.5, 0.5), "2.5");
        assert_eq!(x_label(1e300, 1e299), "1.0e300");
    }

    #[test]
    fn labels_avoid_each_other() {
        let area = Rect {
            x0: 0,
            y0: 0,
            x1: 1000,
            y1: 600,
        };
        let first = place("label", (500, 300), &area, &[]);
        // Right of the point by default.
        assert!(first.rect.x0 > 500 && first.align == Align::Left);
        let second = place("label", (500, 300), &area, &[first.rect]);
        assert_eq!(second.rect.overlap(&first.rect), 0);
        // Left of the point, right-aligned against it.
        assert_eq!((second.align, second.anchor.0), (Align::Right, 491));
        // At the right edge, the label goes left.
        let edge = place("label", (995, 300), &area, &[]);
        assert!(edge.rect.inside(&area) && edge.rect.x1 < 995);
    }
}
