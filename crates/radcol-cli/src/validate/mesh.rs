//! Validation of the mesh and scene options shared by `solve` and `study`:
//! --max-edge, --grade/--grade-zone, and the flags that a scene with
//! materials takes or refuses (--rho/--emission/--exact, --ke).

use crate::args::{KeArg, ProblemArgs};
use crate::error::{bad_input, BadInput};
use crate::scene::SceneSpec;
use radcol_core::run::{Grade, GRADE_RANGE};

/// A scene with materials takes ρ and E from them (refusing --rho,
/// --emission, --exact); `--ke radiance` needs materials.
pub(super) fn scene_flags(p: &ProblemArgs, scene: &SceneSpec) -> Result<(), BadInput> {
    if scene.has_materials() {
        for (flag, given) in [
            ("--rho", p.rho.is_some()),
            ("--emission", p.emission.is_some()),
            ("--exact", p.exact.is_some()),
        ] {
            if given {
                return Err(bad_input(format!(
                    "{flag}: scene '{}' takes ρ and E from its materials (Kd, Ke) and has no known \
                     exact solution; {flag} applies to the analytic surfaces (sphere, ellipsoid, box)",
                    p.scene.trim()
                )));
            }
        }
    }
    if p.ke == KeArg::Radiance && !scene.has_materials() {
        return Err(bad_input(format!(
            "--ke radiance: '{}' has no materials; --ke says how an MTL file's Ke is read (use --emission for a surface)",
            p.scene.trim()
        )));
    }
    Ok(())
}

/// The factor from Ke to E.
pub(super) fn ke_scale(ke: KeArg) -> f64 {
    match ke {
        KeArg::Exitance => 1.0,
        KeArg::Radiance => std::f64::consts::PI,
    }
}

pub(super) fn check_max_edge(h: f64) -> Result<f64, BadInput> {
    if !(h.is_finite() && h > 0.0) {
        return Err(bad_input(format!(
            "--max-edge {h}: the maximum edge length must be a positive finite number (scene units)"
        )));
    }
    Ok(h)
}

pub(super) fn check_grade(q: f64, zone: Option<f64>) -> Result<Grade, BadInput> {
    if !GRADE_RANGE.contains(&q) {
        return Err(bad_input(format!(
            "--grade {q}: the grading exponent must lie in [{}, {}] (1: no grading; 2 suits degree 1)",
            GRADE_RANGE.start(),
            GRADE_RANGE.end()
        )));
    }
    if let Some(d) = zone.filter(|d| !(d.is_finite() && *d > 0.0)) {
        return Err(bad_input(format!(
            "--grade-zone {d}: the zone's width must be a positive finite number (scene units)"
        )));
    }
    Ok(Grade { exponent: q, zone })
}
