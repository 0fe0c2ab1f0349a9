//! Plans of a locally refined mesh that take what they can from the plan of
//! the mesh it was refined from.
//!
//! Every decision of the plan is local to its pair: the class of (row block
//! of element kp, element k) depends on the two elements and the quadrature
//! options, and a partly visible pair's candidate occluders on the two
//! elements and the scene's base triangles. So when both elements of a pair
//! are unchanged by the refinement, the old plan's class and candidates are
//! the new plan's, and the pair's entries of the geometric matrix are the old
//! matrix's, bit for bit (`FillMode::NotReused` skips them; a backend copies
//! them, see [`crate::assembly::AssemblyBackend::assemble_reusing`]).

use crate::matrix::DenseMatrix;
use rayon::prelude::*;

const NEW: u32 = u32::MAX;

/// Which elements of a refined mesh are elements of the mesh it was refined
/// from, both ways.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unchanged {
    old_of: Vec<u32>,
    new_of: Vec<u32>,
    /// For each element of the refined mesh, the old element it is or was
    /// split from, when known ([`Unchanged::refined`]).
    parent_of: Option<Vec<u32>>,
}

impl Unchanged {
    /// From, for each element of the refined mesh, its element in the old
    /// mesh when it is that element unchanged (`None` for new elements);
    /// `old_len` elements in the old mesh.
    ///
    /// # Panics
    /// When an old element is named twice or out of range.
    pub fn new(old_of: &[Option<usize>], old_len: usize) -> Self {
        let mut new_of = vec![NEW; old_len];
        let old_of = old_of
            .iter()
            .enumerate()
            .map(|(k, o)| match *o {
                Some(ok) => {
                    assert_eq!(new_of[ok], NEW, "old element {ok} named twice");
                    new_of[ok] = k as u32;
                    ok as u32
                }
                None => NEW,
            })
            .collect();
        Self {
            old_of,
            new_of,
            parent_of: None,
        }
    }

    /// From a refinement: each element of the refined mesh with the old
    /// element it is or was split from (`parents`), and which old elements
    /// were `split`.
    ///
    /// # Panics
    /// When a parent is out of range, or an unsplit one is named twice.
    pub fn refined(parents: &[usize], split: &[bool]) -> Self {
        let old_of: Vec<Option<usize>> =
            parents.iter().map(|&p| (!split[p]).then_some(p)).collect();
        Self {
            parent_of: Some(parents.iter().map(|&p| p as u32).collect()),
            ..Self::new(&old_of, split.len())
        }
    }

    /// Element `k` of the refined mesh's old element, or the one it was
    /// split from (None when not known).
    #[inline]
    pub fn parent(&self, k: usize) -> Option<usize> {
        match &self.parent_of {
            Some(p) => Some(p[k] as usize),
            None => self.old(k),
        }
    }

    /// Element `k` of the refined mesh in the old mesh, when unchanged.
    #[inline]
    pub fn old(&self, k: usize) -> Option<usize> {
        let o = self.old_of[k];
        (o != NEW).then_some(o as usize)
    }

    /// Old element `ok` in the refined mesh, when unchanged.
    #[inline]
    pub fn new_index(&self, ok: usize) -> Option<usize> {
        let k = self.new_of[ok];
        (k != NEW).then_some(k as usize)
    }

    /// Elements of the refined mesh.
    pub fn len(&self) -> usize {
        self.old_of.len()
    }

    /// Whether the refined mesh has no elements.
    pub fn is_empty(&self) -> bool {
        self.old_of.is_empty()
    }

    /// Elements of the old mesh.
    pub fn old_len(&self) -> usize {
        self.new_of.len()
    }

    /// Copies the entries of the pairs of unchanged elements from `previous`
    /// (the old mesh's matrix, element k's rows and columns
    /// `old[k]..old[k + 1]`) into `matrix` (the refined mesh's, `new`
    /// likewise; [`crate::discretization::Discretization::offsets`]). An
    /// unchanged element has as many unknowns in both.
    pub fn copy_blocks(
        &self,
        previous: &DenseMatrix,
        matrix: &mut DenseMatrix,
        old: &[usize],
        new: &[usize],
    ) {
        let (n_old, n_new) = (old[self.old_len()], new[self.len()]);
        assert_eq!(
            (
                previous.nrows(),
                previous.ncols(),
                matrix.nrows(),
                matrix.ncols()
            ),
            (n_old, n_old, n_new, n_new)
        );
        let cols: Vec<(usize, usize)> = (0..self.len())
            .filter_map(|k| self.old(k).map(|ok| (k, ok)))
            .collect();
        let src = previous.as_slice();
        crate::matrix::row_blocks(matrix.as_mut_slice(), new, n_new)
            .into_par_iter()
            .enumerate()
            .for_each(|(kp, block)| {
                let Some(op) = self.old(kp) else { return };
                for a in 0..new[kp + 1] - new[kp] {
                    let src = &src[(old[op] + a) * n_old..(old[op] + a + 1) * n_old];
                    let dst = &mut block[a * n_new..(a + 1) * n_new];
                    for &(k, ok) in &cols {
                        dst[new[k]..new[k + 1]].copy_from_slice(&src[old[ok]..old[ok + 1]]);
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_both_ways() {
        let u = Unchanged::new(&[Some(0), None, None, Some(2)], 3);
        assert_eq!((u.old(0), u.old(1), u.old(3)), (Some(0), None, Some(2)));
        assert_eq!(
            (u.new_index(0), u.new_index(1), u.new_index(2)),
            (Some(0), None, Some(3))
        );
        assert_eq!((u.len(), u.old_len()), (4, 3));
        assert_eq!((u.parent(0), u.parent(1)), (Some(0), None));
        // Old element 1 split into new 1..5; 0 and 2 kept.
        let r = Unchanged::refined(&[0, 1, 1, 1, 1, 2], &[false, true, false]);
        assert_eq!((r.old(0), r.old(2), r.old(5)), (Some(0), None, Some(2)));
        assert_eq!(
            (r.parent(2), r.parent(5), r.new_index(1)),
            (Some(1), Some(2), None)
        );
    }

    #[test]
    fn copies_the_unchanged_pairs_only() {
        // Old: 2 elements, f = 2; new: old 1, a new element, old 0.
        let mut prev = DenseMatrix::zeros(4, 4);
        for (i, v) in prev.as_mut_slice().iter_mut().enumerate() {
            *v = i as f64;
        }
        let u = Unchanged::new(&[Some(1), None, Some(0)], 2);
        let mut m = DenseMatrix::zeros(6, 6);
        m.as_mut_slice().fill(-1.0);
        u.copy_blocks(&prev, &mut m, &[0, 2, 4], &[0, 2, 4, 6]);
        let at = |m: &DenseMatrix, i: usize, j: usize| m.as_slice()[i * m.ncols() + j];
        // New row 0 = old row 2; new column 4 = old column 0.
        assert_eq!(at(&m, 0, 0), at(&prev, 2, 2));
        assert_eq!(at(&m, 1, 5), at(&prev, 3, 1));
        assert_eq!(at(&m, 5, 4), at(&prev, 1, 0));
        // Rows and columns of the new element are left alone.
        assert_eq!(at(&m, 2, 0), -1.0);
        assert_eq!(at(&m, 0, 2), -1.0);
    }
}
