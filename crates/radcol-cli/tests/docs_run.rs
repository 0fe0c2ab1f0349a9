//! Runs every command that the README and docs/ show (those without
//! placeholders), each in a fresh directory for the files it writes, and
//! fails naming each one that does not exit 0. Some take minutes (the
//! bunny room to 1e-2, the Cornell box to 1e-4): about an hour on 2 cores,
//! so it is left out of the default run:
//!
//! ```text
//! cargo test --release -p radcol-cli --test docs_run -- --ignored --nocapture
//! ```
//!
//! The default tests parse the same commands with the command's own
//! argument parser (`src/args/doc_commands.rs`).

#[allow(dead_code)]
#[path = "../src/args/docs_shown.rs"]
mod shown;

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// The flags whose value is a file the command writes.
const WRITES: [&str; 4] = ["--out", "--error-map", "--plot", "--at-out"];

/// Whether `text` shows `command` refused: the line after it starts with
/// `error:`.
fn shown_refused(text: &str, command: &str) -> bool {
    let args = command.trim_start_matches("radcol ");
    let lines: Vec<&str> = text.lines().collect();
    lines
        .windows(2)
        .any(|w| w[0].trim_end().ends_with(args) && w[1].trim_start().starts_with("error:"))
}

#[test]
fn a_command_shown_refused_is_told() {
    let text = "```\nradcol solve sphere --level 7\nerror: too large\n```\nradcol solve sphere --level 1\n";
    assert!(shown_refused(text, "radcol solve sphere --level 7"));
    assert!(!shown_refused(text, "radcol solve sphere --level 1"));
}

#[test]
#[ignore = "runs every command of the docs: about an hour"]
fn every_command_in_the_docs_runs() {
    let root = shown::root();
    let mut failures = Vec::new();
    let mut ran = 0;
    for (name, text) in shown::read_pages() {
        for command in shown::runnable(&text) {
            if shown::has_placeholder(&command) {
                continue;
            }
            let mut words = shown::words(&command);
            // A scene made by an earlier step of the page (a bench example's
            // output) is not in the repository.
            if let Some(file) = shown::scene_file(&words) {
                if !root.join(file).exists() {
                    eprintln!("{name}: `{command}`: left out, {file} is made by a step before it");
                    continue;
                }
            }
            let dir =
                std::env::temp_dir().join(format!("radcol-docs-{}-{ran}", std::process::id()));
            std::fs::create_dir_all(&dir).expect("temporary directory");
            for i in 1..words.len() {
                if WRITES.contains(&words[i - 1].as_str()) {
                    let file = Path::new(&words[i]).file_name().expect("a file name");
                    words[i] = dir.join(file).display().to_string();
                }
            }
            let t = Instant::now();
            let out = Command::new(env!("CARGO_BIN_EXE_radcol"))
                .args(&words[1..])
                .current_dir(&root)
                .output()
                .expect("radcol runs");
            ran += 1;
            let seconds = t.elapsed().as_secs_f64();
            eprintln!(
                "{name}: `{command}`: {:?} in {seconds:.1} s",
                out.status.code()
            );
            // A command the page shows refused must be refused as bad input.
            let expected = if shown_refused(&text, &command) { 2 } else { 0 };
            if out.status.code() != Some(expected) {
                let err = String::from_utf8_lossy(&out.stderr);
                failures.push(format!("{name}: `{command}`: {}", err.trim()));
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(ran >= 30, "{ran} commands ran");
}
