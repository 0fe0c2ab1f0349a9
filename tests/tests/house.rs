//! The house we keep (ARCHITECTURE.md, "Sizes"): no library or CLI source
//! file over 500 lines (tabulated data aside), no function over 100 lines.
//! Test code (`tests.rs` files, trailing `#[cfg(test)]` blocks) is exempt.

use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 500;
const MAX_FN_LINES: usize = 100;

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable dir") {
        let path = entry.expect("dir entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if name != "tests" && name != "target" {
                sources(&path, out);
            }
        } else if name.ends_with(".rs") && !name.ends_with("_data.rs") && name != "tests.rs" {
            out.push(path);
        }
    }
}

/// The line of `l` without comments and string contents, for brace counting.
fn braces(l: &str) -> (usize, usize) {
    let mut code = String::new();
    let mut in_str = false;
    let mut chars = l.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if in_str => {
                chars.next();
            }
            '"' => in_str = !in_str,
            '/' if !in_str && chars.peek() == Some(&'/') => break,
            _ if !in_str => code.push(c),
            _ => {}
        }
    }
    (code.matches('{').count(), code.matches('}').count())
}

fn is_fn_start(l: &str) -> bool {
    let t = l.trim_start();
    let t = t
        .strip_prefix("pub(crate) ")
        .or_else(|| t.strip_prefix("pub(super) "))
        .or_else(|| t.strip_prefix("pub "))
        .unwrap_or(t);
    let t = t.strip_prefix("const ").unwrap_or(t);
    let t = t.strip_prefix("unsafe ").unwrap_or(t);
    t.starts_with("fn ")
}

/// (start line, length) of every function longer than the limit.
fn long_functions(lines: &[&str]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if !is_fn_start(lines[i]) {
            i += 1;
            continue;
        }
        let (mut depth, mut started, mut j) = (0i64, false, i);
        while j < lines.len() {
            let (open, close) = braces(lines[j]);
            depth += open as i64 - close as i64;
            started |= open > 0;
            if (started && depth <= 0) || (!started && lines[j].trim_end().ends_with(';')) {
                break;
            }
            j += 1;
        }
        if started && j - i + 1 > MAX_FN_LINES {
            out.push((i + 1, j - i + 1));
        }
        i = j + 1;
    }
    out
}

#[test]
fn source_files_and_functions_stay_small() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .join("crates");
    let mut files = Vec::new();
    sources(&root, &mut files);
    assert!(files.len() > 50, "found only {} source files", files.len());
    let mut problems = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("readable source");
        let lines: Vec<&str> = text.lines().collect();
        let end = lines
            .iter()
            .position(|l| l.starts_with("#[cfg(test)]"))
            .unwrap_or(lines.len());
        let shown = file.strip_prefix(&root).unwrap_or(file).display();
        if end > MAX_FILE_LINES {
            problems.push(format!("{shown}: {end} lines (at most {MAX_FILE_LINES})"));
        }
        for (at, len) in long_functions(&lines[..end]) {
            problems.push(format!(
                "{shown}:{at}: function of {len} lines (at most {MAX_FN_LINES})"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_function_scanner_measures_what_it_should() {
    let mut long = vec!["fn big() {"];
    long.extend(std::iter::repeat_n("    let s = \"}\"; // }", 100));
    long.push("}");
    long.push("fn small() {}");
    assert_eq!(long_functions(&long), vec![(1, 102)]);
    assert!(long_functions(&["pub fn decl(x: u8);", "fn f() {", "}"]).is_empty());
}
