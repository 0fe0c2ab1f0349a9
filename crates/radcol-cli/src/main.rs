//! The `radcol` command: solve, study, nodes, info.
//!
//! Three layers (ripgrep's shape): clap arguments ([`args`]) are parsed into
//! validated values ([`validate::Config`]: no I/O, no device, no numerics),
//! which [`run::run`] executes, building the scene, backend and problem on
//! demand ([`setup`]) and reporting through [`report`]. `main` is the
//! one place that turns failures into an exit code (2 for bad input, 1 for
//! anything else) and one `error: ...` line on stderr.
//!
//! ```text
//! radcol solve sphere --degree 1 --level 2 --exact 'x*y+z'
//! radcol study sphere --degree 1 --levels 0..3 --exact 'x*y+z' --plot conv.svg
//! radcol nodes --degree 3
//! radcol info box:1,1,1 --level 3 --degree 2
//! radcol solve cornell --max-edge 60 --out cornell.png --out cornell.glb
//! radcol info scene.obj --json
//! ```

mod args;
mod backend;
mod error;
mod error_map;
mod files;
mod lightmap;
mod objects;
mod output;
mod panics;
mod plot;
mod progress;
mod ranks;
mod report;
mod run;
mod scene;
mod setup;
mod validate;

use clap::error::ErrorKind;
use clap::Parser;
use std::io::Write;
use std::process::ExitCode;

/// `--threads` at most this many per logical CPU.
const MAX_THREADS_PER_CPU: usize = 8;

fn main() -> ExitCode {
    ensure_runtime_dir();
    // A panic is a bug, but the user still gets one line and an exit code
    // (and Rust's backtrace first when RUST_BACKTRACE asks for it).
    panics::install();
    // Ctrl-C, SIGTERM, SIGHUP: no half-written output is left behind, and
    // the exit code says how the run ended (128 + SIGINT's 2).
    let _ = ctrlc::set_handler(|| {
        files::remove_pending();
        // Under mpirun every rank gets the signal; rank 0 says so.
        if ranks::lead() {
            eprintln!("\ninterrupted: no output was left half-written");
        }
        std::process::exit(130);
    });
    // MPI before anything else (a world of one without mpirun).
    let session = match ranks::Session::start() {
        Ok(s) => s,
        Err(why) => {
            eprintln!("error: {why}");
            return ExitCode::FAILURE;
        }
    };
    let outcome = std::panic::catch_unwind(|| try_main(&session));
    let err = match outcome {
        Ok(Ok(())) => return ExitCode::SUCCESS,
        Ok(Err(err)) => err,
        Err(payload) => anyhow::anyhow!(panics::message(payload.as_ref())),
    };
    if error::is_broken_pipe(&err) {
        return ExitCode::SUCCESS;
    }
    let _ = std::io::stdout().flush();
    let code = error::exit_code(&err);
    session.fail(&error::one_line(&err), code);
    ExitCode::from(code)
}

/// Mesa's Vulkan drivers (probed by `--backend auto|gpu`) print "XDG_RUNTIME_DIR
/// is invalid or not set" on stderr in headless sessions, which reads like one of
/// our errors. Without the variable, point it at a private directory, as a login
/// session would. Runs first in `main`, before any thread exists.
fn ensure_runtime_dir() {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
        if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
            return;
        }
        let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
            return;
        };
        let dir = std::env::temp_dir().join(format!("radcol-runtime-{uid}"));
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        // Use it only if it is ours and private (it may predate this run).
        if let Ok(meta) = std::fs::symlink_metadata(&dir) {
            if meta.is_dir() && meta.uid() == uid && meta.permissions().mode() & 0o077 == 0 {
                std::env::set_var("XDG_RUNTIME_DIR", &dir);
            }
        }
    }
}

fn try_main(session: &ranks::Session) -> anyhow::Result<()> {
    let cli = match args::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                e.print()?;
                return Ok(());
            }
            ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                return Err(error::bad_input(
                    "a command is needed: radcol solve|study|nodes|info|completions (see radcol --help)",
                )
                .into())
            }
            _ => return Err(error::bad_input(error::clap_one_line(&e)).into()),
        },
    };
    if ranks::current().is_some() && !matches!(cli.command, args::Command::Solve(_)) {
        return Err(error::bad_input(
            "under mpirun only `radcol solve` runs across ranks; run the other commands as one process",
        )
        .into());
    }
    progress::set_quiet(cli.quiet || !ranks::lead());
    progress::set_verbose(cli.verbose);
    if let Some(n) = cli.threads {
        // Each thread holds its own row blocks and stack: tens of thousands
        // spent minutes starting and switching, for no speed.
        let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
        let most = MAX_THREADS_PER_CPU * cpus;
        if usize::from(n) > most {
            return Err(error::bad_input(format!(
                "--threads {n}: at most {most} ({MAX_THREADS_PER_CPU} per logical CPU; this machine has {cpus})"
            ))
            .into());
        }
        // Before any parallel work: the global pool is built once.
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.into())
            .build_global()
            .map_err(|e| error::bad_input(format!("--threads {n}: {e}")))?;
    } else if session.local_size() > 1 {
        // Ranks sharing this machine share its cores.
        let cpus = std::thread::available_parallelism().map_or(1, |c| c.get());
        rayon::ThreadPoolBuilder::new()
            .num_threads((cpus / session.local_size()).max(1))
            .build_global()
            .map_err(|e| anyhow::anyhow!("the thread pool: {e}"))?;
    }
    run::run(validate::Config::from_cli(cli)?)
}
