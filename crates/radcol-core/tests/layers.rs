//! The module layering of ARCHITECTURE.md, checked on the source: a module
//! of radcol-core may use only modules below it in [`LAYERS`]. Test code
//! (`#[cfg(test)]` blocks and `tests.rs` files) and comments are exempt.

use std::collections::BTreeSet;
use std::path::Path;

/// radcol-core's top-level modules, bottom to top (ARCHITECTURE.md, "Layers").
const LAYERS: &[&str] = &[
    "progress",
    "matrix",
    "kernel",
    "quadrature",
    "geometry",
    "camera",
    "backend_kind",
    "testing",
    "solve",
    "ranks",
    "error",
    "expr",
    "nodes",
    "alpha0",
    "mesh",
    "discretization",
    "visibility",
    "assembly",
    "backend",
    "hmatrix",
    "problem",
    "solution",
    "norms",
    "estimate",
    "run",
    "query",
    "study",
    "render",
    "export",
    "scene",
    "radiosity",
    "prelude",
];

fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().position(|m| *m == module)
}

/// The code of a source file without test blocks and comments.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(cut) => &text[..cut],
        None => text,
    };
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every `crate::name` path and every `name::` inside `use crate::{..}`.
fn uses(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect::<String>()
    };
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            for part in group.split(',') {
                let name = ident(part.trim());
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

fn walk(dir: &Path, files: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable source dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            walk(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    let mut violations = Vec::new();
    let mut unknown = BTreeSet::new();
    for file in &files {
        let rel = file.strip_prefix(&src).expect("under src");
        if rel == Path::new("lib.rs") || file.file_name().is_some_and(|n| n == "tests.rs") {
            continue;
        }
        let top = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .expect("a path")
            .trim_end_matches(".rs")
            .to_string();
        let Some(own) = rank(&top) else {
            unknown.insert(top);
            continue;
        };
        let text = std::fs::read_to_string(file).expect("readable source");
        for used in uses(&code(&text)) {
            if used == top || used == "assert_close" {
                continue;
            }
            match rank(&used) {
                Some(r) if r < own => {}
                Some(_) => violations.push(format!("{} uses crate::{used}", rel.display())),
                None => {
                    unknown.insert(used);
                }
            }
        }
    }
    assert!(
        unknown.is_empty(),
        "modules missing from LAYERS (add them where they belong): {unknown:?}"
    );
    assert!(
        violations.is_empty(),
        "imports against the layering:\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_scanner_sees_both_import_forms() {
    let found = uses("use crate::mesh::Mesh;\nuse crate::{geometry::Surface, nodes};\nfn f() { crate::kernel::g(); }");
    let want: BTreeSet<String> = ["geometry", "kernel", "mesh", "nodes"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(found, want);
    assert!(uses(&code("// crate::run::solve\nfn f() {}")).is_empty());
}
