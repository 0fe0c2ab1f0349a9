//! The geometric matrix as a hierarchical matrix: rows are the collocation
//! points, columns the basis functions, entries sampled from the assembly
//! plan's integrators (every pair class: far tables, adaptive near and self
//! pairs, exact clipping of partly visible pairs), blocks whose element pairs
//! the plan culled (facing away, or hidden) zero without a kernel call.

use super::classes::ClassesAlong;
use super::cluster::{boxes, Aabb};
use super::consecutive_runs;
use super::reuse::with_elements;
use super::{Entries, HMatrix, HOptions, HPrediction, SampledSize, Structure};
use crate::assembly::plan::{AssemblyPlan, PairClass, Unchanged};
use crate::discretization::Discretization;
use glam::DVec3;
use std::collections::HashMap;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU64, Ordering};

/// Samples of the plan's matrix, counting kernel evaluations.
#[derive(Debug)]
pub struct PlanEntries<'a> {
    plan: &'a AssemblyPlan,
    evals: AtomicU64,
}

impl<'a> PlanEntries<'a> {
    /// Entries of the matrix `plan` assembles (square plans only: rows at
    /// the discretization's own collocation points).
    pub fn new(plan: &'a AssemblyPlan) -> Self {
        Self {
            plan,
            evals: AtomicU64::new(0),
        }
    }

    /// Kernel evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.evals.load(Ordering::Relaxed)
    }

    /// The boxes of the rows (points) and of the columns (each basis
    /// function's element, by its bounding ball).
    pub fn boxes(&self) -> (Vec<Aabb>, Vec<Aabb>) {
        boxes(self.plan.discretization())
    }

    /// What [`Self::build`] will store ([`HMatrix::predict`]), counted over
    /// the plan's block tree: unlike [`predict`] from the geometry, the
    /// dense leaves that occlusion splits blocks into are counted exactly
    /// (low-rank leaves still at rank 1).
    pub fn predict(&self, opts: &HOptions, limit: f64) -> HPrediction {
        let (rows, cols) = self.boxes();
        HMatrix::predict(&rows, &cols, self, opts, limit)
    }

    /// The hierarchical matrix of the plan.
    #[cfg(feature = "internals")]
    pub fn build(&self, opts: &HOptions) -> HMatrix {
        let (rows, cols) = self.boxes();
        HMatrix::build(&rows, &cols, self, opts)
    }

    /// The hierarchical matrix of the plan, its size predicted from a sample
    /// of its blocks and passed to `check` before the rest are computed
    /// ([`HMatrix::build_checked`]); blocks untouched since `previous` (the
    /// matrix, same `opts`, of the mesh this one refines) taken from it.
    ///
    /// # Errors
    /// What `check` returns.
    pub fn build_checked<E>(
        &self,
        opts: &HOptions,
        previous: Option<(&HMatrix, &Unchanged)>,
        check: impl FnOnce(&SampledSize) -> Result<(), E>,
    ) -> Result<(HMatrix, SampledSize), E> {
        let (rows, cols) = self.boxes();
        let new = self.plan.discretization().offsets();
        let offsets = self.plan.previous_offsets().map(|old| (old, new));
        with_elements(previous, offsets, |reuse| {
            HMatrix::build_checked(&rows, &cols, self, opts, reuse, check)
        })
    }
}

impl Entries for PlanEntries<'_> {
    /// Rows are grouped by element, and each element's rows filled at once
    /// over each run of consecutive column elements.
    fn column_group(&self, j: usize) -> std::ops::Range<usize> {
        let disc = self.plan.discretization();
        disc.range(disc.element_of(j))
    }

    fn block(&self, rows: &[usize], cols: &[usize], out: &mut [f64]) {
        let (disc, row_disc) = (self.plan.discretization(), self.plan.rows());
        let mut elems: Vec<usize> = cols.iter().map(|&j| disc.element_of(j)).collect();
        elems.sort_unstable();
        elems.dedup();
        let runs = consecutive_runs(&elems);
        // Where each listed element's columns begin in a row of the
        // element-ordered buffer, and the row's width.
        let starts: Vec<usize> = elems
            .iter()
            .scan(0, |w, &e| {
                let at = *w;
                *w += disc.nodes_per(e);
                Some(at)
            })
            .collect();
        let width = elems.iter().map(|&e| disc.nodes_per(e)).sum::<usize>();
        // Where column b lands in a row of the element-ordered buffer.
        let at: Vec<usize> = cols
            .iter()
            .map(|&j| {
                let p = &disc.points()[j];
                starts[elems.binary_search(&p.element).expect("listed")] + p.node
            })
            .collect();
        let mut by_elem: Vec<(usize, usize, usize)> = rows
            .iter()
            .enumerate()
            .map(|(a, &i)| {
                let p = &row_disc.points()[i];
                (p.element, p.node, a)
            })
            .collect();
        by_elem.sort_unstable();
        let (mut buf, mut part) = (Vec::new(), Vec::new());
        let mut evals = 0;
        for group in by_elem.chunk_by(|x, y| x.0 == y.0) {
            let kp = group[0].0;
            let (lo, hi) = (group[0].1, group[group.len() - 1].1 + 1);
            buf.clear();
            buf.resize((hi - lo) * width, 0.0);
            let mut offset = 0;
            for run in &runs {
                let w = disc.range_of(run.clone()).len();
                part.clear();
                part.resize((hi - lo) * w, 0.0);
                evals += self.plan.fill_part(kp, lo..hi, run.clone(), &mut part);
                for (dst, src) in buf.chunks_exact_mut(width).zip(part.chunks_exact(w)) {
                    dst[offset..offset + w].copy_from_slice(src);
                }
                offset += w;
            }
            for &(_, local, a) in group {
                let src = &buf[(local - lo) * width..(local - lo + 1) * width];
                let dst = &mut out[a * cols.len()..(a + 1) * cols.len()];
                for (d, &p) in dst.iter_mut().zip(&at) {
                    *d = src[p];
                }
            }
        }
        self.evals.fetch_add(evals, Ordering::Relaxed);
    }
}

impl Structure for PlanEntries<'_> {
    /// Zero when the plan culled every element pair of the block (each
    /// column element faces away from, lies behind, or is hidden from each
    /// row element).
    fn is_zero(&self, rows: &[usize], _: &Aabb, cols: &[usize], _: &Aabb) -> bool {
        self.all_pairs(rows, cols, |c| c == PairClass::Culled)
    }

    /// Smooth when its planes allow (`planes_clear`), no element pair is
    /// partly visible, and its culled pairs (facing away, coplanar or
    /// hidden) fill whole rows and columns of elements (`cross`),
    /// which compression leaves out ([`Structure::zero_lines`]). Culled
    /// pairs elsewhere are a shadow boundary along element edges, where G
    /// jumps to 0, which ACA's samples miss at any tolerance (on the
    /// Cornell box, ∫u off by 7.5e-6 at tolerances 1e-6 to 1e-11 before
    /// this test). Once the planes are clear, pairs culled by the planes
    /// alone always fill whole rows and columns: the rows lie on one side
    /// of each column element's plane, the columns on one side of each
    /// row point's.
    fn smooth(&self, rows: &[usize], row_box: &Aabb, cols: &[usize], col_box: &Aabb) -> bool {
        let disc = self.plan.discretization();
        planes_clear(disc, rows, row_box, cols, col_box) && self.cross(rows, cols).is_some()
    }

    /// The rows of the row elements, and the columns of the column
    /// elements, whose pairs with every element of the other side are
    /// culled (`culled`).
    fn zero_lines(&self, rows: &[usize], cols: &[usize]) -> (Vec<bool>, Vec<bool>) {
        let (disc, row_disc) = (self.plan.discretization(), self.plan.rows());
        let c = self.culled(rows, cols);
        let zero_cols = c.zero_cols();
        (
            rows.iter()
                .map(|&i| c.zero_rows.binary_search(&row_disc.element_of(i)).is_ok())
                .collect(),
            cols.iter()
                .map(|&j| zero_cols.binary_search(&disc.element_of(j)).is_ok())
                .collect(),
        )
    }
}

/// The culled pairs of a block, by element.
struct Culled {
    /// The block's row and column elements, sorted.
    row_elems: Vec<usize>,
    col_elems: Vec<usize>,
    /// The row elements whose every pair is culled (sorted).
    zero_rows: Vec<usize>,
    /// Per column element, its culled pairs.
    culled_in_col: Vec<usize>,
    /// Some pair is partly visible.
    partial: bool,
}

impl Culled {
    /// The column elements whose every pair is culled (sorted).
    fn zero_cols(&self) -> Vec<usize> {
        self.col_elems
            .iter()
            .zip(&self.culled_in_col)
            .filter(|&(_, &c)| c == self.row_elems.len())
            .map(|(&k, _)| k)
            .collect()
    }
}

impl PlanEntries<'_> {
    /// The block's distinct row and column elements, sorted.
    fn elements(&self, rows: &[usize], cols: &[usize]) -> (Vec<usize>, Vec<usize>) {
        let (disc, row_disc) = (self.plan.discretization(), self.plan.rows());
        let mut row_elems: Vec<usize> = rows.iter().map(|&i| row_disc.element_of(i)).collect();
        row_elems.sort_unstable();
        row_elems.dedup();
        let mut col_elems: Vec<usize> = cols.iter().map(|&j| disc.element_of(j)).collect();
        col_elems.sort_unstable();
        col_elems.dedup();
        (row_elems, col_elems)
    }

    /// With no partly visible pair and the culled pairs filling whole rows
    /// and columns of elements: those row and column elements (sorted).
    fn cross(&self, rows: &[usize], cols: &[usize]) -> Option<(Vec<usize>, Vec<usize>)> {
        let c = self.culled(rows, cols);
        if c.partial {
            return None;
        }
        // Every culled pair lies in a zero row or a zero column: a column's
        // culled pairs outside the zero rows number none unless it is zero.
        let crossing = c
            .culled_in_col
            .iter()
            .all(|&k| k == c.row_elems.len() || k == c.zero_rows.len());
        crossing.then(|| {
            let zero_cols = c.zero_cols();
            (c.zero_rows, zero_cols)
        })
    }

    /// The block's culled pairs by row and column element (a byte lookup
    /// per pair: no kernel call).
    fn culled(&self, rows: &[usize], cols: &[usize]) -> Culled {
        let (row_elems, col_elems) = self.elements(rows, cols);
        let (mut zero_rows, mut culled_in_col) = (Vec::new(), vec![0usize; col_elems.len()]);
        let mut partial = false;
        let along = ClassesAlong::new(self.plan.classes(), &col_elems);
        for &kp in &row_elems {
            let mut all = true;
            let _ = along.row(kp, |at, class| {
                partial |= class == PairClass::Partial;
                if class == PairClass::Culled {
                    culled_in_col[at].iter_mut().for_each(|c| *c += 1);
                } else {
                    all = false;
                }
                ControlFlow::Continue(())
            });
            if all {
                zero_rows.push(kp);
            }
        }
        Culled {
            row_elems,
            col_elems,
            zero_rows,
            culled_in_col,
            partial,
        }
    }

    /// True when every element pair of the block has a class for which `ok`
    /// holds (a byte lookup per pair: no kernel call).
    fn all_pairs(
        &self,
        rows: &[usize],
        cols: &[usize],
        mut ok: impl FnMut(PairClass) -> bool,
    ) -> bool {
        let (row_elems, col_elems) = self.elements(rows, cols);
        let along = ClassesAlong::new(self.plan.classes(), &col_elems);
        row_elems.iter().all(|&kp| {
            along
                .row(kp, |_, class| match ok(class) {
                    true => ControlFlow::Continue(()),
                    false => ControlFlow::Break(()),
                })
                .is_continue()
        })
    }
}

/// Whether the box lies wholly on one side of the plane through `p` with
/// normal `n`.
fn one_side(p: DVec3, n: DVec3, b: &Aabb) -> bool {
    // A box that touches the plane (a wall's elements on the floor's
    // plane) lies on one side: rounding of its corners is not a crossing.
    let eps = COPLANAR * (p.abs().max_element() + b.lo.abs().max(b.hi.abs()).max_element());
    let s = b.corners().map(|c| n.dot(c - p));
    s.iter().all(|&x| x >= -eps) || s.iter().all(|&x| x <= eps)
}

/// The distinct elements of columns `cols` (basis functions, each
/// element's consecutive).
fn column_elements(disc: &Discretization, cols: &[usize]) -> Vec<usize> {
    let mut elems: Vec<usize> = cols.iter().map(|&j| disc.element_of(j)).collect();
    elems.dedup();
    elems
}

/// False when a row point's tangent plane cuts the column cluster's box, or
/// a flat column element's plane cuts the row cluster's box: G clamps its
/// cosines at 0, so its entries have a kink along those planes, and a block
/// across one compresses only slowly (on the Cornell box: a product error
/// of 4e-5 at a tolerance of 1e-6 before this test).
fn planes_clear(
    disc: &Discretization,
    rows: &[usize],
    row_box: &Aabb,
    cols: &[usize],
    col_box: &Aabb,
) -> bool {
    let pts = disc.points();
    let mesh = disc.mesh();
    rows.iter()
        .all(|&i| one_side(pts[i].position, pts[i].normal, col_box))
        && column_elements(disc, cols)
            .into_iter()
            .filter(|&k| mesh.is_flat(k))
            .all(|k| {
                let p = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0);
                one_side(p.position, p.normal, row_box)
            })
}

/// Relative distance from a plane within which a point counts as on it.
const COPLANAR: f64 = 1e-13;

/// The structure of a discretization's geometric matrix from its geometry
/// alone, before any plan: the planes of [`planes_clear`] decide
/// smoothness, and a block is zero when every column element is flat and
/// every row point lies on or behind its plane (coplanar and back-to-back
/// pieces). Occlusion is not known here: it can only make more blocks zero
/// and split more, which [`predict`] leaves out.
struct Geometry<'a> {
    disc: &'a Discretization,
    /// Per element: the index of its plane in `planes` (None when curved).
    plane_of: Vec<Option<usize>>,
    /// Distinct element planes: the normal, and per element its offset n·p
    /// (`offset[k]`).
    normals: Vec<DVec3>,
    offset: Vec<f64>,
}

impl<'a> Geometry<'a> {
    fn new(disc: &'a Discretization) -> Self {
        let mesh = disc.mesh();
        let mut ids: HashMap<[u64; 3], usize> = HashMap::new();
        let (mut normals, mut plane_of, mut offset) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..mesh.len() {
            let p = mesh.point(k, 1.0 / 3.0, 1.0 / 3.0);
            offset.push(p.normal.dot(p.position));
            plane_of.push(mesh.is_flat(k).then(|| {
                *ids.entry(p.normal.to_array().map(f64::to_bits))
                    .or_insert_with(|| {
                        normals.push(p.normal);
                        normals.len() - 1
                    })
            }));
        }
        Self {
            disc,
            plane_of,
            normals,
            offset,
        }
    }
}

impl Structure for Geometry<'_> {
    fn is_zero(&self, rows: &[usize], _: &Aabb, cols: &[usize], _: &Aabb) -> bool {
        let pts = self.disc.points();
        // One test per normal, against the smallest offset n·p among the
        // column elements with it: a row point behind that plane is behind
        // all of theirs. A coplanar block (a floor against itself) costs
        // its rows once, not rows × elements (on a 135 000-triangle scene
        // the prediction took minutes).
        let mut planes: Vec<(usize, f64)> = Vec::new();
        for k in column_elements(self.disc, cols) {
            let Some(id) = self.plane_of[k] else {
                return false;
            };
            planes.push((id, self.offset[k]));
        }
        planes.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        planes.dedup_by_key(|p| p.0);
        planes.iter().all(|&(id, c)| {
            let n = self.normals[id];
            rows.iter().all(|&i| {
                let d = n.dot(pts[i].position);
                // Coplanar points differ from the plane by rounding only.
                d - c <= COPLANAR * (d.abs() + c.abs())
            })
        })
    }

    fn smooth(&self, rows: &[usize], row_box: &Aabb, cols: &[usize], col_box: &Aabb) -> bool {
        planes_clear(self.disc, rows, row_box, cols, col_box)
    }

    /// A flat column element's columns are zero when every row point lies
    /// on or behind its plane; a row is zero when it lies on or behind the
    /// plane of every column element (all flat). The test of
    /// [`Structure::is_zero`] line by line.
    fn zero_lines(&self, rows: &[usize], cols: &[usize]) -> (Vec<bool>, Vec<bool>) {
        let pts = self.disc.points();
        let elems = column_elements(self.disc, cols);
        let behind = |i: usize, k: usize| {
            self.plane_of[k].is_some_and(|id| {
                let (d, c) = (self.normals[id].dot(pts[i].position), self.offset[k]);
                d - c <= COPLANAR * (d.abs() + c.abs())
            })
        };
        let zero_elems: Vec<usize> = elems
            .iter()
            .copied()
            .filter(|&k| rows.iter().all(|&i| behind(i, k)))
            .collect();
        (
            rows.iter()
                .map(|&i| elems.iter().all(|&k| behind(i, k)))
                .collect(),
            cols.iter()
                .map(|&j| zero_elems.contains(&self.disc.element_of(j)))
                .collect(),
        )
    }
}

/// Rank `rank`'s share among `size` of the compressed geometric matrix of
/// `disc`, decided from the geometry and `extra`, a cost per row (unknown)
/// that the geometry does not see ([`super::share::layout`]).
pub(crate) fn layout(
    disc: &Discretization,
    opts: &HOptions,
    extra: &[f64],
    (rank, size): (usize, usize),
) -> super::share::Layout {
    let (rows, cols) = boxes(disc);
    super::share::layout(
        (&rows, &cols),
        &Geometry::new(disc),
        opts,
        extra,
        (rank, size),
        (&|i| disc.element_of(i), &|k| disc.offset(k), disc.mesh().len()),
    )
}

/// What the compressed geometric matrix of `disc` will store
/// (`HMatrix::predict`), from the geometry alone (no assembly plan),
/// stopping once past `limit` bytes. Exact for the dense leaves of a
/// surface without occlusion; occlusion stores less near the diagonal.
pub fn predict(disc: &Discretization, opts: &HOptions, limit: f64) -> HPrediction {
    let (rows, cols) = boxes(disc);
    HMatrix::predict(&rows, &cols, &Geometry::new(disc), opts, limit)
}
