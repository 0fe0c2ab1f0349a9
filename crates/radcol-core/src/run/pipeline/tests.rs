//! The pipeline before any work: the mesh `max_edge` asks for, and its refusals.

use super::*;
use crate::error::InputError;
use crate::geometry::shapes::box_room;
use crate::problem::Field;

/// `max_edge` reaches the mesh, bad values are refused, and the memory
/// check sees the refined count before anything is built.
#[test]
fn discretize_honours_max_edge() {
    let problem = Problem::new(
        Arc::new(box_room(1.0, 2.0, 3.0)),
        Field::Constant(0.5),
        Field::Constant(1.0),
    );
    let cfg = |max_edge| SolveConfig {
        degree: 0,
        level: 0,
        max_edge,
        ..Default::default()
    };
    // Closed form (see mesh.rs): 12 triangles, each 16 children for H = 1.
    let d = discretize(&problem, &cfg(Some(1.0))).unwrap();
    assert_eq!(d.mesh().len(), 192);
    assert_eq!(d.len(), 192);
    assert_eq!(discretize(&problem, &cfg(None)).unwrap().len(), 12);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let msg = discretize(&problem, &cfg(Some(bad)))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("max edge length"), "{msg}");
    }
    if super::super::available_memory().is_some() {
        // GMRES compresses where the dense matrix does not fit; then
        // the plan's pair table is what cannot fit.
        let err = discretize(&problem, &cfg(Some(1e-9))).unwrap_err();
        assert!(
            matches!(err, Error::Input(InputError::PairTableTooLarge { .. })),
            "{err}"
        );
        let dense = SolveConfig {
            operator: super::super::OperatorChoice::Dense,
            ..cfg(Some(1e-9))
        };
        let err = discretize(&problem, &dense).unwrap_err();
        assert!(
            matches!(err, Error::Input(InputError::TooLarge { .. })),
            "{err}"
        );
    }
}

/// A curved surface not known to bound a convex set is refused (radcol
/// cannot clip curved elements); flat ones that occlude are accepted.
#[test]
fn occluding_curved_surfaces_are_refused() {
    let mut open_sphere = crate::geometry::shapes::sphere(1.0);
    open_sphere.convex_enclosure = false;
    let problem = |s| Problem::new(Arc::new(s), Field::Constant(0.5), Field::Constant(1.0));
    let cfg = SolveConfig {
        degree: 0,
        level: 0,
        ..Default::default()
    };
    let backend = crate::assembly::CpuBackend;
    let msg = solve(&problem(open_sphere), &cfg, &backend)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("curved") && msg.contains("octant"), "{msg}");
    let flat = crate::geometry::shapes::room_with_cube();
    assert!(crate::visibility::analyze(&flat).needed);
    assert!(solve(&problem(flat), &cfg, &backend).is_ok());
}
