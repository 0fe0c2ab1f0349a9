//! `radcol info`: a scene's mesh at a level, its size, visibility, contents
//! and an assembly time estimate.

use super::{precise, secs};
use radcol_core::run::MemoryEstimate;
use serde::Serialize;
use std::fmt;

/// Everything `radcol info` reports.
#[derive(Debug, Serialize)]
pub struct InfoReport {
    /// Scene name.
    pub scene: String,
    /// Refinement level asked for.
    pub level: u32,
    /// Maximum edge length after the uniform level, when asked for.
    pub max_edge: Option<f64>,
    /// Degree asked for.
    pub degree: usize,
    /// Elements at `level` (JSON: null when counting stopped, see
    /// `counted_up_to`).
    #[serde(serialize_with = "counted")]
    pub elements: u64,
    /// When the count with a maximum edge stopped: the element count it
    /// stopped at (there are more).
    pub counted_up_to: Option<u64>,
    /// Patches.
    pub patches: usize,
    /// Base triangles (level 0 elements).
    pub base_triangles: usize,
    /// Mesh size h at `level` (largest parameter-space diameter, eq. 11).
    pub h: f64,
    /// Longest edge of the mapped straight elements: min, mean, max.
    pub element_size: ElementSize,
    /// Shape ratio (min, max), measured at `measured_level`.
    pub shape_ratio: ShapeRatio,
    /// Surface area, measured at `measured_level`.
    pub area: f64,
    /// Axis-aligned bounding box of the base triangles' vertices.
    pub bounding_box: BoundingBox,
    /// The level whose mesh was built (below `level` when that mesh is too big to build).
    pub measured_level: u32,
    /// Unknowns N at `degree` and `level` (JSON: null when counting stopped).
    #[serde(serialize_with = "counted")]
    pub unknowns: u64,
    /// Memory of the dense matrices.
    pub memory: MemoryEstimate,
    /// The compressed operator's size predicted from the geometry, when
    /// the job's mesh was built.
    pub compressed: Option<CompressedInfo>,
    /// Whether visibility tests are needed, and why.
    pub visibility: radcol_core::visibility::VisibilityAnalysis,
    /// Triangles, materials and emitters of a scene with materials.
    pub contents: Option<SceneInfo>,
    /// Assembly time and work, measured on a sample (None without `--plan`,
    /// or for large meshes).
    pub estimate: Option<Estimate>,
    /// Whether the plan was asked for (`--plan`).
    pub planned: bool,
}

/// Element sizes (longest edge).
#[derive(Debug, Serialize)]
pub struct ElementSize {
    /// Smallest.
    pub min: f64,
    /// Mean.
    pub mean: f64,
    /// Largest.
    pub max: f64,
}

/// Bounding box.
#[derive(Debug, Serialize)]
pub struct BoundingBox {
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
}

/// What a scene with materials holds.
#[derive(Debug, Serialize)]
pub struct SceneInfo {
    /// File read, for OBJ scenes.
    pub source: Option<String>,
    /// Triangles after repairs.
    pub triangles: usize,
    /// Distinct vertex positions.
    pub vertices: usize,
    /// The materials.
    pub materials: Vec<MaterialInfo>,
    /// Patches (group/material) that emit.
    pub emitters: Vec<String>,
    /// Repairs and suspicious input.
    pub warnings: Vec<String>,
}

/// One material.
#[derive(Debug, Serialize)]
pub struct MaterialInfo {
    /// Name.
    pub name: String,
    /// Kd.
    pub rho: [f64; 3],
    /// Ke.
    pub emission: [f64; 3],
    /// Triangles using it.
    pub triangles: usize,
    /// Their area.
    pub area: f64,
}

/// Assembly estimate from timed row blocks.
#[derive(Debug, Serialize)]
pub struct Estimate {
    /// Seconds to plan (classify pairs, clip tests).
    pub plan_s: f64,
    /// Estimated assembly seconds on the CPU backend (plan included).
    pub assembly_s: f64,
    /// Row blocks timed.
    pub sampled_blocks: usize,
    /// Threads assumed.
    pub threads: usize,
    /// Far pairs.
    pub pairs_far: u64,
    /// Near pairs.
    pub pairs_near: u64,
    /// Partly visible pairs.
    pub pairs_partial: u64,
    /// Culled pairs.
    pub pairs_culled: u64,
    /// 2 N² per GMRES iteration and channel.
    pub gmres_flops_per_iteration: f64,
    /// 2 N³ / 3 for one LU factorisation.
    pub lu_flops: f64,
}

/// Shape ratio range.
#[derive(Debug, Serialize)]
pub struct ShapeRatio {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// What `--operator compressed` would store, before anything is computed.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CompressedInfo {
    /// The hierarchical matrix's bytes ([`radcol_core::hmatrix::HMatrix::predict`]).
    pub prediction: radcol_core::hmatrix::HPrediction,
    /// The plan's table of element pair classes, as expected
    /// ([`radcol_core::assembly::pair_table_bytes`]).
    pub pair_table_bytes: f64,
}

impl InfoReport {
    /// The count with a maximum edge stops at `MAX_EDGE_COUNT_CAP` elements
    /// and saturates: no dense matrix of that size fits anywhere.
    fn stopped(&self) -> bool {
        self.elements == u64::MAX
    }

    /// The unknowns and dense-matrix lines.
    fn fmt_size(&self, w: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = self;
        let avail = i
            .memory
            .available_bytes
            .map(|b| gib(b as f64))
            .unwrap_or_else(|| "unknown".into());
        if i.stopped() {
            let per = radcol_core::nodes::nodes_per_element(i.degree) as u64;
            let n = radcol_core::mesh::MAX_EDGE_COUNT_CAP * per;
            writeln!(w, "  unknowns        more than {n} at r = {}", i.degree)?;
            return writeln!(
                w,
                "  dense matrix    more than {} (does NOT fit); available {avail}",
                gib(8.0 * (n as f64).powi(2))
            );
        }
        writeln!(w, "  unknowns        {} at r = {}", i.unknowns, i.degree)?;
        let yes = |b: bool| if b { "fits" } else { "does NOT fit" };
        writeln!(
            w,
            "  dense matrix    {} ({}); with --solver lu {} ({}); available {avail}",
            gib(i.memory.matrix_bytes),
            yes(i.memory.fits_gmres),
            gib(i.memory.matrix_bytes + i.memory.lu_extra_bytes),
            yes(i.memory.fits_lu)
        )?;
        let Some(c) = &i.compressed else {
            return Ok(());
        };
        let p = &c.prediction;
        writeln!(
            w,
            "  compressed      {} {} from the geometry ({} dense near the diagonal, far blocks at rank 1; occlusion splits more), and {} of pair classes",
            if p.complete { "about" } else { "more than" },
            gib(p.bytes()),
            gib(p.near_bytes),
            gib(c.pair_table_bytes)
        )
    }
}

fn gib(bytes: f64) -> String {
    let g = bytes / 1073741824.0;
    if g < 1e6 {
        format!("{g:.3} GiB")
    } else {
        format!("{g:.3e} GiB")
    }
}

impl fmt::Display for InfoReport {
    fn fmt(&self, w: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = self;
        writeln!(
            w,
            "radcol info: {}, level {}{}, r = {}",
            i.scene,
            i.level,
            i.max_edge
                .map(|h| format!(", max edge {h}"))
                .unwrap_or_default(),
            i.degree
        )?;
        if i.stopped() {
            let cap = radcol_core::mesh::MAX_EDGE_COUNT_CAP;
            writeln!(
                w,
                "  elements        more than {cap} (counting stopped there)"
            )?;
        } else {
            writeln!(w, "  elements        {}", i.elements)?;
        }
        writeln!(w, "  patches         {}", i.patches)?;
        writeln!(w, "  base triangles  {}", i.base_triangles)?;
        writeln!(w, "  h               {:.6}", i.h)?;
        writeln!(
            w,
            "  element size    longest edge {:.6} min, {:.6} mean, {:.6} max",
            i.element_size.min, i.element_size.mean, i.element_size.max
        )?;
        let at = if i.measured_level != i.level {
            format!(
                " (measured at level {}: the level-{} mesh is too big to build here)",
                i.measured_level, i.level
            )
        } else {
            String::new()
        };
        writeln!(
            w,
            "  shape ratio     {:.4} .. {:.4}{at}",
            i.shape_ratio.min, i.shape_ratio.max
        )?;
        writeln!(w, "  area            {}{at}", precise(i.area))?;
        i.fmt_size(w)?;
        writeln!(w, "  visibility      {}", i.visibility.reason)?;
        writeln!(
            w,
            "  bounding box    ({:.6}, {:.6}, {:.6}) .. ({:.6}, {:.6}, {:.6})",
            i.bounding_box.min[0],
            i.bounding_box.min[1],
            i.bounding_box.min[2],
            i.bounding_box.max[0],
            i.bounding_box.max[1],
            i.bounding_box.max[2]
        )?;
        if let Some(sc) = &i.contents {
            sc.fmt_lines(w)?;
        }
        match &i.estimate {
            Some(e) => write!(w, "{e}"),
            None if !i.planned => writeln!(
                w,
                "  time estimate   - (--plan builds the assembly plan: pair counts and timed row blocks)"
            ),
            None => writeln!(
                w,
                "  time estimate   - (more elements than radcol info plans; try a lower --level)"
            ),
        }
    }
}

impl SceneInfo {
    /// The scene lines of the text report.
    fn fmt_lines(&self, w: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sc = self;
        writeln!(
            w,
            "  scene           {} triangles, {} vertices{}",
            sc.triangles,
            sc.vertices,
            sc.source
                .as_ref()
                .map(|s| format!(", from {s}"))
                .unwrap_or_default()
        )?;
        for m in &sc.materials {
            writeln!(
                w,
                "  material        {:<12} ρ = ({:.4}, {:.4}, {:.4}), E = ({:.4}, {:.4}, {:.4}), {} triangles, area {:.6}",
                m.name,
                m.rho[0],
                m.rho[1],
                m.rho[2],
                m.emission[0],
                m.emission[1],
                m.emission[2],
                m.triangles,
                m.area
            )?;
        }
        writeln!(
            w,
            "  emitters        {}",
            if sc.emitters.is_empty() {
                "none: every solution is 0".to_string()
            } else {
                sc.emitters.join(", ")
            }
        )?;
        writeln!(w, "  warnings        {}", sc.warnings.len())?;
        Ok(())
    }
}

impl fmt::Display for Estimate {
    /// The pairs and time-estimate lines of the text report.
    fn fmt(&self, w: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = self;
        writeln!(
            w,
            "  pairs           {} far, {} near, {} partly visible, {} culled",
            e.pairs_far, e.pairs_near, e.pairs_partial, e.pairs_culled
        )?;
        writeln!(
            w,
            "  time estimate   assembly ≈ {} on {} CPU threads (plan {}, {} row blocks timed); \
             solve: {:.3e} flops per GMRES iteration and channel, {:.3e} for an LU factorisation",
            secs(e.assembly_s),
            e.threads,
            secs(e.plan_s),
            e.sampled_blocks,
            e.gmres_flops_per_iteration,
            e.lu_flops
        )
    }
}

/// A count, or null where counting stopped (`u64::MAX`).
fn counted<S: serde::Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
    if *v == u64::MAX {
        s.serialize_none()
    } else {
        s.serialize_u64(*v)
    }
}
