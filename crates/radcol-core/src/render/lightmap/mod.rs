//! UV lightmaps: the solution rasterised into a texture atlas over the
//! scene's own triangles, the form engines consume baked light in.
//!
//! **Charts.** The triangles of one patch (an object's material) that lie
//! in one plane form a chart, projected orthographically onto that plane:
//! no distortion, and a scene of walls and boxes (the Cornell box's faces)
//! gets one chart per face. Or the input's own texture coordinates
//! ([`Atlas::from_uvs`], `input.rs`: OBJ `vt`, glTF TEXCOORD_1 or _0), one
//! chart per patch, when they lie in the unit square; overlapping ones are
//! refused when baked.
//!
//! **Packing.** Charts are placed on shelves (tallest first) in a square
//! atlas of `size` texels, with a gutter of [`GUTTER`] texels on every side,
//! at the largest common texel density that fits (bisection on the
//! density).
//!
//! **Baking.** Every element of the solve's mesh lies in one chart; each
//! texel whose centre lies in an element's projection gets u_n/π (radiance)
//! at that point of the element, exactly as the renderer evaluates it. The
//! empty texels around the charts are then filled from their covered
//! neighbours, [`DILATION`] passes, so bilinear filtering and mipmaps at
//! chart borders do not bleed the background in.

use super::{check_solutions, eval_rgb, Image, RenderError};
use crate::geometry::Surface;
use crate::mesh::Mesh;
use crate::solution::Solution;
use glam::DVec3;
use std::collections::HashMap;
use std::f64::consts::PI;

mod input;

/// Empty texels around every chart.
pub const GUTTER: u32 = 2;

/// Texels the charts are grown by into the empty atlas (their gutters and
/// beyond): viewers and engines sample mipmaps of a lightmap, and a level
/// 2^k smaller averages 2^k texels, so an empty texel within 16 of a chart
/// would bleed black into it down to level 4 (seams seen in pyrender's view
/// with 2).
pub const DILATION: u32 = 16;

/// One chart: coplanar triangles of one patch and their placement.
#[derive(Clone, Debug)]
pub struct Chart {
    /// The patch.
    pub patch: usize,
    /// Indices into the patch's triangles.
    pub triangles: Vec<usize>,
    /// Unit normal and offset of the plane (n · x = offset).
    normal: DVec3,
    offset: f64,
    /// In-plane axes and the lower corner of the projected bounding box.
    axes: [DVec3; 2],
    min: [f64; 2],
    extent: [f64; 2],
    /// Lower corner of the chart's rectangle in the atlas, in texels
    /// (inside the gutter).
    corner: [f64; 2],
}

/// The charts of a flat scene packed into a square atlas.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// Width and height in texels.
    pub size: u32,
    /// Texels per scene unit.
    pub density: f64,
    /// The charts.
    pub charts: Vec<Chart>,
    /// The chart of each surface triangle (patch, index in its triangles).
    chart_of: HashMap<(u32, u32), usize>,
    /// Per patch and triangle, the corners in space and in texture
    /// coordinates, when the atlas is the input's ([`Atlas::from_uvs`]).
    input: Option<Vec<Vec<input::Corners>>>,
}

impl Atlas {
    /// Charts and packing of `surface`'s triangles at `size`×`size` texels.
    /// Curved patches are refused (their elements are not planar).
    pub fn new(surface: &Surface, size: u32) -> Result<Self, RenderError> {
        if !(16..=16384).contains(&size) {
            return Err(RenderError::Lightmap(format!(
                "atlas size {size}: must lie in 16..=16384 texels"
            )));
        }
        let (lo, hi) = surface.bounding_box();
        let scale = (hi - lo).length().max(f64::MIN_POSITIVE);
        let mut charts: Vec<Chart> = Vec::new();
        let mut chart_of = HashMap::new();
        // Charts by patch and plane: the normal and offset rounded to 1e-9
        // (of the scene's size), so equal planes meet in one bucket; a plane
        // that rounds across a bucket's edge only makes two charts.
        let mut by_plane: HashMap<(usize, [i64; 4]), usize> = HashMap::new();
        for (j, patch) in surface.patches.iter().enumerate() {
            for (t, tri) in patch.triangles.iter().enumerate() {
                let Some((n, offset)) = plane_of(patch, tri, scale)? else {
                    continue;
                };
                let q = |x: f64| (x * 1e9).round() as i64;
                let key = (j, [q(n.x), q(n.y), q(n.z), q(offset / scale)]);
                let c = *by_plane.entry(key).or_insert_with(|| {
                    charts.push(Chart::new(j, n, offset));
                    charts.len() - 1
                });
                charts[c].triangles.push(t);
                chart_of.insert((j as u32, t as u32), c);
            }
        }
        for c in &mut charts {
            c.bound(surface);
        }
        let density = pack(&mut charts, size)?;
        Ok(Self {
            size,
            density,
            charts,
            chart_of,
            input: None,
        })
    }

    /// Atlas coordinates (texels) of `x` on triangle `t` of `chart`: its
    /// plane's projection, or the input's coordinates interpolated.
    pub fn texel_on(&self, chart: &Chart, t: usize, x: DVec3) -> [f64; 2] {
        match &self.input {
            Some(input) => {
                let (v, uv) = &input[chart.patch][t];
                input::interpolate(v, uv, x).map(|a| a * self.size as f64)
            }
            None => self.texel(chart, x),
        }
    }

    /// glTF texture coordinates (atlas fraction, from the top-left) of `x`
    /// on triangle `t` of `chart`.
    pub fn uv_on(&self, chart: &Chart, t: usize, x: DVec3) -> [f32; 2] {
        self.texel_on(chart, t, x)
            .map(|a| (a / self.size as f64) as f32)
    }

    /// The chart of the surface triangle `t` of patch `patch`.
    fn chart_of(&self, patch: u32, t: u32) -> Option<&Chart> {
        self.chart_of.get(&(patch, t)).map(|&c| &self.charts[c])
    }

    /// Atlas coordinates (texels, from the top-left corner) of `x` on `chart`.
    pub fn texel(&self, chart: &Chart, x: DVec3) -> [f64; 2] {
        let p = [chart.axes[0].dot(x), chart.axes[1].dot(x)];
        [
            chart.corner[0] + (p[0] - chart.min[0]) * self.density,
            chart.corner[1] + (p[1] - chart.min[1]) * self.density,
        ]
    }

    /// The point of `chart`'s plane at atlas coordinates `texel` (the
    /// inverse of [`Atlas::texel`]).
    pub fn point(&self, chart: &Chart, texel: [f64; 2]) -> DVec3 {
        let p = [
            chart.min[0] + (texel[0] - chart.corner[0]) / self.density,
            chart.min[1] + (texel[1] - chart.corner[1]) / self.density,
        ];
        chart.axes[0] * p[0] + chart.axes[1] * p[1] + chart.normal * chart.offset
    }

    /// glTF texture coordinates (atlas fraction, from the top-left) of `x`.
    pub fn uv(&self, chart: &Chart, x: DVec3) -> [f32; 2] {
        let [a, b] = self.texel(chart, x);
        [(a / self.size as f64) as f32, (b / self.size as f64) as f32]
    }
}

/// The unit normal and offset of a flat surface triangle's plane (None
/// when it has no area); curved patches are refused.
fn plane_of(
    patch: &crate::geometry::Patch,
    tri: &[DVec3; 3],
    scale: f64,
) -> Result<Option<(DVec3, f64)>, RenderError> {
    let v = tri.map(|x| patch.map.map(x));
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    if n.length() == 0.0 {
        return Ok(None);
    }
    let n = n.normalize();
    let flat = tri.iter().all(|&x| {
        let mid = patch.map.map((x + tri[0] + tri[1] + tri[2]) / 4.0);
        (mid - v[0]).dot(n).abs() <= 1e-9 * scale
    });
    if !flat {
        return Err(RenderError::Lightmap(format!(
            "patch '{}' is curved: lightmaps are made for flat scenes",
            patch.name
        )));
    }
    Ok(Some((n, n.dot(v[0]))))
}

impl Chart {
    fn new(patch: usize, normal: DVec3, offset: f64) -> Self {
        let helper = if normal.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let u = normal.cross(helper).normalize();
        let v = normal.cross(u);
        Self {
            patch,
            triangles: Vec::new(),
            normal,
            offset,
            axes: [u, v],
            min: [0.0; 2],
            extent: [0.0; 2],
            corner: [0.0; 2],
        }
    }

    fn bound(&mut self, surface: &Surface) {
        let patch = &surface.patches[self.patch];
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &t in &self.triangles {
            for x in patch.triangles[t] {
                let w = patch.map.map(x);
                for a in 0..2 {
                    let p = self.axes[a].dot(w);
                    lo[a] = lo[a].min(p);
                    hi[a] = hi[a].max(p);
                }
            }
        }
        self.min = lo;
        self.extent = [hi[0] - lo[0], hi[1] - lo[1]];
    }
}

/// Places `charts` on shelves at the largest density that fits `size`;
/// returns the density.
fn pack(charts: &mut [Chart], size: u32) -> Result<f64, RenderError> {
    let largest = charts
        .iter()
        .map(|c| c.extent[0].max(c.extent[1]))
        .fold(0.0, f64::max);
    if charts.is_empty() || largest <= 0.0 {
        return Err(RenderError::Lightmap(
            "the scene has no triangle to map".into(),
        ));
    }
    if !shelves(charts, 0.0, size, false) {
        return Err(RenderError::Lightmap(format!(
            "{} charts do not fit in {size}×{size} texels with their gutters: give a larger size",
            charts.len()
        )));
    }
    let (mut lo, mut hi) = (0.0, (size as f64) / largest);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if shelves(charts, mid, size, false) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    shelves(charts, lo, size, true);
    Ok(lo)
}

/// Whether `charts` fit on shelves (tallest first) in a `size`² atlas at
/// `density` texels per unit with their gutters; with `place`, sets their
/// corners.
fn shelves(charts: &mut [Chart], density: f64, size: u32, place: bool) -> bool {
    let g = GUTTER as f64;
    let dims = |c: &Chart| {
        (
            (c.extent[0] * density).ceil() + 2.0 * g,
            (c.extent[1] * density).ceil() + 2.0 * g,
        )
    };
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| dims(&charts[b]).1.total_cmp(&dims(&charts[a]).1));
    let (mut x, mut y, mut shelf) = (0.0, 0.0, 0.0f64);
    for i in order {
        let (w, h) = dims(&charts[i]);
        if x + w > size as f64 {
            (x, y, shelf) = (0.0, y + shelf, 0.0);
        }
        if x + w > size as f64 || y + h > size as f64 {
            return false;
        }
        if place {
            charts[i].corner = [x + g, y + g];
        }
        x += w;
        shelf = shelf.max(h);
    }
    true
}

/// Bakes `solutions` (1 grey or 3 RGB channels on `mesh`) into `atlas`: an
/// image of radiance u_n/π per texel, coverage 1 where an element lies, 0.5
/// in the dilated gutters (and holes) around them, 0 elsewhere.
pub fn bake(mesh: &Mesh, solutions: &[&Solution], atlas: &Atlas) -> Result<Image, RenderError> {
    check_solutions(mesh, solutions)?;
    let n = atlas.size as usize;
    let mut rgb = vec![[0.0f32; 3]; n * n];
    let mut covered = vec![false; n * n];
    for (k, base) in mesh.base_triangles().into_iter().enumerate() {
        let v = mesh.vertices(k);
        let Some((t, chart)) = base.and_then(|(j, t)| Some((t, atlas.chart_of(j, t)?))) else {
            return Err(RenderError::Lightmap(format!(
                "element {k} lies in no chart (its surface triangle is degenerate or missing)"
            )));
        };
        let p = v.map(|x| atlas.texel_on(chart, t as usize, x));
        raster(p, n, |i, s, r, _| {
            let u = eval_rgb(solutions, k, s, r);
            rgb[i] = u.map(|v| (v / PI) as f32);
            covered[i] = true;
        });
    }
    let charted: Vec<bool> = covered.clone();
    dilate(&mut rgb, &mut covered, n, DILATION as usize);
    Ok(Image {
        width: atlas.size,
        height: atlas.size,
        coverage: charted
            .iter()
            .zip(&covered)
            .map(|(&c, &d)| {
                if c {
                    1.0
                } else if d {
                    0.5
                } else {
                    0.0
                }
            })
            .collect(),
        rgb,
    })
}

/// Calls `texel(index, s, t, inside)` for every texel of an `n`² image whose
/// centre lies in the triangle `p` (texel coordinates), with the centre's
/// barycentric coordinates (s, t) and whether it lies inside by a margin
/// (not on an edge the triangle may share).
pub(super) fn raster(p: [[f64; 2]; 3], n: usize, mut texel: impl FnMut(usize, f64, f64, bool)) {
    let det = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
    if det == 0.0 {
        return;
    }
    let range = |a: usize| {
        let lo = p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(|q| q[a]).fold(0.0, f64::max);
        lo.floor().max(0.0) as usize..hi.ceil().min(n as f64) as usize
    };
    for y in range(1) {
        for x in range(0) {
            let c = [x as f64 + 0.5, y as f64 + 0.5];
            // (s, t): barycentric coordinates of the texel centre.
            let s = ((c[0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (c[1] - p[0][1]))
                / det;
            let t = ((p[1][0] - p[0][0]) * (c[1] - p[0][1])
                - (c[0] - p[0][0]) * (p[1][1] - p[0][1]))
                / det;
            let eps = 1e-9;
            if s < -eps || t < -eps || s + t > 1.0 + eps {
                continue;
            }
            let margin = 1e-6;
            let inside = s > margin && t > margin && s + t < 1.0 - margin;
            let (s, t) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0 - s.clamp(0.0, 1.0)));
            texel(y * n + x, s, t, inside);
        }
    }
}

/// Fills empty texels next to covered ones with their covered neighbours'
/// mean, `passes` times (each pass grows the charts by one texel).
fn dilate(rgb: &mut [[f32; 3]], covered: &mut [bool], n: usize, passes: usize) {
    for _ in 0..passes {
        let mut fill = Vec::new();
        for y in 0..n {
            for x in 0..n {
                if covered[y * n + x] {
                    continue;
                }
                let (mut sum, mut count) = ([0.0f32; 3], 0.0f32);
                for (dx, dy) in [
                    (-1i64, 0i64),
                    (1, 0),
                    (0, -1),
                    (0, 1),
                    (-1, -1),
                    (1, -1),
                    (-1, 1),
                    (1, 1),
                ] {
                    let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                    if xx < 0 || yy < 0 || xx >= n as i64 || yy >= n as i64 {
                        continue;
                    }
                    let i = yy as usize * n + xx as usize;
                    if covered[i] {
                        for c in 0..3 {
                            sum[c] += rgb[i][c];
                        }
                        count += 1.0;
                    }
                }
                if count > 0.0 {
                    fill.push((y * n + x, sum.map(|v| v / count)));
                }
            }
        }
        for (i, v) in fill {
            rgb[i] = v;
            covered[i] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discretization::Discretization;
    use crate::nodes::NodeSet;
    use std::sync::Arc;

    fn cornell() -> Surface {
        (*crate::scene::builtin("cornell").unwrap().unwrap().surface).clone()
    }

    /// A chart per plane of each patch (the Cornell box: 16 faces, and the
    /// red wall, a non-planar quadrilateral, in two), inside
    /// the atlas, their rectangles with gutters disjoint, the density the
    /// largest the shelves allow (1 % more does not fit).
    #[test]
    fn charts_are_faces_packed_without_overlap() {
        let surface = cornell();
        let atlas = Atlas::new(&surface, 256).unwrap();
        assert_eq!(atlas.charts.len(), 17);
        let g = GUTTER as f64;
        let rects: Vec<[f64; 4]> = atlas
            .charts
            .iter()
            .map(|c| {
                let w = (c.extent[0] * atlas.density).ceil();
                let h = (c.extent[1] * atlas.density).ceil();
                [
                    c.corner[0] - g,
                    c.corner[1] - g,
                    c.corner[0] + w + g,
                    c.corner[1] + h + g,
                ]
            })
            .collect();
        for (i, a) in rects.iter().enumerate() {
            assert!(
                a[0] >= 0.0 && a[1] >= 0.0 && a[2] <= 256.0 && a[3] <= 256.0,
                "{a:?}"
            );
            for b in &rects[i + 1..] {
                let apart = a[2] <= b[0] || b[2] <= a[0] || a[3] <= b[1] || b[3] <= a[1];
                assert!(apart, "{a:?} and {b:?} overlap");
            }
        }
        // The density is the largest the shelves take: 1 % more does not fit.
        let mut charts = atlas.charts.clone();
        assert!(shelves(&mut charts, atlas.density, 256, false));
        assert!(!shelves(&mut charts, 1.01 * atlas.density, 256, false));
    }

    /// A u_n that is linear in position (degree 1, its nodal values the
    /// linear function) bakes to that function at every covered texel's
    /// centre, found back in 3D from the chart's plane; the gutters are
    /// filled.
    #[test]
    fn texels_hold_the_solution_at_their_centres() {
        let surface = Arc::new(cornell());
        let mesh = Arc::new(Mesh::new(surface.clone(), 1));
        let disc = Arc::new(Discretization::new(
            mesh.clone(),
            NodeSet::new(1, 0.2).unwrap(),
        ));
        let f = |x: DVec3| 1.0 + 0.001 * x.x + 0.002 * x.y + 0.003 * x.z;
        let values = disc.points().iter().map(|p| f(p.position)).collect();
        let u = Solution::new(disc.clone(), values);
        let atlas = Atlas::new(&surface, 128).unwrap();
        let img = bake(&mesh, &[&u], &atlas).unwrap();
        let n = atlas.size as usize;
        let mut checked = 0;
        for c in &atlas.charts {
            let w = (c.extent[0] * atlas.density).floor() as usize;
            let h = (c.extent[1] * atlas.density).floor() as usize;
            for j in 1..h.saturating_sub(1) {
                for i in 1..w.saturating_sub(1) {
                    let (x, y) = (c.corner[0] as usize + i, c.corner[1] as usize + j);
                    let centre = [x as f64 + 0.5, y as f64 + 0.5];
                    let world = atlas.point(c, centre);
                    if img.coverage[y * n + x] < 1.0 {
                        continue; // not in a triangle (faces that are not rectangles)
                    }
                    let got = img.rgb[y * n + x][0] as f64 * PI;
                    crate::assert_close!(got, f(world), 2e-6 * f(world));
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked} texels checked");
        // The gutters are filled: every texel within two of an element's
        // (the gutter's width) holds a value.
        for y in 0..n {
            for x in 0..n {
                if img.coverage[y * n + x] < 1.0 {
                    continue;
                }
                for (yy, xx) in [
                    (y.saturating_sub(2), x),
                    (y, x.saturating_sub(2)),
                    (y + 2, x + 2),
                ] {
                    if yy < n && xx < n {
                        assert!(img.coverage[yy * n + xx] > 0.0, "({xx}, {yy}) empty");
                    }
                }
            }
        }
    }

    #[test]
    fn refuses_curved_scenes_and_bad_sizes() {
        let sphere = crate::geometry::shapes::sphere(1.0);
        let e = Atlas::new(&sphere, 64).unwrap_err().to_string();
        assert!(e.contains("curved"), "{e}");
        let e = Atlas::new(&cornell(), 8).unwrap_err().to_string();
        assert!(e.contains("16..=16384"), "{e}");
    }
}
