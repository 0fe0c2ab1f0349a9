//! The CLI's one error policy: bad input exits with 2, anything else with 1,
//! and either way exactly one line `error: ...` goes to stderr.

use radcol_core::run::{Error as CoreError, FieldKind, InputError};
use std::fmt;

/// Exit code for bad input (arguments, scenes, expressions, values, files in the way).
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for every other failure (solver, backend, I/O, internal).
pub const EXIT_FAILURE: u8 = 1;

/// Bad input detected by the CLI itself.
#[derive(Debug)]
pub struct BadInput(pub String);

impl fmt::Display for BadInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// A [`BadInput`] with message `msg`.
pub fn bad_input(msg: impl Into<String>) -> BadInput {
    BadInput(msg.into())
}

/// The exit code of `err`: 2 when any cause in its chain is bad input.
pub fn exit_code(err: &anyhow::Error) -> u8 {
    let input = err.chain().any(|cause| {
        cause.is::<BadInput>()
            || cause.is::<InputError>()
            || matches!(cause.downcast_ref::<CoreError>(), Some(CoreError::Input(_)))
    });
    if input {
        EXIT_BAD_INPUT
    } else {
        EXIT_FAILURE
    }
}

/// A core error with the command-line flags that change it named: the
/// library's messages speak of meshes and degrees, the CLI's of flags.
pub fn with_flags(err: CoreError) -> anyhow::Error {
    match &err {
        CoreError::Input(e @ InputError::TooLarge { .. }) => bad_input(format!(
            "{e} (flags: --level, --max-edge, --degree, --operator compressed with --solver gmres)"
        ))
        .into(),
        CoreError::Input(
            e @ (InputError::CompressedTooLarge { .. } | InputError::PairTableTooLarge { .. }),
        ) => bad_input(format!(
            "{e} (flags: --level, --max-edge, --degree, --compression-tol, --no-estimate)"
        ))
        .into(),
        CoreError::Input(e @ InputError::CompressedWontFit { .. }) => {
            bad_input(format!("{e} (flags: --level, --max-edge, --degree)")).into()
        }
        CoreError::Input(e @ InputError::CompressionTolerance { .. }) => {
            bad_input(format!("--compression-tol: {e}")).into()
        }
        CoreError::Input(e @ InputError::CompressedLu) => bad_input(format!(
            "{e} (flags: --solver gmres with --operator compressed, or --operator dense)"
        ))
        .into(),
        CoreError::Input(e @ InputError::HpBackend { .. }) => {
            bad_input(format!("{e} (flags: --backend cpu, or leave out --hp)")).into()
        }
        CoreError::Input(e @ InputError::PeakTooLarge { .. }) => bad_input(format!(
            "{e} (flags: --level, --max-edge, --degree, --no-estimate, --solver gmres)"
        ))
        .into(),
        // Values of the scalar problem's fields come from these flags (a
        // scene's per-channel ones, "reflectivity R", from its materials).
        CoreError::Input(
            e @ (InputError::Reflectivity { name: field, .. }
            | InputError::InvalidValue { what: field, .. }),
        ) if field.channel.is_none() => {
            let flag = match field.kind {
                FieldKind::Reflectivity => "--rho",
                FieldKind::Emission => "--emission",
                FieldKind::ExactSolution => "--exact",
            };
            bad_input(format!("{flag}: {e}")).into()
        }
        _ => anyhow::Error::new(err),
    }
}

/// True when `err` is a closed stdout (`radcol nodes | head`): not worth a message.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// `err` and its causes as one line.
pub fn one_line(err: &anyhow::Error) -> String {
    let text = format!("{err:#}");
    let line = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    line.strip_prefix("error: ").unwrap_or(&line).to_string()
}

/// A clap usage error as one line: its message and hints, without the usage block.
pub fn clap_one_line(err: &clap::Error) -> String {
    let text = err.render().to_string();
    let mut parts = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        if !line.is_empty() {
            parts.push(line.strip_prefix("error: ").unwrap_or(line).to_string());
        }
    }
    let mut msg = parts.join(" ");
    if !msg.contains("--help") {
        msg.push_str(" (see --help)");
    }
    msg
}
