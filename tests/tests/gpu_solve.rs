//! Solutions and convergence studies assembled on the GPU match the CPU's.
//!
//! f64: nodal solutions agree to 1e-12 relative (the matrices agree to
//! rounding, and the systems are well conditioned: ‖(I - ρK)^-1‖ ≤ 1/(1 - ρmax)).
//! f32: the matrix error (≤ 1e-6 relative to a row, see gpu_conformance) passes
//! to the solution amplified by at most 1/(1 - ρmax), so 1e-5 relative.
//! Studies: errors and fitted orders of a study assembled on the GPU equal the
//! CPU's (f64).

use radcol_core::alpha0::auto_alpha;
use radcol_core::assembly::{AssemblyBackend, CpuBackend};
use radcol_core::run::{solve, SolveConfig, SolverKind};
use radcol_core::study::{fitted_order, study};
use radcol_gpu::testing::test_context;
use radcol_gpu::{GpuBackend, Precision};
use radcol_tests::{assert_close, mixed_problems, rel_diff, sphere_closed_form};

#[test]
fn gpu_solutions_match_the_cpu() {
    let Some(ctx) = test_context("gpu_solutions_match_the_cpu") else {
        return;
    };
    let mut backends: Vec<(GpuBackend, f64)> = Vec::new();
    if ctx.supports_f64() {
        backends.push((GpuBackend::new(ctx.clone(), Precision::F64).unwrap(), 1e-12));
    }
    backends.push((GpuBackend::new(ctx, Precision::F32).unwrap(), 1e-5));
    for (name, problem, r, level) in mixed_problems() {
        let cfg = SolveConfig {
            degree: r,
            alpha: 0.12,
            level,
            solver: SolverKind::Lu,
            ..Default::default()
        };
        let cpu = solve(&problem, &cfg, &CpuBackend).unwrap();
        let want = cpu.channels[0].solution.nodal();
        for (gpu, tol) in &backends {
            let out = solve(&problem, &cfg, gpu).unwrap();
            assert_eq!(out.backend.kind, radcol_core::assembly::BackendKind::Gpu);
            assert_eq!(out.kernel_evals, cpu.kernel_evals);
            let got = out.channels[0].solution.nodal();
            let d = rel_diff(got, want);
            println!(
                "{name} r={r} level={level} N={} {}: |u_gpu - u_cpu| / |u_cpu| = {d:.3e} (tol {tol:e}), assembly {:.3} s (device {:?}) vs CPU {:.3} s",
                want.len(),
                out.backend.precision,
                out.timings.assembly_s,
                out.device_seconds,
                cpu.timings.assembly_s
            );
            assert!(
                d <= *tol,
                "{name} {}: solutions differ by {d:.3e} > {tol:e}",
                out.backend.precision
            );
        }
    }
}

/// A convergence study on the unit sphere (closed-form solution, see
/// sphere_orders.rs): GPU-assembled errors and fitted orders equal the CPU's.
#[test]
fn gpu_study_orders_match_the_cpu() {
    let Some(ctx) = test_context("gpu_study_orders_match_the_cpu") else {
        return;
    };
    let gpu = GpuBackend::new(ctx, Precision::Auto).unwrap();
    let problem = sphere_closed_form();
    let cfg = SolveConfig {
        degree: 1,
        alpha: auto_alpha(1),
        ..Default::default()
    };
    let levels = 1..=3;
    let cpu = study(&problem, &cfg, levels.clone(), &CpuBackend, |_| {}).unwrap();
    let dev = study(&problem, &cfg, levels, &gpu, |_| {}).unwrap();
    let f64_run = gpu.precision() == radcol_core::assembly::Scalar::F64;
    for (i, (g, c)) in dev.iter().zip(&cpu).enumerate() {
        println!(
            "level {}: nodes {:.6e} vs {:.6e}, global {:.6e} vs {:.6e} ({})",
            g.level,
            g.nodes_max,
            c.nodes_max,
            g.global_max,
            c.global_max,
            gpu.info().precision
        );
        // Node errors are small differences of O(1) values: the matrix
        // difference (rounding in f64, ~1e-7 in f32) bounds their change.
        let tol = if f64_run { 1e-12 } else { 1e-6 };
        assert_close("nodes_max", i, g.nodes_max, c.nodes_max, tol);
        assert_close(
            "global_max",
            i,
            g.global_max,
            c.global_max,
            tol.max(1e-12 * c.global_max),
        );
    }
    let h: Vec<f64> = cpu.iter().map(|r| r.h).collect();
    let order = |rows: &[radcol_core::study::StudyRow]| {
        fitted_order(&h, &rows.iter().map(|r| r.global_max).collect::<Vec<_>>())
    };
    let (og, oc) = (order(&dev), order(&cpu));
    println!("fitted global order: gpu {og:.6}, cpu {oc:.6}");
    assert_close("global order", 0, og, oc, if f64_run { 1e-9 } else { 1e-3 });
}
