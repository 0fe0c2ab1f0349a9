//! The pair classes of a plan, one row per row block, each row stored as
//! runs of equal codes when that is smaller (5 bytes a run) and as its
//! bytes otherwise. Refinement numbers children consecutively, so
//! neighbours in space share a class and rows have few runs: the built-in
//! room at 5 120 elements has 366 runs a row on average (1.8 KB against
//! 5 KB), and the count grows about as √n, where the bytes grow as n. A
//! byte per pair was 6.25 GiB at 81 920 elements, more than the
//! compressed operator it served.

use std::borrow::Cow;
use std::ops::Range;

/// Bytes per row and per √n of a table of n elements, a bound on what
/// was measured: 5 bytes a run, and 26 √n (the built-in room, 5 120
/// elements) to 35–42 √n (the Cornell box, 1 268 to 20 288 elements,
/// where hidden pairs are culled between partly visible ones) bytes a row.
const BYTES_PER_ROOT: f64 = 44.0;

/// The bytes a table of `elements` elements is expected to take before it
/// is built: 44 n^1.5 (`BYTES_PER_ROOT`), at most n² (every row as
/// bytes). An estimate for scenes whose elements are numbered coherently
/// in space (refinement keeps children together); the plan's measured
/// size ([`ClassTable::heap_bytes`]) is checked once it is built.
pub fn estimated_bytes(elements: f64) -> f64 {
    (BYTES_PER_ROOT * elements.powf(1.5)).min(elements * elements)
}

/// The most elements whose table is expected within `bytes`: the
/// inverse of [`estimated_bytes`].
pub fn elements_within(bytes: f64) -> f64 {
    let runs = (bytes / BYTES_PER_ROOT).powf(2.0 / 3.0);
    // Below BYTES_PER_ROOT² elements rows are stored as bytes: n².
    if runs <= BYTES_PER_ROOT * BYTES_PER_ROOT {
        bytes.sqrt()
    } else {
        runs
    }
}

/// One row: its codes, or its runs (first element, code).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Row {
    Bytes(Box<[u8]>),
    Runs(Box<[u32]>, Box<[u8]>),
}

/// Class codes ([`super::PairClass::code`]) of every (row block, element)
/// pair. Equal tables hold equal codes (a row's storage follows from its
/// codes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClassTable {
    /// Elements per row.
    n: usize,
    rows: Vec<Row>,
}

impl ClassTable {
    /// The table of `rows`, each of `n` codes.
    pub fn new(n: usize, rows: impl IntoIterator<Item = Vec<u8>>) -> Self {
        let rows = rows.into_iter().map(|r| Self::encode(n, &r)).collect();
        Self { n, rows }
    }

    /// The table of rows already encoded by [`ClassTable::encode`] (so a
    /// caller classifying rows in parallel never holds n² bytes).
    pub(super) fn from_encoded(n: usize, rows: Vec<Row>) -> Self {
        Self { n, rows }
    }

    /// One row's storage: its runs when they take fewer bytes.
    pub(super) fn encode(n: usize, row: &[u8]) -> Row {
        assert_eq!(row.len(), n, "a row of n codes");
        let runs = 1 + row.windows(2).filter(|w| w[0] != w[1]).count();
        if row.is_empty() || 5 * runs >= n || n > u32::MAX as usize {
            return Row::Bytes(row.into());
        }
        let (mut starts, mut codes) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
        for (k, &c) in row.iter().enumerate() {
            if codes.last() != Some(&c) {
                starts.push(k as u32);
                codes.push(c);
            }
        }
        Row::Runs(starts.into(), codes.into())
    }

    /// A row of `n` culled pairs (one run), without writing `n` codes.
    pub(super) fn culled(n: usize) -> Row {
        if n == 0 || n > u32::MAX as usize {
            return Row::Bytes(vec![0u8; n].into());
        }
        Row::Runs(vec![0u32].into(), vec![0u8].into())
    }

    /// Elements per row.
    pub fn width(&self) -> usize {
        self.n
    }

    /// Rows (row blocks).
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when there is no row.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The code of (row `kp`, element `k`).
    pub fn get(&self, kp: usize, k: usize) -> u8 {
        match &self.rows[kp] {
            Row::Bytes(b) => b[k],
            Row::Runs(starts, codes) => codes[starts.partition_point(|&s| s as usize <= k) - 1],
        }
    }

    /// The codes of row `kp` for elements `range`: borrowed when the row
    /// is stored as bytes, decoded from its runs otherwise.
    pub fn row(&self, kp: usize, range: Range<usize>) -> Cow<'_, [u8]> {
        match &self.rows[kp] {
            Row::Bytes(b) => Cow::Borrowed(&b[range]),
            Row::Runs(..) => {
                let mut out = Vec::with_capacity(range.len());
                for (run, c) in self.runs(kp, range) {
                    out.resize(out.len() + run.len(), c);
                }
                Cow::Owned(out)
            }
        }
    }

    /// The runs of equal codes of row `kp` within `range`, in order (runs
    /// of a row stored as bytes are found as they are read).
    pub fn runs(&self, kp: usize, range: Range<usize>) -> Runs<'_> {
        let at = match &self.rows[kp] {
            Row::Bytes(_) => 0,
            Row::Runs(starts, _) => {
                starts
                    .partition_point(|&s| s as usize <= range.start)
                    .max(1)
                    - 1
            }
        };
        Runs {
            row: &self.rows[kp],
            n: self.n,
            next: range.start,
            end: range.end,
            at,
        }
    }

    /// Bytes on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.rows.capacity() * std::mem::size_of::<Row>()
            + self
                .rows
                .iter()
                .map(|r| match r {
                    Row::Bytes(b) => b.len(),
                    Row::Runs(s, c) => 4 * s.len() + c.len(),
                })
                .sum::<usize>()
    }
}

/// The runs of one row within a range: (elements, code).
#[derive(Debug)]
pub struct Runs<'a> {
    row: &'a Row,
    n: usize,
    next: usize,
    end: usize,
    /// The run holding `next` (rows stored as runs).
    at: usize,
}

impl Iterator for Runs<'_> {
    type Item = (Range<usize>, u8);

    fn next(&mut self) -> Option<Self::Item> {
        if self.next >= self.end {
            return None;
        }
        let start = self.next;
        let (stop, code) = match self.row {
            Row::Bytes(b) => {
                let c = b[start];
                let len = b[start..self.end].iter().take_while(|&&x| x == c).count();
                (start + len, c)
            }
            Row::Runs(starts, codes) => {
                let stop = starts.get(self.at + 1).map_or(self.n, |&s| s as usize);
                let c = codes[self.at];
                self.at += 1;
                (stop.min(self.end), c)
            }
        };
        self.next = stop;
        Some((start..stop, code))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_and_its_inverse() {
        for n in [10.0, 1000.0, 1936.0, 5000.0, 1e5, 4e6] {
            let b = estimated_bytes(n);
            assert!(b <= n * n);
            crate::assert_close!(elements_within(b), n, 1e-9 * n);
        }
        crate::assert_close!(estimated_bytes(1e4), 4.4e7, 1e-3);
    }

    /// Rows with few runs are stored as runs, others as bytes; every code,
    /// row slice and run list reads back what was given.
    #[test]
    fn reads_back_what_was_stored() {
        let n = 200;
        let runs: Vec<u8> = (0..n).map(|k| (k / 37) as u8 * 3).collect();
        let noisy: Vec<u8> = (0..n).map(|k| (k * 7919 % 13) as u8).collect();
        let table = ClassTable::new(n, [runs.clone(), noisy.clone(), vec![5; n]]);
        assert!(matches!(table.rows[0], Row::Runs(..)));
        assert!(matches!(table.rows[1], Row::Bytes(_)));
        assert!(table.heap_bytes() < 3 * n);
        for (kp, row) in [runs, noisy, vec![5; n]].iter().enumerate() {
            for k in 0..n {
                assert_eq!(table.get(kp, k), row[k]);
            }
            for range in [0..n, 0..1, 36..38, 37..74, 50..51, 199..200, 10..10] {
                assert_eq!(&*table.row(kp, range.clone()), &row[range.clone()]);
                let mut seen = Vec::new();
                let mut last: Option<u8> = None;
                for (r, c) in table.runs(kp, range.clone()) {
                    assert!(!r.is_empty());
                    assert!(row[r.clone()].iter().all(|&x| x == c));
                    assert_ne!(last, Some(c), "runs are maximal");
                    last = Some(c);
                    seen.extend(r);
                }
                assert_eq!(seen, range.collect::<Vec<_>>());
            }
        }
    }

    /// The plans of the built-in room and Cornell box: every pair counted
    /// once over the runs (f_r rows each), each code the one the pair's
    /// class gives, and the table within its estimate and under 3/4 of a
    /// byte per pair (0.36 on the room's 5 120 elements, 0.72 on the
    /// Cornell box's 3 368: the share falls as √n).
    #[test]
    #[cfg(feature = "scenes")]
    fn plans_keep_their_classes_as_runs() {
        use crate::assembly::{AssemblyPlan, QuadratureOptions};
        use crate::discretization::Discretization;
        use crate::mesh::Mesh;
        use crate::nodes::NodeSet;
        use std::sync::Arc;
        for (name, level, h) in [("room", 4, None), ("cornell", 0, Some(85.0))] {
            let scene = crate::scene::builtin(name).unwrap().unwrap();
            let mesh = Arc::new(match h {
                None => Mesh::new(scene.surface.clone(), level),
                Some(h) => Mesh::with_max_edge(scene.surface.clone(), level, h),
            });
            let disc = Arc::new(Discretization::new(mesh, NodeSet::new(1, 0.2).unwrap()));
            let vis = crate::visibility::analyze(&scene.surface);
            let plan = AssemblyPlan::new(disc.clone(), QuadratureOptions::default(), &vis);
            let (t, n) = (plan.classes(), disc.mesh().len());
            let s = plan.stats();
            let pairs =
                s.pairs_far + s.pairs_near + s.pairs_self + s.pairs_culled + s.pairs_partial;
            assert_eq!(pairs, (3 * n * n) as u64, "{name}");
            for kp in (0..n).step_by(7) {
                let row = t.row(kp, 0..n);
                for k in 0..n {
                    assert_eq!(row[k], plan.class(kp, k).code());
                }
            }
            let bytes = t.heap_bytes() as f64;
            assert!(
                bytes <= estimated_bytes(n as f64),
                "{name}: {bytes} for {n}"
            );
            assert!(bytes < 0.75 * (n * n) as f64, "{name}: {bytes} for {n}");
        }
    }
}
