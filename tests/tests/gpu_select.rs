//! Backend selection by name: `cpu` never touches wgpu, `gpu` without an
//! adapter is a clear error, `auto` picks a hardware GPU or the CPU.

use radcol_gpu::testing::gpu_required;
use radcol_gpu::{backend_from_name, AdapterFilter, GpuContext, Precision};

#[test]
fn cpu_is_the_rayon_backend_in_f64() {
    let b = backend_from_name("cpu", None).unwrap();
    let info = b.info();
    assert_eq!(
        (info.kind.as_str(), info.precision.as_str()),
        ("cpu", "f64")
    );
    assert!(backend_from_name("CPU", Some(Precision::F64)).is_ok());
    let e = backend_from_name("cpu", Some(Precision::F32))
        .err()
        .expect("f32 on the CPU is refused");
    assert!(e.to_string().contains("f64 only"), "{e}");
}

#[test]
fn unknown_names_are_refused() {
    let e = backend_from_name("tpu", None)
        .err()
        .expect("unknown backend");
    assert!(e.to_string().contains("expected cpu, gpu or auto"), "{e}");
    let e = "f16".parse::<Precision>().unwrap_err();
    assert!(e.to_string().contains("expected auto, f64 or f32"), "{e}");
    assert_eq!("F32".parse::<Precision>().unwrap(), Precision::F32);
}

#[test]
fn gpu_is_an_adapter_or_a_clear_error() {
    match backend_from_name("gpu", None) {
        Ok(b) => {
            let info = b.info();
            println!("gpu: {} ({})", info.device, info.precision);
            assert_eq!(info.kind, "gpu");
            assert!(info.precision == "f64" || info.precision == "f32");
            assert!(!info.device.is_empty());
        }
        Err(e) => {
            let msg = e.to_string();
            println!("gpu: {msg}");
            assert!(!gpu_required(), "RADCOL_REQUIRE_GPU is set but: {msg}");
            assert!(
                msg.contains("no GPU adapter") && msg.contains("--backend cpu"),
                "{msg}"
            );
        }
    }
}

#[test]
fn auto_uses_a_hardware_gpu_or_the_cpu() {
    let b = backend_from_name("auto", None).unwrap();
    let info = b.info();
    println!(
        "auto: {} on {} ({})",
        info.kind, info.device, info.precision
    );
    let hardware = GpuContext::new(AdapterFilter::Hardware).is_ok();
    assert_eq!(info.kind, if hardware { "gpu" } else { "cpu" });
}
