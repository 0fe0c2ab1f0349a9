//! The per-tile buffers the stream alternates between and the read-back
//! drains.

/// One of the two alternating sets of per-tile buffers.
pub(super) struct Slot {
    pub(super) params: wgpu::Buffer,
    pub(super) classes: wgpu::Buffer,
    pub(super) tile: wgpu::Buffer,
    pub(super) staging: wgpu::Buffer,
    pub(super) resolve: Option<wgpu::Buffer>,
    pub(super) bind_group: wgpu::BindGroup,
}
