//! radcol's cross-crate tests, one integration binary (CI links once): each
//! module is one claim of the verification table in docs/verification.md. The end-to-end
//! tests of the `radcol` command live with it (`crates/radcol-cli/tests/cli.rs`),
//! where cargo builds the binary they run.
//!
//! Run one module with `cargo test --release -p radcol-tests --test
//! integration MODULE::` (for example `visibility::`), and add
//! `-- --nocapture` for the measured figures.

mod bounce;
mod box_constant;
mod circles;
mod contact;
mod cost;
mod discontinuity;
mod edge;
mod edges;
mod ellipsoid_orders;
mod estimate;
mod gltf_input;
mod gpu_conformance;
mod gpu_select;
mod gpu_solve;
mod graded;
mod hmatrix;
mod house;
mod hp;
mod operator;
mod progress;
mod query;
mod ranks;
mod relight;
mod reuse;
mod scenes;
mod shadows;
mod small_shadow;
mod solvers_agree;
mod sphere_orders;
mod visibility;
