//! The value sets of the command line's enumerated options.

use clap::ValueEnum;

/// What a target error is relative to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RelativeToArg {
    /// max |u|: in a lit scene, the light itself.
    MaxU,
    /// The light the surfaces reflect, max over the nodes of u − E.
    Reflected,
}

/// Which linear solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// Restarted GMRES (tolerance --tol).
    Gmres,
    /// Dense LU factorisation (needs a second N×N matrix).
    Lu,
}

/// Which geometric operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OperatorArg {
    /// Dense when the matrix fits in memory or the solver is LU, else compressed.
    Auto,
    /// The dense N×N matrix (8 N² bytes).
    Dense,
    /// A hierarchical matrix (GMRES only).
    Compressed,
}

/// Which assembly backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// rayon on all cores, f64.
    Cpu,
    /// wgpu compute shaders on the best adapter (software ones such as lavapipe
    /// included); an error when there is none.
    Gpu,
    /// A hardware GPU adapter when one exists (and offers f64 when f64 is
    /// asked for), else the CPU; the report says which was used.
    Auto,
}

/// What an MTL file's `Ke` means.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KeArg {
    /// Emitted flux per unit area (W/m², the E of the radiosity equation): Ke as given.
    Exitance,
    /// Emitted radiance (W/m²/sr, as path tracers read it): E = π Ke for a diffuse emitter.
    Radiance,
}

/// How partly visible element pairs are integrated in scenes that occlude.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum VisibilityArg {
    /// Over the exactly clipped visible region (accurate to the quadrature tolerance).
    Clip,
    /// With a ray per quadrature point (the textbook way; errors ~1e-3 at shadow edges).
    Rays,
    /// Clipped where the light comes from (emitters) and where a pair holds much of a
    /// point's view; elsewhere a few rays per pair, within a budget whose bound is added to
    /// the error estimate (docs/visibility.md).
    Approximate,
}

/// Arithmetic precision on the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    /// f64 when the adapter offers SHADER_F64, else f32.
    Auto,
    /// f64 on the device.
    F64,
    /// f32 on the device (results widened to f64).
    F32,
}

/// Tone curve for 8-bit outputs (PNG, vertex colours of PLY and glTF).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TonemapArg {
    /// Narkowicz's ACES filmic fit.
    Aces,
    /// Reinhard's x / (1 + x), per channel.
    Reinhard,
    /// Clamp to [0, 1].
    Linear,
}

/// `--vertices`: where the vertex meshes' values live.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VerticesArg {
    /// A tessellation of every element of radcol's mesh (`--tessellation`).
    Elements,
    /// The scene's own triangles, three vertices each with their own values.
    Input,
    /// The scene's own triangles, corners of one material at one position
    /// and normal shared, their values averaged.
    InputShared,
}
