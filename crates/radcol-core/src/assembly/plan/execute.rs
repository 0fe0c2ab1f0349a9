//! Executing the plan: filling one row block of the geometric matrix, and
//! integrating a partly visible pair over its clipped visible region.

use super::kernels::{contract, far_kernel_flat, far_kernel_row, RUN_CHUNK};
use super::{AssemblyPlan, FillMode, PairClass};
use crate::assembly::integrate::{ElementIntegrator, FieldPoint, Integrand, LagrangeBasis};
use crate::assembly::{QuadratureOptions, VisibilityMode};
use crate::discretization::CollocationPoint;
use crate::visibility::{bounce, clip, sealed};
use glam::DVec3;

/// What every run of one row block shares.
struct BlockFill<'a, 'i> {
    plan: &'a AssemblyPlan,
    kp: usize,
    pts: &'a [CollocationPoint],
    integrator: &'a ElementIntegrator<'i>,
    phi: &'a dyn Integrand,
    ncols: usize,
    /// The block's first column (an element's first unknown).
    first: usize,
}

impl AssemblyPlan {
    /// Integrates the basis times G over the part of element `k` visible from
    /// the point (`position`, `normal`) of element `kp`, for a pair classed
    /// [`PairClass::Partial`]: the visible region is clipped exactly
    /// (`clip::visible_region`) and each convex piece integrated adaptively.
    /// Overwrites `out` (f_r values); returns kernel evaluations.
    ///
    /// # Panics
    /// When the pair is not partial.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_partial(
        &self,
        integrator: &ElementIntegrator<'_>,
        position: DVec3,
        normal: DVec3,
        kp: usize,
        k: usize,
        phi: &dyn Integrand,
        out: &mut [f64],
    ) -> u64 {
        let occ = self
            .occluders
            .as_ref()
            .expect("partial pairs exist only with occluders");
        let row = &self.partial[kp];
        let verts = self.disc.mesh().vertices(k);
        let r = self.disc.degree(k);
        let fp = FieldPoint {
            position,
            normal,
            on_element: None,
        };
        out.fill(0.0);
        if row.is_approx(k) {
            // Bounded approximation: the unoccluded integral times the
            // fraction of a few rays that reach the element (a ray a closed
            // mesh blocks crosses one of its triangles facing P first, so
            // every candidate may be asked).
            let cands = row.candidates_of(k);
            let seen = bounce::visible_fraction(position, &verts, occ, cands);
            if seen == 0.0 {
                return 0;
            }
            let whole = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            let loose = ElementIntegrator::with_self_rule(
                self.disc.mesh(),
                &self.ladder,
                QuadratureOptions {
                    tol: bounce::APPROX_TOL.max(self.opts.tol),
                    ..self.opts.clone()
                },
                self.self_rule.clone(),
            );
            let evals = loose.integrate_region(&fp, k, whole, r, phi, out);
            out.iter_mut().for_each(|x| *x *= seen);
            return evals;
        }
        let cands = sealed::facing_point(occ, &row.in_front, row.candidates_of(k), position);
        let cands = &cands[..];
        if self.opts.visibility == VisibilityMode::Rays {
            let seen = |k: usize, st: [f64; 2], q: DVec3, out: &mut [f64]| {
                if cands.iter().any(|&i| clip::blocks(position, q, occ.get(i))) {
                    out.fill(0.0);
                } else {
                    phi.eval(k, st, q, out);
                }
            };
            let whole = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
            return integrator.integrate_region(&fp, k, whole, r, &seen, out);
        }
        let mut evals = 0;
        for piece in clip::visible_region(position, normal, &verts, occ, cands) {
            for tri in clip::triangles(&piece) {
                evals += integrator.integrate_region(&fp, k, tri, r, phi, out);
            }
        }
        evals
    }

    /// Fills the row block of element `kp`: `block` holds its rows of the
    /// geometric matrix (f_r rows, or the row points per element of an
    /// [`AssemblyPlan::at_points`] plan; length rows · N, row-major). Returns
    /// kernel evaluations.
    pub fn fill_block(&self, kp: usize, block: &mut [f64], mode: FillMode) -> u64 {
        // Columns whose entries are the previous matrix's (FillMode::NotReused).
        let unchanged = self.unchanged().filter(|u| u.old(kp).is_some());
        let skip =
            |k: usize| mode == FillMode::NotReused && unchanged.is_some_and(|u| u.old(k).is_some());
        let mode = match mode {
            FillMode::NotReused => FillMode::All,
            m => m,
        };
        self.fill_block_except(kp, block, mode, skip)
    }

    /// The columns of the elements `wanted` of the row block of element
    /// `kp` (every pair class, as [`AssemblyPlan::fill_block`] fills them);
    /// the other entries of `block` are left as they were. Returns kernel
    /// evaluations.
    pub fn fill_columns(&self, kp: usize, block: &mut [f64], wanted: &[bool]) -> u64 {
        self.fill_block_except(kp, block, FillMode::All, |k| !wanted[k])
    }

    /// [`AssemblyPlan::fill_block`] in `mode` (not `NotReused`) but for the
    /// columns of the elements `skip` names.
    fn fill_block_except(
        &self,
        kp: usize,
        block: &mut [f64],
        mode: FillMode,
        skip: impl Fn(usize) -> bool,
    ) -> u64 {
        // A cancelled solve skips the rest: the pipeline then returns
        // `Error::Cancelled` instead of this matrix.
        if self.progress.as_ref().is_some_and(|p| p.cancelled()) {
            return 0;
        }
        let n = self.disc.mesh().len();
        let ncols = self.disc.len();
        debug_assert_eq!(block.len(), self.rows().nodes_per(kp) * ncols);
        let classes = self.classes.row(kp, 0..n);
        let integrator = self.integrator();
        let disc = &*self.disc;
        let phi = LagrangeBasis(disc);
        let fill = BlockFill {
            plan: self,
            kp,
            pts: &self.rows().points()[self.rows().range(kp)],
            integrator: &integrator,
            phi: &phi,
            ncols,
            first: 0,
        };
        let max_nq = self.max_nq();
        let mut g = vec![0.0f64; RUN_CHUNK * max_nq];
        let mut evals = 0u64;
        // Partly visible pairs of unchanged elements whose entries the
        // previous plan stored are copied, not clipped again.
        let previous = self.stored_previously(kp);
        let stored = |k: usize| mode == FillMode::All && previous.get(self, k).is_some();
        let skip_all = |k: usize| skip(k) || stored(k);
        let mut k = 0;
        while k < n {
            if skip_all(k) {
                k += 1;
                continue;
            }
            // A run of consecutive elements with one class: refinement numbers
            // children consecutively, so neighbours in space share a rule and
            // their rule points are contiguous in the far table.
            // Far runs share the basis table of one node set.
            let (class, set) = (classes[k], disc.set_index(k));
            let mut end = k + 1;
            while end < n
                && end - k < RUN_CHUNK
                && classes[end] == class
                && disc.set_index(end) == set
                && !skip_all(end)
            {
                end += 1;
            }
            evals += fill.run(PairClass::from_code(class), k..end, block, mode, &mut g);
            k = end;
        }
        if mode == FillMode::All {
            self.copy_previous(kp, block, &previous, |k| !skip(k));
            self.store_row(kp, block, &previous, |k| !skip(k));
        }
        if mode != FillMode::FarOnly {
            if let Some(p) = &self.progress {
                p.advance(1);
            }
        }
        evals
    }
}

impl AssemblyPlan {
    /// The most rule points per element of any far table (the size of a
    /// run's kernel buffer per element).
    fn max_nq(&self) -> usize {
        self.tables
            .iter()
            .flatten()
            .map(|t| t.nq)
            .max()
            .unwrap_or(0)
    }

    /// The entries of rows `rows` (local to element `kp`: 0..f_r) and the
    /// columns of elements `elements`, every pair class as in
    /// [`AssemblyPlan::fill_block`]: `out` is rows.len() × (elements.len() ·
    /// f_r), row-major. For the hierarchical matrix's samples. Returns kernel
    /// evaluations.
    pub fn fill_part(
        &self,
        kp: usize,
        rows: std::ops::Range<usize>,
        elements: std::ops::Range<usize>,
        out: &mut [f64],
    ) -> u64 {
        let disc = &*self.disc;
        let cols = disc.range_of(elements.clone());
        let ncols = cols.len();
        debug_assert_eq!(out.len(), rows.len() * ncols);
        let integrator = self.integrator();
        let phi = LagrangeBasis(disc);
        let first_row = self.rows().offset(kp);
        let fill = BlockFill {
            plan: self,
            kp,
            pts: &self.rows().points()[first_row + rows.start..first_row + rows.end],
            integrator: &integrator,
            phi: &phi,
            ncols,
            first: cols.start,
        };
        let max_nq = self.max_nq();
        // Sized to the run, not RUN_CHUNK: samples of one element are common.
        let mut g = vec![0.0f64; elements.len().min(RUN_CHUNK) * max_nq];
        let mut evals = 0u64;
        for (run, class) in self.classes.runs(kp, elements) {
            for same_set in disc.runs_of_one_set(run) {
                for start in same_set.clone().step_by(RUN_CHUNK) {
                    let chunk = start..(start + RUN_CHUNK).min(same_set.end);
                    let class = PairClass::from_code(class);
                    evals += fill.run(class, chunk, out, FillMode::All, &mut g);
                }
            }
        }
        evals
    }
}

impl BlockFill<'_, '_> {
    /// Fills the columns of elements `run` (one class) in every row of the
    /// block, as far as `mode` asks. Returns kernel evaluations.
    #[inline]
    fn run(
        &self,
        class: PairClass,
        run: std::ops::Range<usize>,
        block: &mut [f64],
        mode: FillMode,
        g: &mut [f64],
    ) -> u64 {
        let ncols = self.ncols;
        match class {
            PairClass::Culled if mode == FillMode::All => {
                let cols = self.plan.disc.range_of(run);
                let (a, b) = (cols.start - self.first, cols.end - self.first);
                for row in 0..self.pts.len() {
                    block[row * ncols + a..row * ncols + b].fill(0.0);
                }
                0
            }
            PairClass::Culled => 0,
            PairClass::Near | PairClass::OnElement if mode != FillMode::FarOnly => {
                self.adaptive(run, block)
            }
            PairClass::Partial if mode != FillMode::FarOnly => self.partial(run, block),
            PairClass::Far(d) if mode != FillMode::SpecialOnly => self.far(d, run, block, g),
            _ => 0,
        }
    }

    /// The output slot of element `ke` in row `row` of the block.
    #[inline]
    fn slot<'b>(&self, block: &'b mut [f64], row: usize, ke: usize) -> &'b mut [f64] {
        let cols = self.plan.disc.range(ke);
        let (a, b) = (cols.start - self.first, cols.end - self.first);
        &mut block[row * self.ncols + a..row * self.ncols + b]
    }

    /// Near and on-element pairs: adaptive subdivision (for every row at
    /// once) or the split-at-P rule (row by row).
    fn adaptive(&self, run: std::ops::Range<usize>, block: &mut [f64]) -> u64 {
        let off: Vec<FieldPoint> = self
            .pts
            .iter()
            .map(|p| FieldPoint {
                position: p.position,
                normal: p.normal,
                on_element: None,
            })
            .collect();
        let mut evals = 0;
        let mut rows = Vec::new();
        for ke in run {
            let (r, f) = (self.plan.disc.degree(ke), self.plan.disc.nodes_per(ke));
            if ke != self.kp {
                rows.clear();
                rows.resize(off.len() * f, 0.0);
                evals += self
                    .integrator
                    .integrate_rows(&off, ke, r, self.phi, &mut rows);
                for (row, vals) in rows.chunks_exact(f).enumerate() {
                    self.slot(block, row, ke).copy_from_slice(vals);
                }
                continue;
            }
            for (row, p) in self.pts.iter().enumerate() {
                let out = self.slot(block, row, ke);
                out.fill(0.0);
                let fp = FieldPoint {
                    position: p.position,
                    normal: p.normal,
                    on_element: Some((self.kp, p.st)),
                };
                evals += self.integrator.integrate(&fp, ke, r, self.phi, out);
            }
        }
        evals
    }

    /// Partly visible pairs: over the clipped visible region, row by row.
    fn partial(&self, run: std::ops::Range<usize>, block: &mut [f64]) -> u64 {
        let mut evals = 0;
        for ke in run {
            for (row, p) in self.pts.iter().enumerate() {
                let out = self.slot(block, row, ke);
                evals += self.plan.integrate_partial(
                    self.integrator,
                    p.position,
                    p.normal,
                    self.kp,
                    ke,
                    self.phi,
                    out,
                );
            }
        }
        evals
    }

    /// Far pairs: one vectorised kernel loop over the run's rule points, then
    /// the contraction with the basis, per row.
    #[inline]
    fn far(
        &self,
        degree: u8,
        run: std::ops::Range<usize>,
        block: &mut [f64],
        g: &mut [f64],
    ) -> u64 {
        let ncols = self.ncols;
        let set = self.plan.disc.set_index(run.start);
        let f = self.plan.disc.nodes_per(run.start);
        let t = self.plan.tables[degree as usize]
            .as_ref()
            .expect("plan builds every table it uses");
        let nq = t.nq;
        let len = run.len() * nq;
        let g = &mut g[..len];
        let (flat, s) = (t.flat(), t.span(run.clone()));
        for (row, p) in self.pts.iter().enumerate() {
            match (&s, flat) {
                (Some(s), _) => far_kernel_row(
                    p.position, p.normal, s.px, s.py, s.pz, s.nx, s.ny, s.nz, s.wj, g,
                ),
                (None, Some((elements, rule))) => {
                    for (e, gk) in elements[run.clone()].iter().zip(g.chunks_exact_mut(nq)) {
                        far_kernel_flat(p.position, p.normal, e, rule, gk);
                    }
                }
                (None, None) => unreachable!("a table is flat or holds its points"),
            }
            let cols = self.plan.disc.range_of(run.clone());
            let (a, b) = (cols.start - self.first, cols.end - self.first);
            let out = &mut block[row * ncols + a..row * ncols + b];
            contract(g, &t.basis_t[set], nq, f, out);
        }
        (self.pts.len() * len) as u64
    }
}
