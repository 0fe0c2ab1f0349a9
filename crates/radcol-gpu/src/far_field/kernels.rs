//! The far-field shader, its bind group layout and its pipelines.

use crate::error::GpuError;
use crate::layout::{Params, MAX_NODES_PER_ELEMENT};
use crate::scope::ErrorScopes;
use crate::shader::{self, FAR_FIELD};
use crate::Precision;
use radcol_core::backend::Scalar;
use std::borrow::Cow;
use std::collections::HashMap;
use std::mem::size_of;
use std::sync::Mutex;

/// The far-field shader of one precision, its explicit bind group layout and
/// one pipeline per node count f_r (the WGSL override `F`), compiled on first
/// use and kept.
#[derive(Debug)]
pub struct FarFieldKernels {
    precision: Scalar,
    pub(super) layout: wgpu::BindGroupLayout,
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
            Precision::Auto if has_f64 => Scalar::F64,
            Precision::Auto => Scalar::F32,
            Precision::F64 if !has_f64 => {
                return Err(GpuError::NoF64 {
                    adapter: device.adapter_info().name,
                })
            }
            Precision::F64 => Scalar::F64,
            Precision::F32 => Scalar::F32,
        };
        let scopes = ErrorScopes::push(device);
        let label = format!("radcol far_field {precision}");
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
        let label = format!("radcol far_field {} f={f}", self.precision);
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

    /// The precision compiled for.
    pub fn precision(&self) -> Scalar {
        self.precision
    }
}
