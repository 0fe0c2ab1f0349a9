//! `radcol info`: a scene's mesh at a level, its size, visibility, contents
//! and an assembly time estimate.

use super::{precise, secs};
use radcol_core::run::{AssemblyCost, Extrapolated, MemoryEstimate};
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
    pub visibility: radcol_core::run::VisibilityAnalysis,
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

/// The assembly's and the error estimate's cost, predicted from sampled
/// row blocks ([`AssemblyCost`]), and the solve's arithmetic.
#[derive(Debug, Serialize)]
pub struct Estimate {
    /// Pairs, candidate occluders, plan memory and seconds, extrapolated.
    #[serde(flatten)]
    pub cost: AssemblyCost,
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
    /// The hierarchical matrix's bytes ([`radcol_core::run::predict_compressed_from_geometry`]).
    pub prediction: radcol_core::run::HPrediction,
    /// The plan's table of element pair classes, as expected
    /// ([`radcol_core::run::pair_table_bytes`]).
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
            let per = radcol_core::run::nodes_per_element(i.degree) as u64;
            let n = radcol_core::run::MAX_EDGE_COUNT_CAP * per;
            writeln!(w, "  unknowns        more than {n} at r = {}", i.degree)?;
            return writeln!(
                w,
                "  dense matrix    more than {} (does NOT fit); available {avail}",
                gib(radcol_core::run::dense_bytes(n))
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
            let cap = radcol_core::run::MAX_EDGE_COUNT_CAP;
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
                "  time estimate   - (--plan measures sampled row blocks: pairs, visibility cost, seconds)"
            ),
            None => writeln!(
                w,
                "  time estimate   - (more elements than radcol info builds; try a lower --level)"
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
    /// The pairs, visibility and time-estimate lines of the text report.
    fn fmt(&self, w: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (c, a) = (&self.cost, &self.cost.assembly);
        let measured = if c.sampled == c.rows {
            format!("all {} row blocks measured", c.rows)
        } else {
            format!("{} of {} row blocks measured", c.sampled, c.rows)
        };
        writeln!(
            w,
            "  pairs           {} far, {} near, {} partly visible, {} culled ({measured})",
            count(a.pairs_far),
            count(a.pairs_near),
            count(a.pairs_partial),
            count(a.pairs_culled),
        )?;
        if a.pairs_partial.value > 0.0 {
            writeln!(
                w,
                "  visibility cost {} candidate occluders over the partly visible pairs, {} held while planning, \
                 {} with the estimate's",
                count(a.candidates),
                bytes(a.partial_bytes),
                bytes(Extrapolated {
                    value: a.partial_bytes.value + c.estimate.partial_bytes.value,
                    std_error: a.partial_bytes.std_error + c.estimate.partial_bytes.std_error,
                }),
            )?;
        }
        writeln!(
            w,
            "  time estimate   assembly ≈ {} (plan {}, fill {}), error estimate ≈ {} (plan {}, fill {}), \
             on {} CPU threads; solve: {:.3e} flops per GMRES iteration and channel, {:.3e} for an LU factorisation",
            secs(a.seconds()),
            spread(a.plan_seconds),
            spread(a.fill_seconds),
            secs(c.estimate.seconds()),
            spread(c.estimate.plan_seconds),
            spread(c.estimate.fill_seconds),
            c.threads,
            self.gmres_flops_per_iteration,
            self.lu_flops
        )
    }
}

/// "1.234e5 ± 3 %", or the exact count when nothing was extrapolated.
fn count(e: Extrapolated) -> String {
    if e.std_error == 0.0 {
        format!("{:.0}", e.value)
    } else {
        format!("≈{:.3e}{}", e.value, relative(e))
    }
}

/// Seconds with their relative standard error.
fn spread(e: Extrapolated) -> String {
    format!("{}{}", secs(e.value), relative(e))
}

/// Bytes with their relative standard error.
fn bytes(e: Extrapolated) -> String {
    let v = e.value;
    let text = if v >= 1e9 {
        format!("{:.2} GB", v / 1e9)
    } else {
        format!("{:.1} MB", v / 1e6)
    };
    format!("{text}{}", relative(e))
}

/// " ± 3 %" of an extrapolated amount (nothing when exact or zero).
fn relative(e: Extrapolated) -> String {
    if e.std_error > 0.0 && e.value > 0.0 {
        format!(" ± {:.0} %", (100.0 * e.std_error / e.value).max(1.0))
    } else {
        String::new()
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
