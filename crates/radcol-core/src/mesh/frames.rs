//! Surface points of an element in batches (the rule points of near and
//! self pairs).

use super::Mesh;
use crate::geometry::{FrameBatch, FRAME_BATCH};
use glam::DVec3;

impl Mesh {
    /// [`point`](Self::point) at the batch's (s, t), given in `b.x[0]` and
    /// `b.x[1]` (overwritten by the parameter points), for the whole batch
    /// in one call of the surface map (the rule points of near and self
    /// pairs).
    pub fn frames(&self, k: usize, b: &mut FrameBatch) {
        let [a, p1, p2] = self.elements[k].param.map(|p| p.to_array());
        let (u, v) = (
            [0, 1, 2].map(|j| p1[j] - a[j]),
            [0, 1, 2].map(|j| p2[j] - a[j]),
        );
        let [xs, xt, xz] = &mut b.x;
        for i in 0..b.len.min(FRAME_BATCH) {
            let (s, t) = (xs[i], xt[i]);
            xs[i] = a[0] + u[0] * s + v[0] * t;
            xt[i] = a[1] + u[1] * s + v[1] * t;
            xz[i] = a[2] + u[2] * s + v[2] * t;
        }
        self.map_of(k)
            .frame_batch(b, DVec3::from_array(u), DVec3::from_array(v));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::{box_room, ellipsoid};
    use std::sync::Arc;

    /// A batch of points of curved (the ellipsoid's closed form) and flat
    /// (the map's default, through its tangents) elements against
    /// [`Mesh::point`] one by one.
    #[test]
    fn batched_points_are_the_points() {
        for surface in [ellipsoid(1.0, 0.8, 0.3), box_room(1.0, 2.0, 1.5)] {
            let mesh = Mesh::new(Arc::new(surface), 1);
            for k in [0, 7, mesh.len() - 1] {
                let sts: Vec<[f64; 2]> = (0..FRAME_BATCH - 3)
                    .map(|i| {
                        let s = (i % 6) as f64 / 6.0;
                        [s, (1.0 - s) * (i / 6) as f64 / 5.0]
                    })
                    .collect();
                let mut b = FrameBatch {
                    len: sts.len(),
                    ..Default::default()
                };
                for (i, &[s, t]) in sts.iter().enumerate() {
                    (b.x[0][i], b.x[1][i]) = (s, t);
                }
                mesh.frames(k, &mut b);
                for (i, &[s, t]) in sts.iter().enumerate() {
                    let want = mesh.point(k, s, t);
                    let (p, n, jac) = b.get(i);
                    assert!(
                        (p - want.position).length() <= 1e-15,
                        "{p} against {want:?}"
                    );
                    assert!((n - want.normal).length() <= 1e-14, "{n} against {want:?}");
                    crate::assert_close!(jac, want.jacobian, 1e-14 * want.jacobian);
                }
            }
        }
    }
}
