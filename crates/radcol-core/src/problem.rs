//! A radiosity problem: a surface, reflectivity ρ and emission E per colour
//! channel, and optionally the exact solution u.
//!
//! When u is known but E is not, E is *manufactured* as E = u - K u, with K u
//! computed by a [`ReferenceOperator`]: a fixed mesh of the same surface and a
//! tolerance far below the one under test.

use crate::assembly::{ElementIntegrator, FieldPoint, QuadratureOptions};
use crate::expr::Expr;
use crate::geometry::Surface;
pub use crate::mesh::Site;
use crate::mesh::Mesh;
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
    pub fn manufactured(surface: Arc<Surface>, rho: Field, exact: Field, reference: ReferenceOperator) -> Self {
        let reference = Arc::new(reference);
        let (rho_c, u_c) = (rho.clone(), exact.clone());
        let emission = Field::Custom(Arc::new(move |site: &Site| {
            u_c.eval(site) - rho_c.eval(site) * reference.apply(&u_c, site)
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
/// treated as a polynomial of degree `smoothness` on each element.
#[derive(Debug)]
pub struct ReferenceOperator {
    mesh: Mesh,
    ladder: RuleLadder,
    opts: QuadratureOptions,
    smoothness: usize,
    by_patch: Vec<Vec<usize>>,
}

impl ReferenceOperator {
    /// A reference on `surface` refined `level` times (2 is plenty for the
    /// built-in shapes: the pieces are subdivided further where P is near).
    pub fn new(surface: Arc<Surface>, level: u32) -> Self {
        let mesh = Mesh::new(surface.clone(), level);
        let mut by_patch = vec![Vec::new(); surface.patches.len()];
        for (k, e) in mesh.elements().iter().enumerate() {
            by_patch[e.patch as usize].push(k);
        }
        Self {
            mesh,
            ladder: RuleLadder::new(),
            opts: QuadratureOptions {
                tol: 1e-14,
                max_depth: 16,
                self_order: 24,
            },
            smoothness: 10,
            by_patch,
        }
    }

    /// (1/π) ∫_S G(P, Q) u(Q) dS_Q at the site P.
    pub fn apply(&self, u: &Field, site: &Site) -> f64 {
        let integrator = ElementIntegrator::new(&self.mesh, &self.ladder, self.opts.clone());
        let containing = self.locate(site);
        let phi = |k: usize, st: [f64; 2], _q: DVec3, out: &mut [f64]| {
            out[0] = u.eval(&self.mesh.site(k, st[0], st[1]));
        };
        let mut total = 0.0;
        for k in 0..self.mesh.len() {
            let on = containing.iter().find(|(ke, _)| *ke == k).copied();
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
        for &k in self.by_patch.get(site.patch).map(|v| v.as_slice()).unwrap_or(&[]) {
            let [a, b, c] = self.mesh.elements()[k].param;
            if let Some(st) = barycentric_st(a, b, c, site.param) {
                found.push((k, st));
            }
        }
        found
    }
}

/// (s, t) with a + s (b - a) + t (c - a) = x, if x lies in the triangle (within 1e-12).
pub fn barycentric_st(a: DVec3, b: DVec3, c: DVec3, x: DVec3) -> Option<[f64; 2]> {
    let (e1, e2, d) = (b - a, c - a, x - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let s = (d22 * d1 - d12 * d2) / det;
    let t = (d11 * d2 - d12 * d1) / det;
    let eps = 1e-12;
    let off_plane = (d - e1 * s - e2 * t).length();
    (s >= -eps && t >= -eps && s + t <= 1.0 + eps && off_plane <= 1e-9 * (d11 + d22).sqrt())
        .then_some([s.clamp(0.0, 1.0), t.clamp(0.0, 1.0 - s.clamp(0.0, 1.0))])
}
