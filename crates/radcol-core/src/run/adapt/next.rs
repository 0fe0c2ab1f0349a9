//! From one step of the adaptive loop to the next: the marked elements
//! split 4:1 in place (or, with a degree per element, split one degree
//! lower or raised: [`super::hp`]), and the solution carried to the new
//! nodes as GMRES's starting point.

use super::history::History;
use super::hp::{Change, Degrees};
use crate::assembly::Unchanged;
use crate::geometry::barycentric_st;
use crate::mesh::Mesh;
use crate::nodes::NodeSet;
use crate::run::SolveOutcome;
use crate::solution::Solution;
use std::sync::Arc;

/// `n` flags, set at `split`.
fn marks(n: usize, split: &[usize]) -> Vec<bool> {
    let mut m = vec![false; n];
    for &k in split {
        m[k] = true;
    }
    m
}

/// `mesh` with the elements `split` replaced in place by their four
/// children, and each new element's parent in `mesh`.
pub fn refine(mesh: &Mesh, split: &[usize]) -> (Mesh, Vec<usize>) {
    let marked = marks(mesh.len(), split);
    let mut elements = Vec::with_capacity(mesh.len() + 3 * split.len());
    let mut parents = Vec::with_capacity(elements.capacity());
    for (k, e) in mesh.elements().iter().enumerate() {
        if marked[k] {
            elements.extend(e.children());
            parents.extend([k; 4]);
        } else {
            elements.push(*e);
            parents.push(k);
        }
    }
    let refined = Mesh::from_elements(mesh.surface().clone(), mesh.level(), elements);
    (refined, parents)
}

/// What the next step starts from.
pub(super) struct Carried {
    /// The refined mesh.
    pub(super) mesh: Arc<Mesh>,
    /// The solution of every channel at its nodes (GMRES's start).
    pub(super) guess: Vec<Vec<f64>>,
    /// The elements' estimate history.
    pub(super) history: History,
    /// Which elements it shares with the previous mesh.
    pub(super) unchanged: Arc<Unchanged>,
    /// With a degree per element, every element's degree and lineage.
    pub(super) degrees: Option<Degrees>,
}

/// The step after `out` ([`advance`]), with the solution transferred and
/// the `history` carried over.
pub(super) fn carry(
    out: &SolveOutcome,
    marked: &[usize],
    (indicator, negative): (&[f64], &[bool]),
    degrees: Option<&Degrees>,
    history: &History,
) -> Carried {
    let next = advance(out, marked, (indicator, negative), degrees);
    let guess = transfer(out, &next.mesh, &next.parents, &|k| next.nodes(k, out));
    let mut history = history.refined(&next.parents, &next.changed, indicator);
    for &k in &next.lowered {
        history.forget(k);
    }
    Carried {
        guess,
        history,
        unchanged: Arc::new(Unchanged::refined(&next.parents, &next.changed)),
        mesh: Arc::new(next.mesh),
        degrees: next.degrees,
    }
}

/// The next step's mesh and degrees.
struct Next {
    /// The refined mesh.
    mesh: Mesh,
    /// Each new element's element in the previous mesh.
    parents: Vec<usize>,
    /// Per previous element: split or raised (its rows and columns are
    /// computed again).
    changed: Vec<bool>,
    /// New elements one degree lower than their parent.
    lowered: Vec<usize>,
    /// With a degree per element, every new element's degree and lineage.
    degrees: Option<Degrees>,
}

impl Next {
    /// The node set of new element `k` (`out`: the previous solve).
    fn nodes<'a>(&'a self, k: usize, out: &'a SolveOutcome) -> &'a NodeSet {
        match &self.degrees {
            Some(d) => d.set(d.degrees()[k]),
            None => out.discretization.nodes_of(self.parents[k]),
        }
    }
}

/// The step after `out`: the `marked` elements (`indicator` and where u_n
/// is `negative` per element) split, or with hp split, split one degree
/// lower or raised as [`Degrees::choose`] decides.
fn advance(
    out: &SolveOutcome,
    marked: &[usize],
    (indicator, negative): (&[f64], &[bool]),
    degrees: Option<&Degrees>,
) -> Next {
    let changes = match degrees {
        Some(d) => d.choose(out, marked, indicator, negative),
        None => vec![Change::Split; marked.len()],
    };
    let mesh = out.discretization.mesh();
    let taking = |want: &dyn Fn(Change) -> bool| -> Vec<usize> {
        let pairs = marked.iter().zip(&changes);
        pairs.filter(|(_, &c)| want(c)).map(|(&k, _)| k).collect()
    };
    let (refined, parents) = refine(mesh, &taking(&|c| c != Change::Raise));
    let changed = marks(mesh.len(), marked);
    let lower = marks(mesh.len(), &taking(&|c| c == Change::SplitLower));
    let lowered = (0..parents.len()).filter(|&k| lower[parents[k]]).collect();
    let degrees = degrees.map(|d| d.follow(marked, &changes, indicator, &parents));
    Next {
        mesh: refined,
        parents,
        changed,
        lowered,
        degrees,
    }
}

/// The previous solution of every channel at the nodes of `refined`, the
/// nodes of element k being `nodes(k)`.
pub(super) fn transfer<'a>(
    out: &SolveOutcome,
    refined: &Mesh,
    parents: &[usize],
    nodes: &dyn Fn(usize) -> &'a NodeSet,
) -> Vec<Vec<f64>> {
    out.channels
        .iter()
        .map(|ch| on_refined_at(&ch.solution, refined, parents, nodes))
        .collect()
}

/// `solution` at the nodes of `refined` (a mesh [`refine`] made from its
/// mesh, each element's `parents` element): on each element, its parent's
/// polynomial at the nodes of its parent's node set.
pub fn on_refined(solution: &Solution, refined: &Mesh, parents: &[usize]) -> Vec<f64> {
    let disc = solution.discretization();
    on_refined_at(solution, refined, parents, &|k| disc.nodes_of(parents[k]))
}

/// [`on_refined`] at the nodes `nodes(k)` of each element k of `refined`
/// (a degree per element: a raised or lowered element's new nodes).
pub fn on_refined_at<'a>(
    solution: &Solution,
    refined: &Mesh,
    parents: &[usize],
    nodes: &dyn Fn(usize) -> &'a NodeSet,
) -> Vec<f64> {
    let disc = solution.discretization();
    let old = disc.mesh();
    let mut at = Vec::with_capacity(refined.len() * disc.max_nodes_per_element());
    for (k, e) in refined.elements().iter().enumerate() {
        let [a, b, c] = old.elements()[parents[k]].param;
        for &[s, t] in nodes(k).points() {
            let [s, t] = barycentric_st(a, b, c, e.param_point(s, t)).unwrap_or([s, t]);
            at.push(solution.eval(parents[k], s, t));
        }
    }
    at
}
