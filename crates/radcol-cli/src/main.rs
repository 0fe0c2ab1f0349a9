//! The `radcol` command: solve, study, nodes, info.
//!
//! Two layers (ripgrep's shape): clap arguments ([`args`]) are validated into a
//! [`config::Config`] of core types, which [`run::run`] executes. `main` is the
//! one place that turns failures into an exit code (2 for bad input, 1 for
//! anything else) and one `error: ...` line on stderr.
//!
//! ```text
//! radcol solve sphere --degree 1 --level 2 --exact 'x*y+z'
//! radcol study sphere --degree 1 --levels 0..3 --exact 'x*y+z' --plot conv.svg
//! radcol nodes --degree 3
//! radcol info box:1,1,1 --level 3 --degree 2
//! ```

mod args;
mod config;
mod error;
mod output;
mod plot;
mod report;
mod run;
mod scene;

use clap::error::ErrorKind;
use clap::Parser;
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    // A panic is a bug, but the user still gets one line and an exit code, not
    // a backtrace: the hook stays silent and the payload is reported below.
    std::panic::set_hook(Box::new(|_| {}));
    let outcome = std::panic::catch_unwind(try_main);
    let err = match outcome {
        Ok(Ok(())) => return ExitCode::SUCCESS,
        Ok(Err(err)) => err,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".into());
            anyhow::anyhow!("internal error (please report): {msg}")
        }
    };
    if error::is_broken_pipe(&err) {
        return ExitCode::SUCCESS;
    }
    let _ = std::io::stdout().flush();
    eprintln!("error: {}", error::one_line(&err));
    ExitCode::from(error::exit_code(&err))
}

fn try_main() -> anyhow::Result<()> {
    let cli = match args::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => match e.kind() {
            ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                e.print()?;
                return Ok(());
            }
            ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                return Err(error::bad_input(
                    "a command is needed: radcol solve|study|nodes|info (see radcol --help)",
                )
                .into())
            }
            _ => return Err(error::bad_input(error::clap_one_line(&e)).into()),
        },
    };
    run::run(config::Config::from_cli(cli)?)
}
