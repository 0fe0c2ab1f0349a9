//! How much of each collocation point's view is partly visible, and what
//! that says about bounding an approximate visibility of the bounce pairs.
//!
//! For every row point P of the bunny rooms at r = 1 on their own triangles
//! and every element e that the plan integrates over its clipped visible part
//! (a partly visible pair) and that does not emit, the unoccluded mass
//! m(P, e) = ρ(P)/π ∫_e G(P, Q) dQ (largest channel's ρ; a 64-piece midpoint
//! rule on the flat element): the most by which the entry of K that maps
//! u on e to P can change when e's visibility from P is replaced by any value
//! in [0, 1]. Two bounds of the change of (K u)(P), per unit of the brightest
//! reflecting surface's u:
//!
//! * worst case, every partly visible pair approximated: W(P) = Σ_e m(P, e);
//! * Hoeffding, when the approximations' errors are zero-mean and independent
//!   (rays drawn at random): H(P) = (Σ_e m(P, e)² · ln(2/δ) / 2)^½, which
//!   holds except with probability δ = 1e-6 per point.
//!
//! Printed per scene: their distributions over the row points, and the share
//! of partly visible pairs (the clipping work) that a worst-case budget τ per
//! point could approximate (the smallest masses first).
//!
//!     cargo run --release -p radcol-benches --example partial_mass [-- MAX_TRIANGLES [LEVEL]]

use radcol_core::assembly::{AssemblyPlan, PairClass, QuadratureOptions};
use radcol_core::discretization::Discretization;
use radcol_core::kernel::g;
use radcol_core::mesh::Mesh;
use radcol_core::nodes::NodeSet;
use radcol_core::scene::{load_obj, Scene};
use radcol_core::visibility::analyze;
use rayon::prelude::*;
use std::sync::Arc;

/// Pieces per edge of the midpoint rule (PIECES² pieces).
const PIECES: usize = 8;

/// ln(2/δ) / 2 of Hoeffding's bound at δ = 1e-6.
fn hoeffding_factor() -> f64 {
    (2.0f64 / 1e-6).ln() / 2.0
}

/// ∫_e G(P, Q) dQ / π over flat element `k`.
fn unoccluded(mesh: &Mesh, k: usize, p: glam::DVec3, n_p: glam::DVec3) -> f64 {
    let [a, b, c] = mesh.vertices(k);
    let n_q = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
    let area = 0.5 * (b - a).cross(c - a).length() / (PIECES * PIECES) as f64;
    let h = 1.0 / PIECES as f64;
    let mut sum = 0.0;
    for i in 0..PIECES {
        for j in 0..PIECES - i {
            // The upright piece (i, j) and, but on the last diagonal, the
            // inverted one beside it: their centroids.
            let (s, t) = (i as f64 * h, j as f64 * h);
            let mut at = vec![(s + h / 3.0, t + h / 3.0)];
            if i + j + 1 < PIECES {
                at.push((s + 2.0 * h / 3.0, t + 2.0 * h / 3.0));
            }
            for (s, t) in at {
                let q = a + (b - a) * s + (c - a) * t;
                sum += g(p, n_p, q, n_q) * area;
            }
        }
    }
    sum / std::f64::consts::PI
}

/// Per row point: (W, Σ m², masses ascending).
fn masses(scene: &Scene, plan: &AssemblyPlan) -> Vec<(f64, f64, Vec<f64>)> {
    let disc = plan.discretization();
    let mesh = disc.mesh();
    let elements = mesh.elements();
    let emits = |k: usize| scene.material_of(elements[k].patch as usize).is_emitter();
    let rho = |k: usize| {
        let m = scene.material_of(elements[k].patch as usize);
        m.rho.iter().copied().fold(0.0, f64::max)
    };
    (0..mesh.len())
        .into_par_iter()
        .flat_map_iter(|kp| {
            let partial: Vec<usize> = (0..mesh.len())
                .filter(|&k| plan.class(kp, k) == PairClass::Partial && !emits(k))
                .collect();
            let points = &disc.points()[disc.range(kp)];
            points
                .iter()
                .map(|pt| {
                    let mut m: Vec<f64> = partial
                        .iter()
                        .map(|&k| rho(kp) * unoccluded(mesh, k, pt.position, pt.normal))
                        .collect();
                    m.sort_by(f64::total_cmp);
                    let w = m.iter().sum();
                    let w2 = m.iter().map(|x| x * x).sum();
                    (w, w2, m)
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

fn quantiles(mut v: Vec<f64>) -> [f64; 3] {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.9), at(1.0)]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let max: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(3674);
    let level: u32 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(0);
    let files = radcol_benches::bunny_rooms(&[100, 200, 400, 1000, 3674], max);
    let budgets = [1e-3, 1e-2, 3e-2];
    println!("level {level}; per row point, per unit of the brightest reflector's u: W = Σ m (worst case), H = Hoeffding at δ = 1e-6; median / 90 % / max");
    println!("bunny triangles, elements, partly visible pairs, W, H, share of the pairs a worst-case budget τ per point approximates for τ = {budgets:?}");
    for (n, path) in files {
        let scene = load_obj(&path)?;
        let mesh = Arc::new(Mesh::new(scene.surface.clone(), level));
        let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 1.0 / 6.0)?));
        let plan = AssemblyPlan::new(
            disc.clone(),
            QuadratureOptions::default(),
            &analyze(disc.mesh().surface()),
        );
        let rows = masses(&scene, &plan);
        let pairs: usize = rows.iter().map(|r| r.2.len()).sum();
        let w = quantiles(rows.iter().map(|r| r.0).collect());
        let h = quantiles(
            rows.iter()
                .map(|r| (r.1 * hoeffding_factor()).sqrt())
                .collect(),
        );
        let shares: Vec<String> = budgets
            .iter()
            .map(|&tau| {
                let taken: usize = rows
                    .iter()
                    .map(|(_, _, m)| {
                        let mut sum = 0.0;
                        m.iter()
                            .take_while(|&&x| {
                                sum += x;
                                sum <= tau
                            })
                            .count()
                    })
                    .sum();
                format!("{:.1} %", 100.0 * taken as f64 / pairs.max(1) as f64)
            })
            .collect();
        let f = |q: [f64; 3]| format!("{:.2e} / {:.2e} / {:.2e}", q[0], q[1], q[2]);
        println!(
            "{n:>5} {:>6} {pairs:>9}  W {}  H {}  {}",
            disc.mesh().len(),
            f(w),
            f(h),
            shares.join(", ")
        );
    }
    Ok(())
}
