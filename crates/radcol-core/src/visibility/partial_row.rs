//! The partly visible pairs of one row block, with their candidate
//! occluders and which of them are approximated ([`super::bounce`]).

/// The partial pairs of one row block: elements (ascending) and their
/// occluder candidates, flattened.
#[derive(Debug, Default)]
pub(crate) struct PartialRow {
    pub(crate) elements: Vec<u32>,
    ranges: Vec<(u32, u32)>,
    candidates: Vec<u32>,
    /// The closed components from whose front region every segment of the
    /// row element starts (ascending): their candidates facing away from
    /// a row point cannot block it ([`super::sealed`]).
    pub(crate) in_front: Vec<u32>,
    /// The pairs whose visibility is approximated ([`super::bounce`]),
    /// ascending: a subset of `elements`.
    approx: Vec<u32>,
    /// Their mass bounds, a row point's after another's per pair (f32
    /// rounded up).
    approx_mass: Vec<f32>,
}

impl PartialRow {
    /// Bytes held on the heap.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.elements.capacity() * 4
            + self.ranges.capacity() * 8
            + self.candidates.capacity() * 4
            + self.in_front.capacity() * 4
            + self.approx.capacity() * 4
            + self.approx_mass.capacity() * 4
    }

    /// Whether the pair with element `k` is approximated.
    pub(crate) fn is_approx(&self, k: usize) -> bool {
        self.approx.binary_search(&(k as u32)).is_ok()
    }

    /// How many pairs are approximated.
    pub(crate) fn approximated(&self) -> usize {
        self.approx.len()
    }

    /// Per row point (`rows` of them), the summed mass bounds of the
    /// approximated pairs.
    pub(crate) fn bound_sums(&self, rows: usize) -> Vec<f64> {
        let mut sums = vec![0.0; rows];
        for masses in self.approx_mass.chunks_exact(rows.max(1)) {
            sums.iter_mut()
                .zip(masses)
                .for_each(|(s, &m)| *s += m as f64);
        }
        sums
    }

    /// Marks the last pushed pair approximated, with its mass bounds.
    pub(crate) fn push_approx(&mut self, k: usize, cands: &[u32], mass: &[f64]) {
        self.push(k, cands);
        self.approx.push(k as u32);
        // Rounded up: f32 holds 6e-8 of relative error.
        let up = |m: f64| (m * (1.0 + 1e-6)) as f32;
        self.approx_mass.extend(mass.iter().map(|&m| up(m)));
    }

    /// The mass bounds of approximated pair `i` (its index in `approx`).
    fn masses_of(&self, i: usize) -> &[f32] {
        let rows = self.approx_mass.len() / self.approx.len().max(1);
        &self.approx_mass[i * rows..(i + 1) * rows]
    }

    /// This row's pairs whose element `map` sends to a new index (the
    /// others dropped), with their candidates; `map` must keep the order.
    pub(crate) fn remapped(&self, map: impl Fn(usize) -> Option<usize>) -> PartialRow {
        let mut out = PartialRow {
            in_front: self.in_front.clone(),
            ..PartialRow::default()
        };
        for (i, &k) in self.elements.iter().enumerate() {
            if let Some(nk) = map(k as usize) {
                let (start, len) = self.ranges[i];
                out.push(nk, &self.candidates[start as usize..(start + len) as usize]);
                if let Ok(a) = self.approx.binary_search(&k) {
                    out.approx.push(nk as u32);
                    out.approx_mass.extend_from_slice(self.masses_of(a));
                }
            }
        }
        out
    }

    /// The pairs of both rows (disjoint element sets), ascending.
    pub(crate) fn merged(&self, other: &PartialRow) -> PartialRow {
        // Facts about the same row element: either row's hold.
        let mut in_front = self.in_front.clone();
        in_front.extend_from_slice(&other.in_front);
        in_front.sort_unstable();
        in_front.dedup();
        let mut out = PartialRow {
            in_front,
            ..PartialRow::default()
        };
        let (mut i, mut j) = (0, 0);
        while i < self.elements.len() || j < other.elements.len() {
            let take_self = j == other.elements.len()
                || (i < self.elements.len() && self.elements[i] < other.elements[j]);
            let (row, at) = if take_self {
                (self, &mut i)
            } else {
                (other, &mut j)
            };
            let (start, len) = row.ranges[*at];
            let k = row.elements[*at];
            out.push(
                k as usize,
                &row.candidates[start as usize..(start + len) as usize],
            );
            if let Ok(a) = row.approx.binary_search(&k) {
                out.approx.push(k);
                out.approx_mass.extend_from_slice(row.masses_of(a));
            }
            *at += 1;
        }
        out
    }

    pub(crate) fn push(&mut self, k: usize, cands: &[u32]) {
        debug_assert!(self.elements.last().is_none_or(|&l| (l as usize) < k));
        self.elements.push(k as u32);
        self.ranges
            .push((self.candidates.len() as u32, cands.len() as u32));
        self.candidates.extend_from_slice(cands);
    }

    /// The candidates of the pair with element `k`, when it is listed.
    pub(crate) fn get(&self, k: usize) -> Option<&[u32]> {
        let i = self.elements.binary_search(&(k as u32)).ok()?;
        let (start, len) = self.ranges[i];
        Some(&self.candidates[start as usize..(start + len) as usize])
    }

    pub(crate) fn candidates_of(&self, k: usize) -> &[u32] {
        let i = self
            .elements
            .binary_search(&(k as u32))
            .expect("every partial pair is listed");
        let (start, len) = self.ranges[i];
        &self.candidates[start as usize..(start + len) as usize]
    }
}

/// Over a plan's partial rows: the approximated pairs (row points ×
/// elements, `nodes_per` row points in row block kp) and the largest sum of
/// mass bounds at a row point.
pub(crate) fn totals(rows: &[PartialRow], nodes_per: impl Fn(usize) -> usize) -> (u64, f64) {
    let (pairs, most) = rows
        .iter()
        .enumerate()
        .fold((0, 0.0), |(pairs, bound), (kp, r)| {
            let f = nodes_per(kp);
            let most = r.bound_sums(f).into_iter().fold(bound, f64::max);
            (pairs + (r.approximated() * f) as u64, most)
        });
    (pairs, most * (1.0 + super::bounce::APPROX_TOL))
}
