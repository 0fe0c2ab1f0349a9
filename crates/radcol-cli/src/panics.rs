//! Panics are bugs: the user gets one `error:` line naming the panic's
//! message and where in radcol's source it happened, and the exit code 1.
//! With `RUST_BACKTRACE` set (to anything but `0`), Rust's own report with
//! its backtrace is printed first, as every Rust program does.

use std::any::Any;
use std::sync::Mutex;

/// Where the last panic happened (`file:line`), recorded by the hook.
static LOCATION: Mutex<Option<String>> = Mutex::new(None);

/// Installs the hook: it records the location and, when a backtrace is
/// wanted, hands the panic to Rust's default hook (which prints it).
pub fn install() {
    let default = std::panic::take_hook();
    let full = wants_backtrace(std::env::var("RUST_BACKTRACE").ok().as_deref());
    std::panic::set_hook(Box::new(move |info| {
        if let Some(l) = info.location() {
            let mut at = LOCATION.lock().unwrap_or_else(|e| e.into_inner());
            *at = Some(format!("{}:{}", l.file(), l.line()));
        }
        if full {
            default(info);
        }
    }));
}

/// Whether `RUST_BACKTRACE`'s value asks for the default report.
pub fn wants_backtrace(value: Option<&str>) -> bool {
    matches!(value, Some(v) if v != "0")
}

/// The one line for a panic with `payload`, at the location the hook
/// recorded.
pub fn message(payload: &(dyn Any + Send)) -> String {
    let at = LOCATION.lock().unwrap_or_else(|e| e.into_inner()).clone();
    describe(payload, at.as_deref())
}

/// The line for `payload` at `at`.
fn describe(payload: &(dyn Any + Send), at: Option<&str>) -> String {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown cause".into());
    let at = at.map(|a| format!(" at {a}")).unwrap_or_default();
    format!("internal error (please report): {msg}{at} (RUST_BACKTRACE=1 prints a backtrace)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backtrace_follows_rust_backtrace() {
        assert!(!wants_backtrace(None));
        assert!(!wants_backtrace(Some("0")));
        assert!(wants_backtrace(Some("1")));
        assert!(wants_backtrace(Some("full")));
    }

    #[test]
    fn the_line_names_message_and_place() {
        let p: Box<dyn Any + Send> = Box::new(String::from("index out of bounds"));
        assert_eq!(
            describe(p.as_ref(), Some("crates/x.rs:12")),
            "internal error (please report): index out of bounds at crates/x.rs:12 (RUST_BACKTRACE=1 prints a backtrace)"
        );
        let p: Box<dyn Any + Send> = Box::new(7u8);
        assert!(describe(p.as_ref(), None)
            .starts_with("internal error (please report): unknown cause (RUST"));
    }
}
