//! Executing a validated [`Config`]: call core, then report.

use crate::config::{Config, InfoJob, NodesJob, SolveJob, StudyJob};
use crate::report::{
    self, BoundingBox, ElementSize, Estimate, InfoReport, MaterialInfo, Memory, SceneInfo,
    ShapeRatio,
};
use crate::{output, plot, progress};
use anyhow::{Context, Result};
use radcol_core::alpha0::{auto_alpha, find_alpha0};
use radcol_core::assembly::{AssemblyPlan, FillMode, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::run::{available_memory, check_memory, solve, SolverKind};
use radcol_core::study::study;
use radcol_core::visibility;
use std::io::{self, Write};
use std::sync::Arc;
use std::time::Instant;

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

fn run_solve(mut job: SolveJob, w: &mut dyn Write) -> Result<()> {
    let bar = progress::Bar::for_stderr();
    job.setup.cfg.progress = bar.as_ref().map(|b| b.handle());
    let s = &job.setup;
    let out = solve(&s.problem, &s.cfg, s.backend.imp.as_ref())?;
    let written = output::write_all(&job.outputs, &job.look, &out, bar.as_ref())?;
    if let Some(b) = bar {
        b.finish();
    }
    if s.json {
        print_json(w, &report::solve_json(s, &out, &written))
    } else {
        report::solve_text(w, s, &out, &written)?;
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
    let elements = match job.max_edge {
        Some(h) => Mesh::count_with_max_edge(job.surface.clone(), job.level, h),
        None => base * 4u64.pow(job.level),
    };
    // The finest level we are willing to build; h halves with every level beyond.
    let build = |level: u32| match job.max_edge {
        Some(h) => Mesh::with_max_edge(Arc::clone(&job.surface), level, h),
        None => Mesh::new(Arc::clone(&job.surface), level),
    };
    let mut measured_level = job.level;
    let mesh = Arc::new(if elements <= INFO_MAX_BUILT_ELEMENTS {
        build(job.level)
    } else {
        while measured_level > 0 && base * 4u64.pow(measured_level) > INFO_MAX_BUILT_ELEMENTS {
            measured_level -= 1;
        }
        Mesh::new(Arc::clone(&job.surface), measured_level)
    });
    let shrink = 2f64.powi((job.level - measured_level) as i32);
    let sizes: Vec<f64> = (0..mesh.len())
        .map(|k| {
            let [a, b, c] = mesh.vertices(k);
            (b - a).length().max((c - b).length()).max((a - c).length())
        })
        .collect();
    let (lo, hi) = mesh.shape_ratio_range();
    let f = ((job.degree + 1) * (job.degree + 2) / 2) as u64;
    let unknowns = elements * f;
    let n = unknowns as f64;
    let matrix_bytes = 8.0 * n * n;
    let fits = |solver| usize::try_from(unknowns).is_ok_and(|u| check_memory(u, solver).is_ok());
    let vis = visibility::analyze(&job.surface);
    let bbox = job.surface.bounding_box();
    let contents = job.loaded.scene().map(|sc| {
        let areas = sc.patch_areas();
        let materials = sc
            .materials
            .iter()
            .enumerate()
            .map(|(m, mat)| {
                let patches: Vec<usize> = (0..sc.surface.patches.len())
                    .filter(|&j| sc.patch_material[j] == m)
                    .collect();
                MaterialInfo {
                    name: mat.name.clone(),
                    rho: mat.rho,
                    emission: mat.emission,
                    triangles: patches
                        .iter()
                        .map(|&j| sc.surface.patches[j].triangles.len())
                        .sum(),
                    area: patches.iter().map(|&j| areas[j]).sum(),
                }
            })
            .collect();
        SceneInfo {
            source: sc.source.as_ref().map(|p| p.display().to_string()),
            triangles: sc.triangle_count(),
            vertices: sc.vertex_count(),
            materials,
            emitters: sc
                .emitters()
                .into_iter()
                .map(|j| sc.surface.patches[j].name.clone())
                .collect(),
            warnings: sc.warnings.clone(),
        }
    });
    // Planned on the mesh just built, which is the job's when it is small enough.
    let estimate = (elements <= INFO_MAX_PLANNED_ELEMENTS && measured_level == job.level)
        .then(|| estimate_assembly(&job, &mesh))
        .flatten();
    let rep = InfoReport {
        scene: job.scene.clone(),
        level: job.level,
        max_edge: job.max_edge,
        degree: job.degree,
        elements,
        patches: job.surface.patches.len(),
        base_triangles: base as usize,
        h: mesh.h() / shrink,
        element_size: ElementSize {
            min: sizes.iter().copied().fold(f64::INFINITY, f64::min) / shrink,
            mean: sizes.iter().sum::<f64>() / sizes.len().max(1) as f64 / shrink,
            max: sizes.iter().copied().fold(0.0, f64::max) / shrink,
        },
        shape_ratio: ShapeRatio { min: lo, max: hi },
        area: mesh.area(),
        bounding_box: BoundingBox {
            min: bbox.0.to_array(),
            max: bbox.1.to_array(),
        },
        measured_level,
        unknowns,
        memory: Memory {
            matrix_bytes,
            lu_extra_bytes: matrix_bytes,
            available_bytes: available_memory(),
            fits_gmres: unknowns < 1_000_000_000 && fits(SolverKind::Gmres),
            fits_lu: unknowns < 1_000_000_000 && fits(SolverKind::Lu),
        },
        visibility: vis,
        contents,
        estimate,
    };
    if job.json {
        print_json(w, &serde_json::to_value(&rep)?)
    } else {
        report::info_text(w, &rep)?;
        Ok(())
    }
}

/// Row blocks timed by `radcol info` to estimate the assembly time.
const INFO_SAMPLE_BLOCKS: usize = 24;
/// Largest mesh whose assembly `radcol info` plans (the plan holds n² classes).
const INFO_MAX_PLANNED_ELEMENTS: u64 = 6000;

/// Plans the assembly on `mesh` (the job's) and times a few row blocks spread
/// over it on this machine's CPU, extrapolating to all blocks on all threads.
fn estimate_assembly(job: &InfoJob, mesh: &Arc<Mesh>) -> Option<Estimate> {
    let nodes = NodeSet::new(job.degree, auto_alpha(job.degree)).ok()?;
    let disc = Arc::new(Discretization::new(Arc::clone(mesh), nodes));
    let t = Instant::now();
    let plan = AssemblyPlan::new(disc.clone(), QuadratureOptions::default());
    let plan_s = t.elapsed().as_secs_f64();
    let n = disc.mesh().len();
    let f = disc.nodes_per_element();
    let samples = n.min(INFO_SAMPLE_BLOCKS);
    let mut block = vec![0.0; f * disc.len()];
    let t = Instant::now();
    for i in 0..samples {
        plan.fill_block(i * n / samples, &mut block, FillMode::All);
    }
    let per_block = t.elapsed().as_secs_f64() / samples.max(1) as f64;
    let threads = rayon::current_num_threads();
    let stats = plan.stats();
    let nn = disc.len() as f64;
    Some(Estimate {
        plan_s,
        assembly_s: plan_s + per_block * n as f64 / threads as f64,
        sampled_blocks: samples,
        threads,
        pairs_far: stats.pairs_far,
        pairs_near: stats.pairs_near,
        pairs_partial: stats.pairs_partial,
        pairs_culled: stats.pairs_culled,
        gmres_flops_per_iteration: 2.0 * nn * nn,
        lu_flops: 2.0 / 3.0 * nn * nn * nn,
    })
}
