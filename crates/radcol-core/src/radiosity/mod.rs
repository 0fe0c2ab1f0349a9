//! The front door: [`Radiosity`] owns a solved scene (the scene, its
//! discretization, the assembled operator and the solution of every colour
//! channel) and answers what a program asks of it afterwards: values at
//! points, new lights and materials without reassembly, colours at the
//! input mesh's corners, images.
//!
//! ```
//! use radcol_core::prelude::*;
//!
//! let scene = Scene::builtin("cornell")?;
//! let settings = Settings { target_error: Some(5e-2), ..Settings::default() };
//! let mut solved = Radiosity::solve(scene, &settings)?;
//! let floor = [QueryPoint { position: DVec3::new(278.0, 0.0, 280.0), normal: None }];
//! let before = solved.query(&floor)?[0].channels[0].iterated;
//! solved.relight(&[("light", MaterialChange::Emission([0.0, 0.0, 0.0]))])?;
//! assert!(before > 0.0 && solved.query(&floor)?[0].channels[0].iterated == 0.0);
//! # Ok::<(), radcol_core::prelude::Error>(())
//! ```
//!
//! Its settings are the command's: without a target, one solve on the
//! scene's triangles refined to a tenth of its diagonal at degree 1; with
//! one, adaptive refinement from the scene's own triangles, each starting
//! at the degree its size needs ([`crate::run::start_degree`]).

mod corners;
mod error;
#[cfg(feature = "export")]
mod lightmap;
#[cfg(feature = "export")]
mod write;

pub use corners::CornerValues;
pub use error::Error;
#[cfg(feature = "export")]
pub use lightmap::{Lightmap, LightmapFormat};
#[cfg(feature = "export")]
pub use write::{ImageFormat, MeshFormat};

use crate::alpha0::auto_alpha;
use crate::assembly::{AssemblyBackend, CpuBackend};
use crate::camera::Camera;
use crate::error::InputError;
use crate::estimate::RelativeTo;
use crate::problem::Problem;
use crate::progress::ProgressHandle;
use crate::query::{PointEvaluator, PointValues, QueryPoint, DEFAULT_SNAP};
use crate::render::{render_scene, Corners, Image, RenderOptions, VertexMesh};
use crate::run::adapt::{resume_adaptive, solve_adaptive, AdaptOptions, AdaptStep};
use crate::run::adapt::{Resume, Resumed, StopReason};
use crate::run::{solve, ChannelResult, Relighter, SolveConfig, SolveOutcome};
use crate::scene::{MaterialChange, Scene};
use crate::solution::Solution;
use std::sync::OnceLock;

/// What to solve for. `Settings::default()` is what `radcol solve` does
/// on a scene given no flag.
#[derive(Clone, Debug, Default)]
pub struct Settings {
    /// The largest error to reach, relative to max |u| (the a posteriori
    /// estimate, `crate::estimate`): refine adaptively until it holds.
    /// None: one solve on the default mesh.
    pub target_error: Option<f64>,
    /// Polynomial degree of every element (0..=6). None: degree 1 without
    /// a target; with one, each input triangle starts at the lowest degree
    /// its size needs and the loop raises it where the estimate asks.
    pub degree: Option<usize>,
    /// Progress observer; cancel the solve through it
    /// ([`crate::progress::Cancel`]).
    pub progress: Option<ProgressHandle>,
    /// What `target_error` is relative to: the light the surfaces reflect
    /// (the default, as the command's; max over the nodes of u − E, or max
    /// |u| where nothing is reflected) or max |u| (in a lit scene the light
    /// itself).
    pub relative_to: RelativeTo,
}

impl Settings {
    /// Adaptive refinement to `target_error` (relative to the reflected
    /// light), the rest as [`Settings::default`].
    pub fn target(target_error: f64) -> Self {
        Self {
            target_error: Some(target_error),
            ..Self::default()
        }
    }

    /// These settings reporting to, and cancelled through, `progress`.
    pub fn with_progress(self, progress: ProgressHandle) -> Self {
        Self {
            progress: Some(progress),
            ..self
        }
    }

    /// The solve configuration and, with a target, the adaptive options
    /// these settings give on `scene`.
    pub fn configure(&self, scene: &Scene) -> (SolveConfig, Option<AdaptOptions>) {
        let adapt = self.target_error.map(|target| AdaptOptions {
            target,
            graded_start: self.degree.is_none(),
            relative_to: self.relative_to,
            ..AdaptOptions::default()
        });
        let mut config = scene.solve_config(adapt.is_some());
        if let Some(r) = self.degree {
            config.degree = r;
            config.alpha = auto_alpha(r);
        }
        config.progress = self.progress.clone();
        (config, adapt)
    }
}

/// How an adaptive solve ended.
#[derive(Clone, Debug)]
pub struct Refinement {
    /// Every step, in order.
    pub steps: Vec<AdaptStep>,
    /// Why it stopped.
    pub stop: StopReason,
}

/// A solved scene that owns all it needs (`'static`, `Send + Sync`): query
/// it, relight it, read its colours and render it from any thread.
#[derive(Debug)]
pub struct Radiosity {
    scene: Scene,
    problem: Problem,
    config: SolveConfig,
    outcome: SolveOutcome,
    refinement: Option<Refinement>,
    /// The adaptive loop's options and where it stands; None without a
    /// target.
    adapt: Option<(AdaptOptions, Resume)>,
    /// What a target is relative to when refining a solve that had none.
    relative_to: RelativeTo,
    /// The channels after [`Radiosity::relight`]; None: the solve's.
    relit: Option<Vec<ChannelResult>>,
    evaluator: OnceLock<PointEvaluator>,
}

impl Radiosity {
    /// Solves `scene` on the CPU as `settings` ask.
    ///
    /// # Errors
    /// A scene where nothing emits light ([`InputError::NoEmission`]: its
    /// solution is zero), settings out of range, a problem too large for
    /// memory, a failed solve, [`crate::error::Error::Cancelled`].
    pub fn solve(scene: Scene, settings: &Settings) -> Result<Self, Error> {
        Self::solve_on(scene, settings, &CpuBackend)
    }

    /// [`Radiosity::solve`] with the assembly on `backend` (radcol-gpu's
    /// device backend, for one).
    pub fn solve_on(
        scene: Scene,
        settings: &Settings,
        backend: &dyn AssemblyBackend,
    ) -> Result<Self, Error> {
        let (config, adapt) = settings.configure(&scene);
        let solved = Self::solve_with(scene, config, adapt.as_ref(), backend)?;
        Ok(Self {
            relative_to: settings.relative_to,
            ..solved
        })
    }

    /// Solves `scene` with a configuration of one's own (every setting of
    /// [`SolveConfig`]) and, when given, adaptive refinement.
    pub fn solve_with(
        scene: Scene,
        config: SolveConfig,
        adapt: Option<&AdaptOptions>,
        backend: &dyn AssemblyBackend,
    ) -> Result<Self, Error> {
        let problem = scene.problem();
        if !problem.emits() {
            return Err(InputError::NoEmission.into());
        }
        let relative_to = adapt.map_or(RelativeTo::default(), |a| a.relative_to);
        let (outcome, refinement, adapt) = match adapt {
            None => (solve(&problem, &config, backend)?, None, None),
            Some(opts) => {
                let res = solve_adaptive(&problem, &config, opts, backend, |_| {})?;
                let refinement = Refinement {
                    steps: res.steps,
                    stop: res.stop,
                };
                (
                    res.outcome,
                    Some(refinement),
                    Some((opts.clone(), res.resume)),
                )
            }
        };
        Ok(Self {
            scene,
            problem,
            config,
            outcome,
            refinement,
            adapt,
            relative_to,
            relit: None,
            evaluator: OnceLock::new(),
        })
    }

    /// Refines further, from the mesh solved on, until the estimate is
    /// below `target` (relative as the solve's [`Settings::relative_to`], to the reflected light by default)
    /// or a budget stops it, as the adaptive loop would have gone on: its
    /// new steps are appended to [`Radiosity::refinement`]. The first
    /// split is decided by the estimate at hand; after a relight, or
    /// without an estimate, the current mesh is solved again first, under
    /// the current lights. Nothing changes on an error
    /// ([`crate::error::Error::Cancelled`] included).
    pub fn refine(&mut self, target: f64) -> Result<&Refinement, Error> {
        self.refine_on(target, &CpuBackend)
    }

    /// [`Radiosity::refine`] with the assembly on `backend`.
    pub fn refine_on(
        &mut self,
        target: f64,
        backend: &dyn AssemblyBackend,
    ) -> Result<&Refinement, Error> {
        let (opts, resume) = match &self.adapt {
            Some((opts, resume)) => {
                let opts = AdaptOptions {
                    target,
                    ..opts.clone()
                };
                (opts, resume.clone())
            }
            None => {
                let opts = AdaptOptions {
                    target,
                    relative_to: self.relative_to,
                    ..AdaptOptions::default()
                };
                let fresh = Resume::fresh(&self.outcome, &self.config, &opts, backend)?;
                (opts, fresh)
            }
        };
        let (p, c, from) = (&self.problem, &self.config, &self.outcome);
        let channels = self.channels();
        let resumed = resume_adaptive(p, c, &opts, backend, from, channels, &resume, |_| {})?;
        let refinement = self.refinement.get_or_insert(Refinement {
            steps: Vec::new(),
            stop: StopReason::Reached,
        });
        match resumed {
            Resumed::Stands { stop, .. } => {
                refinement.stop = stop;
                self.adapt = Some((opts, resume));
            }
            Resumed::Refined(res) => {
                let res = *res;
                refinement.steps.extend(res.steps);
                refinement.stop = res.stop;
                self.outcome = res.outcome;
                self.adapt = Some((opts, res.resume));
                self.relit = None;
                self.evaluator = OnceLock::new();
            }
        }
        Ok(refinement)
    }

    /// The scene, with its materials as last relit.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Everything the solve produced: discretization, operator, timings,
    /// pair statistics, and the channels as first solved.
    pub fn outcome(&self) -> &SolveOutcome {
        &self.outcome
    }

    /// The configuration solved with.
    pub fn config(&self) -> &SolveConfig {
        &self.config
    }

    /// The steps of an adaptive solve and why it stopped; None without a
    /// target.
    pub fn refinement(&self) -> Option<&Refinement> {
        self.refinement.as_ref()
    }

    /// The colour channels (R, G, B) under the current lights: u_n, ∫u,
    /// the solver's report and, until the first relight, the error estimate.
    pub fn channels(&self) -> &[ChannelResult] {
        self.relit.as_deref().unwrap_or(&self.outcome.channels)
    }

    /// What to show per channel: u_n made nonnegative where it had negative
    /// values ([`ChannelResult::shown`]).
    pub fn shown(&self) -> Vec<&Solution> {
        self.channels().iter().map(ChannelResult::shown).collect()
    }

    /// u_n, û_n = E + ρ K u_n (the better value, eq. 21) and the estimated
    /// error of u_n on the point's element, per channel, at `points` taken
    /// onto the surface (within 1e-3 of the scene's diagonal; a normal picks
    /// the face at an edge). After a relight the values are the new
    /// lights' and the estimate is None.
    pub fn query(&self, points: &[QueryPoint]) -> Result<Vec<PointValues>, Error> {
        let eval = self.evaluator.get_or_init(|| {
            PointEvaluator::new(
                self.outcome.discretization.clone(),
                self.config.quad.clone(),
                &self.outcome.visibility,
            )
        });
        Ok(eval.query(&self.problem, self.channels(), points, DEFAULT_SNAP)?)
    }

    /// Solves again with the materials named in `changes` given new
    /// emission or reflectance, on the assembled operator (no assembly: a
    /// linear solve per channel). Changes add up over calls. Nothing
    /// changes when a name is unknown or a value out of range.
    pub fn relight(&mut self, changes: &[(&str, MaterialChange)]) -> Result<(), Error> {
        let mut scene = self.scene.clone();
        for &(name, change) in changes {
            scene.change_material(name, change)?;
        }
        let problem = scene.problem();
        let channels = Relighter::new(&self.outcome, &self.config).solve(&problem)?;
        self.scene = scene;
        self.problem = problem;
        self.relit = Some(channels);
        Ok(())
    }

    /// The value of every channel at the three corners of every input
    /// triangle (as read from the file or the builder), with the input's
    /// vertex indices: colours for one's own copy of the mesh.
    pub fn corner_values(&self) -> Result<Vec<CornerValues>, Error> {
        Ok(corners::corner_values(
            &self.scene,
            self.outcome.discretization.mesh(),
            &self.shown(),
        )?)
    }

    /// The scene's triangles with the shown values at their corners, as
    /// a mesh to write (PLY, glTF): corners split per triangle or shared
    /// where position and normal agree.
    pub fn input_vertex_mesh(&self, corners: Corners) -> Result<VertexMesh, Error> {
        Ok(crate::render::input_vertex_mesh(
            self.outcome.discretization.mesh(),
            &self.shown(),
            corners,
        )?)
    }

    /// An image of the shown values from `camera` (None: the scene's own,
    /// or one chosen to show its lit sides), with emitters marked so that
    /// the exposure follows the reflected light.
    pub fn render(&self, camera: Option<&Camera>, options: &RenderOptions) -> Result<Image, Error> {
        let camera = camera
            .copied()
            .unwrap_or_else(|| self.scene.camera_or_auto());
        let emits = self.outcome.emitting_elements();
        Ok(render_scene(
            self.outcome.discretization.mesh(),
            &self.shown(),
            &emits,
            &camera,
            options,
        )?)
    }
}

#[cfg(test)]
mod tests;
