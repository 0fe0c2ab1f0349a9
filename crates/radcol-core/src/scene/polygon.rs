//! Triangulating an OBJ polygon, whatever its convexity.
//!
//! A fan from the first vertex is right only for convex polygons: an L-shaped
//! face listed from its reflex vertex (`f 3 4 5 6 1 2`) gives a flipped
//! triangle outside the L (∫u 9.5 % off, without a word). The polygon is
//! projected on the plane of its Newell normal and ear-clipped by `earcutr`
//! (a port of Mapbox's earcut); every triangle is then turned to the
//! polygon's orientation. When the triangles' areas do not add up to the
//! polygon's own area, the polygon crosses itself, and the caller warns.

use glam::{DVec2, DVec3};

/// Triangles of a polygon, as indices into its vertex list.
#[derive(Debug)]
pub(crate) struct Triangulated {
    pub(crate) triangles: Vec<[usize; 3]>,
    /// Sum of the triangles' areas over the polygon's (Newell) area, when
    /// they differ by more than 1e-9: the polygon intersects itself.
    pub(crate) self_intersecting: Option<f64>,
}

/// The Newell normal: twice the polygon's vector area (zero for a polygon
/// of no area).
pub(crate) fn newell(points: &[DVec3]) -> DVec3 {
    let n = points.len();
    (0..n).fold(DVec3::ZERO, |acc, i| {
        acc + points[i].cross(points[(i + 1) % n])
    })
}

/// Triangulates `points` (at least 3) by ear clipping on the plane of their
/// Newell normal. Triangles and quads that are convex keep the fan from the
/// first vertex, so files of triangles and convex quads mesh as before.
pub(crate) fn triangulate(points: &[DVec3]) -> Triangulated {
    let n = points.len();
    let normal = newell(points);
    let fan = || (1..n - 1).map(|i| [0, i, i + 1]).collect::<Vec<_>>();
    if n == 3 || normal.length() == 0.0 || !normal.is_finite() {
        // Triangles, and polygons of no area: degenerate ones (dropped later)
        // or ones whose lobes cancel, such as a bow tie.
        return Triangulated {
            triangles: fan(),
            self_intersecting: (n > 3 && normal.length() == 0.0).then_some(f64::INFINITY),
        };
    }
    let unit = normal.normalize();
    if is_convex(points, unit) {
        return Triangulated {
            triangles: fan(),
            self_intersecting: None,
        };
    }
    // Coordinates in the polygon's plane, centred for precision.
    let u = unit.any_orthonormal_vector();
    let v = unit.cross(u);
    let centre = points.iter().copied().sum::<DVec3>() / n as f64;
    let flat: Vec<DVec2> = points
        .iter()
        .map(|&p| DVec2::new((p - centre).dot(u), (p - centre).dot(v)))
        .collect();
    let coords: Vec<f64> = flat.iter().flat_map(|p| [p.x, p.y]).collect();
    let indices = earcutr::earcut(&coords, &[], 2).unwrap_or_default();
    let mut triangles: Vec<[usize; 3]> = indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]];
            // Counter-clockwise in (u, v) is the Newell normal's side.
            if (flat[b] - flat[a]).perp_dot(flat[c] - flat[a]) >= 0.0 {
                [a, b, c]
            } else {
                [a, c, b]
            }
        })
        .collect();
    let area: f64 = triangles
        .iter()
        .map(|t| {
            0.5 * (flat[t[1]] - flat[t[0]])
                .perp_dot(flat[t[2]] - flat[t[0]])
                .abs()
        })
        .sum();
    let polygon_area = 0.5 * normal.length();
    let ratio = area / polygon_area;
    let self_intersecting = ((ratio - 1.0).abs() > 1e-9 || triangles.is_empty()).then_some(ratio);
    if triangles.is_empty() {
        triangles = fan();
    }
    Triangulated {
        triangles,
        self_intersecting,
    }
}

/// True when every corner of the polygon turns the same way about `normal`
/// (collinear corners allowed) and the turns add up to one full turn (a
/// pentagram turns the same way at every corner, twice around).
fn is_convex(points: &[DVec3], normal: DVec3) -> bool {
    let n = points.len();
    let scale = points
        .iter()
        .map(|p| (*p - points[0]).length_squared())
        .fold(0.0, f64::max);
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
        let (d1, d2) = (b - a, c - b);
        let sin = d1.cross(d2).dot(normal);
        if sin < -1e-12 * scale {
            return false;
        }
        turning += sin.atan2(d1.dot(d2));
    }
    (turning - std::f64::consts::TAU).abs() < 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(points: &[DVec3], tris: &[[usize; 3]]) -> DVec3 {
        tris.iter()
            .map(|t| 0.5 * (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]))
            .sum()
    }

    /// The L of the issue: the unit square's corners and a notch, listed
    /// from the reflex vertex.
    fn l_shape() -> Vec<DVec3> {
        // (0,0) (2,0) (2,1) (1,1) (1,2) (0,2): the reflex corner is (1,1).
        let l = [[0., 0.], [2., 0.], [2., 1.], [1., 1.], [1., 2.], [0., 2.]];
        let pts: Vec<DVec3> = l.iter().map(|p| DVec3::new(p[0], p[1], 0.5)).collect();
        // Start at the reflex vertex: f 4 5 6 1 2 3.
        (0..6).map(|i| pts[(i + 3) % 6]).collect()
    }

    #[test]
    fn concave_polygons_from_any_vertex_cover_exactly_their_area() {
        let l = l_shape();
        for start in 0..6 {
            let pts: Vec<DVec3> = (0..6).map(|i| l[(i + start) % 6]).collect();
            let t = triangulate(&pts);
            assert_eq!(t.triangles.len(), 4);
            assert!(t.self_intersecting.is_none(), "{start}: {t:?}");
            // Every triangle faces +z (the polygon's side) and they add up to 3.
            for tri in &t.triangles {
                let n = (pts[tri[1]] - pts[tri[0]]).cross(pts[tri[2]] - pts[tri[0]]);
                assert!(n.z > 0.0, "{start}: {tri:?}");
            }
            assert!((area(&pts, &t.triangles) - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-14);
            // Every triangle's centroid is inside the L (not in the notch).
            for tri in &t.triangles {
                let c = (pts[tri[0]] + pts[tri[1]] + pts[tri[2]]) / 3.0;
                assert!(!(c.x > 1.0 && c.y > 1.0), "{start}: {c}");
            }
        }
        // A fan, for comparison, is right only from the two corners the whole
        // L is seen from, (0, 0) and the reflex (1, 1); from the other four it
        // flips a triangle over the notch.
        let flipped_fans = (0..6)
            .filter(|&start| {
                let p = |i: usize| l[(i + start) % 6];
                (1..5).any(|i| (p(i) - p(0)).cross(p(i + 1) - p(0)).z < 0.0)
            })
            .count();
        assert_eq!(flipped_fans, 4);
    }

    #[test]
    fn tilted_and_clockwise_polygons_keep_their_orientation() {
        // The L turned clockwise (normal −z), then tilted out of every axis plane.
        let rot = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let mut l = l_shape();
        l.reverse();
        let pts: Vec<DVec3> = l
            .iter()
            .map(|&p| rot * p + DVec3::new(5.0, -3.0, 2.0))
            .collect();
        let want = rot * DVec3::new(0.0, 0.0, -3.0);
        let t = triangulate(&pts);
        assert!((area(&pts, &t.triangles) - want).length() < 1e-12, "{t:?}");
        assert!(t.self_intersecting.is_none());
    }

    #[test]
    fn convex_polygons_keep_the_fan_and_bow_ties_are_flagged() {
        let quad = [[0., 0.], [1., 0.], [1., 1.], [0., 1.]].map(|p| DVec3::new(p[0], p[1], 0.0));
        let t = triangulate(&quad);
        assert_eq!(t.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        // A bow tie (edges 1-2 and 3-0 cross): its two lobes cancel in the
        // Newell area, so the triangles' area cannot match it.
        let bow = [[0., 0.], [1., 1.], [1., 0.], [0., 1.]].map(|p| DVec3::new(p[0], p[1], 0.0));
        let t = triangulate(&bow);
        assert!(t.self_intersecting.is_some(), "{t:?}");
        // A star pentagram's five points over its convex pentagon.
        let star: Vec<DVec3> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        assert!(triangulate(&star).self_intersecting.is_some());
    }

    #[test]
    fn large_comb_polygons_are_triangulated_whole() {
        // A comb with 20 000 teeth: 80 000 vertices, every other one reflex.
        let mut pts = Vec::new();
        let teeth = 20_000;
        for k in 0..teeth {
            let x = k as f64;
            pts.extend([[x, 0.0], [x, 1.0], [x + 0.5, 1.0], [x + 0.5, 0.1]]);
        }
        pts.push([teeth as f64, 0.1]);
        pts.push([teeth as f64, -1.0]);
        pts.push([0.0, -1.0]);
        let pts: Vec<DVec3> = pts.iter().map(|p| DVec3::new(p[0], p[1], 0.0)).collect();
        let t = triangulate(&pts);
        assert_eq!(t.triangles.len(), pts.len() - 2);
        let want = newell(&pts) * 0.5;
        assert!((area(&pts, &t.triangles) - want).length() < 1e-9 * want.length());
    }
}
