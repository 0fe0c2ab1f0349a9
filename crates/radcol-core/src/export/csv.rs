//! The solution at its collocation nodes as CSV: one row per node, with
//! each channel's u_n and, when the solve was estimated, its element's
//! estimated error.

use super::{Context, Result};
use crate::discretization::Discretization;
use crate::run::ChannelResult;
use std::io::Write;

/// The value columns of `channels`: `u` for one channel, `u_NAME` for
/// several.
pub fn value_columns(channels: &[ChannelResult]) -> Vec<String> {
    if channels.len() == 1 {
        vec!["u".into()]
    } else {
        channels.iter().map(|c| format!("u_{}", c.name)).collect()
    }
}

/// Writes one row per collocation node of `disc`: `element,node,x,y,z`,
/// each channel's u_n ([`value_columns`]) and, when every channel was
/// estimated, each one's `…_error_estimate` (the node's element's
/// estimated max error of u_n, absolute). Every value is in Rust's
/// shortest round-trip form. Returns the number of rows.
///
/// # Errors
/// [`super::ExportError::Invalid`] when a channel has other nodes than
/// `disc`; [`super::ExportError::Write`] when `w` fails.
pub fn write_nodes<W: Write>(
    w: W,
    disc: &Discretization,
    channels: &[ChannelResult],
) -> Result<usize> {
    let points = disc.points();
    if let Some(c) = channels
        .iter()
        .find(|c| c.solution.nodal().len() != points.len())
    {
        bail!(
            "CSV: channel {} has {} values for {} nodes",
            c.name,
            c.solution.nodal().len(),
            points.len()
        );
    }
    let estimates: Option<Vec<&[f64]>> = channels
        .iter()
        .map(|c| c.estimate.as_ref().map(|e| &e.elements[..]))
        .collect();
    let mut columns = value_columns(channels);
    if estimates.is_some() {
        let names = value_columns(channels).into_iter();
        columns.extend(names.map(|c| format!("{c}_error_estimate")));
    }
    let mut w = std::io::BufWriter::new(w);
    let mut rows = || -> std::io::Result<()> {
        writeln!(w, "element,node,x,y,z,{}", columns.join(","))?;
        for (i, p) in points.iter().enumerate() {
            let x = p.position;
            write!(w, "{},{},{:e},{:e},{:e}", p.element, p.node, x.x, x.y, x.z)?;
            for ch in channels {
                write!(w, ",{:e}", ch.solution.nodal()[i])?;
            }
            for e in estimates.iter().flatten() {
                write!(w, ",{:e}", e[p.element])?;
            }
            writeln!(w)?;
        }
        w.flush()
    };
    rows().context("CSV: writing the rows")?;
    Ok(points.len())
}
