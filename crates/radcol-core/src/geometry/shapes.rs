//! Built-in analytic surfaces, as library code shared by tests, benches, CLI and users.

use super::{Identity, Patch, RadialProjection, Surface};
use glam::DVec3;
use std::sync::Arc;

/// The six vertices of the unit octahedron and its eight faces, each ordered so
/// that (b - a) × (c - a) points to the origin (inward).
fn octahedron_faces() -> Vec<(String, [DVec3; 3])> {
    let mut faces = Vec::with_capacity(8);
    for sx in [1.0f64, -1.0] {
        for sy in [1.0f64, -1.0] {
            for sz in [1.0f64, -1.0] {
                let (a, b, c) = (DVec3::X * sx, DVec3::Y * sy, DVec3::Z * sz);
                // (b-a)×(c-a) is parallel to (sy sz, sx sz, sx sy)·…: pick the order
                // whose normal points to the origin, i.e. against the centroid.
                let tri = if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                };
                let sign = |v: f64| if v > 0.0 { '+' } else { '-' };
                faces.push((
                    format!("octant {}x{}y{}z", sign(sx), sign(sy), sign(sz)),
                    tri,
                ));
            }
        }
    }
    faces
}

/// The sphere of radius `radius` centred at the origin: the octahedron projected
/// radially (8 base elements), inner normals.
pub fn sphere(radius: f64) -> Surface {
    let mut s = ellipsoid(radius, radius, radius);
    s.name = if radius == 1.0 {
        "sphere".into()
    } else {
        format!("sphere:{radius}")
    };
    s
}

/// The ellipsoid x²/a² + y²/b² + z²/c² = 1: the octahedron projected radially and
/// stretched (8 base elements), inner normals.
pub fn ellipsoid(a: f64, b: f64, c: f64) -> Surface {
    let map = Arc::new(RadialProjection {
        center: DVec3::ZERO,
        semi_axes: DVec3::new(a, b, c),
    });
    Surface {
        name: format!("ellipsoid:{a},{b},{c}"),
        patches: octahedron_faces()
            .into_iter()
            .map(|(name, tri)| Patch {
                name,
                map: map.clone(),
                triangles: vec![tri],
            })
            .collect(),
        convex_enclosure: true,
    }
}

/// The inside of the axis-aligned box `[0,lx]×[0,ly]×[0,lz]`: six walls, each two
/// triangles (12 base elements), normals pointing into the room.
pub fn box_room(lx: f64, ly: f64, lz: f64) -> Surface {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x * lx, y * ly, z * lz);
    // Each wall as a quad (a, b, c, d) in counter-clockwise order seen from inside.
    let walls: [(&str, [DVec3; 4]); 6] = [
        (
            "floor z=0",
            [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
        ),
        (
            "ceiling z=lz",
            [p(0., 0., 1.), p(0., 1., 1.), p(1., 1., 1.), p(1., 0., 1.)],
        ),
        (
            "wall y=0",
            [p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)],
        ),
        (
            "wall y=ly",
            [p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)],
        ),
        (
            "wall x=0",
            [p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
        ),
        (
            "wall x=lx",
            [p(1., 0., 0.), p(1., 0., 1.), p(1., 1., 1.), p(1., 1., 0.)],
        ),
    ];
    let map = Arc::new(Identity);
    Surface {
        name: format!("box:{lx},{ly},{lz}"),
        patches: walls
            .into_iter()
            .map(|(name, [a, b, c, d])| Patch {
                name: name.into(),
                map: map.clone(),
                triangles: vec![[a, b, c], [a, c, d]],
            })
            .collect(),
        convex_enclosure: true,
    }
}

/// A room [0, 2]³ (normals in) with a floating cube [0.7, 1.3]³ (normals out):
/// a flat scene that occludes, so its plans hold partly visible pairs.
pub fn room_with_cube() -> Surface {
    let corner = |lo: f64, hi: f64, i: usize| {
        DVec3::new(
            if i & 1 == 0 { lo } else { hi },
            if i & 2 == 0 { lo } else { hi },
            if i & 4 == 0 { lo } else { hi },
        )
    };
    // Quads counter-clockwise seen from outside the box.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let patch = |name: &str, lo: f64, hi: f64, inward: bool| {
        let triangles = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .map(|t: [usize; 3]| {
                let t = if inward { [t[0], t[2], t[1]] } else { t };
                t.map(|i| corner(lo, hi, i))
            })
            .collect();
        Patch {
            name: name.into(),
            map: Arc::new(Identity),
            triangles,
        }
    };
    Surface {
        name: "room with cube".into(),
        patches: vec![
            patch("room", 0.0, 2.0, true),
            patch("cube", 0.7, 1.3, false),
        ],
        convex_enclosure: false,
    }
}

/// A receiving floor, the square [-1, 1]² of z = 0 facing up (+z), lit by a
/// convex polygonal `emitter` through a convex polygonal `occluder`, both
/// horizontal, above the floor and facing down: the shadowed family whose
/// direct light has a closed form (Lambert's contour formula on the part of
/// the emitter each floor point sees). Polygons are fanned from their first
/// vertex; patches are named "floor", "emitter" and "occluder", in that order.
pub fn floor_under_occluder(emitter: &[DVec3], occluder: &[DVec3]) -> Surface {
    let facing_down = |poly: &[DVec3]| -> Vec<[DVec3; 3]> {
        (1..poly.len() - 1)
            .map(|i| {
                let t = [poly[0], poly[i], poly[i + 1]];
                if (t[1] - t[0]).cross(t[2] - t[0]).z > 0.0 {
                    [t[0], t[2], t[1]]
                } else {
                    t
                }
            })
            .collect()
    };
    let floor = [
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, 1.0, 0.0),
    ];
    let patch = |name: &str, triangles| Patch {
        name: name.into(),
        map: Arc::new(Identity),
        triangles,
    };
    Surface {
        name: "floor under occluder".into(),
        patches: vec![
            patch(
                "floor",
                vec![
                    [floor[0], floor[1], floor[2]],
                    [floor[0], floor[2], floor[3]],
                ],
            ),
            patch("emitter", facing_down(emitter)),
            patch("occluder", facing_down(occluder)),
        ],
        convex_enclosure: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{FrameBatch, SurfaceMap};

    /// Inward orientation: the normal (b-a)×(c-a) of every base triangle points
    /// towards the centre of the enclosure.
    fn assert_inward(s: &Surface, centre: DVec3) {
        for p in &s.patches {
            for [a, b, c] in &p.triangles {
                let (fa, fb, fc) = (p.map.map(*a), p.map.map(*b), p.map.map(*c));
                let n = (fb - fa).cross(fc - fa);
                let mid = (fa + fb + fc) / 3.0;
                assert!(
                    n.dot(centre - mid) > 0.0,
                    "{}: normal points outward",
                    p.name
                );
            }
        }
    }

    #[test]
    fn built_in_shapes_face_inward() {
        assert_inward(&sphere(2.0), DVec3::ZERO);
        assert_inward(&ellipsoid(1.0, 2.0, 3.0), DVec3::ZERO);
        assert_inward(&box_room(1.0, 2.0, 3.0), DVec3::new(0.5, 1.0, 1.5));
        assert_eq!(sphere(1.0).base_triangle_count(), 8);
        assert_eq!(box_room(1.0, 1.0, 1.0).base_triangle_count(), 12);
    }

    /// The push-forward is the derivative of the map (central differences).
    #[test]
    fn radial_projection_derivative_matches_finite_differences() {
        let f = RadialProjection {
            center: DVec3::new(0.1, 0.2, 0.3),
            semi_axes: DVec3::new(1.0, 2.0, 3.0),
        };
        let x = DVec3::new(0.3, 0.5, 0.2);
        let v = DVec3::new(-0.4, 0.1, 0.7);
        let eps = 1e-6;
        let fd = (f.map(x + v * eps) - f.map(x - v * eps)) / (2.0 * eps);
        assert!((fd - f.push_forward(x, v)).length() < 1e-8);
        // The one-call frame is the map and its two push-forwards.
        let u = DVec3::new(0.2, -0.3, 0.05);
        let [position, du, dv] = f.frame(x, u, v);
        assert!((position - f.map(x)).length() < 1e-15);
        assert!((du - f.push_forward(x, u)).length() < 1e-15);
        assert!((dv - f.push_forward(x, v)).length() < 1e-15);
    }

    /// The batched frames of the radial projection (a closed form with no
    /// tangent formed) against the tangents' cross product, on several
    /// ellipsoids and on points of every octant, the batch partly filled.
    #[test]
    fn radial_projection_batch_is_the_tangents_cross_product() {
        for (centre, axes) in [
            (DVec3::ZERO, DVec3::ONE),
            (DVec3::new(0.1, 0.2, 0.3), DVec3::new(1.0, 2.0, 3.0)),
            (DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 0.8, 0.1)),
        ] {
            let f = RadialProjection {
                center: centre,
                semi_axes: axes,
            };
            let (u, v) = (DVec3::new(-0.4, 0.1, 0.7), DVec3::new(0.2, -0.3, 0.05));
            let mut b = FrameBatch {
                len: 27,
                ..Default::default()
            };
            for i in 0..b.len {
                let sign = |bit: usize| if (i >> bit) & 1 == 0 { 1.0 } else { -1.0 };
                let x = DVec3::new(
                    0.3 * sign(0),
                    0.5 * sign(1),
                    (0.2 + 0.01 * i as f64) * sign(2),
                );
                (b.x[0][i], b.x[1][i], b.x[2][i]) = (x.x, x.y, x.z);
            }
            let xs: Vec<DVec3> = (0..b.len)
                .map(|i| DVec3::new(b.x[0][i], b.x[1][i], b.x[2][i]))
                .collect();
            f.frame_batch(&mut b, u, v);
            for (i, &x) in xs.iter().enumerate() {
                let [position, du, dv] = f.frame(x, u, v);
                let cross = du.cross(dv);
                let (p, n, jac) = b.get(i);
                assert!((p - position).length() <= 1e-15 * position.length().max(1.0));
                assert!(
                    (n - cross.normalize()).length() <= 1e-14,
                    "{n} against {cross}"
                );
                crate::assert_close!(jac, cross.length(), 1e-14 * cross.length());
            }
        }
    }
}
