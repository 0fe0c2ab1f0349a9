//! Every WGSL file of `shaders/` parsed and validated by naga in each precision
//! it is compiled for, host struct layouts checked against naga's layouter, and
//! the kernel's builtins restricted to those that are exact in f64 on every
//! backend. No GPU needed.

use naga::valid::{Capabilities, ValidationFlags, Validator};
use radcol_core::assembly::Scalar;
use radcol_gpu::layout::{Params, PointF32, PointF64, RuleInfo};
use radcol_gpu::shader::{source_for, ShaderFile, SHADERS};
use std::mem::{offset_of, size_of};
use std::path::PathBuf;

const PRECISIONS: [Scalar; 2] = [Scalar::F64, Scalar::F32];

fn shaders_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

/// Parses and validates `file` for `precision`; f32 must validate without the
/// FLOAT64 capability (it runs on adapters that lack it).
fn module(file: &ShaderFile, precision: Scalar) -> naga::Module {
    let src = source_for(file, precision);
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{} ({precision}): {}", file.name, e.emit_to_string(&src)));
    let caps = match precision {
        Scalar::F32 => Capabilities::empty(),
        _ => Capabilities::FLOAT64,
    };
    Validator::new(ValidationFlags::all(), caps)
        .validate(&module)
        .unwrap_or_else(|e| panic!("{} ({precision}): {}", file.name, e.emit_to_string(&src)));
    module
}

#[test]
fn every_shader_file_is_compiled_by_the_crate() {
    let mut on_disk: Vec<String> = std::fs::read_dir(shaders_dir())
        .expect("shaders/ exists")
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = SHADERS.iter().map(|s| s.name.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "shaders/ and radcol_gpu::shader::SHADERS must list the same files"
    );
    for s in SHADERS {
        let text = std::fs::read_to_string(shaders_dir().join(s.name)).unwrap();
        assert_eq!(text, s.source, "{} is stale in the build", s.name);
    }
}

#[test]
fn every_shader_parses_and_validates_in_each_precision() {
    for file in SHADERS {
        for p in PRECISIONS {
            let m = module(file, p);
            assert!(
                m.entry_points
                    .iter()
                    .any(|e| e.name == file.entry_point && e.stage == naga::ShaderStage::Compute),
                "{}: no compute entry point '{}'",
                file.name,
                file.entry_point
            );
            println!("{} ({p}): ok", file.name);
        }
    }
}

/// The f32 source must not need f64, and the f64 one must not validate
/// without FLOAT64 (i.e. the alias really switches the precision).
#[test]
fn the_scalar_alias_switches_precision() {
    for file in SHADERS {
        let src = source_for(file, Scalar::F64);
        let m = naga::front::wgsl::parse_str(&src).unwrap();
        let r = Validator::new(ValidationFlags::all(), Capabilities::empty()).validate(&m);
        assert!(
            r.is_err(),
            "{}: the f64 build validated without FLOAT64",
            file.name
        );
    }
}

/// wgpu issue 6087: f64 transcendental builtins are unreliable on Vulkan
/// (lavapipe returned 0 for sin). The kernels use arithmetic and these only.
#[test]
fn kernels_use_only_exact_builtins() {
    use naga::MathFunction as M;
    let allowed = [M::Max, M::Min, M::Abs, M::Sqrt, M::Fma];
    for file in SHADERS {
        let m = module(file, Scalar::F64);
        let functions = m
            .functions
            .iter()
            .map(|(_, f)| f)
            .chain(m.entry_points.iter().map(|e| &e.function));
        for func in functions {
            for (_, expr) in func.expressions.iter() {
                if let naga::Expression::Math { fun, .. } = expr {
                    assert!(
                        allowed.contains(fun),
                        "{}: uses {fun:?}, not exact in f64 on Vulkan",
                        file.name
                    );
                }
            }
        }
    }
}

/// The shader's accumulator length is the host's limit on f_r.
#[test]
fn accumulator_length_matches_the_host() {
    let m = module(&radcol_gpu::shader::FAR_FIELD, Scalar::F64);
    let (_, c) = m
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("MAX_F"))
        .expect("const MAX_F");
    match m.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => {
            assert_eq!(v as usize, radcol_gpu::layout::MAX_NODES_PER_ELEMENT)
        }
        ref e => panic!("MAX_F is {e:?}"),
    }
}

/// Host structs have the WGSL size and member offsets in both precisions.
#[test]
fn host_structs_match_naga_layouts() {
    for p in PRECISIONS {
        let m = module(&radcol_gpu::shader::FAR_FIELD, p);
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(m.to_ctx()).expect("layouts");
        let find = |name: &str| {
            m.types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("no struct {name}"))
        };
        let check = |name: &str, size: usize, offsets: &[(&str, usize)]| {
            let (h, ty) = find(name);
            let layout = layouter[h];
            assert_eq!(
                layout.size as usize, size,
                "{name} ({p}): WGSL size {} vs host {size}",
                layout.size
            );
            assert_eq!(
                layout.to_stride() as usize,
                size,
                "{name} ({p}): array stride"
            );
            let naga::TypeInner::Struct { members, .. } = &ty.inner else {
                panic!("{name} is not a struct")
            };
            assert_eq!(members.len(), offsets.len(), "{name} ({p}): member count");
            for (m, (field, off)) in members.iter().zip(offsets) {
                assert_eq!(
                    m.name.as_deref(),
                    Some(*field),
                    "{name} ({p}): member order"
                );
                assert_eq!(
                    m.offset as usize, *off,
                    "{name}.{field} ({p}): WGSL offset {} vs host {off}",
                    m.offset
                );
            }
            println!("{name} ({p}): {size} bytes, offsets agree");
        };
        check(
            "Params",
            size_of::<Params>(),
            &[
                ("row0", offset_of!(Params, row0)),
                ("rows", offset_of!(Params, rows)),
                ("kp0", offset_of!(Params, kp0)),
                ("f", offset_of!(Params, f)),
                ("k0", offset_of!(Params, k0)),
                ("nk", offset_of!(Params, nk)),
                ("stride", offset_of!(Params, stride)),
                ("out_cols", offset_of!(Params, out_cols)),
            ],
        );
        check(
            "RuleInfo",
            size_of::<RuleInfo>(),
            &[
                ("offset", offset_of!(RuleInfo, offset)),
                ("nq", offset_of!(RuleInfo, nq)),
                ("basis", offset_of!(RuleInfo, basis)),
                ("far", offset_of!(RuleInfo, far)),
            ],
        );
        match p {
            Scalar::F32 => check(
                "Point",
                size_of::<PointF32>(),
                &[
                    ("p", offset_of!(PointF32, p)),
                    ("wj", offset_of!(PointF32, wj)),
                    ("n", offset_of!(PointF32, n)),
                    ("pad", offset_of!(PointF32, pad)),
                ],
            ),
            _ => check(
                "Point",
                size_of::<PointF64>(),
                &[
                    ("p", offset_of!(PointF64, p)),
                    ("wj", offset_of!(PointF64, wj)),
                    ("n", offset_of!(PointF64, n)),
                    ("pad", offset_of!(PointF64, pad)),
                ],
            ),
        }
    }
}
