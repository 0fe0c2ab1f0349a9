//! Log-log plots drawn with plotters' SVG backend: a study (error vs h and
//! vs total time, three series: nodes max, global max, L²; dashed reference
//! slopes O(h^p) of the theory's orders) and a comparison of degrees and
//! refinements (error vs unknowns and vs wall time, one line per degree and
//! refinement, adaptive ones dashed); two panels sharing the error axis,
//! whole decades, a legend in each.

use plotters::prelude::*;
use radcol_core::study::{speed::Refinement, speed::Setting, StudyRow};

const WIDTH: u32 = 960;
const HEIGHT: u32 = 520;

struct Series {
    name: &'static str,
    color: RGBColor,
    marker: Marker,
    value: fn(&StudyRow) -> f64,
}

#[derive(Clone, Copy)]
enum Marker {
    Circle,
    Square,
    Triangle,
    /// No marker (reference slopes).
    None,
}

const SERIES: [Series; 3] = [
    Series {
        name: "nodes max",
        color: RGBColor(0x1f, 0x77, 0xb4),
        marker: Marker::Circle,
        value: |r| r.nodes_max,
    },
    Series {
        name: "global max",
        color: RGBColor(0xd6, 0x27, 0x28),
        marker: Marker::Square,
        value: |r| r.global_max,
    },
    Series {
        name: "L2",
        color: RGBColor(0x2c, 0xa0, 0x2c),
        marker: Marker::Triangle,
        value: |r| r.l2,
    },
];

/// A log10 axis spanning whole decades.
#[derive(Clone, Copy, Debug)]
struct LogAxis {
    lo: i32,
    hi: i32,
}

impl LogAxis {
    /// The smallest decade range holding every positive finite value (1..10 if none).
    fn covering(values: impl Iterator<Item = f64>) -> Self {
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && *v > 0.0) {
            min = min.min(v);
            max = max.max(v);
        }
        if !min.is_finite() {
            return Self { lo: 0, hi: 1 };
        }
        let lo = min.log10().floor() as i32;
        let mut hi = max.log10().ceil() as i32;
        if hi <= lo {
            hi = lo + 1;
        }
        Self { lo, hi }
    }

    /// The axis's span, 10^lo .. 10^hi.
    fn span(self) -> std::ops::Range<f64> {
        10f64.powi(self.lo)..10f64.powi(self.hi)
    }
}

/// One plotted line: its points (x, y), a marker at each.
struct Line {
    name: String,
    color: RGBColor,
    marker: Marker,
    dashed: bool,
    points: Vec<(f64, f64)>,
}

impl Line {
    /// The points with positive finite coordinates (the others cannot be
    /// drawn on log axes).
    fn drawable(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.points
            .iter()
            .copied()
            .filter(|(a, b)| a.is_finite() && *a > 0.0 && b.is_finite() && *b > 0.0)
    }
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;
type Drawn = Result<(), Box<dyn std::error::Error>>;
/// A panel's lines, its x axis label and where its legend goes (a corner
/// the lines leave empty).
type Panel = (Vec<Line>, &'static str, SeriesLabelPosition);

/// One panel: `lines` against `x_label` on whole decades, the error axis
/// `y`, and a legend of its lines.
fn panel(area: &Area<'_>, (lines, x_label, legend_at): &Panel, y: LogAxis) -> Drawn {
    let x = LogAxis::covering(lines.iter().flat_map(|l| l.drawable().map(|p| p.0)));
    let mut chart = ChartBuilder::on(area)
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x.span().log_scale(), y.span().log_scale())?;
    chart
        .configure_mesh()
        .x_desc(*x_label)
        .y_desc("error")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for line in lines {
        let style = ShapeStyle::from(line.color).stroke_width(2);
        let points: Vec<(f64, f64)> = line.drawable().collect();
        if line.dashed {
            chart
                .draw_series(DashedLineSeries::new(points.clone(), 7, 4, style))?
                .label(line.name.as_str())
                .legend(move |(x, y)| {
                    plotters::element::DashedPathElement::new([(x, y), (x + 24, y)], 7, 4, style)
                });
        } else {
            chart
                .draw_series(LineSeries::new(points.clone(), style))?
                .label(line.name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 24, y)], style));
        }
        let filled = ShapeStyle::from(line.color).filled();
        match line.marker {
            Marker::Circle => {
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, filled)))?;
            }
            Marker::Square => {
                chart.draw_series(
                    points
                        .iter()
                        .map(|&p| EmptyElement::at(p) + Rectangle::new([(-3, -3), (3, 3)], filled)),
                )?;
            }
            Marker::Triangle => {
                chart.draw_series(points.iter().map(|&p| TriangleMarker::new(p, 4, filled)))?;
            }
            Marker::None => {}
        }
    }
    chart
        .configure_series_labels()
        .position(legend_at.clone())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// The document: `title` over the two panels, which share the error axis.
fn document(title: &str, [left, right]: &[Panel; 2]) -> String {
    let y = LogAxis::covering(
        left.0
            .iter()
            .chain(&right.0)
            .flat_map(|l| l.drawable().map(|p| p.1)),
    );
    let mut svg = String::new();
    let drawn = (|| -> Drawn {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 18))?;
        let (l, r) = root.split_horizontally(WIDTH / 2);
        panel(&l, left, y)?;
        panel(&r, right, y)?;
        root.present()?;
        Ok(())
    })();
    // Drawing into a String fails only on a plotters bug: say so in the plot.
    if let Err(e) = drawn {
        return format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><text x=\"10\" y=\"20\">plot failed: {}</text></svg>\n",
            e.to_string().replace('&', "&amp;").replace('<', "&lt;")
        );
    }
    svg
}

/// The SVG document for `rows`, titled `title`, with a dashed reference
/// line O(h^p) in the h panel for each (series name, p) of `orders` (the
/// theory's orders), through that series' finest error above the row's
/// rounding floor (errors at rounding would pin it to noise; with none above
/// it, no line).
pub fn study_svg(rows: &[StudyRow], title: &str, orders: &[(&str, usize)]) -> String {
    document(title, &study_panels(rows, orders))
}

/// The study's panels: error against h (falling to the lower left, the
/// legend in the lower right) with the reference slopes, and against time.
fn study_panels(rows: &[StudyRow], orders: &[(&str, usize)]) -> [Panel; 2] {
    let lines = |x_of: fn(&StudyRow) -> f64| -> Vec<Line> {
        SERIES
            .iter()
            .map(|s| Line {
                name: s.name.to_string(),
                color: s.color,
                marker: s.marker,
                dashed: false,
                points: rows.iter().map(|r| (x_of(r), (s.value)(r))).collect(),
            })
            .collect()
    };
    let mut by_h = lines(|r| r.h);
    for &(name, p) in orders {
        let Some(s) = SERIES.iter().find(|s| s.name == name) else {
            continue;
        };
        let Some(anchor) = rows.iter().rev().find(|r| (s.value)(r) > r.rounding_floor) else {
            continue;
        };
        let (h0, e0) = (anchor.h, (s.value)(anchor));
        by_h.push(Line {
            name: format!("O(h^{p})"),
            color: s.color,
            marker: Marker::None,
            dashed: true,
            points: rows
                .iter()
                .map(|r| (r.h, e0 * (r.h / h0).powi(p as i32)))
                .collect(),
        });
    }
    [
        (by_h, "mesh size h", SeriesLabelPosition::LowerRight),
        (
            lines(|r| r.total_s),
            "total time per level (s)",
            SeriesLabelPosition::UpperRight,
        ),
    ]
}

/// Colours of the degrees, in order.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
];

/// The SVG document comparing `settings` (as `study --degrees/--adaptive`
/// collects them): error against unknowns and against wall seconds, a solid
/// line with circles per degree's uniform study and a dashed one with
/// squares per adaptive run, in the order first met.
pub fn comparison_svg(settings: &[Setting], title: &str) -> String {
    document(title, &comparison_panels(settings))
}

/// The comparison's panels: error against unknowns and against wall time,
/// both falling to the right (the legend in the upper right).
fn comparison_panels(settings: &[Setting]) -> [Panel; 2] {
    let mut keys: Vec<(usize, bool)> = Vec::new();
    for s in settings {
        let key = (
            s.degree,
            matches!(s.refinement, Refinement::Adaptive { .. }),
        );
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    let mut degrees: Vec<usize> = keys.iter().map(|k| k.0).collect();
    degrees.dedup();
    let lines = |x_of: fn(&Setting) -> f64| -> Vec<Line> {
        keys.iter()
            .map(|&(r, adaptive)| {
                let colour = degrees.iter().position(|&d| d == r).unwrap_or(0);
                Line {
                    name: format!("r = {r} {}", if adaptive { "adaptive" } else { "uniform" }),
                    color: PALETTE[colour % PALETTE.len()],
                    marker: if adaptive {
                        Marker::Square
                    } else {
                        Marker::Circle
                    },
                    dashed: adaptive,
                    points: settings
                        .iter()
                        .filter(|s| {
                            s.degree == r
                                && matches!(s.refinement, Refinement::Adaptive { .. }) == adaptive
                        })
                        .map(|s| (x_of(s), s.error))
                        .collect(),
                }
            })
            .collect()
    };
    [
        (
            lines(|s| s.unknowns as f64),
            "unknowns",
            SeriesLabelPosition::UpperRight,
        ),
        (
            lines(|s| s.seconds),
            "wall time (s)",
            SeriesLabelPosition::UpperRight,
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(level: u32, h: f64, e: f64) -> StudyRow {
        StudyRow {
            level,
            elements: 8,
            unknowns: 24,
            h,
            nodes_max: e,
            global_max: 3.0 * e,
            l2: 2.0 * e,
            eoc_nodes: None,
            eoc_global: None,
            eoc_l2: None,
            assembly_s: 0.01,
            solve_s: 0.001,
            total_s: 0.02 * (level + 1) as f64,
            iterations: 5,
            kernel_evals: 1000,
            estimated: false,
            estimate_max: None,
            estimate_l2: None,
            effectivity: None,
            rounding_floor: 2.2e-13,
            scale: 1.0,
        }
    }

    #[test]
    fn axis_covers_whole_decades() {
        let a = LogAxis::covering([3e-5, 0.2].into_iter());
        assert_eq!((a.lo, a.hi), (-5, 0));
        let b = LogAxis::covering([0.5, 0.5].into_iter());
        assert_eq!((b.lo, b.hi), (-1, 0));
        assert_eq!(a.span(), 1e-5..1.0);
    }

    /// The names of a legend's entries in the SVG (plotters writes each
    /// text on its own line).
    fn count(svg: &str, text: &str) -> usize {
        svg.lines().filter(|l| l.trim() == text).count()
    }

    #[test]
    fn svg_has_both_panels_three_series_and_a_legend() {
        let rows = vec![row(0, 1.0, 1e-2), row(1, 0.5, 1e-3), row(2, 0.25, 1e-4)];
        let svg = study_svg(&rows, "sphere <r = 1>", &[]);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        // Each series in both panels' legends, the axes named, the title
        // escaped.
        for name in ["nodes max", "global max", "L2", "error"] {
            assert_eq!(count(&svg, name), 2, "{name}");
        }
        assert_eq!(count(&svg, "mesh size h"), 1);
        assert_eq!(count(&svg, "total time per level (s)"), 1);
        assert!(svg.contains("sphere &lt;r = 1&gt;"), "{svg}");
        // A marker per point: circles (nodes max), squares, triangles.
        assert_eq!(svg.matches("<circle").count(), 6);
    }

    /// A reference O(h^2) through the finest global max error: its first
    /// point lies 2 decades above it when h is 10 times larger; a series
    /// the theory names that is not plotted gets none. Drawn dashed, in
    /// the legend.
    #[test]
    fn reference_slopes_pass_through_the_finest_error() {
        let rows = vec![row(0, 1.0, 1e-2), row(1, 0.1, 1e-4)];
        let orders = [("global max", 2), ("no such series", 9)];
        let [(by_h, _, _), (by_t, _, _)] = study_panels(&rows, &orders);
        assert_eq!((by_h.len(), by_t.len()), (4, 3), "one reference line");
        let reference = &by_h[3];
        assert!(reference.dashed && reference.name == "O(h^2)");
        // Through the finest error (3e-4 at h = 0.1), two decades up at
        // h = 1: the data's own points here (slope exactly 2).
        for (r, d) in reference.points.iter().zip(&by_h[1].points) {
            assert_eq!(r.0, d.0);
            radcol_core::assert_close!(r.1, d.1, 1e-15);
        }
        radcol_core::assert_close!(reference.points[0].1, 3e-2, 1e-15);
        let svg = study_svg(&rows, "t", &orders);
        assert_eq!(count(&svg, "O(h^2)"), 1);
        assert!(!svg.contains("O(h^9)"));
    }

    #[test]
    fn comparison_has_a_line_per_degree_and_refinement() {
        let setting =
            |degree: usize, refinement: Refinement, unknowns: usize, error: f64| Setting {
                degree,
                refinement,
                unknowns,
                seconds: unknowns as f64 * 1e-3,
                error,
                estimated: true,
            };
        let u = |level| Refinement::Uniform { level };
        let a = |step| Refinement::Adaptive { step };
        let settings = vec![
            setting(1, u(1), 96, 1e-2),
            setting(1, u(2), 384, 3e-3),
            setting(1, a(1), 96, 1e-2),
            setting(1, a(2), 200, 1e-3),
            setting(2, u(1), 192, 1e-3),
            setting(2, u(2), 768, 1e-4),
        ];
        // Three lines in each of the two panels, the adaptive one dashed,
        // degree 2 in its own colour.
        for (lines, _, _) in comparison_panels(&settings) {
            let names: Vec<&str> = lines.iter().map(|l| l.name.as_str()).collect();
            assert_eq!(names, ["r = 1 uniform", "r = 1 adaptive", "r = 2 uniform"]);
            let dashed: Vec<bool> = lines.iter().map(|l| l.dashed).collect();
            assert_eq!(dashed, [false, true, false]);
            assert!(lines[0].color == PALETTE[0] && lines[2].color == PALETTE[1]);
        }
        let [(by_n, _, _), (by_t, _, _)] = comparison_panels(&settings);
        assert_eq!(by_n[1].points, [(96.0, 1e-2), (200.0, 1e-3)]);
        assert_eq!(by_t[1].points, [(0.096, 1e-2), (0.2, 1e-3)]);
        let svg = comparison_svg(&settings, "cornell");
        for name in ["r = 1 uniform", "r = 1 adaptive", "r = 2 uniform"] {
            assert_eq!(count(&svg, name), 2, "{name}");
        }
    }
}
