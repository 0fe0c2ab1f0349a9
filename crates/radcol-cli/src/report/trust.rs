//! Whether a solve's answer can be trusted: the warnings of its report
//! (interpolation, quadrature shortfalls, conditioning, residual, estimate)
//! and the one condition that fails the run.

use super::sci;

/// Why the answer of `out` cannot be trusted, if it cannot: a channel whose
/// known condition number (LU's κ₁ estimate, else GMRES's lower bound) times
/// the relative accuracy of the matrix (`--quad-tol`, at least rounding)
/// reaches 1, so that the first-order bound of u's relative error is 100 %
/// (r = 6, α = 0.3 on the sphere: κ₁ ≈ 5e14, errors 7 % where Λ ≈ 3e8).
pub fn untrusted(s: &crate::setup::Setup, out: &radcol_core::run::SolveOutcome) -> Option<String> {
    let delta = s.cfg.quad.tol.max(f64::EPSILON);
    out.channels.iter().find_map(|ch| {
        let k = ch.solver.conditioning()?;
        (k * delta >= 1.0).then(|| {
            format!(
                "channel {}: the answer cannot be trusted: the condition number is {} {}, and errors of \
                 --quad-tol {} in the matrix may change u by up to {} times itself; choose --alpha auto, a \
                 lower --degree or a smaller ρ",
                ch.name,
                if ch.solver.condition.is_some() { "about" } else { "at least" },
                sci(k),
                sci(s.cfg.quad.tol),
                sci(k * delta)
            )
        })
    })
}

/// Warnings about the trustworthiness of a solve: ill-conditioned
/// interpolation (the Lebesgue constant of the nodes), quadrature that fell
/// short of its tolerance (nearly touching surfaces), an inaccurate linear
/// solve (the true residual), and a large estimated error. Each says what to
/// change.
pub fn solve_warnings(
    s: &crate::setup::Setup,
    out: &radcol_core::run::SolveOutcome,
) -> Vec<String> {
    let mut w = Vec::new();
    let r = s.cfg.degree;
    if r > 0 {
        let lebesgue = |a: f64| {
            radcol_core::run::NodeSet::new(r, a).map_or(f64::INFINITY, |n| n.lebesgue_constant())
        };
        let here = lebesgue(s.cfg.alpha);
        let auto = s.alpha.a0.auto_alpha();
        let best = lebesgue(auto);
        if here > 10.0 && here > 2.0 * best {
            w.push(format!(
                "α = {}: its nodes have Lebesgue constant {here:.1} (interpolation amplifies errors up to that much; \
                 collocation near edges is stable roughly while ρ·Λ·cos²(θ/2) < 1); --alpha auto ({auto:.6}) has {best:.1}",
                s.cfg.alpha
            ));
        }
    }
    if let Some(f) = out.plan.shortfall {
        let [x, y, z] = f.point;
        let on = f
            .point_element
            .map_or(String::new(), |k| format!(" on element {k}"));
        w.push(format!(
            "quadrature: {} integral pieces stopped at the subdivision limit short of --quad-tol {}; \
             the closest: the point ({x:.6e}, {y:.6e}, {z:.6e}){on} lies within {} of element {}: surfaces that \
             (nearly) touch there make entries near it less accurate than asked",
            f.pieces,
            sci(s.cfg.quad.tol),
            sci(f.distance),
            f.element
        ));
    }
    let tol = s.cfg.gmres.rel_tol;
    for ch in &out.channels {
        if ch.solver.residual > (1e3 * tol).max(1e-8) {
            w.push(format!(
                "channel {}: the linear solve's true relative residual is {} (asked {}): the system is badly \
                 conditioned; try a smaller α, a lower degree or --solver gmres with more --max-iters",
                ch.name,
                sci(ch.solver.residual),
                sci(tol)
            ));
        }
        // The quadrature error of the matrix reaches u amplified by up to the
        // condition number (box room: 1/(1 - ρ)).
        // (From a bound of 1 on, the run fails instead: `untrusted`.)
        let delta = s.cfg.quad.tol.max(f64::EPSILON);
        if let Some(g) = ch
            .solver
            .conditioning()
            .filter(|&g| g * delta > 1e-6 && g * delta < 1.0)
        {
            w.push(format!(
                "channel {}: the system's condition number is {} {} (ρ close to 1 in a closed scene, or nodes \
                 with a large Lebesgue constant): quadrature errors of --quad-tol {} may reach u amplified that \
                 much; tighten --quad-tol (down to 1e-15)",
                ch.name,
                if ch.solver.condition.is_some() { "about" } else { "at least" },
                sci(g),
                sci(s.cfg.quad.tol)
            ));
        }
        if let Some(e) = &ch.estimate {
            let (scale, of) = super::channel::norm(e);
            if e.max / scale > 0.1 {
                w.push(format!(
                    "channel {}: estimated error {} {of}: refine (--level, --max-edge or --target-error)",
                    ch.name,
                    sci(e.max / scale)
                ));
            }
        }
    }
    w
}
