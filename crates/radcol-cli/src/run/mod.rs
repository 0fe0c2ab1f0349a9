//! Layer 3: executing a validated [`Config`]. Each command builds what it
//! needs (scene, α, problem, backend: [`crate::setup`]), calls core, and
//! reports.

mod advice;
mod info;
mod points;
mod relight;

pub use relight::RelitSet;

use crate::error::with_flags;
use crate::report::{
    self, AdaptLine, AdaptReport, ComparisonReport, DegreePart, Fastest, NodesReport, SolveReport,
    StudyFooter, StudyHeader, StudyLine, StudyReport,
};
use crate::scene::SceneSpec;
use crate::setup::{self, check_writable, resolve_alpha};
use crate::validate::{Config, NodesJob, OutputFile, SolveJob, StudyJob};
use crate::{output, plot, progress};
use anyhow::{Context, Result};
use radcol_core::run::{adapt::solve_adaptive, adapt::AdaptOptions, solve, NodeSet};
use radcol_core::study::{
    predicted_orders, speed::adaptive_settings, speed::fastest_per_decade, speed::uniform_settings,
    Study,
};
use std::io::{self, Write};

/// Runs one command, printing its report to stdout.
pub fn run(config: Config) -> Result<()> {
    let stdout = io::stdout();
    let mut w = stdout.lock();
    match config {
        Config::Solve(job) => run_solve(job, &mut w),
        Config::Study(job) => run_study(job, &mut w),
        Config::Nodes(job) => run_nodes(job, &mut w),
        Config::Info(job) => info::run_info(job, &mut w),
        Config::Completions(shell) => {
            use clap::CommandFactory;
            let mut cmd = crate::args::Cli::command();
            clap_complete::generate(shell, &mut cmd, "radcol", &mut w);
            Ok(())
        }
    }?;
    w.flush()?;
    Ok(())
}

/// The outputs of `job` can be written, and none is one of its inputs or
/// another output, before any work.
fn check_files(job: &SolveJob) -> Result<()> {
    for o in &job.outputs {
        check_writable(&o.file)?;
    }
    let at_out = job.at.as_ref().and_then(|a| a.out.as_ref());
    if let Some(file) = at_out {
        check_writable(file)?;
    }
    let mut inputs: Vec<(&str, &std::path::Path)> = Vec::new();
    if let SceneSpec::Obj(p) | SceneSpec::Gltf(p) = &job.problem.scene {
        inputs.push(("the scene", p));
    }
    if let Some(at) = &job.at {
        inputs.push(("the --at points file", &at.source));
    }
    let files: Vec<&OutputFile> = job.outputs.iter().map(|o| &o.file).chain(at_out).collect();
    Ok(setup::check_distinct(&files, &inputs)?)
}

fn run_solve(job: SolveJob, w: &mut dyn Write) -> Result<()> {
    check_files(&job)?;
    let mut s = setup::setup(&job.problem, job.level, job.max_edge, job.adapt.is_some())?;
    if let Some(at) = &job.at {
        points::precheck(at, &s)?;
    }
    let relit = relight::relit_problems(&job.relight, &s)?;
    let mut look = setup::look(&job.look, &s);
    if let Some(resolution) = look.lightmap {
        // Laid out before the solve, so a surface that cannot be (curved,
        // overlapping coordinates) is refused before any work; kept for
        // the bake.
        let atlas = look.atlas(&s.problem.surface, resolution).map_err(|e| {
            let why = e.to_string();
            let why = why.strip_prefix("lightmap: ").unwrap_or(&why).to_string();
            crate::error::bad_input(format!("--lightmap: {why}"))
        })?;
        look.lightmap_atlas = Some(atlas);
    }
    // Under mpirun, every rank solves together; rank 0 alone shows
    // progress, evaluates points, writes and reports.
    s.cfg.ranks = crate::ranks::current();
    let lead = crate::ranks::lead();
    let bar = progress::Bar::for_stderr().filter(|_| lead);
    s.cfg.progress = bar.as_ref().map(|b| b.handle());
    let (out, adaptive) = match &job.adapt {
        None => (
            solve(&s.problem, &s.cfg, s.backend.as_ref()).map_err(|e| advice::sized(e, &s))?,
            None,
        ),
        Some(opts) => {
            // Each step as it ends: above the bar on a terminal, else on
            // stderr (a long run's log shows its progress; JSON has them all).
            let res = solve_adaptive(
                &s.problem,
                &s.cfg,
                opts,
                s.backend.as_ref(),
                |step| match &bar {
                    Some(b) => b.note(&AdaptLine(step).to_string()),
                    None if lead && !s.json && !progress::quiet() => {
                        eprintln!("{}", AdaptLine(step))
                    }
                    None => {}
                },
            )
            .map_err(with_flags)?;
            let default_degree = job.problem.degree_by_default.then_some(job.problem.degree);
            let report = AdaptReport::new(opts, &res, default_degree);
            (res.outcome, Some(report))
        }
    };
    let sets = relight::relight_all(job.relight.iter().cloned().zip(relit).collect(), &s, &out)?;
    if !lead {
        return Ok(());
    }
    let values = match &job.at {
        Some(at) => {
            if let Some(b) = &bar {
                b.spin(format!("values at {} points", at.points.len()));
            }
            Some(points::evaluate(at, &s, &out)?)
        }
        None => None,
    };
    let written = output::write_all(&job.outputs, &look, &out, bar.as_ref())?;
    if let Some(b) = bar {
        b.finish();
    }
    let unmet = adaptive
        .as_ref()
        .filter(|a| !a.reached())
        .map(|a| a.summary());
    let mut report = SolveReport::new(&s, &out, &written);
    report.adaptive = adaptive;
    report.relit = sets;
    report.points = values;
    report::emit(w, &report, s.json)?;
    if let Some(why) = report::untrusted(&s, &out) {
        return Err(anyhow::anyhow!(why));
    }
    match unmet {
        Some(why) if job.strict => Err(anyhow::anyhow!("--strict: {why}")),
        _ => Ok(()),
    }
}

fn run_study(job: StudyJob, w: &mut dyn Write) -> Result<()> {
    if job.degrees.is_some() || job.adaptive.is_some() {
        return run_comparison(job, w);
    }
    if let Some(p) = &job.plot {
        check_writable(p)?;
    }
    let s = setup::setup(&job.problem, Some(*job.levels.start()), None, false)?;
    let (header, rows) = uniform_study(&s, &job.levels, w)?;
    let theory = predicted_orders(s.cfg.degree, s.alpha.value, &s.alpha.a0);
    let plot_path = match &job.plot {
        Some(file) => {
            let mut orders = vec![("global max", theory.global_max), ("L2", theory.l2)];
            orders.extend(theory.nodes_max.map(|p| ("nodes max", p)));
            let svg = plot::study_svg(&rows, &header.title(), &orders);
            Some(write_svg(file, &svg)?)
        }
        None => None,
    };
    let footer = StudyFooter::new(&rows, theory, plot_path);
    if s.json {
        report::emit(w, &StudyReport::new(header, rows, footer), true)
    } else {
        write!(w, "{footer}")?;
        Ok(())
    }
}

/// The uniform study of `s` over `levels`: checked (the finest level must
/// fit) before the first level is solved; in text, the header and each row
/// printed as they come.
fn uniform_study(
    s: &setup::Setup,
    levels: &std::ops::RangeInclusive<u32>,
    w: &mut dyn Write,
) -> Result<(StudyHeader, Vec<radcol_core::study::StudyRow>)> {
    let checked = Study::new(&s.problem, &s.cfg, levels.clone()).map_err(with_flags)?;
    let header = StudyHeader::new(s, (*levels.start(), *levels.end()));
    if !s.json {
        write!(w, "{header}")?;
        w.flush()?;
    }
    // Rows print as they complete; a failed write stops nothing but is reported after.
    let mut write_error: Option<io::Error> = None;
    let rows = checked
        .run(s.backend.as_ref(), |row| {
            if !s.json && write_error.is_none() {
                if let Err(e) = write!(w, "{}", StudyLine(row)).and_then(|_| w.flush()) {
                    write_error = Some(e);
                }
            }
        })
        .map_err(with_flags)?;
    if let Some(e) = write_error {
        return Err(e.into());
    }
    Ok((header, rows))
}

/// `--degrees` and `--adaptive`: per degree (at its auto α with
/// `--degrees`) the uniform study and, when asked, the adaptive run from the
/// first level; then the fastest setting per decade of error.
fn run_comparison(job: StudyJob, w: &mut dyn Write) -> Result<()> {
    if let Some(p) = &job.plot {
        check_writable(p)?;
    }
    let degrees = job
        .degrees
        .clone()
        .unwrap_or(job.problem.degree..=job.problem.degree);
    let mut parts = Vec::new();
    let mut settings = Vec::new();
    let mut scene = String::new();
    for r in degrees {
        let mut spec = job.problem.clone();
        spec.degree = r;
        let s = setup::setup(&spec, Some(*job.levels.start()), None, false)?;
        scene.clone_from(&s.scene);
        let (header, rows) = uniform_study(&s, &job.levels, w)?;
        let theory = predicted_orders(s.cfg.degree, s.alpha.value, &s.alpha.a0);
        let footer = StudyFooter::new(&rows, theory, None);
        if !s.json {
            write!(w, "{footer}")?;
        }
        settings.extend(uniform_settings(r, &rows));
        let adaptive = match job.adaptive {
            Some(target) => {
                // A study compares degrees: each runs at its own.
                let opts = AdaptOptions {
                    target,
                    graded_start: false,
                    ..Default::default()
                };
                let res = solve_adaptive(&s.problem, &s.cfg, &opts, s.backend.as_ref(), |_| {})
                    .map_err(with_flags)?;
                settings.extend(adaptive_settings(r, &res.steps));
                let report = AdaptReport::new(&opts, &res, None);
                if !s.json {
                    write!(w, "{report}")?;
                }
                Some(report)
            }
            None => None,
        };
        parts.push(DegreePart {
            study: StudyReport::new(header, rows, footer),
            adaptive,
        });
        if !job.problem.json {
            writeln!(w)?;
        }
    }
    let plot = match &job.plot {
        Some(file) => {
            let kind = if settings.iter().any(|s| s.estimated) {
                "estimated"
            } else {
                "true"
            };
            let title = format!("{scene}: {kind} error against unknowns and time");
            Some(write_svg(file, &plot::comparison_svg(&settings, &title))?)
        }
        None => None,
    };
    let fastest = Fastest {
        fastest: fastest_per_decade(&settings),
        settings,
    };
    if job.problem.json {
        let report = ComparisonReport {
            command: "study",
            degrees: parts,
            fastest,
            plot,
        };
        report::emit(w, &report, true)
    } else {
        write!(w, "{fastest}")?;
        if let Some(p) = plot {
            writeln!(w, "wrote plot to {p}")?;
        }
        Ok(())
    }
}

/// Writes a `--plot` SVG; returns its path as shown.
fn write_svg(file: &crate::validate::OutputFile, svg: &str) -> Result<String> {
    let mut f = crate::files::create(file)?;
    f.write_all(svg.as_bytes())
        .with_context(|| format!("writing {}", file.path.display()))?;
    f.commit()?;
    Ok(file.path.display().to_string())
}

fn run_nodes(job: NodesJob, w: &mut dyn Write) -> Result<()> {
    let alpha = resolve_alpha(job.alpha, job.degree);
    let set = NodeSet::new(job.degree, alpha.value)?;
    report::emit(w, &NodesReport::new(&set, &alpha), job.json)
}
