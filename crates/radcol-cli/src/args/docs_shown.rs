//! The commands that the README and docs/ show, as the tests that check
//! them read them: `radcol …` lines of code blocks and code spans, split
//! as a shell would, with the synopses that hold placeholders told apart.
//! Shared by the unit tests that parse them and the ignored test that runs
//! them (`tests/docs_run.rs` includes this file).

use std::path::PathBuf;

/// The repository's root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The markdown files whose commands are checked.
pub fn pages() -> Vec<PathBuf> {
    let mut pages = vec![
        root().join("README.md"),
        root().join("crates/radcol-gpu/README.md"),
    ];
    let docs = std::fs::read_dir(root().join("docs")).expect("docs/");
    let mut more: Vec<PathBuf> = docs
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    more.sort();
    pages.extend(more);
    pages
}

/// Every page of [`pages`], named from the repository's root, with its text.
pub fn read_pages() -> Vec<(String, String)> {
    pages()
        .into_iter()
        .map(|page| {
            let text = std::fs::read_to_string(&page).expect("readable page");
            let name = page
                .strip_prefix(root())
                .unwrap_or(&page)
                .display()
                .to_string();
            (name, text)
        })
        .collect()
}

/// The `radcol …` commands of `text`: lines of code blocks (fenced or
/// indented) and inline code spans, with `cargo run --release [-p
/// radcol-cli] --` read as `radcol`.
pub fn commands(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    let mut take = |s: &str| {
        let s = s.trim().trim_start_matches("$ ");
        let s = s.split(" #").next().unwrap_or(s).trim();
        for prefix in [
            "cargo run --release -p radcol-cli -- ",
            "cargo run --release -- ",
            "radcol ",
        ] {
            if let Some(rest) = s.strip_prefix(prefix) {
                found.push(format!("radcol {rest}"));
                return;
            }
        }
    };
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced || line.starts_with("    ") {
            take(line);
        } else {
            for (i, span) in line.split('`').enumerate() {
                if i % 2 == 1 {
                    take(span);
                }
            }
        }
    }
    found
}

/// Whether `command` holds a placeholder rather than a value (a word in
/// capitals: `SCENE`, `R`, `MAX_TRIANGLES`).
pub fn has_placeholder(command: &str) -> bool {
    command.contains(['[', '|', '…', '<'])
        || command.contains("...")
        || command.split_whitespace().any(|w| {
            let letters: String = w.chars().filter(|c| c.is_alphabetic()).collect();
            !letters.is_empty() && letters.chars().all(|c| c.is_uppercase())
        })
}

/// `command` split as a shell would (single and double quotes).
pub fn words(command: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in command.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                any = true;
            }
            (None, c) if c.is_whitespace() => {
                if any || !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
                any = false;
            }
            (None, c) => {
                word.push(c);
                any = true;
            }
        }
    }
    if any || !word.is_empty() {
        out.push(word);
    }
    out
}

/// The scene file `radcol solve|study|info` reads, when its first
/// argument is a file rather than a built-in.
pub fn scene_file(words: &[String]) -> Option<&str> {
    let sub = words.get(1)?;
    if !["solve", "study", "info"].contains(&sub.as_str()) {
        return None;
    }
    let scene = words.get(2)?;
    let file = [".obj", ".gltf", ".glb"].iter().any(|e| scene.ends_with(e));
    file.then_some(scene.as_str())
}

/// The directory of package `name`'s sources.
pub fn package_dir(name: &str) -> PathBuf {
    match name {
        "radcol-benches" => root().join("benches"),
        "radcol-tests" => root().join("tests"),
        other => root().join("crates").join(other),
    }
}

/// The runnable commands of `text`: those of [`commands`] that are not a
/// subcommand named in prose (`radcol solve`) or a report's first line
/// (`radcol study: sphere, …`).
pub fn runnable(text: &str) -> Vec<String> {
    commands(text)
        .into_iter()
        .filter(|c| {
            let second = c.split_whitespace().nth(1).unwrap_or_default();
            c.split_whitespace().count() >= 3 && !second.ends_with(':')
        })
        .collect()
}
