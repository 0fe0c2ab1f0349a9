//! A progress bar on stderr, shown only when stderr is a terminal: pipes,
//! files and CI logs get the report alone. With `--verbose` every stage is
//! also logged as a line (time since the start, and how long the stage
//! before took), on a terminal or not.

use indicatif::{ProgressBar, ProgressStyle};
use radcol_core::prelude::{Progress, ProgressHandle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The bar (cheap to clone: indicatif's handle and the log are shared).
#[derive(Clone)]
pub struct Bar {
    bar: ProgressBar,
    /// Under `--verbose`: the start and the current stage with its start.
    log: Option<Arc<Log>>,
}

/// The stage log of `--verbose`.
struct Log {
    start: Instant,
    current: Mutex<Option<(String, Instant)>>,
}

/// Set by `--quiet`: no bar and no status lines on stderr.
static QUIET: AtomicBool = AtomicBool::new(false);
/// Set by `--verbose`: a line per stage on stderr.
static VERBOSE: AtomicBool = AtomicBool::new(false);

/// `--quiet` (set once, before any work).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// True under `--quiet`.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// `--verbose` (set once, before any work).
pub fn set_verbose(verbose: bool) {
    VERBOSE.store(verbose, Ordering::Relaxed);
}

impl Bar {
    /// A bar when stderr is a terminal and the run is not `--quiet` (a
    /// hidden one that only logs under `--verbose` elsewhere), else None.
    pub fn for_stderr() -> Option<Self> {
        let terminal = std::io::stderr().is_terminal();
        let verbose = VERBOSE.load(Ordering::Relaxed);
        if quiet() || !(terminal || verbose) {
            return None;
        }
        let bar = if terminal {
            let bar = ProgressBar::new(0);
            bar.enable_steady_tick(Duration::from_millis(120));
            bar
        } else {
            ProgressBar::hidden()
        };
        let log = verbose.then(|| {
            Arc::new(Log {
                start: Instant::now(),
                current: Mutex::new(None),
            })
        });
        Some(Bar { bar, log })
    }

    /// The observer core reports to.
    pub fn handle(&self) -> ProgressHandle {
        ProgressHandle(Arc::new(self.clone()))
    }

    /// A stage without a count (rendering, writing).
    pub fn spin(&self, message: String) {
        self.stage(&message, &message);
        self.bar.set_style(
            ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}]")
                .expect("valid template"),
        );
        self.bar.set_message(message);
    }

    /// Prints a line above the bar (adaptive steps as they end).
    pub fn note(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    /// Removes the bar (and logs the last stage's end).
    pub fn finish(self) {
        self.stage("done", "done");
        self.bar.finish_and_clear();
    }

    /// Under `--verbose`: logs that `what` starts, and how long the stage
    /// before it took (named by its `label`).
    fn stage(&self, what: &str, label: &str) {
        let Some(log) = &self.log else {
            return;
        };
        let now = Instant::now();
        let mut current = log.current.lock().unwrap_or_else(|e| e.into_inner());
        let before = current
            .take()
            .map(|(name, t)| format!(" ({name}: {:.3} s)", (now - t).as_secs_f64()))
            .unwrap_or_default();
        self.note(&format!(
            "radcol: {:9.3} s  {what}{before}",
            (now - log.start).as_secs_f64()
        ));
        *current = Some((label.to_string(), now));
    }
}

impl Progress for Bar {
    fn start(&self, stage: &str, total: u64) {
        let unit = match stage {
            "plan" | "assembly" | "estimate" => "row blocks",
            "solve" => "residual decades",
            _ => "",
        };
        let counted = if unit.is_empty() {
            format!("{stage} ({total})")
        } else {
            format!("{stage} ({total} {unit})")
        };
        self.stage(&counted, stage);
        self.bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {stage:<9} [{{bar:40}}] {{pos}}/{{len}} {unit} [{{elapsed_precise}}, eta {{eta}}]"
            ))
            .expect("valid template")
            .progress_chars("=> "),
        );
        self.bar.set_length(total);
        self.bar.set_position(0);
    }

    fn advance(&self, n: u64) {
        self.bar.inc(n);
    }
}
