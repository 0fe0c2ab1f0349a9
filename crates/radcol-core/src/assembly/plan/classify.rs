//! Pair classes: for every (row block, element) pair, culled, far with a rule
//! degree, partly visible, near, or on the element, judged from the block's
//! points and the element's bounding ball; `classify_all`, every row block's
//! classes and partly visible pairs (bounded approximations chosen here).

use super::{class_table, AssemblyPlan, ClassTable, Unchanged};
use crate::assembly::integrate::QuadratureOptions;
use crate::assembly::integrate::{far_degree, piece_ball};
use crate::discretization::CollocationPoint;
use crate::discretization::Discretization;
use crate::mesh::Mesh;
use crate::progress::ProgressHandle;
use crate::visibility::bounce::Bounce;
use crate::visibility::walk::{partial_pairs, Known, PartialRow, Plane, RefinementTree};
use crate::visibility::{Occluders, VisibilityAnalysis};
use glam::DVec3;
use rayon::prelude::*;

/// How one (row block, element) pair is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairClass {
    /// G = 0 on the whole pair (coplanar or back-facing): not integrated.
    Culled,
    /// One far rule of this degree of precision (0..=30).
    Far(u8),
    /// Partly visible pair in a scene that can occlude (CPU): some triangle
    /// meets the hull of the two elements, or the element straddles the
    /// tangent plane of the block's element. Each row integrates over the
    /// exactly clipped visible part (`crate::visibility::clip::visible_region`).
    Partial,
    /// Near pair: adaptive subdivision (CPU).
    Near,
    /// The collocation points lie on the element (curved elements): split at
    /// each point (CPU).
    OnElement,
}

/// Code of [`PairClass::Culled`].
const CULLED: u8 = 0;
/// Code of [`PairClass::Partial`].
const PARTIAL: u8 = 253;
/// Code of [`PairClass::Near`].
const NEAR: u8 = 254;
/// Code of [`PairClass::OnElement`].
const ON_ELEMENT: u8 = 255;

impl PairClass {
    /// The byte stored in the plan and read by the GPU shader: 0 culled,
    /// degree + 1 far, 253 partial, 254 near, 255 on the element.
    #[inline]
    pub const fn code(self) -> u8 {
        match self {
            PairClass::Culled => CULLED,
            PairClass::Far(d) => d + 1,
            PairClass::Partial => PARTIAL,
            PairClass::Near => NEAR,
            PairClass::OnElement => ON_ELEMENT,
        }
    }

    /// The class of a stored code.
    #[inline]
    pub const fn from_code(code: u8) -> Self {
        match code {
            CULLED => PairClass::Culled,
            PARTIAL => PairClass::Partial,
            NEAR => PairClass::Near,
            ON_ELEMENT => PairClass::OnElement,
            d => PairClass::Far(d - 1),
        }
    }

    /// True for the classes a backend leaves to the CPU's
    /// [`super::AssemblyPlan::fill_block`] with [`super::FillMode::SpecialOnly`]:
    /// partial, near and on-element pairs.
    #[inline]
    pub const fn is_special(self) -> bool {
        matches!(
            self,
            PairClass::Partial | PairClass::Near | PairClass::OnElement
        )
    }
}

/// What classification needs of every element: bounding ball (centre,
/// radius), whether it is flat, and its plane (mapped vertices, normal at
/// the centroid).
pub(super) struct ElementShapes {
    pub(super) balls: Vec<(DVec3, f64, bool)>,
    pub(super) planes: Vec<Plane>,
}

impl ElementShapes {
    pub(super) fn new(mesh: &Mesh) -> Self {
        let n = mesh.len();
        let balls = (0..n)
            .into_par_iter()
            .map(|k| {
                let flat = mesh.is_flat(k);
                let (c, rad) = piece_ball(mesh, k, [[0., 0.], [1., 0.], [0., 1.]], !flat);
                (c, rad, flat)
            })
            .collect();
        let planes = (0..n)
            .map(|k| {
                let v = mesh.vertices(k);
                let nrm = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0).normal;
                (v, nrm)
            })
            .collect();
        Self { balls, planes }
    }

    /// True when element `k` is flat.
    pub(super) fn is_flat(&self, k: usize) -> bool {
        self.balls[k].2
    }

    /// The class of the pair (row block of element `kp` with points `block`,
    /// element `k`) before visibility: culled, far of some degree, near, or
    /// on the element. `tol` is the quadrature tolerance, `r` the degree.
    pub(super) fn classify(
        &self,
        kp: usize,
        block: &[CollocationPoint],
        k: usize,
        tol: f64,
        r: usize,
    ) -> PairClass {
        let (c, rad, flat) = self.balls[k];
        if k == kp {
            return if flat {
                PairClass::Culled
            } else {
                PairClass::OnElement
            };
        }
        let (verts, nk) = self.planes[k];
        let all_culled = block.iter().all(|p| {
            let scale = 1e-12 * (rad + (p.position - c).length());
            if flat {
                let behind_k = (p.position - verts[0]).dot(nk) <= scale;
                let all_behind_p = verts
                    .iter()
                    .all(|v| (*v - p.position).dot(p.normal) <= scale);
                behind_k || all_behind_p
            } else {
                (c - p.position).dot(p.normal) + rad <= 0.0
            }
        });
        if all_culled {
            return PairClass::Culled;
        }
        let dmin = block
            .iter()
            .map(|p| (p.position - c).length())
            .fold(f64::INFINITY, f64::min);
        match far_degree(tol, rad, dmin, r, !flat) {
            Some(d) => PairClass::Far(d as u8),
            None => PairClass::Near,
        }
    }
}

/// Per element, whether its pairs may be approximated: with a budget, the
/// elements of the patches the analysis names.
pub(super) fn bounce_columns(
    disc: &Discretization,
    opts: &QuadratureOptions,
    visibility: &VisibilityAnalysis,
) -> Option<Vec<bool>> {
    let patches = &visibility.bounce_patches;
    (opts.visibility_budget > 0.0 && !patches.is_empty()).then(|| {
        let elements = disc.mesh().elements();
        elements.iter().map(|e| patches[e.patch as usize]).collect()
    })
}

pub(super) fn classify_all(
    disc: &Discretization,
    rows: &Discretization,
    (tol, bounce): (f64, Option<Bounce<'_>>),
    occluders: Option<&Occluders>,
    progress: &Option<ProgressHandle>,
    (prev, known): (Option<(&AssemblyPlan, &Unchanged)>, Option<&AssemblyPlan>),
    only: Option<&[bool]>,
) -> (ClassTable, Vec<PartialRow>, Vec<f32>) {
    let mesh = disc.mesh();
    let n = mesh.len();
    let shapes = ElementShapes::new(mesh);
    let pts = rows.points();
    let tree = match occluders {
        Some(_) => RefinementTree::new(mesh),
        None => RefinementTree::default(),
    };
    let rows: Vec<(class_table::Row, PartialRow, f32)> = (0..n)
        .into_par_iter()
        .map(|kp| {
            let started = std::time::Instant::now();
            // A cancelled solve classifies nothing more (all culled): the
            // pipeline returns `Error::Cancelled` once the plan is built.
            // Rows left out of a sampled plan: all culled, likewise.
            if progress.as_ref().is_some_and(|p| p.cancelled()) || only.is_some_and(|o| !o[kp]) {
                return (ClassTable::culled(n), PartialRow::default(), 0.0);
            }
            let block = &pts[rows.range(kp)];
            // The previous plan's row of this element, when it is unchanged.
            let old = prev.and_then(|(p, u)| u.old(kp).map(|op| (p, u, op)));
            let reused = |k: usize| old.is_some_and(|(_, u, _)| u.old(k).is_some());
            let mut row: Vec<u8> = match old {
                Some((p, u, op)) => {
                    let old_row = p.classes.row(op, 0..u.old_len());
                    (0..n)
                        .map(|k| match u.old(k) {
                            Some(ok) => old_row[ok],
                            None => shapes.classify(kp, block, k, tol, disc.degree(k)).code(),
                        })
                        .collect()
                }
                None => (0..n)
                    .map(|k| shapes.classify(kp, block, k, tol, disc.degree(k)).code())
                    .collect(),
            };
            let mut partial = PartialRow::default();
            if let (Some(occ), true) = (occluders, shapes.is_flat(kp)) {
                // The previous plan's pairs of this row that are kept.
                let kept = old.map(|(p, u, op)| p.partial[op].remapped(|ok| u.new_index(ok)));
                let walk = Occluded {
                    occ,
                    tree: &tree,
                    shapes: &shapes,
                    bounce,
                };
                // The square plan's classes of this row tell which pairs it
                // searched: partly visible ones hold their candidates, far
                // and near ones have none; the rest (culled) are searched.
                let known_row = known.map(|p| (p.classes.row(kp, 0..n), &p.partial[kp]));
                let lookup = |k: usize, out: Option<&mut Vec<u32>>| -> bool {
                    let Some((classes, partial)) = known_row.as_ref() else {
                        return false;
                    };
                    match PairClass::from_code(classes[k]) {
                        PairClass::Partial => match out {
                            Some(out) => partial.get(k).map(|c| out.extend_from_slice(c)).is_some(),
                            None => partial.get(k).is_some(),
                        },
                        PairClass::Far(_) | PairClass::Near => true,
                        _ => false,
                    }
                };
                let known = known.is_some().then_some(&lookup as Known<'_>);
                partial = walk.row(kp, block, &mut row, (&reused, known), kept);
            }
            if let Some(p) = progress {
                p.advance(1);
            }
            let row = ClassTable::encode(n, &row);
            (row, partial, started.elapsed().as_secs_f32())
        })
        .collect();
    let mut classes = Vec::with_capacity(n);
    let mut partial = Vec::with_capacity(if occluders.is_some() { n } else { 0 });
    let mut seconds = Vec::with_capacity(if only.is_some() { n } else { 0 });
    for (row, p, t) in rows {
        classes.push(row);
        if occluders.is_some() {
            partial.push(p);
        }
        if only.is_some() {
            seconds.push(t);
        }
    }
    (ClassTable::from_encoded(n, classes), partial, seconds)
}

/// What the occlusion walk of every row block shares.
struct Occluded<'a> {
    occ: &'a Occluders,
    tree: &'a RefinementTree,
    shapes: &'a ElementShapes,
    bounce: Option<Bounce<'a>>,
}

impl Occluded<'_> {
    /// The partly visible pairs of row block `kp` (points `block`), with
    /// `row`'s classes updated (hidden pairs culled, partial ones marked)
    /// and the previous plan's `kept` pairs merged in; pairs `reused` from
    /// it are not walked.
    fn row(
        &self,
        kp: usize,
        block: &[CollocationPoint],
        row: &mut [u8],
        (reused, known): (&dyn Fn(usize) -> bool, Option<Known<'_>>),
        kept: Option<PartialRow>,
    ) -> PartialRow {
        let shapes = self.shapes;
        let live: Vec<bool> = (0..row.len())
            .map(|k| {
                let c = PairClass::from_code(row[k]);
                !reused(k)
                    && c != PairClass::Culled
                    && c != PairClass::OnElement
                    && shapes.is_flat(k)
            })
            .collect();
        let at: Vec<(DVec3, DVec3)> = block.iter().map(|p| (p.position, p.normal)).collect();
        // The approximation budget the kept pairs already spend.
        let spent = kept.as_ref().map(|r| r.bound_sums(block.len()));
        let bounce = self.bounce.map(|b| Bounce {
            spent: spent.as_deref().unwrap_or(&[]),
            ..b
        });
        let (planes, tree) = (&shapes.planes, self.tree);
        let seen = partial_pairs(
            self.occ,
            tree,
            planes[kp],
            &at,
            planes,
            (&live, known),
            bounce,
        );
        // Pairs hidden from every row point are culled: their entries are
        // zero, and as partial pairs they were clipped at every fill and
        // made every block of a shadow look rough to the compressed
        // operator.
        for &k in &seen.hidden {
            row[k as usize] = PairClass::Culled.code();
        }
        for &k in &seen.partial.elements {
            row[k as usize] = PairClass::Partial.code();
        }
        match kept {
            Some(kept) => seen.partial.merged(&kept),
            None => seen.partial,
        }
    }
}
