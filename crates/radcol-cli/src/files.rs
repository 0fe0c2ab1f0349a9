//! Output files: each opened for writing fresh, or replaced with `--force`.

use crate::error::bad_input;
use crate::validate::OutputFile;
use anyhow::Result;
use std::fs::{File, OpenOptions};
use std::io::BufWriter;

/// Opens `file` for writing: a fresh file, or (with `--force`) a truncated one.
/// `create_new` closes the gap between the check in `setup::check_writable` and this write.
pub fn create(file: &OutputFile) -> Result<BufWriter<File>> {
    let mut opts = OpenOptions::new();
    opts.write(true);
    if file.force {
        opts.create(true).truncate(true);
    } else {
        opts.create_new(true);
    }
    let shown = file.path.display();
    let f = opts.open(&file.path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::AlreadyExists {
            anyhow::Error::new(bad_input(format!(
                "{shown} already exists; pass --force to overwrite it"
            )))
        } else {
            anyhow::Error::new(e).context(format!("cannot create {shown}"))
        }
    })?;
    Ok(BufWriter::new(f))
}
