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

pub use bvh::{ElementBvh, Hit};
pub use tessellation::{tessellation_points, tessellation_triangles, tessellation_vertex_count};
pub use tonemap::{
    luminance, srgb_decode, srgb_encode, tone_map, tone_map_values, ToneMap, ToneOperator,
};
pub use vertex::{vertex_mesh, VertexMesh};

use crate::camera::Camera;
use crate::mesh::Mesh;
use crate::solution::Solution;
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
    /// Zero width or height, or zero supersamples.
    #[error("image size {width}×{height} with {samples}×{samples} samples per pixel: all must be at least 1")]
    ImageSize {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Samples per pixel axis.
        samples: u32,
    },
    /// The camera is degenerate.
    #[error("{0}")]
    Camera(String),
    /// Zero subdivisions for the vertex read-back.
    #[error("vertex mesh subdivisions = {0}: must be at least 1")]
    Subdivisions(u32),
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
    /// Supersamples per pixel axis: `samples`² rays per pixel on a regular grid
    /// (1 shoots one ray through the pixel centre).
    pub samples: u32,
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
            samples: 2,
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

/// Renders with a prebuilt hierarchy (for several views of one mesh).
///
/// Each pixel averages `samples`² rays on a regular sub-grid. A ray that hits a
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
    let RenderOptions {
        width,
        height,
        samples,
        background,
        ..
    } = *opts;
    if width == 0 || height == 0 || samples == 0 {
        return Err(RenderError::ImageSize {
            width,
            height,
            samples,
        });
    }
    camera.validate().map_err(RenderError::Camera)?;
    let w = width as usize;
    let mut rgb = vec![[0.0f32; 3]; w * height as usize];
    let mut coverage = vec![0.0f32; w * height as usize];
    let n = samples as f64;
    let weight = 1.0 / (n * n);
    rgb.par_chunks_mut(w)
        .zip(coverage.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (row, cov))| {
            for x in 0..w {
                let mut acc = [0.0f64; 3];
                let mut hits = 0u32;
                for j in 0..samples {
                    for i in 0..samples {
                        let px = x as f64 + (i as f64 + 0.5) / n;
                        let py = y as f64 + (j as f64 + 0.5) / n;
                        let dir = camera.ray_direction(px, py, width, height);
                        match bvh.closest_hit(camera.eye, dir) {
                            Some(hit) => {
                                hits += 1;
                                if hit.front {
                                    let u = eval_rgb(solutions, hit.element, hit.st[0], hit.st[1]);
                                    for c in 0..3 {
                                        acc[c] += u[c] / PI;
                                    }
                                }
                            }
                            None => {
                                for c in 0..3 {
                                    acc[c] += background[c] as f64;
                                }
                            }
                        }
                    }
                }
                row[x] = acc.map(|a| (a * weight) as f32);
                cov[x] = (hits as f64 * weight) as f32;
            }
        });
    Ok(Image {
        width,
        height,
        rgb,
        coverage,
    })
}

#[cfg(test)]
mod tests;
