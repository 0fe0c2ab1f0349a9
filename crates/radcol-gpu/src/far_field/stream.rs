//! Streaming tiles through the device: static buffers once, two alternating
//! slots of per-tile buffers, one submission per tile, and the read-back of
//! tile t while the device computes tile t + 1.

use super::kernels::FarFieldKernels;
use super::pack::{far_points, tile_codes, tile_params, Rules};
use super::readback::{drain, Pending, ReadBack};
use super::slot::Slot;
use super::FarFieldReport;
use crate::error::GpuError;
use crate::layout::{GpuScalar, Params};
use crate::tiling::{TileLimits, TilePlan, WORKGROUP_X};
use radcol_core::backend::AssemblyPlan;
use std::mem::size_of;
use wgpu::util::DeviceExt;

/// The read-only buffers every tile binds.
struct Static {
    rules: wgpu::Buffer,
    basis: wgpu::Buffer,
    colloc: wgpu::Buffer,
    far_points: wgpu::Buffer,
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

impl Static {
    /// Rules, basis tables and collocation points uploaded; the far-points
    /// buffer sized for the widest column tile.
    fn new<S: GpuScalar>(
        device: &wgpu::Device,
        plan: &AssemblyPlan,
        rules: &Rules<'_>,
        max_nk: usize,
    ) -> Self {
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let basis: Vec<S> = rules.basis_t.iter().map(|&x| S::from_f64(x)).collect();
        let colloc: Vec<S::Point> = plan
            .discretization()
            .points()
            .iter()
            .map(|p| S::point(p.position.to_array(), p.normal.to_array(), 0.0))
            .collect();
        Self {
            rules: init("radcol rules", bytemuck::cast_slice(&rules.infos)),
            basis: init("radcol basis_t", bytemuck::cast_slice(&basis)),
            colloc: init("radcol colloc", bytemuck::cast_slice(&colloc)),
            far_points: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("radcol far_points"),
                size: (max_nk * rules.stride * size_of::<S::Point>()) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

impl Slot {
    /// Slot `s` for tiles of at most `tile_bytes` and `class_bytes`.
    fn new(
        device: &wgpu::Device,
        kernels: &FarFieldKernels,
        statics: &Static,
        s: usize,
        tile_bytes: u64,
        class_bytes: u64,
        timestamps: bool,
    ) -> Self {
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let params = buffer(
            "radcol params",
            size_of::<Params>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let classes = buffer("radcol classes", class_bytes, U::STORAGE | U::COPY_DST);
        let tile = buffer("radcol tile", tile_bytes, U::STORAGE | U::COPY_SRC);
        let extra = if timestamps { 16 } else { 0 };
        let staging = buffer(
            "radcol staging",
            tile_bytes + extra,
            U::MAP_READ | U::COPY_DST,
        );
        let resolve =
            timestamps.then(|| buffer("radcol timestamps", 16, U::QUERY_RESOLVE | U::COPY_SRC));
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(if s == 0 {
                "radcol far_field slot 0"
            } else {
                "radcol far_field slot 1"
            }),
            layout: &kernels.layout,
            entries: &[
                entry(0, &params),
                entry(1, &statics.rules),
                entry(2, &statics.basis),
                entry(3, &statics.colloc),
                entry(4, &statics.far_points),
                entry(5, &classes),
                entry(6, &tile),
            ],
        });
        Self {
            params,
            classes,
            tile,
            staging,
            resolve,
            bind_group,
        }
    }
}

/// Encodes tile pass, copy to staging and (with timestamps) the query
/// resolve of slot `s`; returns the submission.
fn submit(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pipeline: &wgpu::ComputePipeline,
    slot: &Slot,
    s: usize,
    query_set: Option<&wgpu::QuerySet>,
    dispatch: (u32, u32),
    bytes: u64,
) -> wgpu::SubmissionIndex {
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("radcol far_field"),
    });
    let base = s as u32 * 2;
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("radcol far_field"),
            timestamp_writes: query_set.map(|qs| wgpu::ComputePassTimestampWrites {
                query_set: qs,
                beginning_of_pass_write_index: Some(base),
                end_of_pass_write_index: Some(base + 1),
            }),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &slot.bind_group, &[]);
        pass.dispatch_workgroups(dispatch.0, dispatch.1, 1);
    }
    enc.copy_buffer_to_buffer(&slot.tile, 0, &slot.staging, 0, bytes);
    if let (Some(qs), Some(resolve)) = (query_set, &slot.resolve) {
        enc.resolve_query_set(qs, base..base + 2, resolve, 0);
        enc.copy_buffer_to_buffer(resolve, 0, &slot.staging, bytes, 16);
    }
    queue.submit(Some(enc.finish()))
}

/// The two alternating slots for the tiles of `tiles` (f nodes per element,
/// `sb` bytes per scalar), and the timestamp query set when the device has one.
fn slots(
    device: &wgpu::Device,
    kernels: &FarFieldKernels,
    statics: &Static,
    tiles: &TilePlan,
    f: usize,
    sb: usize,
    timestamps: bool,
) -> (Vec<Slot>, Option<wgpu::QuerySet>) {
    let max_nk = tiles.max_nk();
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
            Slot::new(
                device,
                kernels,
                statics,
                s,
                tile_bytes,
                class_bytes,
                timestamps,
            )
        })
        .collect();
    (slots, query_set)
}

/// The far field of `plan` in precision `S`, tile by tile.
pub(super) fn run<S: GpuScalar>(
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
    // One node set (checked by `fill_far_field`).
    let f = disc.max_nodes_per_element();
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
    let max_nk = tiles.max_nk();
    let statics = Static::new::<S>(device, plan, &rules, max_nk);
    let (slots, query_set) = slots(device, kernels, &statics, &tiles, f, sb, timestamps);
    let reader = ReadBack {
        device,
        slots: &slots,
        timestamps,
        period_ns: f64::from(queue.get_timestamp_period()),
        n_dim,
        f,
    };

    let classes = plan.classes();
    let mut device_ns = 0.0f64;
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
            queue.write_buffer(&statics.far_points, 0, bytemuck::cast_slice(&geom));
        }
        let slot = &slots[t % 2];
        queue.write_buffer(&slot.classes, 0, &tile_codes(classes, f, &tile));
        let params = tile_params(&tile, f, rules.stride)?;
        queue.write_buffer(&slot.params, 0, bytemuck::bytes_of(&params));
        let bytes = (tile.rows * tile.nk * f * sb) as u64;
        let dispatch = ((tile.nk as u32).div_ceil(WORKGROUP_X), tile.rows as u32);
        let submission = submit(
            device,
            queue,
            &pipeline,
            slot,
            t % 2,
            query_set.as_ref(),
            dispatch,
            bytes,
        );
        device_ns += drain::<S>(&reader, pending.take(), matrix)?;
        pending = Some(Pending {
            tile,
            slot: t % 2,
            bytes,
            submission,
        });
        count += 1;
    }
    device_ns += drain::<S>(&reader, pending.take(), matrix)?;
    Ok(FarFieldReport {
        kernel_evals: plan.stats().far_kernel_evals,
        device_seconds: timestamps.then_some(device_ns * 1e-9),
        tiles: count,
    })
}
