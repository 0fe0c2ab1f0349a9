//! Speed against error: every way a study reached an error — a degree with
//! a uniform level, or a degree with an adaptive step — as a [`Setting`]
//! (unknowns, wall seconds, error relative to max |u_n|), and for each
//! decade of error the fastest setting that reaches it
//! ([`fastest_per_decade`]).

use super::StudyRow;
use crate::run::adapt::AdaptStep;
use serde::Serialize;

/// How a setting refined its mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Refinement {
    /// Uniform 4:1 refinement to this level.
    Uniform {
        /// The level.
        level: u32,
    },
    /// This step (1 = the first solve) of an adaptive run.
    Adaptive {
        /// The step.
        step: usize,
    },
}

impl std::fmt::Display for Refinement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refinement::Uniform { level } => write!(f, "uniform level {level}"),
            Refinement::Adaptive { step } => write!(f, "adaptive step {step}"),
        }
    }
}

/// One way of reaching an error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Setting {
    /// Degree r.
    pub degree: usize,
    /// Uniform level or adaptive step.
    pub refinement: Refinement,
    /// Unknowns N.
    pub unknowns: usize,
    /// Wall seconds a user spends to get this answer: the level's solve
    /// (uniform), every step up to this one (adaptive: a step needs the
    /// ones before it).
    pub seconds: f64,
    /// Global max error relative to max |u_n|: the true error when the exact
    /// solution is known, else the estimate.
    pub error: f64,
    /// Whether `error` is the estimate.
    pub estimated: bool,
}

/// The settings of a uniform study of degree `r`.
pub fn uniform_settings(r: usize, rows: &[StudyRow]) -> Vec<Setting> {
    rows.iter()
        .map(|row| Setting {
            degree: r,
            refinement: Refinement::Uniform { level: row.level },
            unknowns: row.unknowns,
            seconds: row.total_s,
            error: row.global_max / if row.scale > 0.0 { row.scale } else { 1.0 },
            estimated: row.estimated,
        })
        .collect()
}

/// The settings of an adaptive run of degree `r`, step by step.
pub fn adaptive_settings(r: usize, steps: &[AdaptStep]) -> Vec<Setting> {
    let mut seconds = 0.0;
    steps
        .iter()
        .enumerate()
        .map(|(i, s)| {
            seconds += s.seconds;
            Setting {
                degree: r,
                refinement: Refinement::Adaptive { step: i + 1 },
                unknowns: s.unknowns,
                seconds,
                error: s.true_error.unwrap_or(s.estimate),
                estimated: s.true_error.is_none(),
            }
        })
        .collect()
}

/// The fastest setting for one decade of error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DecadeBest {
    /// The decade: errors at most 10^exponent.
    pub exponent: i32,
    /// The setting with the fewest wall seconds among those whose error is
    /// at most 10^exponent.
    pub fastest: Setting,
    /// The setting with the fewest unknowns among them.
    pub fewest_unknowns: Setting,
}

/// For each decade 10^k from the largest error's down to the smallest's,
/// the fastest setting (and the one with the fewest unknowns) whose error
/// is at most 10^k; decades no setting reaches are left out. Settings with
/// a non-finite error are ignored.
pub fn fastest_per_decade(settings: &[Setting]) -> Vec<DecadeBest> {
    let errors = || {
        settings
            .iter()
            .map(|s| s.error)
            .filter(|e| e.is_finite() && *e > 0.0)
    };
    let (Some(hi), Some(lo)) = (errors().reduce(f64::max), errors().reduce(f64::min)) else {
        return Vec::new();
    };
    let (top, bottom) = (hi.log10().ceil() as i32, lo.log10().ceil() as i32);
    (bottom..=top)
        .rev()
        .filter_map(|k| {
            let bound = 10f64.powi(k);
            let reach = || {
                settings
                    .iter()
                    .filter(move |s| s.error.is_finite() && s.error <= bound)
            };
            let fastest = reach().min_by(|a, b| a.seconds.total_cmp(&b.seconds))?;
            let fewest = reach().min_by_key(|s| s.unknowns)?;
            Some(DecadeBest {
                exponent: k,
                fastest: fastest.clone(),
                fewest_unknowns: fewest.clone(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setting(degree: usize, level: u32, unknowns: usize, seconds: f64, error: f64) -> Setting {
        Setting {
            degree,
            refinement: Refinement::Uniform { level },
            unknowns,
            seconds,
            error,
            estimated: false,
        }
    }

    /// Each decade gets the fastest of the settings that reach it, and the
    /// one with the fewest unknowns, which may differ.
    #[test]
    fn decades_take_the_fastest_setting_that_reaches_them() {
        let s = [
            setting(1, 1, 100, 0.1, 3e-2),
            setting(1, 2, 400, 0.5, 8e-3),
            setting(1, 3, 1600, 4.0, 2e-3),
            setting(2, 1, 200, 0.3, 5e-3),
            setting(2, 2, 800, 0.2, 4e-4),
            setting(2, 3, 3200, 9.0, f64::NAN),
        ];
        let d = fastest_per_decade(&s);
        let ks: Vec<i32> = d.iter().map(|x| x.exponent).collect();
        assert_eq!(ks, vec![-1, -2, -3]);
        // ≤ 1e-1: every finite one; fastest 0.1 s.
        assert_eq!(d[0].fastest, s[0]);
        // ≤ 1e-2: r = 2 level 2 is fastest (0.2 s), r = 2 level 1 has the
        // fewest unknowns among those (200).
        assert_eq!(d[1].fastest, s[4]);
        assert_eq!(d[1].fewest_unknowns, s[3]);
        // ≤ 1e-3: only r = 2 level 2.
        assert_eq!(d[2].fastest, s[4]);
        assert!(fastest_per_decade(&[]).is_empty());
    }

    /// Adaptive settings add up the steps' seconds and take the true error
    /// when it is known.
    #[test]
    fn adaptive_settings_accumulate_time() {
        let step = |estimate: f64, true_error: Option<f64>, seconds: f64| AdaptStep {
            elements: 10,
            unknowns: 30,
            estimate,
            estimate_shown: estimate,
            estimate_rms: estimate / 10.0,
            true_error,
            split: 1,
            negative_elements: 0,
            singular_elements: 0,
            estimate_elsewhere: estimate,
            seconds,
            estimate_updated_within: None,
            timings: Default::default(),
            operator: crate::run::OperatorKind::Dense,
            degrees: vec![0, 10],
        };
        let s = adaptive_settings(2, &[step(1e-2, None, 1.0), step(1e-3, Some(2e-3), 2.5)]);
        assert_eq!(s[1].refinement, Refinement::Adaptive { step: 2 });
        crate::assert_close!(s[1].seconds, 3.5, 1e-15);
        assert_eq!((s[0].error, s[0].estimated), (1e-2, true));
        assert_eq!((s[1].error, s[1].estimated), (2e-3, false));
    }
}
