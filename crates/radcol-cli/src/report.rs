//! Text and JSON reports. Pure formatting: every number comes from core.

use crate::config::{Alpha, Setup};
use radcol_core::alpha0::Alpha0Report;
use radcol_core::nodes::NodeSet;
use radcol_core::run::SolveOutcome;
use radcol_core::study::{fitted_order_above_rounding, StudyRow};
use serde_json::{json, Value};
use std::io::{self, Write};

/// `1.234e-5`: errors, residuals, counts per second.
fn sci(v: f64) -> String {
    format!("{v:.3e}")
}

/// Seconds with a sensible number of digits.
fn secs(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.1} s")
    } else if v >= 0.01 {
        format!("{v:.3} s")
    } else {
        format!("{:.3} ms", v * 1e3)
    }
}

fn alpha_text(a: &Alpha, degree: usize) -> String {
    match (a.auto, degree) {
        (_, 0) => "α unused (r = 0: the centroid node)".into(),
        (true, _) => format!("α = {} (auto)", a.value),
        (false, _) => format!("α = {}", a.value),
    }
}

/// A file `radcol solve` wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Written {
    /// Where.
    pub path: String,
    /// What it holds, one phrase ("38 node rows", "640×480 image").
    pub what: String,
    /// Seconds spent making and writing it.
    pub seconds: f64,
}

/// `radcol solve`, text.
pub fn solve_text(
    w: &mut dyn Write,
    s: &Setup,
    out: &SolveOutcome,
    written: &[Written],
) -> io::Result<()> {
    let disc = &out.discretization;
    let mesh = disc.mesh();
    let (sr_lo, sr_hi) = mesh.shape_ratio_range();
    let t = &out.timings;
    let p = &out.plan;
    writeln!(
        w,
        "radcol solve: {}, r = {}, {}, level {}{}",
        s.scene,
        s.cfg.degree,
        alpha_text(&s.alpha, s.cfg.degree),
        s.cfg.level,
        s.cfg
            .max_edge
            .map(|h| format!(", max edge {h:.6}"))
            .unwrap_or_default()
    )?;
    writeln!(
        w,
        "  mesh        {} elements, {} unknowns, h = {:.6}, shape ratio {:.4} .. {:.4}",
        mesh.len(),
        disc.len(),
        out.h,
        sr_lo,
        sr_hi
    )?;
    writeln!(
        w,
        "  problem     ρ = {}, E = {}, exact u = {}",
        s.rho,
        s.emission,
        s.exact.as_deref().unwrap_or("unknown")
    )?;
    if let Some(scene) = s.loaded.scene() {
        let emitters: Vec<&str> = scene
            .materials
            .iter()
            .filter(|m| m.is_emitter())
            .map(|m| m.name.as_str())
            .collect();
        writeln!(
            w,
            "  scene       {} triangles, {} materials, emitting: {}",
            scene.triangle_count(),
            scene.materials.len(),
            if emitters.is_empty() {
                "none (the solution is 0)".to_string()
            } else {
                emitters.join(", ")
            }
        )?;
    }
    writeln!(w, "  visibility  {}", out.visibility.reason)?;
    writeln!(
        w,
        "  backend     {} ({}, {})",
        out.backend.kind, out.backend.device, out.backend.precision
    )?;
    let rate = if t.assembly_s > 0.0 {
        format!("{}/s", sci(out.kernel_evals as f64 / t.assembly_s))
    } else {
        "-".into()
    };
    writeln!(
        w,
        "  assembly    pairs: {} far, {} near, {} self, {} culled{}; {} kernel evaluations ({rate}){}",
        p.pairs_far,
        p.pairs_near,
        p.pairs_self,
        p.pairs_culled,
        if out.visibility.needed {
            format!(
                ", {} partly visible ({})",
                p.pairs_partial,
                match s.cfg.quad.visibility {
                    radcol_core::assembly::VisibilityMode::Clip => "clipped",
                    radcol_core::assembly::VisibilityMode::Rays => "rays per quadrature point",
                }
            )
        } else {
            String::new()
        },
        out.kernel_evals,
        out.device_seconds
            .map(|d| format!(", device {}", secs(d)))
            .unwrap_or_default()
    )?;
    writeln!(
        w,
        "  timings     mesh {}, rhs {}, assembly {}, solve {}, errors {}, total {}",
        secs(t.mesh_s),
        secs(t.rhs_s),
        secs(t.assembly_s),
        secs(t.solve_s),
        secs(t.errors_s),
        secs(t.total_s)
    )?;
    for ch in &out.channels {
        writeln!(
            w,
            "  channel {:<4}{}: {} iteration{}, relative residual {}",
            ch.name,
            match ch.solver.kind {
                radcol_core::run::SolverKind::Gmres => "gmres",
                radcol_core::run::SolverKind::Lu => "lu",
            },
            ch.solver.iterations,
            if ch.solver.iterations == 1 { "" } else { "s" },
            sci(ch.solver.residual)
        )?;
        writeln!(
            w,
            "              ∫u = {:.12}, ∫E = {:.12}",
            ch.integral_u, ch.integral_e
        )?;
        match &ch.errors {
            Some(e) => writeln!(
                w,
                "              errors: nodes max {}, global max {}, L2 {}",
                sci(e.nodes_max),
                sci(e.global_max),
                sci(e.l2)
            )?,
            None => writeln!(
                w,
                "              errors: - (give --exact EXPR to measure them)"
            )?,
        }
    }
    for f in written {
        writeln!(w, "  wrote {} to {} ({})", f.what, f.path, secs(f.seconds))?;
    }
    Ok(())
}

/// `radcol solve`, JSON.
pub fn solve_json(s: &Setup, out: &SolveOutcome, written: &[Written]) -> Value {
    let disc = &out.discretization;
    let (sr_lo, sr_hi) = disc.mesh().shape_ratio_range();
    let p = &out.plan;
    let t = &out.timings;
    let channels: Vec<Value> = out
        .channels
        .iter()
        .map(|c| {
            json!({
                "name": c.name,
                "solver": c.solver,
                "integral_u": c.integral_u,
                "integral_e": c.integral_e,
                "errors": c.errors,
            })
        })
        .collect();
    json!({
        "command": "solve",
        "scene": s.scene,
        "degree": s.cfg.degree,
        "alpha": s.alpha.value,
        "alpha_auto": s.alpha.auto,
        "level": s.cfg.level,
        "max_edge": s.cfg.max_edge,
        "elements": disc.mesh().len(),
        "unknowns": disc.len(),
        "h": out.h,
        "shape_ratio": { "min": sr_lo, "max": sr_hi },
        "problem": { "rho": s.rho, "emission": s.emission, "exact": s.exact },
        "settings": {
            "gmres_rel_tol": s.cfg.gmres.rel_tol,
            "gmres_restart": s.cfg.gmres.restart,
            "gmres_max_iters": s.cfg.gmres.max_iters,
            "quad_tol": s.cfg.quad.tol,
            "visibility": s.cfg.quad.visibility,
        },
        "backend": out.backend,
        "solver": out.channels.first().map(|c| &c.solver),
        "timings": t,
        "assembly": {
            "kernel_evals": out.kernel_evals,
            "kernel_evals_per_s": if t.assembly_s > 0.0 { Some(out.kernel_evals as f64 / t.assembly_s) } else { None },
            "pairs_far": p.pairs_far,
            "pairs_near": p.pairs_near,
            "pairs_self": p.pairs_self,
            "pairs_culled": p.pairs_culled,
            "pairs_partial": p.pairs_partial,
            "far_kernel_evals": p.far_kernel_evals,
            "device_s": out.device_seconds,
        },
        "visibility": out.visibility,
        "materials": s.loaded.scene().map(|sc| sc.materials.iter().map(|m| json!({
            "name": m.name, "rho": m.rho, "emission": m.emission,
        })).collect::<Vec<_>>()),
        "channels": channels,
        "out": written,
    })
}

/// Fitted orders (least squares over the rows whose error lies above the
/// rounding floor) of the three norms; None with fewer than two such rows.
pub fn fitted(rows: &[StudyRow]) -> [(&'static str, Option<f64>); 3] {
    let fit = |f: fn(&StudyRow) -> f64| fitted_order_above_rounding(rows, f);
    [
        ("nodes_max", fit(|r| r.nodes_max)),
        ("global_max", fit(|r| r.global_max)),
        ("l2", fit(|r| r.l2)),
    ]
}

/// What the theory predicts for degree r at α: (global and L² order, node
/// order if predicted, one sentence).
pub fn theory(r: usize, alpha: f64, a0: &Alpha0Report) -> (usize, Option<usize>, String) {
    let global = r + 1;
    if r.is_multiple_of(2) {
        return (
            global,
            Some(r + 2),
            format!(
                "theory for r = {r}: global max and L2 O(h^{global}) (eq. 23); nodes O(h^{}) (even r, any α: eq. 39)",
                r + 2
            ),
        );
    }
    match a0.alpha0 {
        Some(a) if (a - alpha).abs() <= 1e-12 => (
            global,
            Some(r + 3),
            format!(
                "theory for r = {r}: global max and L2 O(h^{global}) (eq. 23); nodes O(h^{} log h) (odd r at α = α0: eq. 36)",
                r + 3
            ),
        ),
        Some(a) => (
            global,
            None,
            format!(
                "theory for r = {r}: global max and L2 O(h^{global}) (eq. 23); nodes O(h^{} log h) only at α0 = {a} (this run uses α = {alpha})",
                r + 3
            ),
        ),
        None => (
            global,
            None,
            format!(
                "theory for r = {r}: global max and L2 O(h^{global}) (eq. 23); nodes O(h^{} log h) needs α0, which does not exist for r = {r} (see `radcol nodes --degree {r}`)",
                r + 3
            ),
        ),
    }
}

/// Column header of the study table.
pub fn study_header(
    w: &mut dyn Write,
    s: &Setup,
    levels: (u32, u32),
    backend: &str,
) -> io::Result<()> {
    writeln!(
        w,
        "radcol study: {}, r = {}, {}, ρ = {}, u = {}, E = {}, levels {}..={}, backend {}",
        s.scene,
        s.cfg.degree,
        alpha_text(&s.alpha, s.cfg.degree),
        s.rho,
        s.exact.as_deref().unwrap_or("-"),
        s.emission,
        levels.0,
        levels.1,
        backend
    )?;
    writeln!(
        w,
        "{:>5} {:>9} {:>9} {:>10} {:>10} {:>10} {:>10} {:>9} {:>10} {:>7} {:>11} {:>10}",
        "level",
        "elements",
        "unknowns",
        "h",
        "nodes_max",
        "global_max",
        "l2",
        "eoc_nodes",
        "eoc_global",
        "eoc_l2",
        "assembly_s",
        "solve_s"
    )
}

/// One row of the study table.
pub fn study_row(w: &mut dyn Write, r: &StudyRow) -> io::Result<()> {
    let eoc = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_else(|| "-".into());
    writeln!(
        w,
        "{:>5} {:>9} {:>9} {:>10.6} {:>10.3e} {:>10.3e} {:>10.3e} {:>9} {:>10} {:>7} {:>11.4} {:>10.4}",
        r.level,
        r.elements,
        r.unknowns,
        r.h,
        r.nodes_max,
        r.global_max,
        r.l2,
        eoc(r.eoc_nodes),
        eoc(r.eoc_global),
        eoc(r.eoc_l2),
        r.assembly_s,
        r.solve_s
    )
}

/// Fitted orders and the theory, after the table.
pub fn study_footer(w: &mut dyn Write, rows: &[StudyRow], theory_text: &str) -> io::Result<()> {
    let parts: Vec<String> = fitted(rows)
        .iter()
        .map(|(name, v)| {
            format!(
                "{name} {}",
                v.map(|x| format!("{x:.3}")).unwrap_or_else(|| "-".into())
            )
        })
        .collect();
    writeln!(
        w,
        "fitted orders (least squares over the levels above rounding, 1000 ε max|u_n|): {}",
        parts.join(", ")
    )?;
    writeln!(w, "{theory_text}")
}

/// `radcol study`, JSON.
pub fn study_json(
    s: &Setup,
    levels: (u32, u32),
    backend: &Value,
    rows: &[StudyRow],
    theory: (usize, Option<usize>, String),
    plot: Option<&str>,
) -> Value {
    let fitted: serde_json::Map<String, Value> = fitted(rows)
        .into_iter()
        .map(|(k, v)| (k.to_string(), json!(v)))
        .collect();
    json!({
        "command": "study",
        "scene": s.scene,
        "degree": s.cfg.degree,
        "alpha": s.alpha.value,
        "alpha_auto": s.alpha.auto,
        "levels": [levels.0, levels.1],
        "problem": { "rho": s.rho, "emission": s.emission, "exact": s.exact },
        "solver": s.cfg.solver,
        "backend": backend,
        "rows": rows,
        "fitted": fitted,
        "theory": {
            "global_max": theory.0,
            "l2": theory.0,
            "nodes_max": theory.1,
            "note": theory.2,
        },
        "plot": plot,
    })
}

/// `radcol nodes`, text.
pub fn nodes_text(
    w: &mut dyn Write,
    set: &NodeSet,
    alpha: &Alpha,
    a0: &Alpha0Report,
) -> io::Result<()> {
    let r = set.degree();
    writeln!(
        w,
        "radcol nodes: r = {r}, {}, {} nodes on the unit triangle",
        alpha_text(alpha, r),
        set.len()
    )?;
    writeln!(
        w,
        "{:>3} {:>3} {:>22} {:>22} {:>22}",
        "i", "j", "s", "t", "weight"
    )?;
    for ((&(i, j), &[s, t]), &wt) in set.indices().iter().zip(set.points()).zip(set.weights()) {
        writeln!(w, "{i:>3} {j:>3} {s:>22.17} {t:>22.17} {wt:>22.17}")?;
    }
    let sum: f64 = set.weights().iter().sum();
    writeln!(
        w,
        "sum of weights {sum:.17} (area of the unit triangle: 0.5)"
    )?;
    writeln!(w, "degree of precision {}", set.precision())?;
    match a0.alpha0 {
        Some(a) => writeln!(w, "alpha0 = {a:.17}")?,
        None => writeln!(
            w,
            "alpha0: none (best α = {:.17}, relative defect {:.3e})",
            a0.best_alpha, a0.best_defect
        )?,
    }
    writeln!(w, "  {}", a0.reason)
}

/// `radcol nodes`, JSON.
pub fn nodes_json(set: &NodeSet, alpha: &Alpha, a0: &Alpha0Report) -> Value {
    let nodes: Vec<Value> = set
        .indices()
        .iter()
        .zip(set.points())
        .zip(set.weights())
        .map(|((&(i, j), &[s, t]), &weight)| json!({ "i": i, "j": j, "s": s, "t": t, "weight": weight }))
        .collect();
    json!({
        "command": "nodes",
        "degree": set.degree(),
        "alpha": alpha.value,
        "alpha_auto": alpha.auto,
        "nodes": nodes,
        "weight_sum": set.weights().iter().sum::<f64>(),
        "precision": set.precision(),
        "alpha0": a0.alpha0,
        "alpha0_reason": a0.reason,
        "best_alpha": a0.best_alpha,
        "best_defect": a0.best_defect,
        "precision_at_best": a0.precision_at_best,
        "rejected_roots": a0.rejected_roots,
    })
}

/// Everything `radcol info` reports.
#[derive(Debug, serde::Serialize)]
pub struct InfoReport {
    /// Scene name.
    pub scene: String,
    /// Refinement level asked for.
    pub level: u32,
    /// Maximum edge length after the uniform level, when asked for.
    pub max_edge: Option<f64>,
    /// Degree asked for.
    pub degree: usize,
    /// Elements at `level`.
    pub elements: u64,
    /// Patches.
    pub patches: usize,
    /// Base triangles (level 0 elements).
    pub base_triangles: usize,
    /// Mesh size h at `level` (largest parameter-space diameter, eq. 11).
    pub h: f64,
    /// Longest edge of the mapped straight elements: min, mean, max.
    pub element_size: ElementSize,
    /// Shape ratio (min, max), measured at `measured_level`.
    pub shape_ratio: ShapeRatio,
    /// Surface area, measured at `measured_level`.
    pub area: f64,
    /// Axis-aligned bounding box of the base triangles' vertices.
    pub bounding_box: BoundingBox,
    /// The level whose mesh was built (below `level` when that mesh is too big to build).
    pub measured_level: u32,
    /// Unknowns N at `degree` and `level`.
    pub unknowns: u64,
    /// Memory of the dense matrices.
    pub memory: Memory,
    /// Whether visibility tests are needed, and why.
    pub visibility: radcol_core::visibility::VisibilityAnalysis,
    /// Triangles, materials and emitters of a scene with materials.
    pub contents: Option<SceneInfo>,
    /// Assembly time and work, measured on a sample (None for large meshes).
    pub estimate: Option<Estimate>,
}

/// Element sizes (longest edge).
#[derive(Debug, serde::Serialize)]
pub struct ElementSize {
    /// Smallest.
    pub min: f64,
    /// Mean.
    pub mean: f64,
    /// Largest.
    pub max: f64,
}

/// Bounding box.
#[derive(Debug, serde::Serialize)]
pub struct BoundingBox {
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
}

/// What a scene with materials holds.
#[derive(Debug, serde::Serialize)]
pub struct SceneInfo {
    /// File read, for OBJ scenes.
    pub source: Option<String>,
    /// Triangles after repairs.
    pub triangles: usize,
    /// Distinct vertex positions.
    pub vertices: usize,
    /// The materials.
    pub materials: Vec<MaterialInfo>,
    /// Patches (group/material) that emit.
    pub emitters: Vec<String>,
    /// Repairs and suspicious input.
    pub warnings: Vec<String>,
}

/// One material.
#[derive(Debug, serde::Serialize)]
pub struct MaterialInfo {
    /// Name.
    pub name: String,
    /// Kd.
    pub rho: [f64; 3],
    /// Ke.
    pub emission: [f64; 3],
    /// Triangles using it.
    pub triangles: usize,
    /// Their area.
    pub area: f64,
}

/// Assembly estimate from timed row blocks.
#[derive(Debug, serde::Serialize)]
pub struct Estimate {
    /// Seconds to plan (classify pairs, clip tests).
    pub plan_s: f64,
    /// Estimated assembly seconds on the CPU backend (plan included).
    pub assembly_s: f64,
    /// Row blocks timed.
    pub sampled_blocks: usize,
    /// Threads assumed.
    pub threads: usize,
    /// Far pairs.
    pub pairs_far: u64,
    /// Near pairs.
    pub pairs_near: u64,
    /// Partly visible pairs.
    pub pairs_partial: u64,
    /// Culled pairs.
    pub pairs_culled: u64,
    /// 2 N² per GMRES iteration and channel.
    pub gmres_flops_per_iteration: f64,
    /// 2 N³ / 3 for one LU factorisation.
    pub lu_flops: f64,
}

/// Shape ratio range.
#[derive(Debug, serde::Serialize)]
pub struct ShapeRatio {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// Dense-matrix memory estimate.
#[derive(Debug, serde::Serialize)]
pub struct Memory {
    /// 8 N² bytes of the geometric matrix.
    pub matrix_bytes: f64,
    /// Extra bytes of an LU copy (--solver lu).
    pub lu_extra_bytes: f64,
    /// Available memory (MemAvailable), when known.
    pub available_bytes: Option<u64>,
    /// The matrix fits (GMRES), as core's check decides.
    pub fits_gmres: bool,
    /// Matrix and LU copy fit.
    pub fits_lu: bool,
}

fn gib(bytes: f64) -> String {
    let g = bytes / 1073741824.0;
    if g < 1e6 {
        format!("{g:.3} GiB")
    } else {
        format!("{g:.3e} GiB")
    }
}

/// `radcol info`, text.
pub fn info_text(w: &mut dyn Write, i: &InfoReport) -> io::Result<()> {
    writeln!(
        w,
        "radcol info: {}, level {}{}, r = {}",
        i.scene,
        i.level,
        i.max_edge
            .map(|h| format!(", max edge {h:.6}"))
            .unwrap_or_default(),
        i.degree
    )?;
    writeln!(w, "  elements        {}", i.elements)?;
    writeln!(w, "  patches         {}", i.patches)?;
    writeln!(w, "  base triangles  {}", i.base_triangles)?;
    writeln!(w, "  h               {:.6}", i.h)?;
    writeln!(
        w,
        "  element size    longest edge {:.6} min, {:.6} mean, {:.6} max",
        i.element_size.min, i.element_size.mean, i.element_size.max
    )?;
    let at = if i.measured_level != i.level {
        format!(
            " (measured at level {}: the level-{} mesh is too big to build here)",
            i.measured_level, i.level
        )
    } else {
        String::new()
    };
    writeln!(
        w,
        "  shape ratio     {:.4} .. {:.4}{at}",
        i.shape_ratio.min, i.shape_ratio.max
    )?;
    writeln!(w, "  area            {:.12}{at}", i.area)?;
    writeln!(w, "  unknowns        {} at r = {}", i.unknowns, i.degree)?;
    let avail = i
        .memory
        .available_bytes
        .map(|b| gib(b as f64))
        .unwrap_or_else(|| "unknown".into());
    let yes = |b: bool| if b { "fits" } else { "does NOT fit" };
    writeln!(
        w,
        "  dense matrix    {} ({}); with --solver lu {} ({}); available {avail}",
        gib(i.memory.matrix_bytes),
        yes(i.memory.fits_gmres),
        gib(i.memory.matrix_bytes + i.memory.lu_extra_bytes),
        yes(i.memory.fits_lu)
    )?;
    writeln!(w, "  visibility      {}", i.visibility.reason)?;
    writeln!(
        w,
        "  bounding box    ({:.6}, {:.6}, {:.6}) .. ({:.6}, {:.6}, {:.6})",
        i.bounding_box.min[0],
        i.bounding_box.min[1],
        i.bounding_box.min[2],
        i.bounding_box.max[0],
        i.bounding_box.max[1],
        i.bounding_box.max[2]
    )?;
    if let Some(sc) = &i.contents {
        writeln!(
            w,
            "  scene           {} triangles, {} vertices{}",
            sc.triangles,
            sc.vertices,
            sc.source
                .as_ref()
                .map(|s| format!(", from {s}"))
                .unwrap_or_default()
        )?;
        for m in &sc.materials {
            writeln!(
                w,
                "  material        {:<12} ρ = ({:.4}, {:.4}, {:.4}), E = ({:.4}, {:.4}, {:.4}), {} triangles, area {:.6}",
                m.name,
                m.rho[0],
                m.rho[1],
                m.rho[2],
                m.emission[0],
                m.emission[1],
                m.emission[2],
                m.triangles,
                m.area
            )?;
        }
        writeln!(
            w,
            "  emitters        {}",
            if sc.emitters.is_empty() {
                "none: every solution is 0".to_string()
            } else {
                sc.emitters.join(", ")
            }
        )?;
        writeln!(w, "  warnings        {}", sc.warnings.len())?;
    }
    match &i.estimate {
        Some(e) => {
            writeln!(
                w,
                "  pairs           {} far, {} near, {} partly visible, {} culled",
                e.pairs_far, e.pairs_near, e.pairs_partial, e.pairs_culled
            )?;
            writeln!(
                w,
                "  time estimate   assembly ≈ {} on {} CPU threads (plan {}, {} row blocks timed); \
                 solve: {:.3e} flops per GMRES iteration and channel, {:.3e} for an LU factorisation",
                secs(e.assembly_s),
                e.threads,
                secs(e.plan_s),
                e.sampled_blocks,
                e.gmres_flops_per_iteration,
                e.lu_flops
            )
        }
        None => writeln!(
            w,
            "  time estimate   - (more elements than radcol info plans; try a lower --level)"
        ),
    }
}
