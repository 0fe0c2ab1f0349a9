//! WGSL sources (from the crate's `shaders/`) and the one-line
//! preamble that picks the precision.

use radcol_core::backend::Scalar;

/// A WGSL file of `shaders/`, compiled into the crate.
#[derive(Clone, Copy, Debug)]
pub struct ShaderFile {
    /// File name within `shaders/`.
    pub name: &'static str,
    /// Entry point of its compute kernel.
    pub entry_point: &'static str,
    /// The source, without the precision preamble.
    pub source: &'static str,
}

/// The far-field kernel.
pub const FAR_FIELD: ShaderFile = ShaderFile {
    name: "far_field.wgsl",
    entry_point: "far_field",
    source: include_str!("../shaders/far_field.wgsl"),
};

/// Every shader the crate compiles (the tests check this lists all of `shaders/`).
pub const SHADERS: &[ShaderFile] = &[FAR_FIELD];

/// The precision preamble: the scalar alias every shader is written against.
/// naga needs no `enable` directive for f64; the device needs
/// [`wgpu::Features::SHADER_F64`].
pub fn preamble(precision: Scalar) -> &'static str {
    match precision {
        Scalar::F32 => "alias scalar = f32;\n",
        Scalar::F64 => "alias scalar = f64;\n",
    }
}

/// `file`'s source with the preamble of `precision` prepended: exactly what is
/// handed to the device.
pub fn source_for(file: &ShaderFile, precision: Scalar) -> String {
    let mut s = String::with_capacity(file.source.len() + 32);
    s.push_str(preamble(precision));
    s.push_str(file.source);
    s
}
