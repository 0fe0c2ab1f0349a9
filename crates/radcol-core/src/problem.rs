//! A radiosity problem: a surface, reflectivity ρ and emission E per colour
//! channel, and optionally the exact solution u.
//!
//! When u is known but E is not, E is *manufactured* as E = u - K u, with K u
//! computed by a [`ReferenceOperator`]: a fixed mesh of the same surface and a
//! tolerance far below the one under test.

use crate::assembly::{ElementIntegrator, FieldPoint, QuadratureOptions};
use crate::expr::Expr;
use crate::geometry::{barycentric_st, Surface};
use crate::mesh::Mesh;
pub use crate::mesh::Site;
use crate::quadrature::RuleLadder;
use glam::DVec3;
use std::fmt;
use std::sync::Arc;

/// A scalar function on S.
#[derive(Clone)]
pub enum Field {
    /// The same value everywhere.
    Constant(f64),
    /// An expression in x, y, z.
    Expr(Arc<Expr>),
    /// One value per patch (materials).
    PerPatch(Arc<Vec<f64>>),
    /// Any function of the site.
    Custom(Arc<dyn Fn(&Site) -> f64 + Send + Sync>),
}

impl fmt::Debug for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Field::Constant(v) => write!(f, "Constant({v})"),
            Field::Expr(e) => write!(f, "Expr({:?})", e.text()),
            Field::PerPatch(v) => write!(f, "PerPatch({} values)", v.len()),
            Field::Custom(_) => write!(f, "Custom(..)"),
        }
    }
}

impl Field {
    /// True when the field is zero everywhere by construction (a zero
    /// constant, or zero on every patch); expressions and functions are
    /// not inspected.
    pub fn is_zero(&self) -> bool {
        match self {
            Field::Constant(v) => *v == 0.0,
            Field::PerPatch(v) => v.iter().all(|&x| x == 0.0),
            Field::Expr(_) | Field::Custom(_) => false,
        }
    }

    /// The field times `k`.
    pub fn scaled(&self, k: f64) -> Field {
        match self {
            Field::Constant(v) => Field::Constant(k * v),
            Field::PerPatch(v) => Field::PerPatch(Arc::new(v.iter().map(|x| k * x).collect())),
            other => {
                let f = other.clone();
                Field::Custom(Arc::new(move |site: &Site| k * f.eval(site)))
            }
        }
    }

    /// Parses an expression; a plain number becomes a [`Field::Constant`].
    pub fn parse(text: &str) -> Result<Self, crate::error::InputError> {
        if let Ok(v) = text.trim().parse::<f64>() {
            return Ok(Field::Constant(v));
        }
        Ok(Field::Expr(Arc::new(Expr::parse(text)?)))
    }

    /// Value at `site`.
    #[inline]
    pub fn eval(&self, site: &Site) -> f64 {
        match self {
            Field::Constant(v) => *v,
            Field::Expr(e) => e.eval(site.position),
            Field::PerPatch(v) => v.get(site.patch).copied().unwrap_or(f64::NAN),
            Field::Custom(f) => f(site),
        }
    }

    /// Value at a point known by position, building the full `Site` only for
    /// fields that need more than the position.
    #[inline]
    pub fn eval_with(&self, position: DVec3, site: impl FnOnce() -> Site) -> f64 {
        match self {
            Field::Constant(v) => *v,
            Field::Expr(e) => e.eval(position),
            _ => self.eval(&site()),
        }
    }

    /// A short description for reports.
    pub fn describe(&self) -> String {
        match self {
            Field::Constant(v) => format!("{v}"),
            Field::Expr(e) => e.text().to_string(),
            Field::PerPatch(_) => "per material".into(),
            Field::Custom(_) => "computed".into(),
        }
    }
}

/// One colour channel: reflectivity and emission.
#[derive(Clone, Debug)]
pub struct Channel {
    /// "u" for a scalar problem, "R", "G", "B" for colour.
    pub name: String,
    /// ρ, in [0, 1).
    pub rho: Field,
    /// E.
    pub emission: Field,
}

/// A radiosity problem.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The surface S.
    pub surface: Arc<Surface>,
    /// Colour channels (one for a scalar problem).
    pub channels: Vec<Channel>,
    /// The exact solution u of the (single) channel, when known.
    pub exact: Option<Field>,
}

impl Problem {
    /// The largest reflectance over every channel, when the fields say it
    /// without evaluation (constants and per-patch values); None when a
    /// channel's ρ is an expression or a function.
    pub fn rho_bound(&self) -> Option<f64> {
        self.channels
            .iter()
            .try_fold(0.0f64, |most, c| match &c.rho {
                Field::Constant(r) => Some(most.max(*r)),
                Field::PerPatch(v) => Some(v.iter().copied().fold(most, f64::max)),
                Field::Expr(_) | Field::Custom(_) => None,
            })
    }

    /// Whether anything may emit light: false when every channel's
    /// emission is zero by construction ([`Field::is_zero`]), and then u = 0.
    pub fn emits(&self) -> bool {
        !self.channels.iter().all(|c| c.emission.is_zero())
    }

    /// Multiplies every channel's emission by `k` (for example π, to read
    /// emission given as radiance as the exitance the equation takes).
    pub fn scale_emission(&mut self, k: f64) {
        for c in &mut self.channels {
            c.emission = c.emission.scaled(k);
        }
    }

    /// A single-channel problem with given ρ and E.
    pub fn new(surface: Arc<Surface>, rho: Field, emission: Field) -> Self {
        Self {
            surface,
            channels: vec![Channel {
                name: "u".into(),
                rho,
                emission,
            }],
            exact: None,
        }
    }

    /// A single-channel problem with exact solution `exact` and E manufactured
    /// as u - K u by `reference`.
    pub fn manufactured(
        surface: Arc<Surface>,
        rho: Field,
        exact: Field,
        reference: ReferenceOperator,
    ) -> Self {
        let k_u = reference.bind(exact.clone());
        let (rho_c, u_c) = (rho.clone(), exact.clone());
        let emission = Field::Custom(Arc::new(move |site: &Site| {
            u_c.eval(site) - rho_c.eval(site) * k_u(site)
        }));
        Self {
            surface,
            channels: vec![Channel {
                name: "u".into(),
                rho,
                emission,
            }],
            exact: Some(exact),
        }
    }
}

/// Computes (1/π) ∫_S G(P, Q) u(Q) dS_Q accurately, for manufactured solutions
/// and checks: a fixed mesh of the surface, tolerance 1e-14, and an integrand
/// treated as a polynomial of degree 8 on each element beyond the kernel's own
/// degree (adaptive pieces near P are small enough for that to hold).
///
/// For far elements the rule points, normals, weights × Jacobians and values of
/// u are tabulated once per element and degree, so applying the operator at a
/// point costs one kernel evaluation per rule point; near and self pieces go
/// through the adaptive `ElementIntegrator`.
#[derive(Debug)]
pub struct ReferenceOperator {
    mesh: Mesh,
    ladder: RuleLadder,
    opts: QuadratureOptions,
    smoothness: usize,
    by_patch: Vec<Vec<usize>>,
    balls: Vec<(DVec3, f64, bool)>,
}

/// Tabulated far rules of a [`ReferenceOperator`] for one u: for element k and
/// degree d, points `[x, y, z, nx, ny, nz, w·J/π · u]`.
struct BoundTables {
    tables: Vec<Vec<Vec<[f64; 7]>>>,
}

impl ReferenceOperator {
    /// A reference on `surface` refined `level` times (2 for the built-in
    /// shapes): far elements use tabulated rules, elements near P are
    /// subdivided adaptively, and the element containing P is split at P.
    pub fn new(surface: Arc<Surface>, level: u32) -> Self {
        let mesh = Mesh::new(surface.clone(), level);
        let mut by_patch = vec![Vec::new(); surface.patches.len()];
        for (k, e) in mesh.elements().iter().enumerate() {
            by_patch[e.patch as usize].push(k);
        }
        let balls = (0..mesh.len())
            .map(|k| {
                let curved = !mesh.is_flat(k);
                let (c, r) = crate::assembly::integrate::piece_ball(
                    &mesh,
                    k,
                    [[0., 0.], [1., 0.], [0., 1.]],
                    curved,
                );
                (c, r, curved)
            })
            .collect();
        Self {
            mesh,
            ladder: RuleLadder::new(),
            opts: QuadratureOptions {
                tol: 1e-14,
                max_depth: 16,
                self_order: 24,
                ..QuadratureOptions::default()
            },
            smoothness: 8,
            by_patch,
            balls,
        }
    }

    /// Binds the operator to `u`: tabulates u on every far rule once and returns
    /// P ↦ (1/π) ∫_S G(P, Q) u(Q) dS_Q.
    pub fn bind(self, u: Field) -> impl Fn(&Site) -> f64 + Send + Sync {
        use rayon::prelude::*;
        let mesh = &self.mesh;
        let tables = (0..mesh.len())
            .into_par_iter()
            .map(|k| {
                (0..=crate::quadrature::MAX_RULE_DEGREE)
                    .map(|d| {
                        let rule = self.ladder.rule(d);
                        rule.points
                            .iter()
                            .zip(&rule.weights)
                            .map(|(&[s, t], &w)| {
                                let q = mesh.point(k, s, t);
                                let uq = u.eval(&mesh.site(k, s, t));
                                let p = q.position;
                                let n = q.normal;
                                [
                                    p.x,
                                    p.y,
                                    p.z,
                                    n.x,
                                    n.y,
                                    n.z,
                                    w * q.jacobian * std::f64::consts::FRAC_1_PI * uq,
                                ]
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let bound = BoundTables { tables };
        move |site: &Site| self.apply_bound(&u, &bound, site)
    }

    fn apply_bound(&self, u: &Field, bound: &BoundTables, site: &Site) -> f64 {
        let integrator = ElementIntegrator::new(&self.mesh, &self.ladder, self.opts.clone());
        let containing = self.locate(site);
        let phi = |k: usize, st: [f64; 2], q: DVec3, out: &mut [f64]| {
            out[0] = u.eval_with(q, || self.mesh.site(k, st[0], st[1]));
        };
        let mut total = 0.0;
        for k in 0..self.mesh.len() {
            let on = containing.iter().find(|(ke, _)| *ke == k).copied();
            if on.is_none() {
                let (c, rad, curved) = self.balls[k];
                let dist = (site.position - c).length();
                if let Some(d) = integrator.far_degree(rad, dist, self.smoothness, curved) {
                    for v in &bound.tables[k][d] {
                        let q = DVec3::new(v[0], v[1], v[2]);
                        let nq = DVec3::new(v[3], v[4], v[5]);
                        total += crate::kernel::g(site.position, site.normal, q, nq) * v[6];
                    }
                    continue;
                }
            }
            let fp = FieldPoint {
                position: site.position,
                normal: site.normal,
                on_element: on,
            };
            let mut acc = [0.0];
            integrator.integrate(&fp, k, self.smoothness, &phi, &mut acc);
            total += acc[0];
        }
        total
    }

    /// Elements of the reference mesh whose parameter triangle contains the site,
    /// with the site's (s, t) in each.
    fn locate(&self, site: &Site) -> Vec<(usize, [f64; 2])> {
        let mut found = Vec::new();
        for &k in self
            .by_patch
            .get(site.patch)
            .map(|v| v.as_slice())
            .unwrap_or(&[])
        {
            let [a, b, c] = self.mesh.elements()[k].param;
            if let Some(st) = barycentric_st(a, b, c, site.param) {
                found.push((k, st));
            }
        }
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{ellipsoid, sphere};

    fn site_on(mesh: &Mesh, k: usize, s: f64, t: f64) -> Site {
        mesh.site(k, s, t)
    }

    /// On the unit sphere (1/π) ∫ G u = (1/4π) ∫ u; for u = exp(a·P) that is
    /// sinh|a| / |a| at every point (closed form).
    #[test]
    fn reference_operator_matches_the_sphere_closed_form() {
        let surface = Arc::new(sphere(1.0));
        let u = Field::parse("exp(0.3*x + 0.5*y + 0.8*z)").unwrap();
        let k_u = ReferenceOperator::new(surface.clone(), 3).bind(u);
        let a = 0.98f64.sqrt();
        let want = a.sinh() / a;
        let probe = Mesh::new(surface, 3);
        for (k, s, t) in [
            (0, 0.2, 0.3),
            (17, 0.5, 0.5),
            (300, 0.0, 0.0),
            (511, 1.0 / 3.0, 0.1),
        ] {
            let got = k_u(&site_on(&probe, k, s, t));
            assert!(
                (got - want).abs() < 1e-12 * want,
                "element {k}: {got} vs {want}"
            );
        }
    }

    /// On an ellipsoid two reference meshes of different levels agree (the
    /// points fall inside elements, on edges and on vertices of the coarser one).
    #[test]
    fn reference_operator_is_mesh_independent_on_an_ellipsoid() {
        let surface = Arc::new(ellipsoid(1.0, 1.3, 0.8));
        let u = Field::parse("1 + x*y - z^2").unwrap();
        let coarse = ReferenceOperator::new(surface.clone(), 1).bind(u.clone());
        let fine = ReferenceOperator::new(surface.clone(), 3).bind(u);
        let probe = Mesh::new(surface, 2);
        for (k, s, t) in [
            (0, 0.2, 0.3),
            (5, 0.5, 0.0),
            (40, 0.0, 0.0),
            (100, 0.25, 0.6),
        ] {
            let site = site_on(&probe, k, s, t);
            let (a, b) = (coarse(&site), fine(&site));
            assert!(
                (a - b).abs() < 1e-11 * a.abs().max(1.0),
                "element {k}: {a} vs {b}"
            );
        }
    }
}
