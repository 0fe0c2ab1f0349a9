//! The adaptive loop's parts: splitting, marking, budget, options.

use super::*;
use crate::error::InputError;
use crate::geometry::shapes::box_room;

/// Splitting keeps area, counts and the parent map, and children follow
/// their parent's place.
#[test]
fn refine_splits_in_place() {
    let mesh = Mesh::new(Arc::new(box_room(1.0, 2.0, 1.5)), 1);
    let (refined, parents) = refine(&mesh, &[3, 0, 40]);
    assert_eq!(refined.len(), mesh.len() + 9);
    crate::assert_close!(refined.area(), mesh.area(), 1e-12 * mesh.area());
    assert_eq!(&parents[..5], &[0, 0, 0, 0, 1]);
    assert_eq!(parents.iter().filter(|&&p| p == 40).count(), 4);
    for (k, &p) in parents.iter().enumerate() {
        let c = refined.position(k, 1.0 / 3.0, 1.0 / 3.0);
        assert!(mesh.locate(c).is_some_and(|(q, _)| q == p));
    }
}

/// Marking takes the elements above the threshold, worst first, except
/// those no longer split.
#[test]
fn marking_skips_capped_elements() {
    let ind = [0.1, 0.5, 0.01, 0.3, 0.2];
    assert_eq!(mark(&ind, 0.15, &|_| false), vec![1, 3, 4]);
    assert_eq!(mark(&ind, 0.15, &|k| k == 1), vec![3, 4]);
    assert!(mark(&ind, 0.15, &|_| true).is_empty());
}

/// The fraction of the worst element that sets the threshold is taken of
/// the worst element that is not stalling (a stalled split away from being
/// frozen): a stalling element far above the rest is split with them, not
/// alone; when every splittable element is stalling, of the worst of those.
#[test]
fn a_stalling_element_does_not_set_the_threshold_alone() {
    let opts = AdaptOptions {
        target: 1e-4,
        max_unknowns: Some(1_000_000),
        ..Default::default()
    };
    let cfg = SolveConfig::default();
    let ind = [8e-3, 4e-4, 3e-4, 1e-4, 6e-5, 2e-3];
    let marked = |stalling: &dyn Fn(usize) -> bool, frozen: &dyn Fn(usize) -> bool| {
        let m = Marking {
            indicator: &ind,
            frozen,
            stalling,
        };
        decide(
            &opts,
            &cfg,
            (8e-3, 1),
            &m,
            (ind.len(), 3 * ind.len(), &|_| 9),
        )
        .1
    };
    // Element 0 stalls: the threshold is 1/4 of element 5's 2e-3 (5e-4),
    // and element 0 is split with element 5.
    assert_eq!(marked(&|k| k == 0, &|_| false), vec![0, 5]);
    // Element 5 frozen too: 1/4 of 4e-4, every element above 1e-4 split.
    assert_eq!(marked(&|k| k == 0, &|k| k == 5), vec![0, 1, 2]);
    // Nothing stalls: 1/4 of 8e-3 (2e-3) leaves element 0 alone.
    assert_eq!(marked(&|_| false, &|_| false), vec![0]);
    // Everything splittable stalls: measured against the worst of them.
    assert_eq!(marked(&|_| true, &|_| false), vec![0]);
}

/// Targets outside [MIN_TARGET, 1) and size floors outside [0, 1) are refused.
#[test]
fn options_out_of_range_are_refused() {
    let ok = AdaptOptions::default();
    assert!(ok.check().is_ok());
    for target in [0.0, 1e-300, 0.5 * MIN_TARGET, 1.0, -1e-3, f64::NAN] {
        let o = AdaptOptions {
            target,
            ..ok.clone()
        };
        assert!(matches!(o.check(), Err(InputError::TargetError { .. })));
    }
    for min_size in [-1e-9, 1.0, f64::NAN] {
        let o = AdaptOptions {
            min_size,
            ..ok.clone()
        };
        assert!(matches!(o.check(), Err(InputError::MinSize { .. })));
    }
    assert!(AdaptOptions {
        min_size: 0.0,
        ..ok
    }
    .check()
    .is_ok());
}

/// A problem where nothing emits is refused before any assembly: u = 0,
/// and a target relative to max |u| cannot be measured.
#[test]
fn a_problem_without_emission_is_refused() {
    use crate::problem::{Field, Problem};
    let room = std::sync::Arc::new(box_room(1.0, 1.0, 1.0));
    let dark = Problem::new(room.clone(), Field::Constant(0.5), Field::Constant(0.0));
    let cfg = SolveConfig::default();
    let run = |p: &Problem| {
        solve_adaptive(
            p,
            &cfg,
            &AdaptOptions::default(),
            &crate::assembly::CpuBackend,
            |_| {},
        )
    };
    assert!(matches!(
        run(&dark),
        Err(Error::Input(InputError::NoEmission))
    ));
    let lit = Problem::new(room, Field::Constant(0.5), Field::Constant(1.0));
    assert!(lit.emits());
}

/// The budget splits the worst elements that fit, and says why none fit.
#[test]
fn budget_caps_the_split() {
    let cfg = SolveConfig {
        check_memory: false,
        ..Default::default()
    };
    let opts = AdaptOptions {
        max_unknowns: Some(3 * (10 + 3 * 4)),
        ..Default::default()
    };
    let split = |elements: usize, marked: usize| {
        budget(&opts, &cfg, (elements, 3 * elements), &vec![9; marked])
    };
    assert_eq!(split(10, 2), Ok(2));
    assert_eq!(split(10, 9), Ok(4));
    assert_eq!(split(22, 9), Err(StopReason::MaxUnknowns));
    // A degree per element: each marked element adds what it may.
    let growth = [18, 3, 3, 3, 9];
    assert_eq!(budget(&opts, &cfg, (10, 30), &growth), Ok(5));
    assert_eq!(budget(&opts, &cfg, (10, 40), &growth), Ok(3));
    assert_eq!(
        budget(&opts, &cfg, (10, 49), &growth),
        Err(StopReason::MaxUnknowns)
    );
}

/// After the first step GMRES stops where the algebraic error is a sliver
/// of the target ([`step_tolerance`]): on the Cornell box to 1e-2 of max
/// |u|, the last step's residual is above the asked 1e-12, and
/// its u_n differs from the same mesh solved to 1e-13 by at most
/// [`ALGEBRAIC_SHARE`] of the target at every node. Fails if the bound is
/// not kept, or if the tolerance is not relaxed at all.
#[cfg(feature = "scenes")]
#[test]
fn later_steps_solve_only_as_far_as_the_target_needs() {
    let scene = crate::scene::builtin("cornell").unwrap().unwrap();
    let problem = scene.problem();
    let cfg = SolveConfig {
        degree: 1,
        alpha: crate::alpha0::auto_alpha(1),
        ..scene.solve_config(true)
    };
    let opts = AdaptOptions {
        target: 1e-2,
        graded_start: false,
        relative_to: RelativeTo::MaxU,
        ..Default::default()
    };
    let backend = crate::assembly::CpuBackend;
    let res = solve_adaptive(&problem, &cfg, &opts, &backend, |_| {}).unwrap();
    assert!(res.steps.len() > 2, "{:?}", res.steps);
    let loose = &res.outcome;
    let tight_cfg = SolveConfig {
        estimate: false,
        gmres: crate::solve::GmresParams {
            rel_tol: 1e-13,
            ..cfg.gmres.clone()
        },
        ..cfg.clone()
    };
    let mesh = loose.discretization.mesh().clone();
    let (tight, _) = super::super::pipeline::solve_step(
        &problem,
        &tight_cfg,
        (mesh, None),
        &backend,
        None,
        None,
    )
    .unwrap();
    for (a, b) in loose.channels.iter().zip(&tight.channels) {
        assert!(
            a.solver.residual > 1e-11,
            "{}: {}",
            a.name,
            a.solver.residual
        );
        let e = a.estimate.as_ref().unwrap();
        let allowed = ALGEBRAIC_SHARE * opts.target * e.scale_of(opts.relative_to);
        let worst = a
            .solution
            .nodal()
            .iter()
            .zip(b.solution.nodal())
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            worst > 0.0 && worst <= allowed,
            "{}: {worst:e} against {allowed:e}",
            a.name
        );
    }
}
