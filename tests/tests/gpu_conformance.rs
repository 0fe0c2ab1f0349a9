//! CPU–GPU conformance of the geometric matrix: the GPU backend executes the
//! same plan as the CPU backend, so in f64 the two agree to rounding entry by
//! entry, and in f32 within a measured bound.
//!
//! Skips with a printed reason when no adapter exists; with
//! RADCOL_REQUIRE_GPU=1 (CI with lavapipe) a missing adapter fails instead.
//!
//! Tolerances. f64: every entry within 1e-13 of the CPU's, relative to the
//! larger of the entry itself and 1e-3 × the largest |entry| of its row. An
//! entry is a sum Σ_q G_q wj_q l_j(q) whose terms have both signs (l_j dips
//! below zero between nodes), so an entry that nearly cancels carries the
//! rounding of its largest terms, which are of the row's size, not its own.
//! SPIR-V lets the driver contract a·b + c into a fused multiply-add (naga
//! marks nothing NoContraction), and lavapipe does once the accumulator loop
//! is unrolled, so single entries that cancel to 1e-3 of their row differ from
//! the CPU's by ~1e-12 of themselves while every entry is within ~1e-14 of
//! that floor. A pure per-entry criterion would measure cancellation, not
//! disagreement; the 1e-3 floor keeps the criterion per entry for every entry
//! that does not cancel. (Both maxima are printed.) f32: 1e-5 relative to the
//! row's largest entry (10× the measured 9.4e-7 at these levels). The f32
//! error grows like ε_f32 · (element size / distance) of the closest far pairs
//! through Q - P, i.e. about 2× per refinement level.

use radcol_core::assembly::conformance::{check_backend, compare_matrices, MatrixDiff};
use radcol_core::assembly::{AssemblyBackend, AssemblyPlan, FillMode, QuadratureOptions};
use radcol_core::assembly::{BackendKind, Scalar};
use radcol_core::discretization::Discretization;
use radcol_core::geometry::shapes::{box_room, sphere};
use radcol_core::geometry::Surface;
use radcol_core::matrix::DenseMatrix;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_gpu::far_field::fill_far_field;
use radcol_gpu::testing::test_context;
use radcol_gpu::{GpuBackend, Precision, TileLimits};
use radcol_tests::assert_close;
use std::sync::Arc;

const F64_TOL: f64 = 1e-13;
const F64_ROW_FLOOR: f64 = 1e-3;
const F32_TOL: f64 = 1e-5;

fn plan(surface: Surface, r: usize, level: u32) -> AssemblyPlan {
    let mesh = Arc::new(Mesh::new(Arc::new(surface), level));
    let disc = Arc::new(Discretization::new(mesh, NodeSet::new(r, 0.1).unwrap()));
    let visibility = radcol_core::visibility::analyze(disc.mesh().surface());
    AssemblyPlan::new(disc, QuadratureOptions::default(), &visibility)
}

#[test]
fn gpu_f64_matrices_equal_the_cpu_ones() {
    let Some(ctx) = test_context("gpu_f64_matrices_equal_the_cpu_ones") else {
        return;
    };
    if !ctx.supports_f64() {
        println!(
            "SKIPPED f64 conformance: {} has no SHADER_F64",
            ctx.description()
        );
        return;
    }
    let gpu = GpuBackend::new(ctx, Precision::F64).unwrap();
    let info = gpu.info();
    assert_eq!((info.kind, info.precision), (BackendKind::Gpu, Scalar::F64));
    println!("device: {}", info.device);
    let diffs = check_backend(&gpu, F64_TOL, F64_ROW_FLOOR).unwrap_or_else(|e| panic!("{e}"));
    let mut worst = MatrixDiff::default();
    for (name, d) in &diffs {
        println!(
            "{name:28} entry rel {:.2e}  row-floored rel {:.2e}",
            d.entry_rel, d.floored_rel
        );
        worst.entry_rel = worst.entry_rel.max(d.entry_rel);
        worst.floored_rel = worst.floored_rel.max(d.floored_rel);
    }
    println!(
        "f64 worst: plain per-entry relative {:.3e}, row-floored relative {:.3e} (tolerance {F64_TOL:e})",
        worst.entry_rel, worst.floored_rel
    );
}

#[test]
fn gpu_f32_matrices_are_within_the_documented_bound() {
    let Some(ctx) = test_context("gpu_f32_matrices_are_within_the_documented_bound") else {
        return;
    };
    let gpu = GpuBackend::new(ctx, Precision::F32).unwrap();
    assert_eq!(gpu.info().precision, Scalar::F32);
    let diffs = check_backend(&gpu, F32_TOL, 1.0).unwrap_or_else(|e| panic!("{e}"));
    let mut worst = 0.0f64;
    for (name, d) in &diffs {
        println!("{name:28} f32 relative to row max {:.2e}", d.floored_rel);
        worst = worst.max(d.floored_rel);
    }
    println!("f32 worst: relative to the row's largest entry {worst:.3e} (bound {F32_TOL:e})");
}

/// Tiny tiles force many row and column tiles (and both buffer slots); the
/// result must be bit-identical to the one-tile assembly.
#[test]
fn gpu_tiling_does_not_change_the_matrix() {
    let Some(ctx) = test_context("gpu_tiling_does_not_change_the_matrix") else {
        return;
    };
    let gpu = GpuBackend::new(ctx, Precision::Auto).unwrap();
    // Each element's record of far points is ~1800 points (every used rule)
    // here, ~116 KiB in f64: 512 KiB bindings give column tiles of a few
    // elements, and 4 KiB target tiles a few dozen rows.
    let tiny = TileLimits {
        max_binding_bytes: 512 << 10,
        max_buffer_bytes: u64::MAX,
        max_workgroups: 64,
        target_tile_bytes: 4 << 10,
    };
    let tiled = gpu.clone().with_tile_limits(tiny);
    for (name, p) in [
        ("box r=1 level=2", plan(box_room(1.0, 2.0, 1.5), 1, 2)),
        ("sphere r=2 level=1", plan(sphere(1.0), 2, 1)),
    ] {
        let whole = gpu.assemble(&p).unwrap();
        let pieces = tiled.assemble(&p).unwrap();
        assert_eq!(whole.kernel_evals, pieces.kernel_evals);
        for (i, (a, b)) in pieces
            .matrix
            .as_slice()
            .iter()
            .zip(whole.matrix.as_slice())
            .enumerate()
        {
            assert_close(name, i, *a, *b, 0.0);
        }
        // The work function directly, on the context's device and queue.
        let ctx = tiled.context();
        let mut far = vec![f64::NAN; p.dim() * p.dim()];
        let report = fill_far_field(
            ctx.device(),
            ctx.queue(),
            ctx.kernels(tiled.precision()).unwrap(),
            &p,
            &tiled.tile_limits(),
            &mut far,
        )
        .unwrap();
        assert!(report.tiles > 10, "{name}: only {} tiles", report.tiles);
        let mut cpu_far = DenseMatrix::zeros(p.dim(), p.dim());
        let f = p.discretization().max_nodes_per_element();
        for (kp, block) in cpu_far
            .as_mut_slice()
            .chunks_exact_mut(f * p.dim())
            .enumerate()
        {
            p.fill_block(kp, block, FillMode::FarOnly);
        }
        let got = DenseMatrix::from_row_major(p.dim(), p.dim(), far);
        let (tol, floor) = if tiled.precision() == Scalar::F64 {
            (F64_TOL, F64_ROW_FLOOR)
        } else {
            (F32_TOL, 1.0)
        };
        compare_matrices(&got, &cpu_far, tol, floor).unwrap_or_else(|e| panic!("{name}: {e}"));
        println!(
            "{name}: {} tiles, identical to one tile, far pairs equal to the CPU's ({} entries)",
            report.tiles,
            got.as_slice().len()
        );
    }
}

/// Lemma 1(c) from the GPU matrix alone: rows of a convex enclosure sum to 1.
#[test]
fn gpu_rows_of_the_sphere_sum_to_one() {
    let Some(ctx) = test_context("gpu_rows_of_the_sphere_sum_to_one") else {
        return;
    };
    let gpu = GpuBackend::new(ctx, Precision::Auto).unwrap();
    let p = plan(sphere(1.0), 1, 2);
    let out = gpu.assemble(&p).unwrap();
    let tol = if gpu.precision() == Scalar::F64 {
        1e-9
    } else {
        1e-5
    };
    for i in 0..out.matrix.nrows() {
        let s: f64 = out.matrix.row(i).iter().sum();
        assert_close("sphere row sum", i, s, 1.0, tol);
    }
}

/// The far-field shader takes one node set per assembly: a plan with a
/// degree per element is refused with a message that says so and names the
/// CPU backend, before any work.
#[test]
fn gpu_refuses_a_degree_per_element() {
    let Some(ctx) = test_context("gpu_refuses_a_degree_per_element") else {
        return;
    };
    let gpu = GpuBackend::new(ctx, Precision::Auto).unwrap();
    let mixed = radcol_core::assembly::conformance::mixed_degree_cases();
    let (name, p) = &mixed[0];
    let err = gpu.assemble(p).unwrap_err().to_string();
    assert!(
        err.contains("degree per element") && err.contains("CPU backend"),
        "{name}: {err}"
    );
}
