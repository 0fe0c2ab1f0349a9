//! How a piece the rules cannot integrate is split.

/// A triangle thinner than this (its height over its longest edge) is
/// split across its length instead of into four like ones
/// ([`split`]).
const THIN: f64 = 1.0 / 16.0;

/// The pieces `tri` is split into when a rule cannot integrate it: its
/// four midpoint triangles, like it, when it is shaped well. A thin piece
/// (a sliver of a clipped visible region, next to an edge or a corner) is
/// cut across instead: the four like ones of a needle are needles of half
/// its width, so next to a point at its wide end every level doubled the
/// pieces near the point, to a million and more (a query a hair from a
/// block's foot corner on the Cornell box: minutes). A needle (apex a,
/// short edge bc) gives the half needle at a and the two halves of the
/// rest, [ab, b, c] and [ab, c, ca], so the pieces next to its ends grow
/// by one per level; a flat sliver (no short edge) is bisected from its
/// obtuse corner into two needles.
pub(super) fn split(tri: [[f64; 2]; 3]) -> Vec<[[f64; 2]; 3]> {
    let mid = |u: [f64; 2], v: [f64; 2]| [(u[0] + v[0]) * 0.5, (u[1] + v[1]) * 0.5];
    let len2 = |u: [f64; 2], v: [f64; 2]| (u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2);
    // Edge i is opposite corner i.
    let edges = [0, 1, 2].map(|i| len2(tri[(i + 1) % 3], tri[(i + 2) % 3]));
    let longest = (0..3)
        .max_by(|&i, &j| edges[i].total_cmp(&edges[j]))
        .unwrap_or(0);
    let shortest = (0..3)
        .min_by(|&i, &j| edges[i].total_cmp(&edges[j]))
        .unwrap_or(0);
    let [a, b, c] = tri;
    let twice_area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
    let (l2, s2) = (edges[longest], edges[shortest]);
    if twice_area >= THIN * l2 || l2 == 0.0 {
        let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
        return vec![[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]];
    }
    let rot = |i: usize| [tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]];
    if s2 * 16.0 < l2 {
        // A needle: apex a opposite the short edge bc.
        let [a, b, c] = rot(shortest);
        let (ab, ca) = (mid(a, b), mid(c, a));
        vec![[a, ab, ca], [ab, b, c], [ab, c, ca]]
    } else {
        // A flat sliver: bisect the longest edge bc from its opposite corner a.
        let [a, b, c] = rot(longest);
        let m = mid(b, c);
        vec![[a, b, m], [a, m, c]]
    }
}
