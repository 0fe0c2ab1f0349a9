//! Progress and cancellation through the observer (`radcol_core::progress`):
//! every stage's units add up to its total, the solve stage counts decades
//! of the residual, and an observer that asks to stop gets
//! `Error::Cancelled` naming the stage, from the plan, the assembly and
//! GMRES alike.

use radcol_core::assembly::CpuBackend;
use radcol_core::error::Error;
use radcol_core::progress::{Progress, ProgressHandle};
use radcol_core::run::{solve, SolveConfig, SolverKind};
use radcol_core::scene::builtin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// Records each stage's total and the units advanced; cancels once the
/// stage `stop_at` has started (and `after` units of it are done).
#[derive(Default)]
struct Recorder {
    stages: Mutex<Vec<(String, u64, u64)>>,
    stop_at: Option<(&'static str, u64)>,
    stop: AtomicBool,
}

impl Progress for Recorder {
    fn start(&self, stage: &str, total: u64) {
        self.stages
            .lock()
            .unwrap()
            .push((stage.to_string(), total, 0));
        self.check();
    }
    fn advance(&self, n: u64) {
        if let Some(s) = self.stages.lock().unwrap().last_mut() {
            s.2 += n;
        }
        self.check();
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

impl Recorder {
    fn check(&self) {
        let stages = self.stages.lock().unwrap();
        if let (Some((stage, after)), Some(last)) = (self.stop_at, stages.last()) {
            if last.0 == stage && last.2 >= after {
                self.stop.store(true, Ordering::Relaxed);
            }
        }
    }
}

fn config(rec: &Arc<Recorder>) -> SolveConfig {
    SolveConfig {
        level: 1,
        progress: Some(ProgressHandle(rec.clone())),
        ..Default::default()
    }
}

#[test]
fn stages_count_to_their_totals_and_the_solve_counts_decades() {
    let problem = builtin("cornell").unwrap().unwrap().problem();
    for solver in [SolverKind::Gmres, SolverKind::Lu] {
        let rec = Arc::new(Recorder::default());
        let cfg = SolveConfig {
            solver,
            level: 0,
            ..config(&rec)
        };
        solve(&problem, &cfg, &CpuBackend).expect("solves");
        let stages = rec.stages.lock().unwrap().clone();
        println!("{solver:?}: {stages:?}");
        let names: Vec<&str> = stages.iter().map(|s| s.0.as_str()).collect();
        assert_eq!(names, ["plan", "assembly", "solve", "estimate"]);
        for (name, total, done) in &stages {
            assert_eq!(done, total, "{solver:?} {name}");
        }
        // Three channels, twelve decades each at the default 1e-12.
        assert_eq!(stages[2].1, 36);
    }
}

#[test]
fn an_observer_that_asks_stops_the_solve_in_the_stage_it_asks() {
    let problem = builtin("cornell").unwrap().unwrap().problem();
    for (stage, after) in [("plan", 5), ("assembly", 5), ("solve", 2), ("estimate", 0)] {
        let rec = Arc::new(Recorder {
            stop_at: Some((stage, after)),
            ..Default::default()
        });
        match solve(&problem, &config(&rec), &CpuBackend) {
            Err(Error::Cancelled { stage: got }) => assert_eq!(got, stage),
            other => panic!("{stage}: {:?}", other.map(|_| "solved")),
        }
        // Nothing after the stage that was stopped.
        let stages = rec.stages.lock().unwrap();
        assert_eq!(stages.last().unwrap().0, stage, "{stages:?}");
        if stage == "solve" {
            // GMRES stopped within the first channel.
            assert!(stages.last().unwrap().2 < 12, "{stages:?}");
        }
    }
}
