//! What the CLI test binaries share: the binary under test and scratch space.

use std::path::{Path, PathBuf};

/// The `radcol` binary under test: cargo's own build of this crate's
/// `radcol` (`CARGO_BIN_EXE_radcol`), made by the same `cargo test`.
pub fn radcol_bin() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_radcol"))
}

/// A fresh scratch directory under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = radcol_bin()
        .parent()
        .expect("profile dir")
        .join("cli-test-scratch")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}
