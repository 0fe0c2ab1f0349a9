//! Files the CLI writes: the nodal CSV, and the overwrite rule shared by every file.

use crate::config::OutputFile;
use crate::error::bad_input;
use anyhow::{Context, Result};
use radcol_core::run::SolveOutcome;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};

/// Opens `file` for writing: a fresh file, or (with `--force`) a truncated one.
/// `create_new` closes the gap between the check in `config` and this write.
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

/// Column names of the channels: `u` for one channel, `u_<name>` otherwise.
pub fn channel_columns(out: &SolveOutcome) -> Vec<String> {
    if out.channels.len() == 1 {
        vec!["u".into()]
    } else {
        out.channels
            .iter()
            .map(|c| format!("u_{}", c.name))
            .collect()
    }
}

/// Writes one row per collocation node: `element,node,x,y,z,u…`, every value
/// in Rust's shortest round-trip form. Returns the number of rows.
pub fn write_csv(file: &OutputFile, out: &SolveOutcome) -> Result<usize> {
    let mut w = create(file)?;
    let write = |w: &mut BufWriter<File>| -> std::io::Result<usize> {
        writeln!(w, "element,node,x,y,z,{}", channel_columns(out).join(","))?;
        let points = out.discretization.points();
        for (i, p) in points.iter().enumerate() {
            write!(
                w,
                "{},{},{:e},{:e},{:e}",
                p.element, p.node, p.position.x, p.position.y, p.position.z
            )?;
            for ch in &out.channels {
                write!(w, ",{:e}", ch.solution.nodal()[i])?;
            }
            writeln!(w)?;
        }
        w.flush()?;
        Ok(points.len())
    };
    write(&mut w).with_context(|| format!("writing {}", file.path.display()))
}
