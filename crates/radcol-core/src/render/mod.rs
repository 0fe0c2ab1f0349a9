//! Rendering and per-vertex read-back of solutions.
//!
//! * [`ElementBvh`]: closest-hit ray queries on a mesh's elements, mapping a hit
//!   back to the element and its (s, t).
//! * [`render`]: a pinhole image of the solution. Each (sub)pixel ray evaluates
//!   the element polynomials u_n at the hit's (s, t) — no interpolation of vertex
//!   colours — and stores linear radiance L = u / π (a Lambertian surface of
//!   radiosity u emits radiance u / π in every direction).
//! * [`tone_map`]: exposure, a tone curve and the sRGB transfer function, for
//!   8-bit images and vertex colours.
//! * [`vertex_mesh`]: every element tessellated into its own small triangles with
//!   u_n evaluated at their vertices, for PLY/glTF export.

mod bvh;
mod tessellation;
mod tonemap;
mod vertex;

mod input_mesh;
pub mod lightmap;

pub use crate::camera::Camera;

pub use input_mesh::{input_vertex_mesh, Corners};

pub use bvh::{ElementBvh, Hit};
pub use tessellation::{tessellation_points, tessellation_triangles, tessellation_vertex_count};
pub use tonemap::{
    luminance, srgb_decode, srgb_encode, tone_map, tone_map_values, ToneMap, ToneOperator,
};
pub use vertex::{vertex_mesh, VertexMesh};

use crate::mesh::Mesh;
use crate::solution::Solution;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Bad input to rendering or read-back.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// Neither one (grey) nor three (RGB) channels.
    #[error("{count} solutions given: rendering takes 1 (grey) or 3 (R, G, B)")]
    ChannelCount {
        /// Number of solutions passed.
        count: usize,
    },
    /// A solution lives on a mesh with another number of elements.
    #[error("solution of channel {channel} has {elements} elements but the mesh has {expected}")]
    MeshMismatch {
        /// Channel index.
        channel: usize,
        /// Elements of the solution's mesh.
        elements: usize,
        /// Elements of the mesh rendered.
        expected: usize,
    },
    /// Zero width or height, or zero samples per pixel.
    #[error("image size {width}×{height} with {samples_per_pixel} samples per pixel: all must be at least 1")]
    ImageSize {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Samples (rays) per pixel.
        samples_per_pixel: u32,
    },
    /// The camera is degenerate.
    #[error("{0}")]
    Camera(String),
    /// Zero subdivisions for the vertex read-back.
    #[error("vertex mesh subdivisions = {0}: must be at least 1")]
    Subdivisions(u32),
    /// A corner of a scene triangle lies in none of its elements (vertex
    /// colours on the input mesh).
    #[error("input mesh: {0}")]
    InputMesh(String),
    /// A lightmap cannot be made (size, curved patches, packing).
    #[error("lightmap: {0}")]
    Lightmap(String),
    /// The vertex mesh would need more than u32 indices.
    #[error("vertex mesh of {elements} elements × {per_element} vertices exceeds the 32-bit index range")]
    TooManyVertices {
        /// Elements of the mesh.
        elements: usize,
        /// Vertices per element.
        per_element: usize,
    },
}

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Rays per pixel ([`pixel_samples`]): a square n² on the regular n × n
    /// grid, any other count on a low-discrepancy set (1 shoots one ray
    /// through the pixel centre).
    pub samples_per_pixel: u32,
    /// Linear value of pixels (or sub-samples) whose ray hits nothing.
    pub background: [f32; 3],
    /// Facets per curved-element edge in the BVH (n² facets per curved element).
    pub curved_subdivisions: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            samples_per_pixel: 4,
            background: [0.0; 3],
            curved_subdivisions: 8,
        }
    }
}

/// A linear-radiance image.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Radiance L = u / π per pixel and channel (grey replicated), row-major, top row first.
    pub rgb: Vec<[f32; 3]>,
    /// Fraction of each pixel's sub-samples that hit a surface (front or back),
    /// same layout as `rgb`; auto exposure looks only at covered pixels.
    pub coverage: Vec<f32>,
    /// Fraction of each pixel's sub-samples that hit the front of an
    /// element that emits, same layout as `rgb`, when the renderer was told
    /// which do ([`render_scene`]); empty otherwise. Auto exposure then
    /// looks only at covered pixels where no ray met an emitter: at the
    /// light that surfaces reflect.
    pub emitted: Vec<f32>,
}

/// Checks the channel count and that every solution lives on a mesh like `mesh`.
pub(crate) fn check_solutions(mesh: &Mesh, solutions: &[&Solution]) -> Result<(), RenderError> {
    if solutions.len() != 1 && solutions.len() != 3 {
        return Err(RenderError::ChannelCount {
            count: solutions.len(),
        });
    }
    for (channel, s) in solutions.iter().enumerate() {
        let elements = s.discretization().mesh().len();
        if elements != mesh.len() {
            return Err(RenderError::MeshMismatch {
                channel,
                elements,
                expected: mesh.len(),
            });
        }
    }
    Ok(())
}

/// u_n of every channel at (s, t) of element k, grey replicated to three.
pub(crate) fn eval_rgb(solutions: &[&Solution], k: usize, s: f64, t: f64) -> [f64; 3] {
    match solutions {
        [g] => [g.eval(k, s, t); 3],
        _ => [0, 1, 2].map(|c| solutions[c].eval(k, s, t)),
    }
}

/// Renders `solutions` (1 grey or 3 RGB channels, on `mesh`) seen by `camera`:
/// builds an [`ElementBvh`] and calls [`render_with`].
pub fn render(
    mesh: &Mesh,
    solutions: &[&Solution],
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    check_solutions(mesh, solutions)?;
    let bvh = ElementBvh::new(mesh, opts.curved_subdivisions);
    render_with(&bvh, mesh, solutions, camera, opts)
}

/// [`render`], told which elements emit (`emits`, one flag per element of
/// `mesh`, such as [`crate::run::SolveOutcome::emitting_elements`]): the
/// image records where rays met an emitter ([`Image::emitted`]), so that
/// auto exposure ([`ToneMap`]) is set by the light the surfaces reflect, not
/// by the lights themselves. A view in which the light covers more than
/// 1 % of the pixels would otherwise be exposed for the light, and the
/// room around it shown nearly black.
pub fn render_scene(
    mesh: &Mesh,
    solutions: &[&Solution],
    emits: &[bool],
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    check_solutions(mesh, solutions)?;
    check_per_element(mesh, emits.len())?;
    let bvh = ElementBvh::new(mesh, opts.curved_subdivisions);
    shade_solutions(&bvh, solutions, Some(emits), camera, opts)
}

/// Renders with a prebuilt hierarchy (for several views of one mesh).
///
/// Each pixel averages its [`pixel_samples`] rays. A ray that hits a
/// front face contributes u_n / π at the hit, a back face contributes black, a
/// miss the background. Rows are rendered in parallel.
pub fn render_with(
    bvh: &ElementBvh,
    mesh: &Mesh,
    solutions: &[&Solution],
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    check_solutions(mesh, solutions)?;
    shade_solutions(bvh, solutions, None, camera, opts)
}

/// The image of `solutions`, with where rays met the elements `emits` marks
/// when given ([`Image::emitted`]), in one pass of rays.
fn shade_solutions(
    bvh: &ElementBvh,
    solutions: &[&Solution],
    emits: Option<&[bool]>,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    let shade = |hit: Option<&Hit>| {
        Some(match hit {
            Some(h) if h.front => eval_rgb(solutions, h.element, h.st[0], h.st[1]).map(|u| u / PI),
            Some(_) => [0.0; 3],
            None => opts.background.map(f64::from),
        })
    };
    trace(bvh, camera, opts, &shade, emits)
}

/// Refuses a per-element list of `len` values for `mesh` of another length.
fn check_per_element(mesh: &Mesh, len: usize) -> Result<(), RenderError> {
    if len != mesh.len() {
        return Err(RenderError::MeshMismatch {
            channel: 0,
            elements: len,
            expected: mesh.len(),
        });
    }
    Ok(())
}

/// A per-element value seen by `camera`: each pixel holds the mean of
/// `per_element` (length `mesh.len()`) over its rays that hit a front face
/// (NaN when none did), grey replicated to three channels; back faces and
/// misses are left out of the mean, not averaged in as black. For maps of
/// the element error estimates.
pub fn render_element_values(
    mesh: &Mesh,
    per_element: &[f64],
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    check_per_element(mesh, per_element.len())?;
    let bvh = ElementBvh::new(mesh, opts.curved_subdivisions);
    let shade = |hit: Option<&Hit>| hit.filter(|h| h.front).map(|h| [per_element[h.element]; 3]);
    trace(&bvh, camera, opts, &shade, None)
}

/// Where in a pixel (offsets in [0, 1)²) its `spp` rays go: a square
/// count n² on the regular n × n grid of cell centres; any other count on
/// the R2 low-discrepancy sequence (M. Roberts, "The unreasonable
/// effectiveness of quasirandom sequences", 2018: offsets 1/2 + i (1/g,
/// 1/g²) modulo 1, g the plastic number), whose points spread evenly for
/// every count.
pub fn pixel_samples(spp: u32) -> Vec<[f64; 2]> {
    let n = (spp as f64).sqrt().round() as u32;
    if n * n == spp {
        let m = n as f64;
        return (0..n)
            .flat_map(|j| (0..n).map(move |i| [(i as f64 + 0.5) / m, (j as f64 + 0.5) / m]))
            .collect();
    }
    const G: f64 = 1.324_717_957_244_746;
    let a = [1.0 / G, 1.0 / (G * G)];
    (0..spp)
        .map(|i| a.map(|a| (0.5 + i as f64 * a).fract()))
        .collect()
}

/// The pixel loop: [`pixel_samples`] rays per pixel; each pixel is the
/// mean of `shade` over its rays (a hit, or None for a miss) where `shade`
/// gives a value, NaN where it gives none. Rows in parallel.
fn trace(
    bvh: &ElementBvh,
    camera: &Camera,
    opts: &RenderOptions,
    shade: &(dyn Fn(Option<&Hit>) -> Option<[f64; 3]> + Sync),
    emits: Option<&[bool]>,
) -> Result<Image, RenderError> {
    let RenderOptions {
        width,
        height,
        samples_per_pixel,
        ..
    } = *opts;
    if width == 0 || height == 0 || samples_per_pixel == 0 {
        return Err(RenderError::ImageSize {
            width,
            height,
            samples_per_pixel,
        });
    }
    camera.validate().map_err(RenderError::Camera)?;
    let w = width as usize;
    let mut rgb = vec![[0.0f32; 3]; w * height as usize];
    let mut coverage = vec![0.0f32; w * height as usize];
    let mut emitted = vec![
        0.0f32;
        if emits.is_some() {
            w * height as usize
        } else {
            0
        }
    ];
    let offsets = pixel_samples(samples_per_pixel);
    let weight = 1.0 / offsets.len() as f64;
    // Rows of `emitted` (none when it is empty).
    let lit_rows: Vec<&mut [f32]> = emitted.chunks_mut(w).collect();
    let mut lit_rows: Vec<Option<&mut [f32]>> = lit_rows.into_iter().map(Some).collect();
    lit_rows.resize_with(height as usize, || None);
    rgb.par_chunks_mut(w)
        .zip(coverage.par_chunks_mut(w))
        .zip(lit_rows.into_par_iter())
        .enumerate()
        .for_each(|(y, ((row, cov), mut lit))| {
            for x in 0..w {
                let mut acc = [0.0f64; 3];
                let (mut hits, mut shaded, mut lights) = (0u32, 0u32, 0u32);
                for &[dx, dy] in &offsets {
                    let (px, py) = (x as f64 + dx, y as f64 + dy);
                    let dir = camera.ray_direction(px, py, width, height);
                    let hit = bvh.closest_hit(camera.eye, dir);
                    hits += u32::from(hit.is_some());
                    let light = |e: &[bool]| hit.as_ref().is_some_and(|h| h.front && e[h.element]);
                    lights += u32::from(emits.is_some_and(light));
                    if let Some(v) = shade(hit.as_ref()) {
                        shaded += 1;
                        for c in 0..3 {
                            acc[c] += v[c];
                        }
                    }
                }
                // 1 / shaded is `weight` exactly when every ray counts.
                let mean = if shaded > 0 {
                    1.0 / shaded as f64
                } else {
                    f64::NAN
                };
                row[x] = acc.map(|a| (a * mean) as f32);
                cov[x] = (hits as f64 * weight) as f32;
                if let Some(lit) = lit.as_deref_mut() {
                    lit[x] = (lights as f64 * weight) as f32;
                }
            }
        });
    Ok(Image {
        width,
        height,
        rgb,
        coverage,
        emitted,
    })
}

/// Probe rays per axis of each candidate view in [`auto_camera`].
const PROBE: u32 = 24;

/// A camera that shows the lit side of `mesh`, for scenes that bring none
/// (an OBJ file has no camera).
///
/// Candidates: from outside the bounding box along the 8 diagonals and the 6
/// axes (far enough back for a 40° field of view to take in the whole box),
/// then from the box's centre along the 6 axes with a 90° field of view (rooms
/// are lit inside). Each is scored by the fraction of a 24 × 24 probe grid of
/// rays that meets front faces, the side light leaves from; the first best
/// wins, so a scene seen equally well from outside is shown from outside, in
/// three-quarter view.
pub fn auto_camera(mesh: &Mesh) -> Camera {
    let bvh = ElementBvh::new(mesh, 2);
    let (lo, hi) = bvh.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(f64::MIN_POSITIVE);
    let fov: f64 = 40.0;
    let distance = radius / (fov.to_radians() * 0.5).sin();
    let up_for = |d: DVec3| {
        if d.normalize().cross(DVec3::Y).length() > 1e-3 {
            DVec3::Y
        } else {
            DVec3::Z
        }
    };
    let axes = [
        DVec3::NEG_Z,
        DVec3::Z,
        DVec3::NEG_X,
        DVec3::X,
        DVec3::Y,
        DVec3::NEG_Y,
    ];
    let mut candidates = Vec::new();
    for sx in [-1.0, 1.0] {
        for sy in [1.0, -1.0] {
            for sz in [-1.0, 1.0] {
                let d = DVec3::new(sx, sy * 0.6, sz).normalize();
                candidates.push((centre + d * distance, centre, fov));
            }
        }
    }
    for d in axes {
        candidates.push((centre + d * distance, centre, fov));
    }
    for d in axes {
        candidates.push((centre, centre + d * radius, 90.0));
    }
    let score = |cam: &Camera| {
        let mut front = 0u32;
        for y in 0..PROBE {
            for x in 0..PROBE {
                let dir = cam.ray_direction(x as f64 + 0.5, y as f64 + 0.5, PROBE, PROBE);
                if bvh.closest_hit(cam.eye, dir).is_some_and(|h| h.front) {
                    front += 1;
                }
            }
        }
        front
    };
    let mut best: Option<(u32, Camera)> = None;
    for (eye, target, fov_y_deg) in candidates {
        let cam = Camera {
            eye,
            target,
            up: up_for(target - eye),
            fov_y_deg,
        };
        let s = score(&cam);
        if best.as_ref().is_none_or(|(b, _)| s > *b) {
            best = Some((s, cam));
        }
    }
    best.expect("at least one candidate").1
}

#[cfg(test)]
mod tests;
