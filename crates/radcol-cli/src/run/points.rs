//! `--at`: u_n, the iterated û_n and the element estimate at the user's
//! points, after the solve ([`radcol_core::prelude::query`]). Every point is found on
//! the surface before anything is solved, so a point off the scene costs
//! nothing.

use crate::error::bad_input;
use crate::files::create;
use crate::report::{PointChannel, PointLine, PointsReport};
use crate::setup::Setup;
use crate::validate::PointsSpec;
use anyhow::{Context, Result};
use radcol_core::prelude::{query, QueryError, DEFAULT_SNAP};
use radcol_core::run::{Locator, Mesh, SolveOutcome};
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

/// Points listed in the text report at most (beyond, only with no --at-out).
const LISTED: usize = 50;

/// Refuses, before the solve, a point that lies farther than the snapping
/// distance from the surface (or, with a normal, from every face it
/// meets the front of). The surface is the same at every refinement, so the
/// unrefined mesh answers.
pub fn precheck(spec: &PointsSpec, s: &Setup) -> Result<()> {
    let mesh = Mesh::new(Arc::clone(&s.problem.surface), 0);
    let (lo, hi) = s.problem.surface.bounding_box();
    let reach = DEFAULT_SNAP * (hi - lo).length();
    let locator = Locator::new(&mesh);
    for (i, q) in spec.points.iter().enumerate() {
        if locator
            .nearest(&mesh, q.position, q.normal, reach)
            .is_none()
        {
            return Err(off_surface(spec, i, q.normal.is_some(), reach).into());
        }
    }
    Ok(())
}

fn off_surface(spec: &PointsSpec, i: usize, faced: bool, reach: f64) -> crate::error::BadInput {
    let p = spec.points[i].position;
    bad_input(format!(
        "{}:{}: the point ({}, {}, {}) is not on the surface: no face{} within {reach:.3e} (1e-3 of the scene's diagonal)",
        spec.source.display(),
        spec.lines[i],
        p.x,
        p.y,
        p.z,
        if faced { " whose front its normal looks at" } else { "" }
    ))
}

/// The values at every point of `spec` for `out`, written to --at-out when
/// given.
pub fn evaluate(spec: &PointsSpec, s: &Setup, out: &SolveOutcome) -> Result<PointsReport> {
    let t = Instant::now();
    let values = query(
        &s.problem,
        out,
        s.cfg.quad.clone(),
        &spec.points,
        DEFAULT_SNAP,
    )
    .map_err(|e| match e {
        QueryError::NotOnSurface {
            index,
            faced,
            reach,
            ..
        } => anyhow::Error::new(off_surface(spec, index, faced, reach)),
    })?;
    let lines: Vec<PointLine> = values
        .iter()
        .enumerate()
        .map(|(i, v)| PointLine {
            label: spec.labels.as_ref().map(|l| l[i].clone()),
            line: spec.lines[i],
            position: v.located.position.to_array(),
            element: v.located.element,
            distance: v.located.distance,
            channels: v
                .channels
                .iter()
                .zip(&out.channels)
                .map(|(c, ch)| PointChannel {
                    name: ch.name.clone(),
                    u: c.u,
                    iterated: c.iterated,
                    estimate: c.estimate,
                    iterated_estimate: c.iterated_estimate,
                })
                .collect(),
        })
        .collect();
    let written = match &spec.out {
        Some(file) => {
            let mut f = create(file)?;
            write_csv(&mut f, &lines)
                .with_context(|| format!("writing {}", file.path.display()))?;
            f.commit()?;
            Some(file.path.display().to_string())
        }
        None => None,
    };
    Ok(PointsReport {
        source: spec.source.display().to_string(),
        listed: written.is_none() || lines.len() <= LISTED,
        max_distance: lines.iter().map(|l| l.distance).fold(0.0, f64::max),
        seconds: t.elapsed().as_secs_f64(),
        written,
        points: lines,
    })
}

/// The --at-out CSV: a header, then a row per point.
fn write_csv(w: &mut dyn Write, lines: &[PointLine]) -> Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    let Some(first) = lines.first() else {
        return Ok(());
    };
    let single = first.channels.len() == 1;
    let mut header: Vec<String> = ["label", "x", "y", "z", "element", "distance"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for c in &first.channels {
        for what in ["u", "uhat", "estimate", "uhat_estimate"] {
            header.push(if single {
                what.to_string()
            } else {
                format!("{what}_{}", c.name)
            });
        }
    }
    csv.write_record(&header)?;
    for l in lines {
        let mut row = vec![
            l.label
                .clone()
                .unwrap_or_else(|| format!("line {}", l.line)),
            format!("{:e}", l.position[0]),
            format!("{:e}", l.position[1]),
            format!("{:e}", l.position[2]),
            l.element.to_string(),
            format!("{:e}", l.distance),
        ];
        for c in &l.channels {
            row.push(format!("{:e}", c.u));
            row.push(format!("{:e}", c.iterated));
            row.push(c.estimate.map_or(String::new(), |e| format!("{e:e}")));
            row.push(
                c.iterated_estimate
                    .map_or(String::new(), |e| format!("{e:e}")),
            );
        }
        csv.write_record(&row)?;
    }
    csv.flush()?;
    Ok(())
}
