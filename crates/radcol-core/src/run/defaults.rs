//! The library's defaults, which are the command's: what `radcol solve`
//! builds when a flag is not given is what [`SolveConfig::recommended`]
//! (and [`crate::scene::Scene::solve_config`]) build here. The command
//! takes every default from this file, [`SolveConfig::default`] and the
//! `Default`s of the settings' own types; it states none of its own.

use super::SolveConfig;
use crate::alpha0::auto_alpha;

/// Degree r of a solve when none is given.
pub const DEFAULT_DEGREE: usize = 1;

/// Degree r of an adaptive solve (one with a target error) when none is
/// given. Measured, adaptive runs to 1e-2, 1e-3 and 1e-4 (docs/accuracy.md,
/// "Which degree with a target"): on the Cornell box r = 2 reached 1e-3
/// with 6 078 unknowns against 6 963 at r = 1 and 7 640 at r = 3, and 1e-4
/// in about 10 minutes, where r = 1 ran out of memory and r = 3 was at
/// 3.3e-4 after 7 (r = 2 then at 3.0e-4); on the shadowed floor r = 2 took
/// 2.2–3.8× fewer unknowns than r = 1 to 1e-3 (square occluder: 4 824
/// against 10 854, 1.28 s against 2.98 s). Uniform refinement keeps
/// [`DEFAULT_DEGREE`].
pub const ADAPTIVE_DEGREE: usize = 2;

/// The degree an element of an adaptive solve's starting mesh starts at,
/// when the loop grades its start ([`crate::run::adapt::AdaptOptions::graded_start`]):
/// the lowest r ≤ `top` with (h/D)^{r+1} ≤ `target`, h the element's
/// longest edge and D the diagonal of the scene's bounding box; `top` when
/// none is. (h/D)^{r+1} is the relative interpolation error at degree r of
/// a function that varies on the scale of the scene, so an element small
/// against the scene needs no high degree for the light that reaches it
/// from afar; where the light varies faster (a shadow's edge, a contact
/// line) the estimate finds it and the loop splits there. A scanned mesh's
/// triangles are elements already: the Stanford bunny's 3 674 in a 550 mm
/// room (h/D about 1e-2) start at r = 0 to a target of 1e-2 and at r = 1
/// to 1e-3, while the room's walls keep `top`.
pub fn start_degree(longest_edge: f64, diagonal: f64, target: f64, top: usize) -> usize {
    let x = longest_edge / diagonal;
    if !(x.is_finite() && x >= 0.0) {
        return top;
    }
    (0..top)
        .find(|&r| x.powi(r as i32 + 1) <= target)
        .unwrap_or(top)
}

/// Uniform refinement level of a solve on a surface (not a scene with
/// materials) when neither a level nor a maximum edge is given.
pub const DEFAULT_LEVEL: u32 = 2;

/// A scene with materials given neither a level nor a maximum edge is
/// refined, from its own triangles, to edges of at most this fraction of
/// its bounding box's diagonal (a scene's triangles are sized for
/// modelling, not for the light).
pub const DEFAULT_EDGE_FRACTION: f64 = 0.1;

/// Refinement level of the reference mesh on which a manufactured emission
/// E = u − K u is computed ([`crate::problem::ReferenceOperator`]).
pub const REFERENCE_LEVEL: u32 = 2;

/// The visibility budget of a solve that approximates the visibility of
/// bounce pairs ([`crate::assembly::QuadratureOptions::visibility_budget`])
/// when none is given: per point, at most a thousandth of its view. On the
/// bunny room at r = 1 on its own triangles that approximates 36 % of the
/// partly visible pairs (356 454 of 982 521; docs/visibility.md); an
/// adaptive solve lowers it to what its target allows
/// ([`visibility_budget_for`]).
pub const DEFAULT_VISIBILITY_BUDGET: f64 = 1e-3;

/// The visibility budget an adaptive solve to `target` (relative to
/// max |u|) uses, at most `budget`: the approximation then moves the
/// solution by at most a quarter of the target (ρ_max B / (1 − ρ_max) ≤
/// target / 4, [`crate::estimate::ErrorEstimate::visibility_bound`]).
/// `rho_max`: the largest reflectance (None: not known, `budget` kept).
pub fn visibility_budget_for(budget: f64, target: f64, rho_max: Option<f64>) -> f64 {
    match rho_max {
        Some(r) if budget > 0.0 && r > 0.0 => budget.min(target * (1.0 - r) / (4.0 * r)),
        _ => budget,
    }
}

/// The mesh a solve starts from: the uniform `level` of the base
/// triangulation, then 4:1 splits until no edge is longer than `max_edge`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartMesh {
    /// Uniform refinement level.
    pub level: u32,
    /// Longest mapped edge allowed after it (scene units); None: uniform.
    pub max_edge: Option<f64>,
}

impl StartMesh {
    /// The start mesh from what was given (None: not given).
    /// `scene_diagonal` is the diagonal of a scene's bounding box when the
    /// surface is a scene with materials, None for the built-in analytic
    /// surfaces.
    ///
    /// * A level, alone or with a maximum edge, is taken as given.
    /// * A maximum edge alone refines the surface's own triangles (level 0):
    ///   a uniform level under it would only add elements it does not ask
    ///   for.
    /// * Neither, for a scene: its own triangles when the solve is
    ///   `adaptive` (the loop puts the unknowns where the error is; a
    ///   uniform start only adds unknowns it does not need: the Cornell box
    ///   to 1e-3, 7 710 unknowns and 71 s from its 50 triangles against
    ///   17 052 and 5 min 48 s from the uniform default), else its own
    ///   triangles refined to [`DEFAULT_EDGE_FRACTION`] of the diagonal.
    /// * Neither, for a surface: [`DEFAULT_LEVEL`].
    pub fn resolve(
        scene_diagonal: Option<f64>,
        level: Option<u32>,
        max_edge: Option<f64>,
        adaptive: bool,
    ) -> Self {
        let (level, max_edge) = match (level, max_edge, scene_diagonal) {
            (None, None, Some(_)) if adaptive => (0, None),
            (None, None, Some(d)) => (0, Some(DEFAULT_EDGE_FRACTION * d)),
            (None, Some(h), _) => (0, Some(h)),
            (level, max_edge, _) => (level.unwrap_or(DEFAULT_LEVEL), max_edge),
        };
        Self { level, max_edge }
    }
}

impl SolveConfig {
    /// What `radcol solve` runs when given no flag: degree
    /// [`DEFAULT_DEGREE`] ([`ADAPTIVE_DEGREE`] when `adaptive`), the
    /// degree's automatic α ([`auto_alpha`]), the mesh of
    /// [`StartMesh::resolve`] with nothing given, and
    /// [`SolveConfig::default`]'s solver, quadrature, operator and estimate
    /// settings. `scene_diagonal`: as for [`StartMesh::resolve`].
    pub fn recommended(scene_diagonal: Option<f64>, adaptive: bool) -> Self {
        let degree = if adaptive {
            ADAPTIVE_DEGREE
        } else {
            DEFAULT_DEGREE
        };
        let mesh = StartMesh::resolve(scene_diagonal, None, None, adaptive);
        SolveConfig {
            degree,
            alpha: auto_alpha(degree),
            level: mesh.level,
            max_edge: mesh.max_edge,
            ..SolveConfig::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default configuration is the recommended one on a surface, to
    /// the last bit of α.
    #[test]
    fn the_default_is_the_recommended_configuration_on_a_surface() {
        let d = SolveConfig::default();
        let r = SolveConfig::recommended(None, false);
        assert_eq!(format!("{d:?}"), format!("{r:?}"));
        assert_eq!(d.alpha.to_bits(), auto_alpha(DEFAULT_DEGREE).to_bits());
    }

    /// An adaptive solve's budget leaves the approximation at most a
    /// quarter of the target (ρ/(1 − ρ) · τ ≤ target/4), never raises the
    /// budget given, and keeps it when ρ is not known.
    #[test]
    fn an_adaptive_budget_leaves_a_quarter_of_the_target() {
        let b = visibility_budget_for(1e-3, 1e-2, Some(0.75));
        assert!(
            b < 1e-3 && 0.75 / 0.25 * b <= 1e-2 / 4.0 * (1.0 + 1e-12),
            "{b}"
        );
        assert_eq!(visibility_budget_for(1e-3, 1e-1, Some(0.5)), 1e-3);
        assert_eq!(visibility_budget_for(0.0, 1e-2, Some(0.5)), 0.0);
        assert_eq!(visibility_budget_for(1e-3, 1e-2, None), 1e-3);
    }

    #[test]
    fn a_scene_starts_from_its_own_triangles() {
        let m = |l, h, a| StartMesh::resolve(Some(1000.0), l, h, a);
        assert_eq!(
            m(None, None, true),
            StartMesh {
                level: 0,
                max_edge: None
            }
        );
        assert_eq!(m(None, None, false).max_edge, Some(100.0));
        assert_eq!(
            m(None, Some(5.0), false),
            StartMesh {
                level: 0,
                max_edge: Some(5.0)
            }
        );
        assert_eq!(
            m(Some(3), None, true),
            StartMesh {
                level: 3,
                max_edge: None
            }
        );
        let s = StartMesh::resolve(None, None, None, true);
        assert_eq!(
            s,
            StartMesh {
                level: DEFAULT_LEVEL,
                max_edge: None
            }
        );
        let c = SolveConfig::recommended(Some(1000.0), true);
        assert_eq!((c.degree, c.level, c.max_edge), (ADAPTIVE_DEGREE, 0, None));
        assert_eq!(c.alpha, auto_alpha(ADAPTIVE_DEGREE));
    }
}
