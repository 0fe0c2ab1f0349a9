//! The `--at` part of the solve report: u_n, û_n and their estimates
//! at each point.

use super::{sci, secs};
use serde::Serialize;
use std::fmt;

/// One channel's values at one point.
#[derive(Clone, Debug, Serialize)]
pub struct PointChannel {
    /// Channel name.
    pub name: String,
    /// u_n at the point.
    pub u: f64,
    /// û_n = E + K u_n at the point.
    pub iterated: f64,
    /// Estimated error of u_n at the point (the residual there plus what
    /// the elements it sees carry to it), when estimated.
    pub estimate: Option<f64>,
    /// Estimated error of û_n at the point, when estimated.
    pub iterated_estimate: Option<f64>,
}

/// One point.
#[derive(Clone, Debug, Serialize)]
pub struct PointLine {
    /// Its label in the file, when the file has labels.
    pub label: Option<String>,
    /// Its line in the file.
    pub line: u64,
    /// The point of the surface it was taken to.
    pub position: [f64; 3],
    /// The element holding it.
    pub element: usize,
    /// How far the given point was from the surface.
    pub distance: f64,
    /// Per channel.
    pub channels: Vec<PointChannel>,
}

/// The values at the points of `--at`.
#[derive(Clone, Debug, Serialize)]
pub struct PointsReport {
    /// The file read.
    pub source: String,
    /// The largest distance a point was moved onto the surface.
    pub max_distance: f64,
    /// Seconds spent on the values (the rows of K at the points).
    pub seconds: f64,
    /// The --at-out file, when written.
    pub written: Option<String>,
    /// Whether the text report lists every point.
    #[serde(skip)]
    pub listed: bool,
    /// Every point.
    pub points: Vec<PointLine>,
}

impl fmt::Display for PointsReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "  points      {} from {} (moved onto the surface by at most {}), {}: u_n with \
             its element's estimated error, û_n = E + K u_n with its own",
            self.points.len(),
            self.source,
            sci(self.max_distance),
            secs(self.seconds)
        )?;
        if let Some(w) = &self.written {
            writeln!(
                f,
                "  wrote the point values to {w} (u_n and û_n, each with its estimated error)"
            )?;
        }
        if !self.listed {
            return Ok(());
        }
        let width = self
            .points
            .iter()
            .map(|p| p.label.as_ref().map_or(8, |l| l.chars().count()))
            .max()
            .unwrap_or(8)
            .clamp(8, 40);
        writeln!(
            f,
            "    {:<width$} {:>7} {:>13} {:>10} {:>13} {:>10}",
            "point", "channel", "u_n", "estimate", "û_n", "estimate"
        )?;
        for p in &self.points {
            let name = p
                .label
                .clone()
                .unwrap_or_else(|| format!("line {}", p.line));
            let name: String = name.chars().take(width).collect();
            for (i, c) in p.channels.iter().enumerate() {
                writeln!(
                    f,
                    "    {:<width$} {:>7} {:>13.6e} {:>10} {:>13.6e} {:>10}",
                    if i == 0 { name.as_str() } else { "" },
                    c.name,
                    c.u,
                    c.estimate.map_or("-".to_string(), sci),
                    c.iterated,
                    c.iterated_estimate.map_or("-".to_string(), sci)
                )?;
            }
        }
        Ok(())
    }
}
