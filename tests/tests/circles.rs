//! No circle of imports between files (ARCHITECTURE.md, "Layers"): in each
//! crate's `src/`, a file that names an item of a sibling file (through
//! `super::`, `crate::` or `self::` paths) must not be named back by it,
//! directly or through other files. A module's own file (`mod.rs`,
//! `lib.rs`, `main.rs`) and its submodules may refer to each other: that is
//! how Rust declares and re-exports them, not a circle. Test code
//! (`tests.rs` files, trailing `#[cfg(test)]` blocks) is left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The module path of every source file of `src` (`a/b.rs` and `a/b/mod.rs`:
/// ["a", "b"]; `lib.rs`, `main.rs`: []).
fn modules(src: &Path, dir: &Path, out: &mut BTreeMap<Vec<String>, PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            modules(src, &path, out);
            continue;
        }
        let rel = path.strip_prefix(src).expect("under src");
        let mut parts: Vec<String> = rel
            .iter()
            .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
            .collect();
        match parts.last().map(String::as_str) {
            Some("tests") => continue,
            Some("mod" | "lib" | "main") => {
                parts.pop();
            }
            _ => {}
        }
        if path.extension().is_some_and(|e| e == "rs") {
            out.insert(parts, path);
        }
    }
}

/// The code of `text` before its trailing test block, without comments.
fn code(text: &str) -> String {
    let end = text.find("#[cfg(test)]\nmod tests").unwrap_or(text.len());
    text[..end]
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every `crate::`, `super::` or `self::` path in `code` resolved against
/// module `at`, as module paths.
fn paths(code: &str, at: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let bytes: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let start_ok = i == 0 || !(ident(bytes[i - 1]) || bytes[i - 1] == ':');
        let rest: String = bytes[i..bytes.len().min(i + 8)].iter().collect();
        let rooted = ["crate::", "super::", "self::"]
            .iter()
            .any(|r| rest.starts_with(r));
        if !(rooted && start_ok) {
            i += 1;
            continue;
        }
        let mut j = i;
        let mut segs: Vec<String> = Vec::new();
        loop {
            let s: String = bytes[j..].iter().take_while(|&&c| ident(c)).collect();
            if s.is_empty() {
                break;
            }
            j += s.len();
            segs.push(s);
            if bytes.get(j) == Some(&':') && bytes.get(j + 1) == Some(&':') {
                j += 2;
            } else {
                break;
            }
        }
        // `use super::{a, b}`: each braced name after the prefix.
        let mut heads = vec![segs.clone()];
        if bytes.get(j) == Some(&'{') {
            let inner: String = bytes[j + 1..].iter().take_while(|&&c| c != '}').collect();
            heads = inner
                .split(',')
                .map(|n| {
                    let mut h = segs.clone();
                    h.extend(n.trim().split("::").map(|x| x.trim().to_string()));
                    h
                })
                .collect();
        }
        for segs in heads {
            let mut base: Vec<String> = at.to_vec();
            let mut k = 0;
            match segs.first().map(String::as_str) {
                Some("crate") => {
                    base.clear();
                    k = 1;
                }
                Some("self") => {
                    base = at.to_vec();
                    k = 1;
                }
                _ => {}
            }
            while segs.get(k).map(String::as_str) == Some("super") {
                base.pop();
                k += 1;
            }
            let mut full = base;
            full.extend(segs[k..].iter().cloned());
            out.push(full);
        }
        i = j.max(i + 1);
    }
    out
}

/// The file module a path names: its longest prefix that is a module.
fn owner(path: &[String], mods: &BTreeMap<Vec<String>, PathBuf>) -> Option<Vec<String>> {
    (0..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| mods.contains_key(p))
}

/// The circles among `src`'s files, each as its files in order.
fn circles(src: &Path) -> Vec<Vec<String>> {
    let mut mods = BTreeMap::new();
    modules(src, src, &mut mods);
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (m, file) in &mods {
        let text = std::fs::read_to_string(file).expect("readable source");
        for p in paths(&code(&text), m) {
            let Some(to) = owner(&p, &mods) else { continue };
            // A module and its ancestors' files are not circles.
            if to == *m || m.starts_with(&to) || to.starts_with(m) {
                continue;
            }
            edges.entry(m.clone()).or_default().insert(to);
        }
    }
    let mut found = Vec::new();
    for start in edges.keys() {
        // Depth-first search for a way back to `start` through larger names
        // only, so that each circle is reported once.
        let mut stack = vec![(start.clone(), vec![start.clone()])];
        while let Some((at, trail)) = stack.pop() {
            for next in edges.get(&at).into_iter().flatten() {
                if next == start {
                    found.push(trail.iter().map(|m| m.join("::")).collect());
                } else if next > start && !trail.contains(next) {
                    let mut t = trail.clone();
                    t.push(next.clone());
                    stack.push((next.clone(), t));
                }
            }
        }
    }
    found
}

#[test]
fn no_circle_of_imports_between_files() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut all = Vec::new();
    for krate in ["radcol-core", "radcol-cli", "radcol-gpu"] {
        for c in circles(&root.join("crates").join(krate).join("src")) {
            all.push(format!("{krate}: {}", c.join(" -> ")));
        }
    }
    assert!(all.is_empty(), "circles between files:\n{}", all.join("\n"));
}

/// The check finds a circle when there is one (a scratch tree of three
/// files, two of which name each other).
#[test]
fn a_circle_between_two_files_is_found() {
    let dir = std::env::temp_dir().join(format!("radcol-circles-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "mod b;\nmod c;\n").unwrap();
    std::fs::write(src.join("a/b.rs"), "use super::c::C;\npub struct B;\n").unwrap();
    std::fs::write(src.join("a/c.rs"), "pub struct C(super::b::B);\n").unwrap();
    let found = circles(&src);
    std::fs::write(src.join("a/c.rs"), "pub struct C;\n").unwrap();
    let none = circles(&src);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found, vec![vec!["a::b".to_string(), "a::c".to_string()]]);
    assert!(none.is_empty(), "{none:?}");
}
