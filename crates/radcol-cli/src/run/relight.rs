//! `radcol solve … --relight SPEC`: after the solve, the same assembled
//! matrix solves again for each new set of lights or materials
//! ([`Relighter`]), one solve time per set and no reassembly.
//!
//! A SPEC is, for a scene with materials, `;`-separated assignments
//! `NAME=R,G,B` or `NAME.Ke=R,G,B` (the emission of material NAME) and
//! `NAME.Kd=R,G,B` (its reflectance), the others kept; for a surface with
//! expressions, a new emission expression (ρ kept).

use crate::error::bad_input;
use crate::setup::Setup;
use anyhow::Result;
use radcol_core::run::{Field, Problem, Relighter, SolveOutcome, SolverReport};
use radcol_core::scene::{MaterialChange, Scene, SceneError};
use serde::Serialize;
use std::fmt;
use std::time::Instant;

/// One relit set: what was asked, how long its solve took, and each
/// channel's answer.
#[derive(Clone, Debug, Serialize)]
pub struct RelitSet {
    /// The SPEC as given.
    pub spec: String,
    /// Wall seconds of this set's solves (fields at the nodes and the
    /// linear systems; no assembly).
    pub seconds: f64,
    /// Per channel.
    pub channels: Vec<RelitChannel>,
}

/// One channel of a relit set.
#[derive(Clone, Debug, Serialize)]
pub struct RelitChannel {
    /// Channel name.
    pub name: String,
    /// ∫u over the surface.
    pub integral_u: f64,
    /// ∫E over the surface.
    pub integral_e: f64,
    /// The linear solve.
    pub solver: SolverReport,
}

impl fmt::Display for RelitSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "  relit       '{}' in {:.3} s:", self.spec, self.seconds)?;
        for c in &self.channels {
            write!(f, " {} ∫u = {:.6e}", c.name, c.integral_u)?;
        }
        writeln!(f)
    }
}

/// The problems of `specs` against the loaded scene or surface of `s`,
/// checked before anything is solved (a typo must not cost a solve).
pub fn relit_problems(specs: &[String], s: &Setup) -> Result<Vec<Problem>> {
    specs
        .iter()
        .map(|spec| match s.loaded.scene() {
            Some(scene) => scene_problem(spec, scene).map(|mut p| {
                p.scale_emission(s.ke_scale);
                p
            }),
            None => {
                let e = Field::parse(spec)
                    .map_err(|e| bad_input(format!("--relight '{spec}': {e}")))?;
                let mut p = s.problem.clone();
                p.channels.iter_mut().for_each(|c| c.emission = e.clone());
                p.exact = None; // it belonged to the first emission
                Ok(p)
            }
        })
        .collect()
}

fn scene_problem(spec: &str, scene: &Scene) -> Result<Problem> {
    let mut changed = scene.clone();
    let assignments: Vec<&str> = spec
        .split(';')
        .map(str::trim)
        .filter(|a| !a.is_empty())
        .collect();
    if assignments.is_empty() {
        return Err(bad_input(format!("--relight '{spec}': nothing to change")).into());
    }
    for a in assignments {
        let wrong = || {
            bad_input(format!(
                "--relight '{spec}': '{a}' should be NAME=R,G,B, NAME.Ke=R,G,B or NAME.Kd=R,G,B"
            ))
        };
        let (key, value) = a.split_once('=').ok_or_else(wrong)?;
        let key = key.trim();
        let rgb: Vec<f64> = value
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| wrong())?;
        let [r, g, b] = rgb[..] else {
            return Err(wrong().into());
        };
        let (name, change) = match key.rsplit_once('.') {
            Some((n, "Kd")) => (n, MaterialChange::Reflectance([r, g, b])),
            Some((n, "Ke")) => (n, MaterialChange::Emission([r, g, b])),
            _ => (key, MaterialChange::Emission([r, g, b])),
        };
        // Every material of that name (a scene may hold two: its warnings say so).
        changed
            .change_material(name, change)
            .map_err(|e| bad_input(format!("--relight '{spec}': {}", why(&e))))?;
    }
    Ok(changed.problem())
}

/// What is wrong with a material change, without the place the library
/// names (the flag says it).
fn why(e: &SceneError) -> String {
    match e {
        SceneError::Reflectance { .. } => "Kd must lie in [0, 1)".into(),
        SceneError::Emission { .. } => "Ke must be finite and ≥ 0".into(),
        other => other.to_string(),
    }
}

/// Solves every problem on the matrix of `out`, timing each.
pub fn relight_all(
    problems: Vec<(String, Problem)>,
    s: &Setup,
    out: &SolveOutcome,
) -> Result<Vec<RelitSet>> {
    let mut relighter = Relighter::new(out, &s.cfg);
    problems
        .into_iter()
        .map(|(spec, p)| {
            let t = Instant::now();
            let channels = relighter
                .solve(&p)
                .map_err(|e| anyhow::Error::new(e).context(format!("--relight '{spec}'")))?;
            Ok(RelitSet {
                spec,
                seconds: t.elapsed().as_secs_f64(),
                channels: channels
                    .into_iter()
                    .map(|c| RelitChannel {
                        name: c.name,
                        integral_u: c.integral_u,
                        integral_e: c.integral_e,
                        solver: c.solver,
                    })
                    .collect(),
            })
        })
        .collect()
}
