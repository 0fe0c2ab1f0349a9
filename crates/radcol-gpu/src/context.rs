//! The GPU context: instance, adapter, device, queue and compiled pipelines,
//! built once and shared (behind an `Arc`) by every assembly.

use crate::error::GpuError;
use crate::far_field::FarFieldKernels;
use crate::tiling::TileLimits;
use crate::Precision;
use radcol_core::backend::Scalar;
use std::sync::Arc;

/// Which adapters a context may use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AdapterFilter {
    /// Any adapter, hardware preferred; software rasterisers (lavapipe) accepted.
    #[default]
    Any,
    /// Hardware only: software rasterisers run on the same cores as the CPU
    /// backend and are slower than it, so `auto` skips them.
    Hardware,
}

/// A device and queue with the far-field pipelines compiled for it.
#[derive(Debug)]
pub struct GpuContext {
    info: wgpu::AdapterInfo,
    device: wgpu::Device,
    queue: wgpu::Queue,
    f64_kernels: Option<FarFieldKernels>,
    f32_kernels: FarFieldKernels,
}

impl GpuContext {
    /// The best adapter `filter` allows (discrete before integrated before
    /// virtual before other before software; f64 support breaks ties), a device
    /// with the adapter's limits and, when offered, `SHADER_F64` and
    /// `TIMESTAMP_QUERY`, and the pipelines of both precisions.
    pub fn new(filter: AdapterFilter) -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let described: Vec<String> = adapters
            .iter()
            .map(|a| {
                let i = a.get_info();
                format!("{} [{:?}, {:?}]", i.name, i.device_type, i.backend)
            })
            .collect();
        let adapter = adapters
            .into_iter()
            .filter(|a| {
                filter == AdapterFilter::Any || a.get_info().device_type != wgpu::DeviceType::Cpu
            })
            .max_by_key(|a| {
                let rank = match a.get_info().device_type {
                    wgpu::DeviceType::DiscreteGpu => 4,
                    wgpu::DeviceType::IntegratedGpu => 3,
                    wgpu::DeviceType::VirtualGpu => 2,
                    wgpu::DeviceType::Other => 1,
                    wgpu::DeviceType::Cpu => 0,
                };
                (rank, a.features().contains(wgpu::Features::SHADER_F64))
            })
            .ok_or_else(|| GpuError::NoAdapter {
                detail: if described.is_empty() {
                    "wgpu enumerated no adapters".into()
                } else {
                    format!(
                        "only software adapters, which {filter:?} excludes: {}",
                        described.join(", ")
                    )
                },
            })?;
        let info = adapter.get_info();
        let wanted = wgpu::Features::SHADER_F64 | wgpu::Features::TIMESTAMP_QUERY;
        let desc = wgpu::DeviceDescriptor {
            label: Some("radcol-gpu"),
            required_features: adapter.features() & wanted,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| {
            GpuError::RequestDevice {
                adapter: info.name.clone(),
                message: e.to_string(),
            }
        })?;
        Self::from_device(info, device, queue)
    }

    /// A context around a device and queue the caller made (tests, benches,
    /// applications that own their device). Compiles the pipelines: f64 when
    /// the device has `SHADER_F64`, f32 always.
    pub fn from_device(
        info: wgpu::AdapterInfo,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self, GpuError> {
        // Every operation of this crate runs inside error scopes; anything
        // else is logged rather than turned into wgpu's default panic.
        device.on_uncaptured_error(Arc::new(|e: wgpu::Error| {
            eprintln!("radcol-gpu: uncaptured wgpu error: {e}");
        }));
        let f64_kernels = if device.features().contains(wgpu::Features::SHADER_F64) {
            Some(FarFieldKernels::new(&device, Precision::F64)?)
        } else {
            None
        };
        let f32_kernels = FarFieldKernels::new(&device, Precision::F32)?;
        Ok(Self {
            info,
            device,
            queue,
            f64_kernels,
            f32_kernels,
        })
    }

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The adapter's description.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// "name (driver driver_info)", as reports print it.
    pub fn description(&self) -> String {
        let i = &self.info;
        let driver = [i.driver.as_str(), i.driver_info.as_str()]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
        if driver.is_empty() {
            format!("{} ({:?})", i.name, i.backend)
        } else {
            format!("{} ({driver})", i.name)
        }
    }

    /// True for software rasterisers (lavapipe, llvmpipe, WARP).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Whether the device runs f64 shaders.
    pub fn supports_f64(&self) -> bool {
        self.f64_kernels.is_some()
    }

    /// Whether compute passes are timed with timestamp queries.
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// `precision` with `Auto` resolved: f64 when supported, else f32.
    pub fn resolve(&self, precision: Precision) -> Result<Scalar, GpuError> {
        match precision {
            Precision::Auto if self.supports_f64() => Ok(Scalar::F64),
            Precision::Auto | Precision::F32 => Ok(Scalar::F32),
            Precision::F64 if self.supports_f64() => Ok(Scalar::F64),
            Precision::F64 => Err(GpuError::NoF64 {
                adapter: self.info.name.clone(),
            }),
        }
    }

    /// The far-field pipelines for `precision`.
    pub fn kernels(&self, precision: Scalar) -> Result<&FarFieldKernels, GpuError> {
        match precision {
            Scalar::F64 => self.f64_kernels.as_ref().ok_or_else(|| GpuError::NoF64 {
                adapter: self.info.name.clone(),
            }),
            Scalar::F32 => Ok(&self.f32_kernels),
        }
    }

    /// Tile limits of this device (default target tile size).
    pub fn tile_limits(&self) -> TileLimits {
        TileLimits::from_device_limits(&self.device.limits())
    }
}
