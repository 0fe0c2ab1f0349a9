//! Every `radcol` command shown in the README and in docs/ is one the
//! command accepts: its flags exist and clap takes their values, and the
//! scene files it reads are in the repository. Commands with placeholders
//! (`SCENE`, `[--flag]`, `a|b`, `…`) are left out; the test counts both.

use super::docs_shown::scene_file;
use super::docs_shown::{
    commands, has_placeholder, package_dir, read_pages, root, runnable, words,
};
use crate::args::Cli;
use clap::Parser;
use std::path::Path;

#[test]
fn every_command_in_the_docs_is_accepted() {
    let (mut checked, mut skipped) = (0, 0);
    let mut failures = Vec::new();
    for (shown, text) in read_pages() {
        for command in runnable(&text) {
            if has_placeholder(&command) {
                skipped += 1;
                continue;
            }
            checked += 1;
            let words = words(&command);
            let help = |e: &clap::Error| {
                use clap::error::ErrorKind::{DisplayHelp, DisplayVersion};
                matches!(e.kind(), DisplayHelp | DisplayVersion)
            };
            if let Err(e) = Cli::try_parse_from(&words).map_err(|e| (help(&e), e)) {
                let (asked_help, e) = e;
                if asked_help {
                    continue;
                }
                let first = e.to_string().lines().next().unwrap_or_default().to_string();
                failures.push(format!("{shown}: `{command}`: {first}"));
                continue;
            }
            // Files written by earlier steps of a page (hall.obj) are made by
            // the command shown before them; the repository's must exist.
            if let Some(file) = scene_file(&words) {
                let local = file.starts_with("scenes/") || file.starts_with("benches/");
                if local && !Path::new(&root().join(file)).exists() {
                    failures.push(format!("{shown}: `{command}`: no file {file}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The docs show 35 runnable commands and 19 synopses with placeholders
    // (2026-12-07): most must be checked, not skipped.
    assert!(
        checked >= 30 && checked > skipped,
        "{checked} checked, {skipped} skipped"
    );
    eprintln!("{checked} commands checked, {skipped} with placeholders left out");
}

#[test]
fn commands_are_found_in_blocks_and_spans_and_placeholders_are_told() {
    let text = "Run `radcol nodes --degree 3` or\n\n    cargo run --release -- solve cornell --level 0  # quick\n\n```sh\nradcol info SCENE --plan\n```\n";
    let found = commands(text);
    assert_eq!(
        found,
        [
            "radcol nodes --degree 3",
            "radcol solve cornell --level 0",
            "radcol info SCENE --plan"
        ]
    );
    assert!(!has_placeholder(&found[0]) && has_placeholder(&found[2]));
    assert_eq!(
        words("radcol solve sphere --exact 'x*y + z'"),
        ["radcol", "solve", "sphere", "--exact", "x*y + z"]
    );
    assert!(Cli::try_parse_from(words("radcol solve cornell --no-such-flag")).is_err());
}

/// Every `cargo run -p P --example E` and `cargo bench -p P --bench B`
/// shown names an example or a bench that exists.
#[test]
fn every_example_and_bench_in_the_docs_exists() {
    let mut checked = 0;
    let mut failures = Vec::new();
    for (shown, text) in read_pages() {
        for line in text.lines().flat_map(|l| l.split('`')) {
            let words: Vec<&str> = line.split_whitespace().collect();
            let Some(at) = words.iter().position(|w| *w == "cargo") else {
                continue;
            };
            let words = &words[at..];
            let after = |flag: &str| {
                let i = words.iter().position(|w| *w == flag)?;
                words.get(i + 1).copied()
            };
            let (Some(package), kind) = (after("-p"), words.get(1).copied()) else {
                continue;
            };
            let target = match kind {
                Some("run") => after("--example").map(|e| ("examples", e)),
                Some("bench") => after("--bench").map(|b| ("benches", b)),
                _ => None,
            };
            let Some((dir, name)) = target else { continue };
            if has_placeholder(name) {
                continue;
            }
            checked += 1;
            let file = package_dir(package).join(dir).join(format!("{name}.rs"));
            if !file.exists() {
                failures.push(format!(
                    "{shown}: `{}`: no {}",
                    words.join(" "),
                    file.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 10, "{checked} examples and benches checked");
    eprintln!("{checked} examples and benches checked");
}
