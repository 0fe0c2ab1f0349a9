//! Executing a validated [`Config`]: call core, then report.

use crate::config::{Config, InfoJob, NodesJob, SolveJob, StudyJob};
use crate::report::{self, InfoReport, Memory, ShapeRatio};
use crate::{output, plot};
use anyhow::{Context, Result};
use radcol_core::alpha0::find_alpha0;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::run::{available_memory, check_memory, solve, SolverKind};
use radcol_core::study::study;
use std::io::{self, Write};
use std::sync::Arc;

/// Largest mesh `radcol info` builds to measure shape ratios and area.
const INFO_MAX_BUILT_ELEMENTS: u64 = 1 << 17;
/// Beyond this level `radcol info` refuses: the counts stop meaning anything.
const INFO_MAX_LEVEL: u32 = 24;

/// Runs one command, printing its report to stdout.
pub fn run(config: Config) -> Result<()> {
    let stdout = io::stdout();
    let mut w = stdout.lock();
    match config {
        Config::Solve(job) => run_solve(job, &mut w),
        Config::Study(job) => run_study(job, &mut w),
        Config::Nodes(job) => run_nodes(job, &mut w),
        Config::Info(job) => run_info(job, &mut w),
    }?;
    w.flush()?;
    Ok(())
}

fn print_json(w: &mut dyn Write, v: &serde_json::Value) -> Result<()> {
    // Rendered first so that a closed stdout surfaces as a plain io::Error.
    let text = serde_json::to_string_pretty(v)?;
    writeln!(w, "{text}")?;
    Ok(())
}

fn run_solve(job: SolveJob, w: &mut dyn Write) -> Result<()> {
    let s = &job.setup;
    let out = solve(&s.problem, &s.cfg, s.backend.imp.as_ref())?;
    let csv = match &job.out {
        Some(file) => Some((
            file.path.display().to_string(),
            output::write_csv(file, &out)?,
        )),
        None => None,
    };
    if s.json {
        print_json(
            w,
            &report::solve_json(s, &out, csv.as_ref().map(|c| c.0.as_str())),
        )
    } else {
        report::solve_text(w, s, &out, csv.as_ref().map(|(p, n)| (p.as_str(), *n)))?;
        Ok(())
    }
}

fn run_study(job: StudyJob, w: &mut dyn Write) -> Result<()> {
    let s = &job.setup;
    let levels = (*job.levels.start(), *job.levels.end());
    let info = s.backend.imp.info();
    if !s.json {
        report::study_header(
            w,
            s,
            levels,
            &format!("{} ({}, {})", info.kind, info.device, info.precision),
        )?;
        w.flush()?;
    }
    // Rows print as they complete; a failed write stops nothing but is reported after.
    let mut write_error: Option<io::Error> = None;
    let rows = study(
        &s.problem,
        &s.cfg,
        job.levels.clone(),
        s.backend.imp.as_ref(),
        |row| {
            if !s.json && write_error.is_none() {
                if let Err(e) = report::study_row(w, row).and_then(|_| w.flush()) {
                    write_error = Some(e);
                }
            }
        },
    )?;
    if let Some(e) = write_error {
        return Err(e.into());
    }
    let theory = report::theory(s.cfg.degree, s.alpha.value, &find_alpha0(s.cfg.degree));
    let plot_path = match &job.plot {
        Some(file) => {
            let title = format!(
                "radcol study: {}, r = {}, α = {:.6}, ρ = {}, u = {}",
                s.scene,
                s.cfg.degree,
                s.alpha.value,
                s.rho,
                s.exact.as_deref().unwrap_or("-")
            );
            let svg = plot::study_svg(&rows, &title);
            let mut f = output::create(file)?;
            f.write_all(svg.as_bytes())
                .and_then(|_| f.flush())
                .with_context(|| format!("writing {}", file.path.display()))?;
            Some(file.path.display().to_string())
        }
        None => None,
    };
    if s.json {
        let backend = serde_json::to_value(&info)?;
        print_json(
            w,
            &report::study_json(s, levels, &backend, &rows, theory, plot_path.as_deref()),
        )
    } else {
        report::study_footer(w, &rows, &theory.2)?;
        if let Some(p) = plot_path {
            writeln!(w, "wrote plot to {p}")?;
        }
        Ok(())
    }
}

fn run_nodes(job: NodesJob, w: &mut dyn Write) -> Result<()> {
    let set = NodeSet::new(job.degree, job.alpha.value)?;
    let a0 = find_alpha0(job.degree);
    if job.json {
        print_json(w, &report::nodes_json(&set, &job.alpha, &a0))
    } else {
        report::nodes_text(w, &set, &job.alpha, &a0)?;
        Ok(())
    }
}

fn run_info(job: InfoJob, w: &mut dyn Write) -> Result<()> {
    if job.level > INFO_MAX_LEVEL {
        return Err(crate::error::bad_input(format!(
            "--level {}: radcol info handles levels up to {INFO_MAX_LEVEL}",
            job.level
        ))
        .into());
    }
    let base = job.surface.base_triangle_count() as u64;
    let elements = base * 4u64.pow(job.level);
    // The finest level we are willing to build; h halves with every level beyond.
    let mut measured_level = job.level;
    while measured_level > 0 && base * 4u64.pow(measured_level) > INFO_MAX_BUILT_ELEMENTS {
        measured_level -= 1;
    }
    let mesh = Mesh::new(Arc::clone(&job.surface), measured_level);
    let h = mesh.h() / 2f64.powi((job.level - measured_level) as i32);
    let (lo, hi) = mesh.shape_ratio_range();
    let f = ((job.degree + 1) * (job.degree + 2) / 2) as u64;
    let unknowns = elements * f;
    let n = unknowns as f64;
    let matrix_bytes = 8.0 * n * n;
    let fits = |solver| usize::try_from(unknowns).is_ok_and(|u| check_memory(u, solver).is_ok());
    let convex = job.surface.convex_enclosure;
    let rep = InfoReport {
        scene: job.scene.clone(),
        level: job.level,
        degree: job.degree,
        elements,
        patches: job.surface.patches.len(),
        base_triangles: base as usize,
        h,
        shape_ratio: ShapeRatio { min: lo, max: hi },
        area: mesh.area(),
        measured_level,
        unknowns,
        memory: Memory {
            matrix_bytes,
            lu_extra_bytes: matrix_bytes,
            available_bytes: available_memory(),
            fits_gmres: unknowns < 1_000_000_000 && fits(SolverKind::Gmres),
            fits_lu: unknowns < 1_000_000_000 && fits(SolverKind::Lu),
        },
        convex_enclosure: convex,
        visibility: if convex {
            "visibility not needed: the surface bounds a convex set".into()
        } else {
            "visibility tests needed: parts of the surface may occlude others".into()
        },
    };
    if job.json {
        print_json(w, &serde_json::to_value(&rep)?)
    } else {
        report::info_text(w, &rep)?;
        Ok(())
    }
}
