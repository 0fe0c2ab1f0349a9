//! What the pipeline checks and evaluates before it solves: sizes, scene
//! extent and quadrature tolerance before anything is built, then ρ, E and
//! the exact solution at the nodes.

use super::operator::decide_now;
use super::size::mesh_size;
use super::SolveConfig;
use crate::assembly::MIN_QUAD_TOL;
use crate::discretization::Discretization;
use crate::error::{Error, FieldKind, FieldName, InputError};
use crate::mesh::grading::{Grading, GRADE_RANGE};
use crate::mesh::Mesh;
use crate::nodes::NodeSet;
use crate::problem::{Field, Problem};
use crate::visibility::VisibilityAnalysis;
use rayon::prelude::*;
use std::sync::Arc;

/// Checks, before anything is built, that the mesh `cfg` asks for on
/// `problem`'s surface is valid and its operator (dense or compressed:
/// [`super::operator::decide`]) can fit in memory (when
/// `cfg.check_memory`); returns its unknowns.
pub fn check_size(problem: &Problem, cfg: &SolveConfig) -> Result<u64, InputError> {
    if let Some(h) = cfg.max_edge {
        if !(h.is_finite() && h > 0.0) {
            return Err(InputError::MaxEdge { value: h });
        }
    }
    if let Some(grade) = &cfg.grade {
        let q = grade.exponent;
        if !GRADE_RANGE.contains(&q) {
            return Err(InputError::Grade {
                value: q,
                range: GRADE_RANGE,
            });
        }
        if let Some(d) = grade.zone {
            if !(d.is_finite() && d > 0.0) {
                return Err(InputError::GradeZone { value: d });
            }
        }
    }
    let size = mesh_size(
        &problem.surface,
        cfg.level,
        cfg.max_edge,
        cfg.grade.as_ref(),
        cfg.degree,
    );
    decide_now(cfg, size.unknowns, size.elements)?;
    Ok(size.unknowns)
}

/// Builds the mesh and collocation points for `cfg`, refusing sizes that do
/// not fit in memory ([`check_size`]) before building anything.
pub fn discretize(problem: &Problem, cfg: &SolveConfig) -> Result<Arc<Discretization>, Error> {
    check_quadrature(cfg)?;
    check_extent(&problem.surface)?;
    let nodes = NodeSet::new(cfg.degree, cfg.alpha)?;
    check_size(problem, cfg)?;
    let surface = &problem.surface;
    let mesh = Arc::new(match (&cfg.grade, cfg.max_edge) {
        (Some(grade), h) => {
            let grading = Grading::towards_concave_lines(surface, grade);
            Mesh::graded(surface.clone(), cfg.level, h, &grading)
        }
        (None, Some(h)) => Mesh::with_max_edge(surface.clone(), cfg.level, h),
        (None, None) => Mesh::new(surface.clone(), cfg.level),
    });
    Ok(Arc::new(Discretization::new(mesh, nodes)))
}

/// Scenes between this many units across and its inverse are solved. The
/// kernel divides by |x − y|⁴, which overflows f64 from |x − y| ≈ 1e77 and
/// underflows below 1e-77; 1e50 leaves 27 decades for elements far smaller
/// than the scene (box rooms from 1e-60 to 1e60 across give ∫u / L² equal to
/// 13 digits; at 1e100 the matrix was zero and u = E without a word).
pub const MAX_EXTENT: f64 = 1e50;
/// The smallest scene solved, 1 / [`MAX_EXTENT`].
pub const MIN_EXTENT: f64 = 1e-50;

/// Refuses scenes whose bounding-box diagonal lies outside
/// [[`MIN_EXTENT`], [`MAX_EXTENT`]] (or is not finite).
fn check_extent(surface: &crate::geometry::Surface) -> Result<(), InputError> {
    let (lo, hi) = surface.bounding_box();
    let d = hi - lo;
    // The diagonal without squaring tiny or huge components.
    let m = d.abs().max_element();
    let extent = if m > 0.0 && m.is_finite() {
        m * (d / m).length()
    } else {
        m
    };
    if !(MIN_EXTENT..=MAX_EXTENT).contains(&extent) {
        return Err(InputError::SceneExtent {
            extent,
            min: MIN_EXTENT,
            max: MAX_EXTENT,
        });
    }
    Ok(())
}

/// The surface's visibility analysis ([`crate::visibility::analyze`]),
/// refused when radcol cannot model it; with a visibility budget, the
/// patches whose pairs may be approximated: those where no channel emits.
pub(crate) fn visibility_of(
    problem: &Problem,
    cfg: &SolveConfig,
) -> Result<VisibilityAnalysis, InputError> {
    let analysis = crate::visibility::analyze(&problem.surface);
    analysis.check_supported()?;
    let budget = cfg.quad.visibility_budget;
    if !(0.0..1.0).contains(&budget) {
        return Err(InputError::VisibilityBudget { value: budget });
    }
    if budget == 0.0 {
        return Ok(analysis);
    }
    let patches = problem.surface.patches.len();
    let dark = |j: usize| {
        problem.channels.iter().all(|c| match &c.emission {
            Field::Constant(e) => *e == 0.0,
            Field::PerPatch(v) => v[j] == 0.0,
            Field::Expr(_) | Field::Custom(_) => false,
        })
    };
    Ok(analysis.with_bounce_patches((0..patches).map(dark).collect()))
}

/// Refuses a quadrature tolerance outside [MIN_QUAD_TOL, 1).
pub(crate) fn check_quadrature(cfg: &SolveConfig) -> Result<(), InputError> {
    let tol = cfg.quad.tol;
    if !(MIN_QUAD_TOL..1.0).contains(&tol) {
        return Err(InputError::QuadratureTolerance {
            value: tol,
            min: MIN_QUAD_TOL,
        });
    }
    Ok(())
}

/// Evaluates `field` at every collocation point, rejecting non-finite values.
fn eval_at_nodes(
    disc: &Discretization,
    field: &Field,
    what: FieldName,
) -> Result<Vec<f64>, InputError> {
    let mesh = disc.mesh();
    let values: Vec<f64> = disc
        .points()
        .par_iter()
        .map(|p| field.eval(&mesh.site(p.element, p.st[0], p.st[1])))
        .collect();
    if let Some((i, &v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        let p = disc.points()[i];
        return Err(InputError::InvalidValue {
            what,
            value: v,
            element: p.element,
            node: p.node,
            position: p.position,
        });
    }
    Ok(values)
}

/// ρ and E of one channel at the nodes.
pub(crate) type NodalFields = (Vec<f64>, Vec<f64>);

/// ρ and E of every channel at the nodes, ρ checked against [0, 1), and the
/// exact solution (when given) checked finite there like E.
pub(crate) fn fields(disc: &Discretization, problem: &Problem) -> Result<Vec<NodalFields>, Error> {
    // Errors against an exact u that is not finite everywhere would be ∞ or
    // NaN; checked first, as a manufactured E would inherit the fault.
    if let Some(exact) = &problem.exact {
        let what = FieldName {
            kind: FieldKind::ExactSolution,
            channel: None,
        };
        eval_at_nodes(disc, exact, what)?;
    }
    let single = problem.channels.len() == 1;
    let mut fields = Vec::new();
    for ch in &problem.channels {
        // "reflectivity" alone for a scalar problem, "reflectivity R" for a colour channel.
        let label = |kind: FieldKind| FieldName {
            kind,
            channel: (!single).then(|| ch.name.clone()),
        };
        let rho = eval_at_nodes(disc, &ch.rho, label(FieldKind::Reflectivity))?;
        if let Some((i, &v)) = rho
            .iter()
            .enumerate()
            .find(|(_, v)| !(0.0..1.0).contains(*v))
        {
            let p = disc.points()[i];
            return Err(InputError::Reflectivity {
                name: label(FieldKind::Reflectivity),
                value: v,
                element: p.element,
                node: p.node,
                position: p.position,
            }
            .into());
        }
        let emission = eval_at_nodes(disc, &ch.emission, label(FieldKind::Emission))?;
        fields.push((rho, emission));
    }
    Ok(fields)
}
