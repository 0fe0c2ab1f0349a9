//! A progress bar on stderr, shown only when stderr is a terminal: pipes,
//! files and CI logs get the report alone.

use indicatif::{ProgressBar, ProgressStyle};
use radcol_core::progress::{Progress, ProgressHandle};
use std::io::IsTerminal;
use std::sync::Arc;
use std::time::Duration;

/// The bar (cheap to clone: indicatif's handle is shared).
#[derive(Clone)]
pub struct Bar(ProgressBar);

/// Set by `--quiet`: no bar and no status lines on stderr.
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `--quiet` (set once, before any work).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, std::sync::atomic::Ordering::Relaxed);
}

/// True under `--quiet`.
pub fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

impl Bar {
    /// A bar when stderr is a terminal and the run is not `--quiet`, else None.
    pub fn for_stderr() -> Option<Self> {
        if quiet() || !std::io::stderr().is_terminal() {
            return None;
        }
        let bar = ProgressBar::new(0);
        bar.enable_steady_tick(Duration::from_millis(120));
        Some(Bar(bar))
    }

    /// The observer core reports to.
    pub fn handle(&self) -> ProgressHandle {
        ProgressHandle(Arc::new(self.clone()))
    }

    /// A stage without a count (rendering, writing).
    pub fn spin(&self, message: String) {
        self.0.set_style(
            ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}]")
                .expect("valid template"),
        );
        self.0.set_message(message);
    }

    /// Prints a line above the bar (adaptive steps as they end).
    pub fn note(&self, line: &str) {
        self.0.println(line);
    }

    /// Removes the bar.
    pub fn finish(self) {
        self.0.finish_and_clear();
    }
}

impl Progress for Bar {
    fn start(&self, stage: &str, total: u64) {
        let unit = match stage {
            "plan" | "assembly" => "row blocks",
            "solve" => "channels",
            _ => "",
        };
        self.0.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {stage:<9} [{{bar:40}}] {{pos}}/{{len}} {unit} [{{elapsed_precise}}, eta {{eta}}]"
            ))
            .expect("valid template")
            .progress_chars("=> "),
        );
        self.0.set_length(total);
        self.0.set_position(0);
    }

    fn advance(&self, n: u64) {
        self.0.inc(n);
    }
}
