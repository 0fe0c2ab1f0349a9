//! Hand-written SVG log-log plots: a study (error vs h and vs total time,
//! three series: nodes max, global max, L²) and a comparison of degrees and
//! refinements (error vs unknowns and vs wall time, one line per degree and
//! refinement); two panels sharing the error axis, decade ticks, a legend.

use radcol_core::study::speed::{Refinement, Setting};
use radcol_core::study::StudyRow;
use std::fmt::Write as _;

const WIDTH: f64 = 960.0;
const HEIGHT: f64 = 520.0;
const PANEL_W: f64 = 360.0;
const PANEL_H: f64 = 330.0;
const PANEL_TOP: f64 = 70.0;
const PANEL_LEFT: [f64; 2] = [90.0, 570.0];

struct Series {
    name: &'static str,
    color: &'static str,
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
        color: "#1f77b4",
        marker: Marker::Circle,
        value: |r| r.nodes_max,
    },
    Series {
        name: "global max",
        color: "#d62728",
        marker: Marker::Square,
        value: |r| r.global_max,
    },
    Series {
        name: "L2",
        color: "#2ca02c",
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

    /// Position of `v` in [0, 1] along the axis.
    fn frac(&self, v: f64) -> f64 {
        (v.log10() - self.lo as f64) / (self.hi - self.lo) as f64
    }

    /// Label every `step`-th decade so that at most about 8 labels show.
    fn label_step(&self) -> i32 {
        ((self.hi - self.lo) + 7) / 8
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `10^k` as SVG text with a superscript exponent.
fn decade_label(k: i32) -> String {
    format!("10<tspan dy=\"-7\" font-size=\"10\">{k}</tspan>")
}

fn marker(svg: &mut String, m: Marker, x: f64, y: f64, color: &str) {
    let _ = match m {
        Marker::Circle => writeln!(
            svg,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="4" fill="{color}"/>"#
        ),
        Marker::Square => writeln!(
            svg,
            r#"<rect x="{:.2}" y="{:.2}" width="8" height="8" fill="{color}"/>"#,
            x - 4.0,
            y - 4.0
        ),
        Marker::Triangle => writeln!(
            svg,
            r#"<polygon points="{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}" fill="{color}"/>"#,
            x,
            y - 5.0,
            x - 5.0,
            y + 4.0,
            x + 5.0,
            y + 4.0
        ),
        Marker::None => Ok(()),
    };
}

/// Decade grid lines, ticks and labels of `axis` (the x axis when
/// `horizontal`) on the panel at `left`; minor ticks at 2..9 × 10^k.
fn ticks(svg: &mut String, axis: LogAxis, horizontal: bool, left: f64) {
    let top = PANEL_TOP;
    let bottom = top + PANEL_H;
    let step = axis.label_step();
    for k in axis.lo..=axis.hi {
        let f = (k - axis.lo) as f64 / (axis.hi - axis.lo) as f64;
        let labelled = (k - axis.lo) % step == 0;
        if horizontal {
            let xp = left + f * PANEL_W;
            let _ = writeln!(
                svg,
                r##"<line x1="{xp:.2}" y1="{top}" x2="{xp:.2}" y2="{bottom}" stroke="#e4e4e4"/>"##
            );
            let _ = writeln!(
                svg,
                r##"<line x1="{xp:.2}" y1="{bottom}" x2="{xp:.2}" y2="{:.2}" stroke="#333333"/>"##,
                bottom + 6.0
            );
            if labelled {
                let _ = writeln!(
                    svg,
                    r#"<text x="{xp:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
                    bottom + 22.0,
                    decade_label(k)
                );
            }
        } else {
            let yp = bottom - f * PANEL_H;
            let _ = writeln!(
                svg,
                r##"<line x1="{left}" y1="{yp:.2}" x2="{:.2}" y2="{yp:.2}" stroke="#e4e4e4"/>"##,
                left + PANEL_W
            );
            let _ = writeln!(
                svg,
                r##"<line x1="{:.2}" y1="{yp:.2}" x2="{left}" y2="{yp:.2}" stroke="#333333"/>"##,
                left - 6.0
            );
            if labelled {
                let _ = writeln!(
                    svg,
                    r#"<text x="{:.2}" y="{:.2}" text-anchor="end">{}</text>"#,
                    left - 9.0,
                    yp + 4.0,
                    decade_label(k)
                );
            }
        }
        if k < axis.hi {
            for m in 2..=9 {
                let g = f + (m as f64).log10() / (axis.hi - axis.lo) as f64;
                if horizontal {
                    let xp = left + g * PANEL_W;
                    let _ = writeln!(
                        svg,
                        r##"<line x1="{xp:.2}" y1="{bottom}" x2="{xp:.2}" y2="{:.2}" stroke="#333333"/>"##,
                        bottom + 3.0
                    );
                } else {
                    let yp = bottom - g * PANEL_H;
                    let _ = writeln!(
                        svg,
                        r##"<line x1="{:.2}" y1="{yp:.2}" x2="{left}" y2="{yp:.2}" stroke="#333333"/>"##,
                        left - 3.0
                    );
                }
            }
        }
    }
}

/// One plotted line: its points (x, y), a marker at each.
struct Line {
    name: String,
    color: &'static str,
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

/// One panel at `left`: frame, ticks, labels, and `lines` on axes `x`, `y`.
fn panel(svg: &mut String, left: f64, lines: &[Line], x_label: &str, y: LogAxis) {
    let x = LogAxis::covering(lines.iter().flat_map(|l| l.drawable().map(|p| p.0)));
    let top = PANEL_TOP;
    let bottom = top + PANEL_H;
    let px = |v: f64| left + x.frac(v) * PANEL_W;
    let py = |v: f64| bottom - y.frac(v) * PANEL_H;

    let _ = writeln!(
        svg,
        r##"<rect x="{left}" y="{top}" width="{PANEL_W}" height="{PANEL_H}" fill="#ffffff" stroke="#333333"/>"##
    );
    // Decade grid lines, ticks and labels; minor ticks at 2..9 × 10^k.
    for (axis, horizontal) in [(x, true), (y, false)] {
        ticks(svg, axis, horizontal, left);
    }
    let _ = writeln!(
        svg,
        r#"<text x="{:.2}" y="{:.2}" text-anchor="middle" font-size="14">{}</text>"#,
        left + PANEL_W / 2.0,
        bottom + 46.0,
        escape(x_label)
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.2}" y="{:.2}" text-anchor="middle" font-size="14" transform="rotate(-90 {:.2} {:.2})">error</text>"#,
        left - 58.0,
        top + PANEL_H / 2.0,
        left - 58.0,
        top + PANEL_H / 2.0
    );
    for line in lines {
        let pts: Vec<(f64, f64)> = line.drawable().map(|(a, b)| (px(a), py(b))).collect();
        if pts.len() > 1 {
            let path: Vec<String> = pts.iter().map(|(a, b)| format!("{a:.2},{b:.2}")).collect();
            let dash = if line.dashed {
                r#" stroke-dasharray="7 4""#
            } else {
                ""
            };
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.8"{dash}/>"#,
                path.join(" "),
                line.color
            );
        }
        for &(a, b) in &pts {
            marker(svg, line.marker, a, b, line.color);
        }
    }
}

/// The document: `title`, the two panels (sharing the error axis) and a
/// legend of the left panel's lines, in rows of six under both panels.
fn document(title: &str, left: (&[Line], &str), right: (&[Line], &str)) -> String {
    let y = LogAxis::covering(
        left.0
            .iter()
            .chain(right.0)
            .flat_map(|l| l.drawable().map(|p| p.1)),
    );
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(
        svg,
        r##"<rect width="100%" height="100%" fill="#ffffff"/>"##
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="32" text-anchor="middle" font-size="17">{}</text>"#,
        WIDTH / 2.0,
        escape(title)
    );
    panel(&mut svg, PANEL_LEFT[0], left.0, left.1, y);
    panel(&mut svg, PANEL_LEFT[1], right.0, right.1, y);
    const PER_ROW: usize = 6;
    for (row, chunk) in left.0.chunks(PER_ROW).enumerate() {
        let legend_y = HEIGHT - 28.0 - 20.0 * (left.0.len().div_ceil(PER_ROW) - 1 - row) as f64;
        let mut lx = WIDTH / 2.0 - 75.0 * chunk.len() as f64 + 15.0;
        for line in chunk {
            let dash = if line.dashed {
                r#" stroke-dasharray="7 4""#
            } else {
                ""
            };
            let _ = writeln!(
                svg,
                r#"<line x1="{lx:.1}" y1="{legend_y}" x2="{:.1}" y2="{legend_y}" stroke="{}" stroke-width="1.8"{dash}/>"#,
                lx + 36.0,
                line.color
            );
            marker(&mut svg, line.marker, lx + 18.0, legend_y, line.color);
            let _ = writeln!(
                svg,
                r#"<text x="{:.1}" y="{:.1}">{}</text>"#,
                lx + 44.0,
                legend_y + 4.0,
                escape(&line.name)
            );
            lx += 150.0;
        }
    }
    svg.push_str("</svg>\n");
    svg
}

/// The SVG document for `rows`, titled `title`, with a dashed reference
/// line O(h^p) in the h panel for each (series name, p) of `orders` (the
/// theory's orders), through that series' finest error above the row's
/// rounding floor (errors at rounding would pin it to noise; with none above
/// it, no line).
pub fn study_svg(rows: &[StudyRow], title: &str, orders: &[(&str, usize)]) -> String {
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
    document(
        title,
        (&by_h, "mesh size h"),
        (&lines(|r| r.total_s), "total time per level (s)"),
    )
}

/// Colours of the degrees, in order.
const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
];

/// The SVG document comparing `settings` (as `study --degrees/--adaptive`
/// collects them): error against unknowns and against wall seconds, a solid
/// line with circles per degree's uniform study and a dashed one with
/// squares per adaptive run, in the order first met.
pub fn comparison_svg(settings: &[Setting], title: &str) -> String {
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
    document(
        title,
        (&lines(|s| s.unknowns as f64), "unknowns"),
        (&lines(|s| s.seconds), "wall time (s)"),
    )
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
        radcol_core::assert_close!(a.frac(1e-5), 0.0, 1e-12);
        radcol_core::assert_close!(a.frac(1.0), 1.0, 1e-12);
    }

    #[test]
    fn svg_has_both_panels_three_series_and_a_legend() {
        let rows = vec![row(0, 1.0, 1e-2), row(1, 0.5, 1e-3), row(2, 0.25, 1e-4)];
        let svg = study_svg(&rows, "sphere <r = 1>", &[]);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<polyline").count(), 6);
        assert!(svg.contains("nodes max") && svg.contains("global max") && svg.contains(">L2<"));
        assert!(svg.contains("sphere &lt;r = 1&gt;"));
    }

    /// A reference O(h^2) through the finest global max error: its first
    /// point lies 2 decades above it when h is 10 times larger.
    #[test]
    fn reference_slopes_pass_through_the_finest_error() {
        let rows = vec![row(0, 1.0, 1e-2), row(1, 0.1, 1e-4)];
        let svg = study_svg(&rows, "t", &[("global max", 2), ("no such series", 9)]);
        assert_eq!(svg.matches("<polyline").count(), 7, "one reference line");
        assert!(svg.contains("O(h^2)") && !svg.contains("O(h^9)"));
        assert!(svg.contains(r#"stroke-dasharray="7 4""#));
        // Its points coincide with the data's here (slope exactly 2): the
        // reference polyline repeats the global max polyline's coordinates.
        let polys: Vec<&str> = svg
            .lines()
            .filter(|l| l.starts_with("<polyline"))
            .map(|l| l.split('"').nth(1).unwrap())
            .collect();
        assert_eq!(polys[1], polys[3], "global max and its O(h^2) reference");
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
        let svg = comparison_svg(&settings, "cornell");
        // Three lines in each of the two panels, one of them dashed.
        assert_eq!(svg.matches("<polyline").count(), 6);
        assert_eq!(svg.matches("stroke-dasharray").count(), 2 + 1);
        for name in ["r = 1 uniform", "r = 1 adaptive", "r = 2 uniform"] {
            assert_eq!(svg.matches(name).count(), 1, "{name}");
        }
        // Degree 2 has its own colour.
        assert!(svg.contains(PALETTE[1]) && !svg.contains(PALETTE[2]));
    }
}
