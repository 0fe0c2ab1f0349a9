//! # radcol-core
//!
//! Piecewise-polynomial collocation for the radiosity equation
//!
//! ```text
//! u(P) - ρ(P)/π ∫_S u(Q) G(P,Q) dS_Q = E(P),   G = [(Q-P)·n_P][(P-Q)·n_Q] / |P-Q|⁴
//! ```
//!
//! on triangulated surfaces, after Micula (2006): piecewise polynomials of
//! degree r on the elements, collocated at interior nodes q_ij(α) (with the
//! superconvergent α0 where it exists), a distance-adaptive quadrature,
//! exact visibility in scenes that occlude, a dense or compressed operator,
//! GMRES or LU, an a posteriori error estimate and adaptive refinement.
//!
//! The library's edge:
//!
//! * [`prelude`]: the front door. [`prelude::Radiosity`] owns a solved
//!   scene (query points, relight, refine, colours for the input mesh,
//!   images, files); one error type, [`prelude::Error`], that every fallible
//!   call converts into.
//! * [`run`]: one solve below the front door: its configuration, its
//!   outcome and the types they are made of; the adaptive loop.
//! * [`query`]: the solution at any point of the surface: u_n, û_n and
//!   their estimated errors.
//! * [`study`]: convergence studies over levels, fitted orders, node sets.
//! * [`scene`]: scenes from OBJ and glTF files, the built-ins, one's own
//!   buffers.
//! * [`render`] and [`export`]: images, vertex meshes and lightmaps, and
//!   their writers.
//! * [`backend`]: what an assembly backend on another device implements.
//!
//! The stages behind them (geometry, meshes, nodes, quadrature, visibility,
//! assembly, the compressed operator, solvers, the estimate) are private;
//! the `bake` example (`cargo run --release -p radcol-core --example bake`)
//! solves a scene file adaptively, reads its light back at points and
//! writes an image through the prelude alone.
//!
//! ```
//! use radcol_core::backend::CpuBackend;
//! use radcol_core::run::shapes::sphere;
//! use radcol_core::run::{solve, Field, Problem, SolveConfig};
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
//! # Ok::<(), radcol_core::run::Error>(())
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

/// Declares modules behind the library's edge: crate-private, unless the
/// `internals` feature makes them public (and hidden from the docs) for
/// this workspace's tests, benches and the GPU backend's tests. They carry
/// no promise of stability; what a program needs of them is re-exported by
/// the public modules.
macro_rules! internal {
    ($($(#[$attr:meta])* $name:ident;)*) => {$(
        $(#[$attr])*
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $name;
        $(#[$attr])*
        #[cfg(not(feature = "internals"))]
        pub(crate) mod $name;
    )*};
}

pub mod backend;
#[cfg(feature = "export")]
pub mod export;
#[cfg(all(feature = "scenes", feature = "render"))]
pub mod prelude;
pub mod query;
pub mod ranks;
#[cfg(feature = "render")]
pub mod render;
pub mod run;
#[cfg(feature = "scenes")]
pub mod scene;
pub mod study;

mod backend_kind;
internal! {
    alpha0;
    assembly;
    #[cfg(any(feature = "scenes", feature = "render"))]
    camera;
    discretization;
    error;
    estimate;
    expr;
    geometry;
    hmatrix;
    kernel;
    matrix;
    mesh;
    nodes;
    norms;
    problem;
    progress;
    quadrature;
    #[cfg(all(feature = "scenes", feature = "render"))]
    radiosity;
    solution;
    solve;
    visibility;
}
#[cfg(any(test, feature = "conformance"))]
pub mod testing;

/// The README's library example, compiled and run as a doctest.
#[cfg(all(doctest, feature = "scenes", feature = "export"))]
#[doc = include_str!("../../../README.md")]
struct ReadmeExample;
