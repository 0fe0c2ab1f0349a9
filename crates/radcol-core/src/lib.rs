//! # radcol-core
//!
//! Piecewise-polynomial collocation for the radiosity equation
//!
//! ```text
//! u(P) - ρ(P)/π ∫_S u(Q) G(P,Q) dS_Q = E(P),   G = [(Q-P)·n_P][(P-Q)·n_Q] / |P-Q|⁴
//! ```
//!
//! on triangulated surfaces, after Micula (2006): surfaces as smooth maps of
//! planar polygons ([`geometry`]), uniformly refined meshes ([`mesh`]), interior
//! nodes q_ij(α) with their Lagrange basis and the superconvergent α0
//! ([`nodes`], [`alpha0`]), distance-adaptive quadrature ([`quadrature`],
//! [`assembly`]), dense solvers ([`solve`]), solutions and error norms
//! ([`solution`], [`norms`]) and refinement studies ([`study`]).
//!
//! For graphics: triangle scenes with materials from OBJ files, vertex buffers
//! or the built-ins ([`scene`]), occlusion where the geometry needs it
//! ([`visibility`]: exact clipping of partly hidden elements), and images and
//! per-vertex colours of the solution ([`render`], [`camera`]), and the
//! solution at any point ([`query`]).
//!
//! An embedding program needs one import, [`prelude`], with one error type
//! ([`prelude::Error`]) that every fallible call converts into; the
//! `bake` example (`cargo run --release -p radcol-core --example bake`)
//! solves a scene file adaptively, reads its light back at points and
//! writes an image through it.
//!
//! ```
//! use radcol_core::assembly::CpuBackend;
//! use radcol_core::geometry::shapes::sphere;
//! use radcol_core::problem::{Field, Problem};
//! use radcol_core::run::{solve, SolveConfig};
//! use std::sync::Arc;
//!
//! // On the unit sphere G ≡ 1/4 and ∫_S G dS = π, so with ρ = 0.5 and E = 1 the
//! // solution is the constant E / (1 - ρ) = 2.
//! let problem = Problem::new(Arc::new(sphere(1.0)), Field::Constant(0.5), Field::Constant(1.0));
//! let config = SolveConfig { degree: 1, level: 1, ..Default::default() };
//! let outcome = solve(&problem, &config, &CpuBackend)?;
//! for u in outcome.channels[0].solution.nodal() {
//!     assert!((u - 2.0).abs() < 1e-10);
//! }
//! # Ok::<(), radcol_core::error::Error>(())
//! ```
//!
//! A scene with occlusion, solved in three colour channels and rendered:
//!
//! ```
//! # #[cfg(all(feature = "scenes", feature = "render"))] {
//! use radcol_core::prelude::*;
//!
//! let scene = builtin("cornell").expect("a built-in scene")?;
//! let config = SolveConfig { degree: 0, level: 0, ..Default::default() };
//! let outcome = solve(&scene.problem(), &config, &CpuBackend)?;
//! assert!(outcome.visibility.needed, "the blocks cast shadows");
//! let rgb: Vec<_> = outcome.channels.iter().map(|c| &c.solution).collect();
//! let options = RenderOptions { width: 64, height: 48, ..Default::default() };
//! let image = render(outcome.discretization.mesh(), &rgb, &scene.camera_or_auto(), &options)?;
//! let pixels: Vec<[u8; 3]> = tone_map(&image, &ToneMap::default());
//! assert_eq!(pixels.len(), 64 * 48);
//! # }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod alpha0;
pub mod assembly;
pub mod backend;
mod backend_kind;
pub mod camera;
pub mod discretization;
pub mod error;
pub mod estimate;
#[cfg(feature = "export")]
pub mod export;
pub mod expr;
pub mod geometry;
pub mod hmatrix;
pub mod kernel;
pub mod matrix;
pub mod mesh;
pub mod nodes;
pub mod norms;
#[cfg(all(feature = "scenes", feature = "render"))]
pub mod prelude;
pub mod problem;
pub mod progress;
pub mod quadrature;
pub mod query;
#[cfg(all(feature = "scenes", feature = "render"))]
pub mod radiosity;
#[cfg(feature = "render")]
pub mod render;
pub mod run;
#[cfg(feature = "scenes")]
pub mod scene;
pub mod solution;
pub mod solve;
pub mod study;
#[cfg(any(test, feature = "conformance"))]
pub mod testing;
pub mod visibility;

/// The README's library example, compiled and run as a doctest.
#[cfg(all(doctest, feature = "scenes", feature = "export"))]
#[doc = include_str!("../../../README.md")]
struct ReadmeExample;
