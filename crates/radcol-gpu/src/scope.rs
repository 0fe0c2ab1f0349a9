//! Error scopes: wgpu reports validation and out-of-memory errors
//! asynchronously; pushing scopes around a piece of work turns them into
//! [`GpuError`]s instead of the default panic.

use crate::error::GpuError;

/// Out-of-memory, internal and validation scopes, innermost last. Scopes are
/// thread-local: push and pop on the same thread.
pub(crate) struct ErrorScopes {
    oom: wgpu::ErrorScopeGuard,
    internal: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
}

impl ErrorScopes {
    pub(crate) fn push(device: &wgpu::Device) -> Self {
        Self {
            oom: device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
            internal: device.push_error_scope(wgpu::ErrorFilter::Internal),
            validation: device.push_error_scope(wgpu::ErrorFilter::Validation),
        }
    }

    /// Pops the scopes (innermost first) and returns the first error caught.
    pub(crate) fn pop(self, stage: &'static str) -> Result<(), GpuError> {
        let validation = pollster::block_on(self.validation.pop());
        let internal = pollster::block_on(self.internal.pop());
        let oom = pollster::block_on(self.oom.pop());
        match validation.or(internal).or(oom) {
            Some(e) => Err(GpuError::from_wgpu(stage, e)),
            None => Ok(()),
        }
    }
}
