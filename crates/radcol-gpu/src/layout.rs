//! Host mirrors of the WGSL structs in `shaders/far_field.wgsl`.
//!
//! Every struct is `#[repr(C)]` + [`bytemuck::Pod`] with its padding spelled
//! out, so that its bytes are exactly what the shader reads; the crate's tests
//! compare sizes and member offsets with naga's layouter in both precisions.

use bytemuck::{Pod, Zeroable};

/// Where a tile sits in the matrix (WGSL `Params`, a uniform). 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Params {
    /// First matrix row of the tile.
    pub row0: u32,
    /// Rows in the tile.
    pub rows: u32,
    /// Element of the tile's first row block, `row0 / f`.
    pub kp0: u32,
    /// Nodes per element f_r.
    pub f: u32,
    /// First element of the column tile.
    pub k0: u32,
    /// Elements in the column tile.
    pub nk: u32,
    /// Far points per element record in the geometry buffer.
    pub stride: u32,
    /// Scalars per tile row, `nk * f`.
    pub out_cols: u32,
}

/// The far rule behind one class code (WGSL `RuleInfo`). 16 bytes; the shader
/// reads an array of 256, indexed by class code.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RuleInfo {
    /// Offset of the rule's points within an element record.
    pub offset: u32,
    /// Points of the rule.
    pub nq: u32,
    /// Offset of the rule's `nq × f` basis table in the basis buffer.
    pub basis: u32,
    /// 1 for a far rule, 0 otherwise.
    pub far: u32,
}

/// A point, its inner unit normal and its weight in f64 (WGSL `Point` with
/// `scalar = f64`): `vec3<f64>` has size 24 and alignment 32, so `wj` fills the
/// gap before `n` and `pad` rounds the size up to 64.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PointF64 {
    /// Position.
    pub p: [f64; 3],
    /// Weight × Jacobian / π (0 for collocation points).
    pub wj: f64,
    /// Inner unit normal.
    pub n: [f64; 3],
    /// Explicit padding to the WGSL size.
    pub pad: f64,
}

/// The same in f32 (`vec3<f32>` has size 12 and alignment 16): 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PointF32 {
    /// Position.
    pub p: [f32; 3],
    /// Weight × Jacobian / π (0 for collocation points).
    pub wj: f32,
    /// Inner unit normal.
    pub n: [f32; 3],
    /// Explicit padding to the WGSL size.
    pub pad: f32,
}

/// Number of class codes (`u8`), the length of the shader's rule array.
pub const RULE_SLOTS: usize = 256;

/// Largest f_r the shader's accumulator holds (r = 6).
pub const MAX_NODES_PER_ELEMENT: usize = 28;

/// A device scalar: f64 or f32, with its point record.
pub trait GpuScalar: Pod + Send + Sync + 'static {
    /// The WGSL type name, as in `alias scalar = f64;`.
    const WGSL: &'static str;
    /// The host mirror of WGSL `Point` for this scalar.
    type Point: Pod + Send + Sync;
    /// Rounds an f64 to this scalar.
    fn from_f64(x: f64) -> Self;
    /// Widens to f64.
    fn to_f64(self) -> f64;
    /// A point record: position, normal, weight.
    fn point(p: [f64; 3], n: [f64; 3], wj: f64) -> Self::Point;
}

impl GpuScalar for f64 {
    const WGSL: &'static str = "f64";
    type Point = PointF64;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn point(p: [f64; 3], n: [f64; 3], wj: f64) -> PointF64 {
        PointF64 { p, wj, n, pad: 0.0 }
    }
}

impl GpuScalar for f32 {
    const WGSL: &'static str = "f32";
    type Point = PointF32;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn point(p: [f64; 3], n: [f64; 3], wj: f64) -> PointF32 {
        let c = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
        PointF32 {
            p: c(p),
            wj: wj as f32,
            n: c(n),
            pad: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn host_sizes_are_the_documented_ones() {
        assert_eq!(size_of::<Params>(), 32);
        assert_eq!(size_of::<RuleInfo>(), 16);
        assert_eq!(size_of::<PointF64>(), 64);
        assert_eq!(size_of::<PointF32>(), 32);
        assert_eq!(offset_of!(PointF64, n), 32);
        assert_eq!(offset_of!(PointF32, n), 16);
    }
}
