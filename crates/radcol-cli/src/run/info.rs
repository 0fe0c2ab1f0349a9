//! `radcol info`: a scene's mesh at a refinement, measured (shape ratios,
//! area, element sizes) on the mesh itself when it is small enough to build,
//! with the sizes, visibility decision and an assembly estimate.

use crate::report::{
    self, BoundingBox, CompressedInfo, ElementSize, Estimate, InfoReport, MaterialInfo, SceneInfo,
    ShapeRatio,
};
use crate::scene::Loaded;
use crate::setup::{default_refinement, load};
use crate::validate::InfoJob;
use anyhow::Result;
use radcol_core::run::{
    analyze_visibility, auto_alpha, AssemblyCost, Discretization, HOptions, MemoryEstimate, Mesh,
    NodeSet, QuadratureOptions, Surface, VisibilityAnalysis,
};
use std::io::Write;
use std::sync::Arc;

/// Largest mesh `radcol info` builds to measure shape ratios and area.
const INFO_MAX_BUILT_ELEMENTS: u64 = 1 << 17;
/// Beyond this level `radcol info` refuses: the counts stop meaning anything.
const INFO_MAX_LEVEL: u32 = 24;

/// `radcol info`: describes the scene's mesh at the job's refinement.
pub fn run_info(job: InfoJob, w: &mut dyn Write) -> Result<()> {
    let loaded = load(&job.scene)?;
    let (level, max_edge) = default_refinement(&loaded, job.level, job.max_edge, false);
    if level > INFO_MAX_LEVEL {
        return Err(crate::error::bad_input(format!(
            "--level {level}: radcol info handles levels up to {INFO_MAX_LEVEL}"
        ))
        .into());
    }
    let refinement = Refinement {
        surface: loaded.surface().clone(),
        level,
        max_edge,
        degree: job.degree,
        plan: job.plan,
    };
    report::emit(w, &info_report(&refinement, &loaded), job.json)
}

/// The refinement and degree `radcol info` describes.
struct Refinement {
    surface: Arc<Surface>,
    level: u32,
    max_edge: Option<f64>,
    degree: usize,
    /// Row blocks to measure for a cost prediction (`--plan`).
    plan: Option<usize>,
}

/// The mesh of `job`, or when it is too big to build, the finest uniform
/// level that is not (with that level).
fn measured_mesh(job: &Refinement, elements: u64) -> (Arc<Mesh>, u32) {
    let base = job.surface.base_triangle_count() as u64;
    if elements <= INFO_MAX_BUILT_ELEMENTS {
        let mesh = match job.max_edge {
            Some(h) => Mesh::with_max_edge(Arc::clone(&job.surface), job.level, h),
            None => Mesh::new(Arc::clone(&job.surface), job.level),
        };
        return (Arc::new(mesh), job.level);
    }
    let mut level = job.level;
    while level > 0 && base * 4u64.pow(level) > INFO_MAX_BUILT_ELEMENTS {
        level -= 1;
    }
    (Arc::new(Mesh::new(Arc::clone(&job.surface), level)), level)
}

fn info_report(job: &Refinement, loaded: &Loaded) -> InfoReport {
    let size = radcol_core::run::mesh_size(&job.surface, job.level, job.max_edge, None, job.degree);
    let (elements, unknowns) = (size.elements, size.unknowns);
    let (mesh, measured_level) = measured_mesh(job, elements);
    // h halves with every level beyond the one measured.
    let shrink = 2f64.powi((job.level - measured_level) as i32);
    let sizes: Vec<f64> = (0..mesh.len())
        .map(|k| {
            let [a, b, c] = mesh.vertices(k);
            (b - a).length().max((c - b).length()).max((a - c).length())
        })
        .collect();
    let (lo, hi) = mesh.shape_ratio_range();
    let vis = analyze_visibility(&job.surface);
    let bbox = job.surface.bounding_box();
    // Planned on the mesh just built, which is the job's when it is small enough.
    let estimate = job
        .plan
        .filter(|_| measured_level == job.level)
        .and_then(|rows| estimate_assembly(job.degree, &mesh, &vis, rows));
    InfoReport {
        scene: job.surface.name.clone(),
        level: job.level,
        max_edge: job.max_edge,
        degree: job.degree,
        elements,
        counted_up_to: (elements == u64::MAX && job.max_edge.is_some())
            .then_some(radcol_core::run::MAX_EDGE_COUNT_CAP),
        patches: job.surface.patches.len(),
        base_triangles: job.surface.base_triangle_count(),
        h: mesh.h() / shrink,
        element_size: ElementSize {
            min: sizes.iter().copied().fold(f64::INFINITY, f64::min) / shrink,
            mean: sizes.iter().sum::<f64>() / sizes.len().max(1) as f64 / shrink,
            max: sizes.iter().copied().fold(0.0, f64::max) / shrink,
        },
        shape_ratio: ShapeRatio { min: lo, max: hi },
        area: mesh.area(),
        bounding_box: BoundingBox {
            min: bbox.0.to_array(),
            max: bbox.1.to_array(),
        },
        measured_level,
        unknowns,
        memory: MemoryEstimate::new(unknowns),
        compressed: (measured_level == job.level)
            .then(|| predict_compressed(job.degree, &mesh))
            .flatten(),
        visibility: vis,
        contents: loaded.scene().map(|sc| scene_info(sc)),
        planned: job.plan.is_some(),
        estimate,
    }
}

/// Triangles, materials (with their area) and emitters of a scene.
fn scene_info(sc: &radcol_core::scene::Scene) -> SceneInfo {
    let areas = sc.patch_areas();
    let materials = sc
        .materials
        .iter()
        .enumerate()
        .map(|(m, mat)| {
            let patches: Vec<usize> = (0..sc.surface.patches.len())
                .filter(|&j| sc.patch_material[j] == m)
                .collect();
            MaterialInfo {
                name: mat.name.clone(),
                rho: mat.rho,
                emission: mat.emission,
                triangles: patches
                    .iter()
                    .map(|&j| sc.surface.patches[j].triangles.len())
                    .sum(),
                area: patches.iter().map(|&j| areas[j]).sum(),
            }
        })
        .collect();
    SceneInfo {
        source: sc.source.as_ref().map(|p| p.display().to_string()),
        triangles: sc.triangle_count(),
        vertices: sc.vertex_count(),
        materials,
        emitters: sc
            .emitters()
            .into_iter()
            .map(|j| sc.surface.patches[j].name.clone())
            .collect(),
        warnings: sc.warnings.clone(),
    }
}

/// The compressed operator's size on `mesh` at `degree`, from the
/// geometry alone, counted up to four times the memory available.
fn predict_compressed(degree: usize, mesh: &Arc<Mesh>) -> Option<CompressedInfo> {
    let nodes = NodeSet::new(degree, auto_alpha(degree)).ok()?;
    let disc = Discretization::new(Arc::clone(mesh), nodes);
    let limit = radcol_core::run::available_memory().map_or(f64::INFINITY, |a| 4.0 * a as f64);
    Some(CompressedInfo {
        prediction: radcol_core::run::predict_compressed_from_geometry(
            &disc,
            &HOptions::default(),
            limit,
        ),
        pair_table_bytes: radcol_core::run::pair_table_bytes(mesh.len() as f64),
    })
}

/// Predicts the assembly's and the error estimate's cost on `mesh` (the
/// job's) from `rows` row blocks, with the solve's default quadrature, on
/// this machine's CPU threads.
fn estimate_assembly(
    degree: usize,
    mesh: &Arc<Mesh>,
    visibility: &VisibilityAnalysis,
    rows: usize,
) -> Option<Estimate> {
    let nodes = NodeSet::new(degree, auto_alpha(degree)).ok()?;
    let disc = Arc::new(Discretization::new(Arc::clone(mesh), nodes));
    let cost = AssemblyCost::predict(&disc, &QuadratureOptions::default(), visibility, rows);
    let nn = disc.len() as f64;
    Some(Estimate {
        cost,
        gmres_flops_per_iteration: 2.0 * nn * nn,
        lu_flops: 2.0 / 3.0 * nn * nn * nn,
    })
}
