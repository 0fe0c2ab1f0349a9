//! radcol-core: collocation for the radiosity equation.
pub mod alpha0;
pub mod assembly;
pub mod discretization;
pub mod error;
pub mod expr;
pub mod geometry;
pub mod kernel;
pub mod matrix;
pub mod mesh;
pub mod nodes;
pub mod norms;
pub mod problem;
pub mod quadrature;
pub mod run;
pub mod solution;
pub mod solve;
pub mod study;
