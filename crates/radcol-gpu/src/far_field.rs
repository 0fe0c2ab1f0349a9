//! The far-field work function: far pairs of an [`AssemblyPlan`] on a device,
//! tile by tile, streamed back into the host matrix.
//!
//! Device data (all read-only except the tile):
//!
//! * `rules`: 256 [`RuleInfo`], one per class code;
//! * `basis_t`: the basis tables of the used far rules, concatenated, each
//!   `nq × f` with row q contiguous (the plan's `FarTable::basis_t`);
//! * `colloc`: the N collocation points;
//! * `far_points`: the far-rule points of the column tile's `nk` elements,
//!   point-major: slot s = (offset of a used rule) + q holds rule point q of
//!   every element, `far_points[s · nk + e]`, the used rules concatenated in
//!   degree order (`stride` = Σ nq slots). Neighbouring invocations (elements
//!   e, e + 1) of the same rule read neighbouring records: coalesced loads;
//! * `classes`: the tile's class codes, four per u32;
//! * `tile`: the output, `rows × nk·f`, row-major.
//!
//! Two slots of (params, classes, tile, staging) buffers alternate so that the
//! host copies tile t while the device fills tile t + 1.

use crate::error::GpuError;
use crate::layout::{GpuScalar, Params, RuleInfo, MAX_NODES_PER_ELEMENT, RULE_SLOTS};
use crate::scope::ErrorScopes;
use crate::shader::{self, FAR_FIELD};
use crate::tiling::{Tile, TileLimits, TilePlan, WORKGROUP_X};
use crate::Precision;
use radcol_core::assembly::{AssemblyPlan, FarTable};
use radcol_core::quadrature::MAX_RULE_DEGREE;
use rayon::prelude::*;
use std::borrow::Cow;
use std::collections::HashMap;
use std::mem::size_of;
use std::sync::{mpsc, Mutex};
use wgpu::util::DeviceExt;

/// The far-field shader of one precision, its explicit bind group layout and
/// one pipeline per node count f_r (the WGSL override `F`), compiled on first
/// use and kept.
#[derive(Debug)]
pub struct FarFieldKernels {
    precision: Precision,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    pipelines: Mutex<HashMap<usize, wgpu::ComputePipeline>>,
}

impl FarFieldKernels {
    /// Compiles `shaders/far_field.wgsl` for `precision` (`F64` or `F32`;
    /// `Auto` picks f64 when the device has [`wgpu::Features::SHADER_F64`])
    /// and builds the pipeline for f_r = 3 (r = 1), the common case, so that
    /// backend compilers are exercised up front. Shader and pipeline errors
    /// are caught with error scopes.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Result<Self, GpuError> {
        let has_f64 = device.features().contains(wgpu::Features::SHADER_F64);
        let precision = match precision {
            Precision::Auto if has_f64 => Precision::F64,
            Precision::Auto => Precision::F32,
            Precision::F64 if !has_f64 => {
                return Err(GpuError::NoF64 {
                    adapter: device.adapter_info().name,
                })
            }
            p => p,
        };
        let scopes = ErrorScopes::push(device);
        let label = format!("radcol far_field {}", precision.name());
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&label),
            source: wgpu::ShaderSource::Wgsl(Cow::Owned(shader::source_for(&FAR_FIELD, precision))),
        });
        let layout = Self::bind_group_layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        scopes.pop("compiling the far-field shader")?;
        let kernels = Self {
            precision,
            layout,
            pipeline_layout,
            module,
            pipelines: Mutex::new(HashMap::new()),
        };
        kernels.pipeline(device, 3)?;
        Ok(kernels)
    }

    /// The pipeline for `f` nodes per element (1 ≤ f ≤ 28), compiled on first use.
    pub fn pipeline(
        &self,
        device: &wgpu::Device,
        f: usize,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        if f == 0 || f > MAX_NODES_PER_ELEMENT {
            return Err(GpuError::Unsupported(format!(
                "{f} nodes per element: the far-field shader holds 1 to {MAX_NODES_PER_ELEMENT} (r = 0..=6)"
            )));
        }
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = cache.get(&f) {
            return Ok(p.clone());
        }
        let scopes = ErrorScopes::push(device);
        let label = format!("radcol far_field {} f={f}", self.precision.name());
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&label),
            layout: Some(&self.pipeline_layout),
            module: &self.module,
            entry_point: Some(FAR_FIELD.entry_point),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &[("F", f as f64)],
                ..Default::default()
            },
            cache: None,
        });
        scopes.pop("building the far-field pipeline")?;
        cache.insert(f, pipeline.clone());
        Ok(pipeline)
    }

    /// The explicit layout of group 0 (bindings as in the WGSL source).
    pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("radcol far_field"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<Params>() as u64),
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, true),
                storage(5, true),
                storage(6, false),
            ],
        })
    }

    /// The precision compiled for (`F64` or `F32`).
    pub fn precision(&self) -> Precision {
        self.precision
    }
}

/// What [`fill_far_field`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FarFieldReport {
    /// Far kernel evaluations (the plan's count: f · nq per far pair of elements).
    pub kernel_evals: u64,
    /// Summed duration of the compute passes from timestamp queries, seconds,
    /// when the device has [`wgpu::Features::TIMESTAMP_QUERY`].
    pub device_seconds: Option<f64>,
    /// Tiles dispatched.
    pub tiles: usize,
}

/// Fills the far pairs of `plan` into `matrix` (N × N, row-major, length N²)
/// on `device`: every entry of a far pair gets its value, every other entry
/// (culled, near, self) is overwritten with 0, so near and self pairs must be
/// merged afterwards. Tiles respect `limits`.
pub fn fill_far_field(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &FarFieldKernels,
    plan: &AssemblyPlan,
    limits: &TileLimits,
    matrix: &mut [f64],
) -> Result<FarFieldReport, GpuError> {
    let n_dim = plan.dim();
    assert_eq!(matrix.len(), n_dim * n_dim, "matrix must be N × N");
    let f = plan.discretization().nodes_per_element();
    if f > MAX_NODES_PER_ELEMENT {
        return Err(GpuError::Unsupported(format!(
            "{f} nodes per element: the far-field shader holds at most {MAX_NODES_PER_ELEMENT} (r = 6)"
        )));
    }
    let scopes = ErrorScopes::push(device);
    let out = match kernels.precision {
        Precision::F32 => run::<f32>(device, queue, kernels, plan, limits, matrix),
        _ => run::<f64>(device, queue, kernels, plan, limits, matrix),
    };
    // A validation error explains any later failure (a failed map, say): report it first.
    scopes.pop("filling far pairs")?;
    out
}

/// The used far rules, laid out for the device.
struct Rules<'a> {
    /// (table, offset in an element record, offset in basis_t).
    used: Vec<(&'a FarTable, usize, usize)>,
    infos: Vec<RuleInfo>,
    basis_t: Vec<f64>,
    stride: usize,
}

impl<'a> Rules<'a> {
    fn new(plan: &'a AssemblyPlan) -> Result<Self, GpuError> {
        let mut infos = vec![RuleInfo::default(); RULE_SLOTS];
        let mut used = Vec::new();
        let mut basis_t = Vec::new();
        let mut stride = 0usize;
        for d in 0..=MAX_RULE_DEGREE {
            let Some(t) = plan.far_table(d) else { continue };
            let code = d + 1;
            if code >= RULE_SLOTS {
                return Err(GpuError::Unsupported(format!(
                    "far rule degree {d} has no class code"
                )));
            }
            infos[code] = RuleInfo {
                offset: to_u32(stride, "far points per element")?,
                nq: to_u32(t.nq, "rule points")?,
                basis: to_u32(basis_t.len(), "basis table length")?,
                far: 1,
            };
            used.push((t, stride, basis_t.len()));
            basis_t.extend_from_slice(&t.basis_t);
            stride += t.nq;
        }
        Ok(Self {
            used,
            infos,
            basis_t,
            stride,
        })
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

fn to_u32(x: usize, what: &str) -> Result<u32, GpuError> {
    u32::try_from(x).map_err(|_| GpuError::TooLarge {
        message: format!("{what} = {x} exceeds u32"),
    })
}

/// One of the two alternating sets of per-tile buffers.
struct Slot {
    params: wgpu::Buffer,
    classes: wgpu::Buffer,
    tile: wgpu::Buffer,
    staging: wgpu::Buffer,
    resolve: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
}

/// A submitted tile awaiting readback.
struct Pending {
    tile: Tile,
    slot: usize,
    bytes: u64,
    submission: wgpu::SubmissionIndex,
}

fn run<S: GpuScalar>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &FarFieldKernels,
    plan: &AssemblyPlan,
    limits: &TileLimits,
    matrix: &mut [f64],
) -> Result<FarFieldReport, GpuError> {
    let disc = plan.discretization();
    let n_dim = plan.dim();
    let n = disc.mesh().len();
    let f = disc.nodes_per_element();
    let rules = Rules::new(plan)?;
    if rules.used.is_empty() || n_dim == 0 {
        matrix.fill(0.0);
        return Ok(FarFieldReport::default());
    }
    let sb = size_of::<S>();
    let pb = size_of::<S::Point>();
    let tiles = TilePlan::new(n, f, rules.stride, pb, sb, limits)?;
    let bind = limits.binding_bytes();
    if (n_dim * pb) as u64 > bind {
        return Err(GpuError::TooLarge {
            message: format!("{n_dim} collocation points take {} bytes, more than one storage binding ({bind} bytes)", n_dim * pb),
        });
    }
    let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
    let pipeline = kernels.pipeline(device, f)?;

    // Static data: rules, basis tables, collocation points.
    let rules_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("radcol rules"),
        contents: bytemuck::cast_slice(&rules.infos),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let basis: Vec<S> = rules.basis_t.iter().map(|&x| S::from_f64(x)).collect();
    let basis_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("radcol basis_t"),
        contents: bytemuck::cast_slice(&basis),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let colloc: Vec<S::Point> = disc
        .points()
        .iter()
        .map(|p| S::point(p.position.to_array(), p.normal.to_array(), 0.0))
        .collect();
    let colloc_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("radcol colloc"),
        contents: bytemuck::cast_slice(&colloc),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let max_nk = tiles.max_nk();
    let geom_buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("radcol far_points"),
        size: (max_nk * rules.stride * pb) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });

    // Per-tile slots.
    let rows = tiles.rows_per_tile;
    let tile_bytes = (rows * max_nk * f * sb) as u64;
    let class_bytes = ((rows / f + 2) * max_nk).div_ceil(4) as u64 * 4;
    let query_set = timestamps.then(|| {
        device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("radcol far_field timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 4,
        })
    });
    let slots: Vec<Slot> = (0..2)
        .map(|s| {
            let params = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("radcol params"),
                size: size_of::<Params>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let classes = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("radcol classes"),
                size: class_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let tile = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("radcol tile"),
                size: tile_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let staging = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("radcol staging"),
                size: tile_bytes + if timestamps { 16 } else { 0 },
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let resolve = timestamps.then(|| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("radcol timestamps"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(if s == 0 {
                    "radcol far_field slot 0"
                } else {
                    "radcol far_field slot 1"
                }),
                layout: &kernels.layout,
                entries: &[
                    entry(0, &params),
                    entry(1, &rules_buf),
                    entry(2, &basis_buf),
                    entry(3, &colloc_buf),
                    entry(4, &geom_buf),
                    entry(5, &classes),
                    entry(6, &tile),
                ],
            });
            Slot {
                params,
                classes,
                tile,
                staging,
                resolve,
                bind_group,
            }
        })
        .collect();

    let classes = plan.classes();
    let mut device_ns = 0.0f64;
    let period = f64::from(queue.get_timestamp_period());
    let mut pending: Option<Pending> = None;
    let mut current_k0 = usize::MAX;
    let mut count = 0usize;
    for (t, tile) in tiles.tiles().enumerate() {
        if tile.k0 != current_k0 {
            // A new column tile: its elements' far points. Queue writes are
            // ordered after earlier submissions, so tiles still reading the
            // previous points are unaffected.
            current_k0 = tile.k0;
            let geom = far_points::<S>(&rules, tile.k0, tile.nk);
            queue.write_buffer(&geom_buf, 0, bytemuck::cast_slice(&geom));
        }
        let slot = &slots[t % 2];
        let kp0 = tile.row0 / f;
        let kp1 = (tile.row0 + tile.rows - 1) / f + 1;
        let mut codes = Vec::with_capacity(((kp1 - kp0) * tile.nk).div_ceil(4) * 4);
        for kp in kp0..kp1 {
            codes.extend_from_slice(&classes[kp * n + tile.k0..kp * n + tile.k0 + tile.nk]);
        }
        codes.resize(codes.len().div_ceil(4) * 4, 0);
        queue.write_buffer(&slot.classes, 0, &codes);
        let params = Params {
            row0: to_u32(tile.row0, "row")?,
            rows: to_u32(tile.rows, "rows")?,
            kp0: to_u32(kp0, "element")?,
            f: f as u32,
            k0: to_u32(tile.k0, "element")?,
            nk: to_u32(tile.nk, "elements")?,
            stride: to_u32(rules.stride, "stride")?,
            out_cols: to_u32(tile.nk * f, "columns")?,
        };
        queue.write_buffer(&slot.params, 0, bytemuck::bytes_of(&params));

        let bytes = (tile.rows * tile.nk * f * sb) as u64;
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("radcol far_field"),
        });
        {
            let base = (t % 2) as u32 * 2;
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("radcol far_field"),
                timestamp_writes: query_set
                    .as_ref()
                    .map(|qs| wgpu::ComputePassTimestampWrites {
                        query_set: qs,
                        beginning_of_pass_write_index: Some(base),
                        end_of_pass_write_index: Some(base + 1),
                    }),
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &slot.bind_group, &[]);
            pass.dispatch_workgroups((tile.nk as u32).div_ceil(WORKGROUP_X), tile.rows as u32, 1);
        }
        enc.copy_buffer_to_buffer(&slot.tile, 0, &slot.staging, 0, bytes);
        if let (Some(qs), Some(resolve)) = (&query_set, &slot.resolve) {
            let base = (t % 2) as u32 * 2;
            enc.resolve_query_set(qs, base..base + 2, resolve, 0);
            enc.copy_buffer_to_buffer(resolve, 0, &slot.staging, bytes, 16);
        }
        let submission = queue.submit(Some(enc.finish()));
        if let Some(p) = pending.take() {
            device_ns += read_back::<S>(
                device,
                &slots[p.slot],
                &p,
                timestamps,
                period,
                n_dim,
                f,
                matrix,
            )?;
        }
        pending = Some(Pending {
            tile,
            slot: t % 2,
            bytes,
            submission,
        });
        count += 1;
    }
    if let Some(p) = pending.take() {
        device_ns += read_back::<S>(
            device,
            &slots[p.slot],
            &p,
            timestamps,
            period,
            n_dim,
            f,
            matrix,
        )?;
    }
    Ok(FarFieldReport {
        kernel_evals: plan.stats().far_kernel_evals,
        device_seconds: timestamps.then_some(device_ns * 1e-9),
        tiles: count,
    })
}

/// The far points of elements `k0..k0 + nk`, point-major: `out[s · nk + e]` is
/// slot s (rule offset + q, the used rules in degree order) of element k0 + e.
fn far_points<S: GpuScalar>(rules: &Rules<'_>, k0: usize, nk: usize) -> Vec<S::Point> {
    let stride = rules.stride;
    let mut out = vec![S::point([0.0; 3], [0.0; 3], 0.0); nk * stride];
    // Slot s = offset + q of a rule holds that point for every element of the tile.
    let mut slot_rule = Vec::with_capacity(stride);
    for &(t, offset, _) in &rules.used {
        for q in 0..t.nq {
            slot_rule.push((t, q));
            debug_assert_eq!(slot_rule.len(), offset + q + 1);
        }
    }
    out.par_chunks_exact_mut(nk)
        .zip(slot_rule.par_iter())
        .for_each(|(slot, &(t, q))| {
            let nq = t.nq;
            for (e, rec) in slot.iter_mut().enumerate() {
                let i = (k0 + e) * nq + q;
                *rec = S::point(
                    [t.px[i], t.py[i], t.pz[i]],
                    [t.nx[i], t.ny[i], t.nz[i]],
                    t.wj[i],
                );
            }
        });
    out
}

/// Waits for tile `p`, copies it into `matrix` and returns the device
/// nanoseconds of its pass (0 without timestamps).
fn read_back<S: GpuScalar>(
    device: &wgpu::Device,
    slot: &Slot,
    p: &Pending,
    timestamps: bool,
    period_ns: f64,
    n_dim: usize,
    f: usize,
    matrix: &mut [f64],
) -> Result<f64, GpuError> {
    let len = p.bytes + if timestamps { 16 } else { 0 };
    let (tx, rx) = mpsc::channel();
    slot.staging
        .map_async(wgpu::MapMode::Read, 0..len, move |r| {
            // The receiver outlives the poll below; a send error cannot happen.
            let _ = tx.send(r);
        });
    device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(p.submission.clone()),
            timeout: None,
        })
        .map_err(|e| GpuError::Device {
            stage: "waiting for a tile",
            message: e.to_string(),
        })?;
    let mapped = rx.recv().map_err(|_| GpuError::Device {
        stage: "mapping a tile",
        message: "the map callback never ran".into(),
    })?;
    mapped.map_err(|e| GpuError::Device {
        stage: "mapping a tile",
        message: e.to_string(),
    })?;
    let mut ns = 0.0;
    {
        let view = slot
            .staging
            .get_mapped_range(0..len)
            .map_err(|e| GpuError::Device {
                stage: "reading a tile",
                message: e.to_string(),
            })?;
        let (data, ts) = view.split_at(p.bytes as usize);
        let tile = p.tile;
        let cols = tile.nk * f;
        let dst = &mut matrix[tile.row0 * n_dim..(tile.row0 + tile.rows) * n_dim];
        match bytemuck::try_cast_slice::<u8, S>(data) {
            Ok(src) => dst
                .par_chunks_exact_mut(n_dim)
                .zip(src.par_chunks_exact(cols))
                .for_each(|(row, src)| {
                    for (d, s) in row[tile.k0 * f..tile.k0 * f + cols].iter_mut().zip(src) {
                        *d = s.to_f64();
                    }
                }),
            // Mapped memory is page-aligned in practice; this path is for safety only.
            Err(_) => dst
                .par_chunks_exact_mut(n_dim)
                .zip(data.par_chunks_exact(cols * size_of::<S>()))
                .for_each(|(row, src)| {
                    for (d, s) in row[tile.k0 * f..tile.k0 * f + cols]
                        .iter_mut()
                        .zip(src.chunks_exact(size_of::<S>()))
                    {
                        *d = bytemuck::pod_read_unaligned::<S>(s).to_f64();
                    }
                }),
        }
        if timestamps {
            let begin: u64 = bytemuck::pod_read_unaligned(&ts[0..8]);
            let end: u64 = bytemuck::pod_read_unaligned(&ts[8..16]);
            ns = end.wrapping_sub(begin) as f64 * period_ns;
            if !(ns.is_finite() && ns >= 0.0 && end >= begin) {
                ns = 0.0;
            }
        }
    }
    slot.staging.unmap();
    Ok(ns)
}
