//! A solve spread over ranks (`radcol_core::ranks`) gives the one-process
//! solve's answer: the compressed operator's rows shared among 2 and 3
//! ranks (threads of this process exchanging through shared memory, the
//! same collectives MPI runs in `radcol-cli`'s `mpi` tests), GMRES's dot
//! products summed over them. Compared at every node of every channel with
//! the one-process compressed solve: the same values to 1e-10 of the
//! largest, the same GMRES iterations, each rank holding a share of the
//! operator, and the shares adding up to the whole. Each rank plans only
//! its own rows (and those of clusters straddling its edges), so these
//! tests also check that its block tree is the one-process tree.

use radcol_core::assembly::CpuBackend;
use radcol_core::error::{Error, InputError};
use radcol_core::hmatrix::HOptions;
use radcol_core::problem::Problem;
use radcol_core::ranks::{Ranks, Threads};
use radcol_core::run::{solve, OperatorChoice, SolveConfig, SolveOutcome, SolverKind};
use radcol_core::scene::builtin;
use radcol_tests::max_rel_nodal as max_rel;
use std::sync::Arc;

fn config(ranks: Option<Arc<dyn Ranks>>) -> SolveConfig {
    SolveConfig {
        level: 0,
        max_edge: Some(150.0),
        operator: OperatorChoice::Compressed,
        compression: HOptions {
            tol: 1e-8,
            ..SolveConfig::default().compression
        },
        estimate: false,
        ranks,
        ..Default::default()
    }
}

/// `run` on each of `size` thread ranks, with `cfg` and its rank set:
/// every rank's result.
fn on_ranks<T: Send>(
    size: usize,
    cfg: &SolveConfig,
    run: impl Fn(&SolveConfig) -> T + Sync,
) -> Vec<T> {
    std::thread::scope(|s| {
        let handles: Vec<_> = Threads::new(size)
            .into_iter()
            .map(|rank| {
                let cfg = SolveConfig {
                    ranks: Some(Arc::new(rank) as Arc<dyn Ranks>),
                    ..cfg.clone()
                };
                let run = &run;
                s.spawn(move || run(&cfg))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

/// Every rank's outcome of `cfg` over `size` thread ranks.
fn spread(problem: &Problem, size: usize, cfg: &SolveConfig) -> Vec<Result<SolveOutcome, Error>> {
    on_ranks(size, cfg, |cfg| solve(problem, cfg, &CpuBackend))
}

#[test]
fn shared_rows_give_the_one_process_solution() {
    let problem = builtin("cornell").unwrap().unwrap().problem();
    let alone = solve(&problem, &config(None), &CpuBackend).unwrap();
    let whole = alone.operator.stats().unwrap();
    println!(
        "one process: {} unknowns, {} numbers stored",
        alone.discretization.len(),
        whole.stored
    );
    // Five: cuts fall inside clusters that the geometry finds admissible
    // against others, whose rows the ranks on both sides must classify.
    for size in [2, 3, 5] {
        let outs: Vec<SolveOutcome> = spread(&problem, size, &config(None))
            .into_iter()
            .map(Result::unwrap)
            .collect();
        let mut stored = 0;
        for (rank, out) in outs.iter().enumerate() {
            let share = out.operator.shared().expect("a share of the rows");
            assert_eq!((share.ranks().rank(), share.ranks().size()), (rank, size));
            let held = share.stats().stored;
            stored += held;
            let diff = max_rel(out, &alone);
            let iters: Vec<usize> = out.channels.iter().map(|c| c.solver.iterations).collect();
            let alone_iters: Vec<usize> =
                alone.channels.iter().map(|c| c.solver.iterations).collect();
            println!(
                "{size} ranks, rank {rank}: {} rows, {held} numbers ({:.1} %), max |Δu| / max |u| = {diff:.1e}, iterations {iters:?}",
                share.rows().len(),
                100.0 * held as f64 / whole.stored as f64
            );
            assert!(diff <= 1e-10, "rank {rank} of {size}: {diff:e}");
            assert_eq!(iters, alone_iters, "rank {rank} of {size}");
            // Every rank's figures, the same on each: its own work ends
            // before the assembly it waited in; ranks that share a process
            // have no CPU seconds of their own.
            let report = out.ranks.as_ref().expect("the ranks' figures");
            let mine = &report.per_rank[rank];
            assert_eq!((report.size, mine.rows), (size, share.rows().len()));
            assert!(
                mine.work_s > 0.0 && mine.work_s <= mine.assembly_s,
                "{mine:?}"
            );
            assert!(
                mine.work_cpu_s.is_none() && mine.kernel_evals > 0,
                "{mine:?}"
            );
            assert!(
                (held as f64) < 0.8 * whole.stored as f64,
                "rank {rank} of {size} holds {held} of {}",
                whole.stored
            );
        }
        // Leaves that straddle a cut are held on both sides: never fewer
        // numbers than the whole, a few more.
        assert!(
            stored >= whole.stored && (stored as f64) < 1.1 * whole.stored as f64,
            "{stored} against {}",
            whole.stored
        );
    }
}

/// With the estimate (its check rows and shadow probes spread over the
/// ranks too): the same element figures and probes as one process, to
/// 1e-10 of the largest.
#[test]
fn a_spread_estimate_gives_the_one_process_figures() {
    let problem = builtin("cornell").unwrap().unwrap().problem();
    let cfg = SolveConfig {
        estimate: true,
        max_edge: Some(250.0),
        ..config(None)
    };
    let alone = solve(&problem, &cfg, &CpuBackend).unwrap();
    for out in spread(&problem, 3, &cfg) {
        let out = out.unwrap();
        for (a, b) in out.channels.iter().zip(&alone.channels) {
            let (a, b) = (a.estimate.as_ref().unwrap(), b.estimate.as_ref().unwrap());
            let worst = a
                .elements
                .iter()
                .zip(&b.elements)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 1e-10 * b.max, "{worst:e} of {:e}", b.max);
            assert!((a.max - b.max).abs() <= 1e-10 * b.max);
            // Shadow probes found on each rank's elements and gathered.
            assert!(
                b.probes > 0 && a.probes == b.probes,
                "{} {}",
                a.probes,
                b.probes
            );
        }
    }
}

/// The adaptive loop over ranks (each step's operator and estimate
/// shared, marking and stopping on every rank alike): the same steps,
/// unknowns and final solution as one process.
#[test]
fn a_spread_adaptive_loop_takes_the_one_process_steps() {
    use radcol_core::run::adapt::{solve_adaptive, AdaptOptions, AdaptOutcome};
    let problem = builtin("shadow").unwrap().unwrap().problem();
    let cfg = SolveConfig {
        estimate: true,
        max_edge: None,
        ..config(None)
    };
    let opts = AdaptOptions {
        target: 1e-2,
        ..Default::default()
    };
    let run = |cfg: &SolveConfig| solve_adaptive(&problem, cfg, &opts, &CpuBackend, |_| {});
    let unknowns = |r: &AdaptOutcome| r.steps.iter().map(|s| s.unknowns).collect::<Vec<_>>();
    let alone = run(&cfg).unwrap();
    println!("one process: steps {:?}", unknowns(&alone));
    assert!(alone.steps.len() >= 3, "{:?}", unknowns(&alone));
    let outs: Vec<AdaptOutcome> = on_ranks(2, &cfg, |cfg| run(cfg).unwrap());
    for out in &outs {
        assert_eq!(unknowns(out), unknowns(&alone));
        assert_eq!(out.stop, alone.stop);
        let diff = max_rel(&out.outcome, &alone.outcome);
        assert!(diff <= 1e-10, "{diff:e}");
    }
}

#[test]
fn a_spread_solve_refuses_the_dense_operator_and_lu() {
    let problem = builtin("cornell").unwrap().unwrap().problem();
    for cfg in [
        SolveConfig {
            operator: OperatorChoice::Dense,
            ..config(None)
        },
        SolveConfig {
            operator: OperatorChoice::Auto,
            solver: SolverKind::Lu,
            ..config(None)
        },
    ] {
        for out in spread(&problem, 2, &cfg) {
            let err = out.unwrap_err();
            assert!(
                matches!(err, Error::Input(InputError::NotDistributed { ranks: 2 })),
                "{err}"
            );
        }
    }
}

/// More ranks than unknowns: every rank refuses alike, in one error that
/// says how many of each (nothing hangs on a rank with no rows).
#[test]
fn more_ranks_than_unknowns_are_refused_on_every_rank() {
    use radcol_core::geometry::shapes::sphere;
    use radcol_core::problem::Field;
    let problem = Problem::new(
        Arc::new(sphere(1.0)),
        Field::Constant(0.5),
        Field::Constant(1.0),
    );
    let cfg = SolveConfig {
        degree: 0,
        level: 0,
        max_edge: None,
        ..config(None)
    };
    for out in spread(&problem, 9, &cfg) {
        let err = out.unwrap_err();
        assert!(
            matches!(
                err,
                Error::Input(InputError::TooFewRows {
                    unknowns: 8,
                    ranks: 9
                })
            ),
            "{err}"
        );
    }
}
