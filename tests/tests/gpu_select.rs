//! Backend selection: `cpu` never touches wgpu, `gpu` without an adapter is
//! a clear error, `auto` picks a hardware GPU or the CPU.

use radcol_core::assembly::{BackendKind, Scalar};
use radcol_gpu::testing::gpu_required;
use radcol_gpu::{select_backend, AdapterFilter, BackendChoice, GpuContext, Precision};

fn named(
    name: &str,
    precision: Precision,
) -> Result<Box<dyn radcol_core::assembly::AssemblyBackend>, String> {
    let choice: BackendChoice = name
        .parse()
        .map_err(|e: radcol_gpu::GpuError| e.to_string())?;
    select_backend(choice, precision).map_err(|e| e.to_string())
}

#[test]
fn cpu_is_the_rayon_backend_in_f64() {
    let b = named("cpu", Precision::Auto).unwrap();
    let info = b.info();
    assert_eq!((info.kind, info.precision), (BackendKind::Cpu, Scalar::F64));
    assert!(named("CPU", Precision::F64).is_ok());
    let e = named("cpu", Precision::F32)
        .err()
        .expect("f32 on the CPU is refused");
    assert!(e.contains("f64 only"), "{e}");
}

#[test]
fn unknown_names_are_refused() {
    let e = named("tpu", Precision::Auto)
        .err()
        .expect("unknown backend");
    assert!(e.contains("expected cpu, gpu or auto"), "{e}");
    let e = "f16".parse::<Precision>().unwrap_err();
    assert!(e.to_string().contains("expected auto, f64 or f32"), "{e}");
    assert_eq!("F32".parse::<Precision>().unwrap(), Precision::F32);
}

#[test]
fn gpu_is_an_adapter_or_a_clear_error() {
    match named("gpu", Precision::Auto) {
        Ok(b) => {
            let info = b.info();
            println!("gpu: {} ({})", info.device, info.precision);
            assert_eq!(info.kind, BackendKind::Gpu);
            assert!(!info.device.is_empty());
        }
        Err(msg) => {
            println!("gpu: {msg}");
            assert!(!gpu_required(), "RADCOL_REQUIRE_GPU is set but: {msg}");
            // The library names the fallback; the CLI adds its flag
            // (crates/radcol-cli/tests/cli.rs).
            assert!(
                msg.contains("no GPU adapter") && msg.contains("CPU backend"),
                "{msg}"
            );
        }
    }
}

#[test]
fn auto_uses_a_hardware_gpu_or_the_cpu() {
    let b = named("auto", Precision::Auto).unwrap();
    let info = b.info();
    println!("auto: {info}");
    let hardware = GpuContext::new(AdapterFilter::Hardware).is_ok();
    let want = if hardware {
        BackendKind::Gpu
    } else {
        BackendKind::Cpu
    };
    assert_eq!(info.kind, want);
}
