//! The library's edge as its own crates use it: the command is a layer
//! over the library that names the prelude and at most five other modules
//! of radcol-core (configuring and running a solve, studies, images,
//! files, scenes), and the GPU backend names only the module made for
//! backends. Test code is left out (tests may reach further).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The top-level modules of radcol-core that `code` names: after
/// `radcol_core::`, directly or inside `radcol_core::{…}`.
fn named(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in code.match_indices("radcol_core::") {
        let rest = &code[i + "radcol_core::".len()..];
        if let Some(inner) = rest.strip_prefix('{') {
            let inner = &inner[..inner.find('}').unwrap_or(inner.len())];
            for part in inner.split(',') {
                out.insert(ident(part.trim()));
            }
        } else {
            out.insert(ident(rest));
        }
    }
    // Exported macros live at the crate's root, in no module.
    out.retain(|m| !m.is_empty() && m != "assert_close");
    out
}

/// The code of `text` before its trailing test block, without comments.
fn code(text: &str) -> String {
    let body = text.split("#[cfg(test)]").next().unwrap_or(text);
    body.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The modules of radcol-core named by the source files under `dir`
/// (`tests.rs` files left out).
fn named_in(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for entry in std::fs::read_dir(dir).expect("readable dir") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            out.extend(named_in(&path));
        } else if path.extension().is_some_and(|e| e == "rs")
            && path.file_name().is_some_and(|n| n != "tests.rs")
        {
            let text = std::fs::read_to_string(&path).expect("readable source");
            out.extend(named(&code(&text)));
        }
    }
    out
}

fn crate_src(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../crates")
        .join(name)
        .join("src")
}

#[test]
fn the_command_names_the_prelude_and_five_other_modules() {
    let named = named_in(&crate_src("radcol-cli"));
    let allowed: BTreeSet<String> = ["prelude", "run", "study", "render", "export", "scene"]
        .map(String::from)
        .into();
    let beyond: Vec<_> = named.difference(&allowed).collect();
    assert!(
        beyond.is_empty(),
        "the command names radcol-core's {beyond:?}: reach them through the prelude or {allowed:?}"
    );
}

#[test]
fn the_gpu_backend_names_only_the_backend_module() {
    let named = named_in(&crate_src("radcol-gpu"));
    let allowed: BTreeSet<String> = ["backend".to_string()].into();
    assert_eq!(
        named, allowed,
        "radcol-gpu should reach radcol-core through `backend` only"
    );
}

#[test]
fn the_scanner_sees_paths_and_braces() {
    let found = named("use radcol_core::run::Mesh;\nuse radcol_core::{mesh::Mesh, nodes};\nfn f() { radcol_core::assert_close!(1.0, 1.0, 0.0); }");
    let expected: BTreeSet<String> = ["run", "mesh", "nodes"].map(String::from).into();
    assert_eq!(found, expected);
    assert!(named(&code("// radcol_core::kernel::g\nfn f() {}")).is_empty());
}
