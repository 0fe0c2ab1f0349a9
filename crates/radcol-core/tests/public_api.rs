//! The public API of radcol-core is listed in `public-api.txt`, so that a
//! change to it is made on purpose: every public declaration of the
//! modules declared `pub` (their `pub` items and re-exports, the `pub`
//! fields of their structs and the `pub` methods of their types, with
//! signatures as written), one per line, by file; then, for the items
//! that they re-export from the stages behind the edge, their declarations
//! there (marked "behind the edge"), fields and methods included.
//!
//! When the test fails, read the difference it prints; if the change is
//! meant, write the list again and commit it with the change:
//!
//! ```text
//! RADCOL_BLESS_API=1 cargo test --release -p radcol-core --test public_api
//! ```

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The source of `text` before its trailing test block, without comments
/// and attributes.
fn code(text: &str) -> String {
    let body = text.split("\n#[cfg(test)]").next().unwrap_or(text);
    body.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .filter(|l| !l.trim_start().starts_with("#["))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The file of module `name` declared in `file` (`a.rs` declares `b`:
/// `a/b.rs` or `a/b/mod.rs`; `lib.rs` and `mod.rs` declare beside them).
fn module_file(file: &Path, name: &str) -> Option<PathBuf> {
    let stem = file.file_stem()?.to_str()?;
    let dir = match stem {
        "lib" | "mod" => file.parent()?.to_path_buf(),
        _ => file.parent()?.join(stem),
    };
    [
        dir.join(format!("{name}.rs")),
        dir.join(name).join("mod.rs"),
    ]
    .into_iter()
    .find(|p| p.exists())
}

/// Whitespace runs as one space, and none inside brackets or before a
/// closing one (rustfmt's line breaks and trailing commas undone).
fn squeeze(s: &str) -> String {
    let mut out = s.split_whitespace().collect::<Vec<_>>().join(" ");
    for (from, to) in [
        (", )", ")"),
        (", }", "}"),
        ("( ", "("),
        ("{ ", "{"),
        (" )", ")"),
        (" }", "}"),
    ] {
        out = out.replace(from, to);
    }
    out
}

/// The public declarations of `code`: each `pub` (not `pub(crate)` or
/// `pub(super)`) declaration's head, up to its body, its `;` or the end of
/// a field, with the modules it declares `pub`.
fn declarations(code: &str) -> (Vec<String>, Vec<String>) {
    let mut out = Vec::new();
    let mut modules = Vec::new();
    let bytes = code.as_bytes();
    let mut search = 0;
    while let Some(found) = code[search..].find("pub ") {
        let at = search + found;
        search = at + 4;
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        // The declaration's head: to the first `{`, `;` or, for a field,
        // `,` at depth 0 of (), <> and [].
        let mut depth = 0i32;
        let mut end = at;
        while end < bytes.len() {
            match bytes[end] {
                b'(' | b'[' | b'<' => depth += 1,
                b')' | b']' => depth -= 1,
                b'>' if end > 0 && bytes[end - 1] != b'-' && bytes[end - 1] != b'=' => depth -= 1,
                b'{' if depth <= 0 && !code[at..end].starts_with("pub use") => break,
                b';' => break,
                b',' | b'}' if depth <= 0 => break,
                _ => {}
            }
            end += 1;
        }
        if code[at..end].starts_with("pub use") {
            // A re-export with braces runs to its `;`.
            end = code[at..].find(';').map_or(end, |e| at + e);
        }
        let mut head = squeeze(&code[at..end]);
        if let Some(outer) = enclosing(code, at) {
            head = format!("{outer} > {head}");
        }
        if let Some(name) = head.strip_prefix("pub mod ") {
            modules.push(name.trim().to_string());
        }
        out.push(head);
    }
    (out, modules)
}

/// The head of the item whose block holds the declaration at `at` when it
/// is indented (a method's impl, a field's struct): the nearest line above
/// it that starts at the margin, up to its `{`. rustfmt's layout is
/// assumed.
fn enclosing(code: &str, at: usize) -> Option<String> {
    let line_start = code[..at].rfind('\n').map_or(0, |i| i + 1);
    if at == line_start {
        return None;
    }
    let outer = code[..line_start]
        .lines()
        .rev()
        .find(|l| l.starts_with(|c: char| !c.is_whitespace() && c != '}'))?;
    Some(squeeze(outer.split('{').next().unwrap_or(outer)))
}

/// The private modules declared in `code` (`mod x;`): reached through
/// their parent's re-exports and types, so their `pub` items are listed.
fn private_modules(code: &str) -> Vec<String> {
    code.lines()
        .map(str::trim)
        .filter_map(|l| l.strip_prefix("mod "))
        .filter_map(|l| l.strip_suffix(';'))
        .map(|n| n.trim().to_string())
        .collect()
}

/// The listing of `file` (module path `path`) and of the modules below it;
/// with `only`, just the declarations of those names (and their fields and
/// methods).
fn list(
    root: &Path,
    file: &Path,
    path: &str,
    only: Option<&BTreeSet<String>>,
    out: &mut Vec<String>,
) {
    let text = std::fs::read_to_string(file).expect("readable source");
    let code = code(&text);
    let (decls, modules) = declarations(&code);
    let shown = file
        .strip_prefix(root)
        .unwrap_or(file)
        .display()
        .to_string();
    let shown = match only {
        Some(_) => format!("behind the edge, {shown}"),
        None => shown,
    };
    // A macro's template (`pub mod $name`) declares nothing by itself.
    for d in decls.iter().filter(|d| !d.contains('$')) {
        if only.is_none_or(|names| item_name(d).is_some_and(|n| names.contains(&n))) {
            out.push(format!("{path} ({shown}): {d}"));
        }
    }
    for m in modules.iter().chain(&private_modules(&code)) {
        if let Some(f) = module_file(file, m) {
            list(root, &f, &format!("{path}::{m}"), only, out);
        }
    }
}

/// The name a declaration (as [`declarations`] gives it) declares, or for
/// a field or method, the name of its type.
fn item_name(decl: &str) -> Option<String> {
    let head = decl.split(" > ").next().unwrap_or(decl);
    // A re-export inside the stages is plumbing: what it names is listed
    // where it is declared.
    if head.starts_with("pub use ") {
        return None;
    }
    let mut words = head
        .split(|c: char| c.is_whitespace() || c == '<' || c == '(' || c == ':')
        .filter(|w| !w.is_empty());
    let keywords = [
        "pub", "fn", "struct", "enum", "trait", "type", "const", "static", "unsafe", "async",
        "mod", "impl", "for",
    ];
    let mut name = None;
    // `impl<T> Trait for Type` names Type; anything else its first word
    // after the keywords.
    for w in words.by_ref() {
        if keywords.contains(&w) || w.starts_with('\'') || w.starts_with('>') {
            continue;
        }
        name = Some(
            w.trim_end_matches(['>', ','])
                .rsplit("::")
                .next()?
                .to_string(),
        );
        break;
    }
    if head.starts_with("impl") && head.contains(" for ") {
        let ty = head.rsplit(" for ").next()?;
        name = Some(
            ty.split(['<', ' '])
                .next()?
                .rsplit("::")
                .next()?
                .to_string(),
        );
    }
    name
}

/// The names that the `pub use` lines of `listed` re-export (before any
/// `as`).
fn reexported(listed: &[String]) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    for line in listed {
        let Some((_, used)) = line.split_once("pub use ") else {
            continue;
        };
        let inner = used.split_once('{').map_or(used, |(_, rest)| rest);
        for part in inner.split([',', '{', '}']) {
            let original = part.split(" as ").next().unwrap_or(part).trim();
            if let Some(name) = original.rsplit("::").next().filter(|n| !n.is_empty()) {
                names.insert(name.to_string());
            }
        }
    }
    names
}

/// The modules behind the edge, as `lib.rs` declares them in `internal!`.
fn internal_modules(lib: &str) -> Vec<String> {
    let Some((_, rest)) = lib.split_once("internal! {") else {
        return Vec::new();
    };
    let block = rest.split('}').next().unwrap_or_default();
    block
        .split(';')
        .filter_map(|m| m.split_whitespace().last())
        .filter(|m| {
            m.chars()
                .all(|c| c.is_ascii_lowercase() || c == '_' || c.is_ascii_digit())
        })
        .map(String::from)
        .collect()
}

/// The public modules' declarations, then those of the modules behind the
/// edge that are re-exported (with their fields and methods).
fn listing() -> String {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = root.join("lib.rs");
    let mut out = Vec::new();
    list(&root, &lib, "radcol_core", None, &mut out);
    let names = reexported(&out);
    let lib_code = code(&std::fs::read_to_string(&lib).expect("lib.rs"));
    for m in internal_modules(&lib_code) {
        if let Some(f) = module_file(&lib, &m) {
            list(
                &root,
                &f,
                &format!("radcol_core::{m}"),
                Some(&names),
                &mut out,
            );
        }
    }
    out.join("\n") + "\n"
}

#[test]
fn the_public_api_is_the_listed_one() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("public-api.txt");
    let now = listing();
    if std::env::var_os("RADCOL_BLESS_API").is_some() {
        std::fs::write(&file, &now).expect("writable public-api.txt");
        return;
    }
    let listed = std::fs::read_to_string(&file).unwrap_or_default();
    if listed == now {
        return;
    }
    let old: BTreeSet<&str> = listed.lines().collect();
    let new: BTreeSet<&str> = now.lines().collect();
    let gone: Vec<_> = old.difference(&new).collect();
    let added: Vec<_> = new.difference(&old).collect();
    let show = |lines: Vec<&&str>| match lines.is_empty() {
        true => "(none)".to_string(),
        false => lines.iter().map(|s| format!("\n  {s}")).collect(),
    };
    panic!(
        "the public API changed (run with RADCOL_BLESS_API=1 to accept it):\nremoved: {}\nadded: {}",
        show(gone),
        show(added)
    );
}

#[test]
fn the_scanner_finds_items_fields_methods_and_reexports() {
    let code = code(
        "pub mod a;\nmod b;\npub use b::{X, Y};\npub(crate) fn hidden() {}\n\
         /// doc\npub struct S {\n    pub x: Vec<u8>,\n    y: u8,\n}\n\
         impl S {\n    pub fn new(x: Vec<u8>) -> Self { Self { x, y: 0 } }\n    fn private() {}\n}\n\
         pub const C: usize = 3;\n",
    );
    let (decls, modules) = declarations(&code);
    assert_eq!(
        decls,
        [
            "pub mod a",
            "pub use b::{X, Y}",
            "pub struct S",
            "pub struct S > pub x: Vec<u8>",
            "impl S > pub fn new(x: Vec<u8>) -> Self",
            "pub const C: usize = 3",
        ]
    );
    assert_eq!(modules, ["a"]);
    assert_eq!(private_modules(&code), ["b"]);
    let names: Vec<_> = decls.iter().filter_map(|d| item_name(d)).collect();
    assert_eq!(names, ["a", "S", "S", "S", "C"]);
    assert_eq!(
        item_name("impl<'a> Display for Wrap<'a> > pub fn x()").as_deref(),
        Some("Wrap")
    );
    let listed = ["m (m.rs): pub use x::{A, b::C as D}".to_string()];
    assert_eq!(reexported(&listed), ["A", "C"].map(String::from).into());
    assert_eq!(
        internal_modules("internal! {\n    alpha0;\n    #[cfg(x)]\n    radiosity;\n}"),
        ["alpha0", "radiosity"]
    );
}
