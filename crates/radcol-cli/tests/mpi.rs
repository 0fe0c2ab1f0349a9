//! `mpirun -np P radcol solve …` (feature `mpi`): the same answer as one
//! process, over 2 and 3 ranks (3 oversubscribing the 2-core CI machine),
//! each rank holding its share of the compressed operator; and faults
//! that end every rank with one error line and a non-zero code.
//!
//! Needs `mpirun` (CI installs OpenMPI); run with
//! `cargo test --release -p radcol-cli --features mpi --test mpi`. The
//! world size is checked in every report: a binary started by another
//! MPI's launcher runs as independent single processes and would pass a
//! check of the answer alone.

mod common;

use common::{radcol_bin, scratch};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// One MPI job at a time: ranks waiting in a collective spin, so jobs run
/// side by side on a 2-core machine starve each other's ranks for seconds
/// (a failing rank then gives up waiting for the others to fail alike and
/// ends the world alone: another exit code). Each test holds this.
static ONE_JOB_AT_A_TIME: Mutex<()> = Mutex::new(());

fn one_job_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_JOB_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// `mpirun -q -np ranks radcol args` (one thread per rank), or the binary
/// alone when `ranks` is 0. `-q`: OpenMPI's own notes about exit codes
/// stay out of stderr, which then holds radcol's lines only.
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    let mut cmd = if ranks == 0 {
        Command::new(radcol_bin())
    } else {
        let mut c = Command::new("mpirun");
        c.args(["-q", "--oversubscribe", "-np", &ranks.to_string()])
            .arg(radcol_bin());
        c
    };
    cmd.args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .expect("mpirun runs (install OpenMPI: see docs/scaling.md)")
}

fn json(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON report ({e}):\n{}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// The u columns of a nodes CSV, row by row.
fn nodal(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cols: Vec<usize> = (0..header.len())
        .filter(|&i| header[i].starts_with("u_") && !header[i].ends_with("_estimate"))
        .collect();
    assert!(!cols.is_empty(), "{header:?}");
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            cols.iter().map(|&i| f[i].parse().unwrap()).collect()
        })
        .collect()
}

/// max |a − b| over nodes and channels, relative to max |b|.
fn max_rel(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    assert_eq!(a.len(), b.len(), "the same nodes");
    let scale = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs() / scale)
        .fold(0.0, f64::max)
}

/// GMRES iterations per channel of a report's solve (or a relit set).
fn iterations(channels: &Value) -> Vec<u64> {
    channels
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["solver"]["iterations"].as_u64().unwrap())
        .collect()
}

/// `radcol solve args --out nodes.csv --json` over `ranks` (0: one process
/// without mpirun): the report and the nodal values.
fn solve(dir: &Path, ranks: usize, args: &[&str]) -> (Value, Vec<Vec<f64>>) {
    let csv = dir.join(format!("nodes_{ranks}.csv"));
    let csv_arg = csv.to_str().unwrap();
    let mut all = vec!["solve"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", csv_arg, "--json", "--threads", "1"]);
    let report = json(&mpirun(ranks, &all));
    (report, nodal(&csv))
}

/// The world size a report says ran, and each rank's stored bytes. Each
/// rank is a process of its own: its own work has CPU seconds, at most its
/// wall seconds times the threads it ran (one) with a margin for MPI's.
fn world(report: &Value) -> (u64, Vec<u64>) {
    let r = &report["operator"]["ranks"];
    let per: Vec<u64> = r["per_rank"]
        .as_array()
        .unwrap_or_else(|| panic!("no ranks in {}", report["operator"]))
        .iter()
        .map(|p| {
            let (cpu, wall) = (p["work_cpu_s"].as_f64(), p["work_s"].as_f64().unwrap());
            assert!(cpu.is_some_and(|c| c > 0.0 && c <= 1.5 * wall + 0.1), "{p}");
            p["stored_bytes"].as_u64().unwrap()
        })
        .collect();
    (r["size"].as_u64().unwrap(), per)
}

/// The Cornell box's compressed operator over 2 and 3 ranks: the values at
/// every node within 1e-10 of one process's, the same GMRES iterations,
/// the world size the report says, and each of 2 ranks storing at most
/// 60 % of the one-process operator; a relit set the same as well.
#[test]
fn cornell_over_ranks_is_the_one_process_solve() {
    let _one = one_job_at_a_time();
    let dir = scratch("mpi_cornell");
    let args = [
        "cornell",
        "--operator",
        "compressed",
        "--max-edge",
        "120",
        "--no-estimate",
        "--relight",
        "light.Ke=5,5,5",
    ];
    let (alone, u1) = solve(&dir, 0, &args);
    assert!(alone["operator"]["ranks"].is_null(), "one process");
    let whole = alone["operator"]["bytes"].as_u64().unwrap();
    for ranks in [2, 3] {
        let (report, u) = solve(&dir, ranks, &args);
        let (size, stored) = world(&report);
        assert_eq!(size, ranks as u64, "the world size");
        let diff = max_rel(&u, &u1);
        println!(
            "{ranks} ranks: max |Δu| / max |u| = {diff:.1e}, stored {stored:?} of {whole} bytes"
        );
        assert!(diff <= 1e-10, "{ranks} ranks: {diff:e}");
        assert_eq!(
            iterations(&report["channels"]),
            iterations(&alone["channels"])
        );
        let relit = &report["relit"][0];
        assert_eq!(
            iterations(&relit["channels"]),
            iterations(&alone["relit"][0]["channels"])
        );
        for (a, b) in relit["channels"]
            .as_array()
            .unwrap()
            .iter()
            .zip(alone["relit"][0]["channels"].as_array().unwrap())
        {
            let (a, b) = (
                a["integral_u"].as_f64().unwrap(),
                b["integral_u"].as_f64().unwrap(),
            );
            assert!((a - b).abs() <= 1e-10 * b.abs(), "relit ∫u {a} against {b}");
        }
        if ranks == 2 {
            for s in &stored {
                assert!(*s as f64 <= 0.6 * whole as f64, "{s} of {whole}");
            }
        }
    }
}

/// The shadowed floor to 1e-3 over 2 and 3 ranks: the same adaptive
/// steps (unknowns at each), the same final values and the last step's
/// GMRES iterations as one process.
#[test]
fn the_adaptive_loop_over_ranks_takes_the_one_process_steps() {
    let _one = one_job_at_a_time();
    let dir = scratch("mpi_shadow");
    let args = [
        "shadow",
        "--target-error",
        "1e-3",
        "--operator",
        "compressed",
    ];
    let steps = |r: &Value| -> Vec<u64> {
        r["adaptive"]["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["unknowns"].as_u64().unwrap())
            .collect()
    };
    let (alone, u1) = solve(&dir, 0, &args);
    assert!(steps(&alone).len() >= 5, "{:?}", steps(&alone));
    for ranks in [2, 3] {
        let (report, u) = solve(&dir, ranks, &args);
        assert_eq!(world(&report).0, ranks as u64, "the world size");
        assert_eq!(steps(&report), steps(&alone), "{ranks} ranks");
        assert_eq!(
            iterations(&report["channels"]),
            iterations(&alone["channels"]),
            "the last step's GMRES"
        );
        let diff = max_rel(&u, &u1);
        assert!(diff <= 1e-10, "{ranks} ranks: {diff:e}");
    }
}

/// Stderr's lines and the exit code of a run that must fail, and how long
/// it took.
fn failing(ranks: usize, args: &[&str]) -> (Vec<String>, Option<i32>, Duration) {
    let t = Instant::now();
    let out = mpirun(ranks, args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines = stderr
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_string)
        .collect();
    (lines, out.status.code(), t.elapsed())
}

/// Bad input seen by every rank (a missing scene, NaN in an expression):
/// one error line, exit code 2, every rank gone within 10 s.
#[test]
fn bad_input_under_mpirun_is_one_line() {
    let _one = one_job_at_a_time();
    let missing = ["solve", "no_such_scene.obj"];
    let nan = [
        "solve",
        "sphere",
        "--emission",
        "0/0",
        "--operator",
        "compressed",
    ];
    for args in [&missing[..], &nan[..]] {
        let (lines, code, took) = failing(2, args);
        assert_eq!(lines.len(), 1, "{args:?}: {lines:?}");
        assert!(lines[0].starts_with("error: "), "{lines:?}");
        assert_eq!(code, Some(2), "{args:?}: {lines:?}");
        assert!(took < Duration::from_secs(10), "{took:?}");
    }
    // Only `solve` runs across ranks.
    let (lines, code, _) = failing(2, &["info", "cornell"]);
    assert_eq!(code, Some(2), "{lines:?}");
    assert!(
        lines.len() == 1 && lines[0].contains("only `radcol solve`"),
        "{lines:?}"
    );
}

/// The children of process `pid` (Linux).
fn children(pid: u32) -> Vec<u32> {
    let path = format!("/proc/{pid}/task/{pid}/children");
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .split_whitespace()
        .filter_map(|p| p.parse().ok())
        .collect()
}

/// A rank killed mid-assembly: mpirun ends the others and exits non-zero
/// within 10 s; no rank is left running.
#[test]
fn a_rank_killed_mid_assembly_ends_the_run() {
    let _one = one_job_at_a_time();
    let mut child = Command::new("mpirun")
        .args(["-q", "--oversubscribe", "-np", "2"])
        .arg(radcol_bin())
        .args([
            "solve",
            "cornell",
            "--operator",
            "compressed",
            "--max-edge",
            "40",
        ])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("mpirun runs");
    // Both ranks started and at work.
    let start = Instant::now();
    let ranks = loop {
        let ranks: Vec<u32> = children(child.id());
        if ranks.len() == 2 || start.elapsed() > Duration::from_secs(20) {
            break ranks;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(ranks.len(), 2, "two ranks under mpirun");
    std::thread::sleep(Duration::from_secs(3));
    let killed = Command::new("kill")
        .args(["-9", &ranks[1].to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t.elapsed() > Duration::from_secs(10) {
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let Some(status) = status else {
        let _ = child.kill();
        panic!("mpirun still running 10 s after a rank was killed");
    };
    assert!(!status.success(), "{status:?}");
    assert!(
        !Path::new(&format!("/proc/{}", ranks[0])).exists()
            || std::fs::read_to_string(format!("/proc/{}/stat", ranks[0]))
                .is_ok_and(|s| s.contains(") Z ")),
        "rank 0 left running"
    );
}
