//! Lightmaps in the input's own texture coordinates: the layout an engine
//! already has for its lightmaps (glTF TEXCOORD_1, or the only set; OBJ
//! `vt`), used as given when it lies in the unit square, one chart per
//! patch. Texels are baked through each element's corners mapped into the
//! coordinates of its surface triangle (affine on a flat triangle), and a
//! layout that puts one texel inside two triangles is refused.

use super::{plane_of, raster, Atlas, Chart, RenderError};
use crate::geometry::Surface;
use glam::DVec3;

/// A surface triangle's corners in space and in texture coordinates.
pub(super) type Corners = ([DVec3; 3], [[f64; 2]; 3]);

impl Atlas {
    /// The atlas of the input's texture coordinates `uvs` (per patch and
    /// triangle of `surface`, as [`crate::scene::Scene::uvs`]; v down from
    /// the top) at `size`×`size` texels. `density` is then the mean texel
    /// density, √(texel area / surface area).
    ///
    /// # Errors
    /// A curved patch, a size outside 16..=16384, `uvs` that do not match
    /// the surface's triangles, coordinates outside [0, 1] or not finite,
    /// a triangle whose coordinates have no area (it would get no texel),
    /// and two triangles over one texel centre (a lightmap needs a unique
    /// layout), each naming the patch and triangle.
    pub fn from_uvs(
        surface: &Surface,
        uvs: &[Vec<[[f64; 2]; 3]>],
        size: u32,
    ) -> Result<Self, RenderError> {
        let bad = |m: String| Err(RenderError::Lightmap(m));
        if !(16..=16384).contains(&size) {
            return bad(format!("atlas size {size}: must lie in 16..=16384 texels"));
        }
        if uvs.len() != surface.patches.len()
            || uvs
                .iter()
                .zip(&surface.patches)
                .any(|(u, p)| u.len() != p.triangles.len())
        {
            return bad("the texture coordinates do not match the surface's triangles".into());
        }
        let (lo, hi) = surface.bounding_box();
        let scale = (hi - lo).length().max(f64::MIN_POSITIVE);
        let (mut charts, mut input) = (Vec::new(), Vec::new());
        let (mut uv_area, mut area) = (0.0, 0.0);
        for (j, (patch, uvs)) in surface.patches.iter().zip(uvs).enumerate() {
            let mut chart = Chart {
                patch: j,
                triangles: Vec::new(),
            };
            let mut corners = Vec::new();
            for (t, (tri, uv)) in patch.triangles.iter().zip(uvs).enumerate() {
                let at = || format!("patch '{}' triangle {t}", patch.name);
                if let Some(x) = uv.iter().flatten().find(|x| !(0.0..=1.0).contains(*x)) {
                    return bad(format!(
                        "{}: texture coordinate {x} outside [0, 1]: a lightmap's layout lies in the \
                         unit square (tiling sets are not); give the scene a lightmap set \
                         (glTF TEXCOORD_1) or generate a layout (`Atlas::new`)",
                        at()
                    ));
                }
                let v = tri.map(|x| patch.map.map(x));
                let a = coordinate_area(uv);
                if plane_of(patch, tri, scale)?.is_some() && a == 0.0 {
                    return bad(format!(
                        "{}: its texture coordinates have no area, so it would get no texel; \
                         give the scene a lightmap set (glTF TEXCOORD_1) or generate a layout (`Atlas::new`)",
                        at()
                    ));
                }
                uv_area += a.abs();
                area += space_area(&v);
                chart.triangles.push(t);
                corners.push((v, *uv));
            }
            charts.push(chart);
            input.push(corners);
        }
        overlaps(&input, size).check(surface)?;
        let texels = uv_area * (size as f64).powi(2);
        Ok(Self {
            size,
            density: if area > 0.0 {
                (texels / area).sqrt()
            } else {
                0.0
            },
            charts,
            generated_charts: None,
            input,
        })
    }
}

impl Atlas {
    /// The atlas of the input's texture coordinates `uvs` sized for
    /// `texels_per_unit` texels per scene unit of length on average: the
    /// side is `texels_per_unit` · √(surface area / coordinate area),
    /// rounded up, at least 16 (so `density` is at least the one asked).
    ///
    /// # Errors
    /// A density that is not positive and finite or that needs more than
    /// 16384 texels a side (the error says the largest that fits), and
    /// the errors of [`Atlas::from_uvs`].
    pub fn from_uvs_with_density(
        surface: &Surface,
        uvs: &[Vec<[[f64; 2]; 3]>],
        texels_per_unit: f64,
    ) -> Result<Self, RenderError> {
        let bad = |m: String| Err(RenderError::Lightmap(m));
        if !(texels_per_unit.is_finite() && texels_per_unit > 0.0) {
            return bad(format!(
                "texel density {texels_per_unit}: must be positive and finite"
            ));
        }
        let (mut uv_area, mut area) = (0.0, 0.0);
        for (patch, uvs) in surface.patches.iter().zip(uvs) {
            for (tri, uv) in patch.triangles.iter().zip(uvs) {
                area += space_area(&tri.map(|x| patch.map.map(x)));
                uv_area += coordinate_area(uv).abs();
            }
        }
        let side = texels_per_unit * (area / uv_area).sqrt();
        if !side.is_finite() {
            // No coordinate area (or no area at all): from_uvs says which
            // triangle.
            return Self::from_uvs(surface, uvs, 16);
        }
        if side > 16384.0 {
            let fits = 16384.0 * (uv_area / area).sqrt();
            return bad(format!(
                "texel density {texels_per_unit}: the texture coordinates need a \
                 {side:.0}×{side:.0} atlas, more than 16384 texels a side; a density up to \
                 about {fits:.3e} fits"
            ));
        }
        Self::from_uvs(surface, uvs, (side.ceil() as u32).max(16))
    }
}

/// The signed area of a triangle in texture coordinates.
fn coordinate_area(uv: &[[f64; 2]; 3]) -> f64 {
    0.5 * ((uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1])
        - (uv[2][0] - uv[0][0]) * (uv[1][1] - uv[0][1]))
}

/// The area of a triangle in space.
fn space_area(v: &[DVec3; 3]) -> f64 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// The texture coordinates at `x` of the flat triangle `v` whose corners
/// have `uv` (affine in the triangle's plane; x projected onto it).
pub(super) fn interpolate(v: &[DVec3; 3], uv: &[[f64; 2]; 3], x: DVec3) -> [f64; 2] {
    let [s, t] = crate::geometry::plane_st(v[0], v[1], v[2], x);
    [0, 1].map(|i| uv[0][i] + s * (uv[1][i] - uv[0][i]) + t * (uv[2][i] - uv[0][i]))
}

/// The texel centres inside two triangles of `input` at `size` texels.
fn overlaps(input: &[Vec<Corners>], size: u32) -> Overlap {
    let n = size as usize;
    // The first triangle over each texel: 1 + its index over all patches
    // (4 bytes a texel: 1 GiB at the largest size), 0 for none.
    let mut owner = vec![0u32; n * n];
    let mut triangles: Vec<(u32, u32)> = Vec::new();
    let mut overlap = Overlap::default();
    for (j, tris) in input.iter().enumerate() {
        for (t, (_, uv)) in tris.iter().enumerate() {
            let me = (j as u32, t as u32);
            triangles.push(me);
            let id = triangles.len() as u32;
            raster(
                uv.map(|c| c.map(|a| a * size as f64)),
                n,
                |i, _, _, inside| match owner[i] {
                    0 => owner[i] = id,
                    other if inside => overlap.note(triangles[other as usize - 1], me),
                    _ => {}
                },
            );
        }
    }
    overlap
}

/// Texel centres inside two surface triangles: how many, and the first pair.
#[derive(Debug, Default)]
struct Overlap {
    count: usize,
    first: Option<((u32, u32), (u32, u32))>,
}

impl Overlap {
    /// A texel inside triangle `b` that triangle `a` covered first.
    fn note(&mut self, a: (u32, u32), b: (u32, u32)) {
        self.count += 1;
        self.first.get_or_insert((a, b));
    }

    /// Refuses a layout with overlapping triangles, naming the first pair.
    fn check(&self, surface: &Surface) -> Result<(), RenderError> {
        let Some((a, b)) = self.first else {
            return Ok(());
        };
        let name = |(j, t): (u32, u32)| {
            format!("patch '{}' triangle {t}", surface.patches[j as usize].name)
        };
        Err(RenderError::Lightmap(format!(
            "the input's texture coordinates overlap: {} texels lie inside two triangles (first {} \
             and {}); a lightmap needs each texel in one place: give the scene a lightmap set \
             (glTF TEXCOORD_1) or generate a layout (`Atlas::new`)",
            self.count,
            name(a),
            name(b)
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::super::bake;
    use super::*;
    use crate::discretization::Discretization;
    use crate::mesh::Mesh;
    use crate::nodes::NodeSet;
    use crate::scene::{Material, SceneBuilder};
    use crate::solution::Solution;
    use std::f64::consts::PI;
    use std::sync::Arc;

    /// A 2 × 1 floor whose texture coordinates are rotated and scaled
    /// (u = 0.1 + 0.4 y, v = 0.05 + 0.45 x), and a lamp above it mapped to
    /// `lamp_uv`.
    fn scene(lamp_uv: [[f64; 2]; 4]) -> crate::scene::Scene {
        let mut b = SceneBuilder::new("uv");
        let white = b
            .add_material(Material::diffuse("white", [0.5; 3]))
            .unwrap();
        let light = b
            .add_material(Material::emitter("light", [0.0; 3], [1.0; 3]))
            .unwrap();
        let rect =
            |z: f64| [(0., 0.), (2., 0.), (2., 1.), (0., 1.)].map(|(x, y)| DVec3::new(x, y, z));
        let floor = rect(0.0);
        let uv: Vec<[f64; 2]> = floor
            .iter()
            .map(|p| [0.1 + 0.4 * p.y, 0.05 + 0.45 * p.x])
            .collect();
        b.add_mesh_with_uvs("floor", &floor, &uv, &[[0, 1, 2], [0, 2, 3]], white)
            .unwrap();
        b.add_mesh_with_uvs("lamp", &rect(1.0), &lamp_uv, &[[0, 2, 1], [0, 3, 2]], light)
            .unwrap();
        b.build().unwrap()
    }

    /// A u_n linear in position bakes, at every texel centre of the floor,
    /// to that function at the point the floor's own coordinates put there
    /// (inverted by hand here); the layout is the input's, not packed.
    #[test]
    fn texels_follow_the_input_coordinates() {
        let s = scene([[0.6, 0.1], [0.9, 0.1], [0.9, 0.3], [0.6, 0.3]]);
        let atlas = Atlas::from_uvs(&s.surface, s.uvs.as_ref().unwrap(), 256).unwrap();
        assert!(atlas.is_input());
        assert_eq!(atlas.charts.len(), 2);
        let mesh = Arc::new(Mesh::new(s.surface.clone(), 2));
        let disc = Arc::new(Discretization::new(
            mesh.clone(),
            NodeSet::new(1, 0.2).unwrap(),
        ));
        let f = |x: DVec3| 1.0 + 0.3 * x.x - 0.2 * x.y + 0.5 * x.z;
        let u = Solution::new(
            disc.clone(),
            disc.points().iter().map(|p| f(p.position)).collect(),
        );
        let img = bake(&mesh, &[&u], &atlas).unwrap();
        let n = 256usize;
        let mut checked = 0;
        for y in 0..n {
            for x in 0..n {
                let (tu, tv) = ((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
                let (px, py) = ((tv - 0.05) / 0.45, (tu - 0.1) / 0.4);
                let inside = (0.01..1.99).contains(&px) && (0.01..0.99).contains(&py);
                if !inside {
                    continue;
                }
                assert_eq!(img.coverage[y * n + x], 1.0, "({x}, {y})");
                let got = img.rgb[y * n + x][0] as f64 * PI;
                let want = f(DVec3::new(px, py, 0.0));
                crate::assert_close!(got, want, 2e-6 * want);
                checked += 1;
            }
        }
        // 0.45 × 256 by 0.4 × 256 texels, less the margin
        assert!(checked > 10_000, "{checked}");
        // the mean density: floor 0.9 × 0.4 of the atlas for 2 units²
        let texels = (0.9 * 0.4 * 0.5 + 0.3 * 0.2 * 0.5) * 2.0 * 65536.0;
        crate::assert_close!(atlas.density, (texels / 4.0f64).sqrt(), 1e-9);
    }

    /// At a chosen density the side is density · √(area / coordinate
    /// area), rounded up (here 4 units² on 0.4 · 0.9 + 0.3 · 0.2 = 0.42 of
    /// the square), at least 16; densities needing more than 16384 texels
    /// or not positive are refused.
    #[test]
    fn a_chosen_density_sizes_the_atlas() {
        let s = scene([[0.6, 0.1], [0.9, 0.1], [0.9, 0.3], [0.6, 0.3]]);
        let uvs = s.uvs.as_ref().unwrap();
        let ratio = (4.0f64 / 0.42).sqrt();
        let atlas = Atlas::from_uvs_with_density(&s.surface, uvs, 100.0).unwrap();
        assert_eq!(atlas.size, (100.0 * ratio).ceil() as u32);
        assert!(atlas.density >= 100.0 && atlas.density < 100.0 * (1.0 + 1.0 / 400.0));
        let small = Atlas::from_uvs_with_density(&s.surface, uvs, 1.0).unwrap();
        assert_eq!(small.size, 16);
        let e = Atlas::from_uvs_with_density(&s.surface, uvs, 1e4)
            .unwrap_err()
            .to_string();
        let fits = format!("{:.3e}", 16384.0 / ratio);
        assert!(e.contains("more than 16384") && e.contains(&fits), "{e}");
        for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = Atlas::from_uvs_with_density(&s.surface, uvs, d)
                .unwrap_err()
                .to_string();
            assert!(e.contains("must be positive and finite"), "{d}: {e}");
        }
    }

    /// A lamp mapped onto the floor's texels is refused, naming a triangle
    /// of each; coordinates outside [0, 1] and a lamp mapped to
    /// a line are refused with the patch and triangle.
    #[test]
    fn overlaps_and_bad_coordinates_are_refused() {
        let s = scene([[0.1, 0.05], [0.1, 0.95], [0.5, 0.95], [0.5, 0.05]]);
        let e = Atlas::from_uvs(&s.surface, s.uvs.as_ref().unwrap(), 64)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("texture coordinates overlap")
                && e.contains("patch 'floor/white' triangle")
                && e.contains("patch 'lamp/light' triangle"),
            "{e}"
        );
        let s = scene([[0.6, 0.1], [1.5, 0.1], [0.9, 0.3], [0.6, 0.3]]);
        let e = Atlas::from_uvs(&s.surface, s.uvs.as_ref().unwrap(), 64)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("patch 'lamp/light' triangle 0: texture coordinate 1.5 outside [0, 1]"),
            "{e}"
        );
        let s = scene([[0.6, 0.1], [0.7, 0.1], [0.8, 0.1], [0.9, 0.1]]);
        let e = Atlas::from_uvs(&s.surface, s.uvs.as_ref().unwrap(), 64)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("patch 'lamp/light' triangle 0: its texture coordinates have no area"),
            "{e}"
        );
    }
}
