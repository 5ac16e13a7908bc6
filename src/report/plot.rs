//! The sweep's picture: error (log axis) against GPU time, every
//! combination a labelled point, the Pareto front connected and
//! highlighted. Drawn with `plotters` into an SVG string.
//!
//! Two things plotters does not do for us:
//!
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

    // The floor for error 0: a decade below the smallest non-zero error
    // (rounded down to a power of ten, so it sits on a grid line).
    let min_positive = points
        .iter()
        .map(|p| p.y)
        .filter(|&y| y > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if min_positive.is_finite() {
        10f64.powf(min_positive.log10().floor() - 1.0)
    } else {
        1e-6
    };
    let y_of = |p: &PlotPoint| if p.y > 0.0 { p.y } else { floor };
    let y_max = points.iter().map(y_of).fold(floor, f64::max);
    // Half a decade of room below the lowest point and above the highest.
    let y_min = if points.iter().any(|p| p.y <= 0.0) {
        floor
    } else {
        min_positive
    };
    let y_range = y_min / 3.0..y_max * 3.0;

    let (x_min, x_max) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.x), hi.max(p.x))
        });
    let span = if x_max > x_min {
        x_max - x_min
    } else {
        x_max.max(1.0) * 0.2
    };
    // Extra room on the right for the labels of the slowest points.
    let x_range = (x_min - 0.1 * span).max(0.0)..x_max + 0.25 * span;

    let mut svg = String::new();
    draw(plot, floor, x_range, y_range, &mut svg).map_err(|e| PlotError::Draw(e.to_string()))?;
    Ok(svg)
}

fn draw(
    plot: &Plot<'_>,
    floor: f64,
    x_range: std::ops::Range<f64>,
    y_range: std::ops::Range<f64>,
    svg: &mut String,
) -> Result<(), Box<dyn std::error::Error>> {
    let points = plot.points;
    let y_of = |p: &PlotPoint| if p.y > 0.0 { p.y } else { floor };
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
        .build_cartesian_2d(x_range, y_range.log_scale())?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label)
        .y_desc(plot.y_label)
        .x_label_formatter(&|v| format!("{v:.1}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .light_line_style(WHITE)
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()?;

    // The floor line, only when something sits on it.
    let any_zero = points.iter().any(|p| p.y <= 0.0);
    let (x0, x1) = {
        let r = chart.x_range();
        (r.start, r.end)
    };
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
            front.iter().map(|p| (p.x, y_of(p))),
            FRONT.stroke_width(2),
        ))?
        .label(FRONT_LABEL)
        .legend(|(x, y)| PathElement::new([(x, y), (x + 24, y)], FRONT.stroke_width(2)));
    chart
        .draw_series(
            points
                .iter()
                .filter(|p| !p.pareto)
                .map(|p| Circle::new((p.x, y_of(p)), 4, OTHER.filled())),
        )?
        .label("other combinations")
        .legend(|(x, y)| Circle::new((x + 12, y), 4, OTHER.filled()));
    chart.draw_series(
        front
            .iter()
            .map(|p| Circle::new((p.x, y_of(p)), 5, FRONT.filled())),
    )?;
    if points.iter().any(|p| p.reference) {
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| p.reference)
                    .map(|p| Circle::new((p.x, y_of(p)), 9, BLACK.stroke_width(2))),
            )?
            .label(format!(
                "reference: error 0, drawn at {floor:.0e} (grey line)"
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

    // Labels, in pixels of the whole picture (chart coordinates map to the
    // same backend pixels).
    let pixel: Vec<(i32, i32)> = points
        .iter()
        .map(|p| chart.backend_coord(&(p.x, y_of(p))))
        .collect();
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    let area = Rect {
        x0: xs.start,
        y0: ys.start,
        x1: xs.end,
        y1: ys.end,
    };
    // Markers are obstacles too; the reference's ring is larger.
    let mut taken: Vec<Rect> = points
        .iter()
        .zip(&pixel)
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
        let spot = place(&text, pixel[i], &area, &taken);
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
    root.present()?;
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
