//! Output files, written whole or not at all: each is written to a hidden
//! temporary file beside its final name and moved there only when every
//! byte is written ([`Staged::commit`]). An interrupted or failed write
//! (a full disk, an error, a signal) leaves the final name as it was: no
//! file, or with `--force` the previous output, never a truncated one.

use crate::error::bad_input;
use crate::validate::OutputFile;
use anyhow::{Context, Result};
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

/// The temporary files being written, for [`remove_pending`].
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary output file still being written: what a signal
/// that ends the process does first (`main`), so that an interrupted run
/// leaves no hidden file beside its outputs.
pub fn remove_pending() {
    let pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
    for path in pending.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// `path` is no longer being written.
fn settled(path: &Path) {
    let mut pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
    pending.retain(|p| p != path);
}

/// An output being written under a temporary name.
pub struct Staged {
    writer: Option<BufWriter<File>>,
    temporary: PathBuf,
    /// Where it goes: the file's path, or where a symbolic link there leads.
    target: PathBuf,
    file: OutputFile,
}

/// Distinguishes the temporary files of one process.
static SERIAL: AtomicU32 = AtomicU32::new(0);

/// The temporary name beside `path`: hidden, naming the process.
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let serial = SERIAL.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(
        ".{name}.radcol-{}-{serial}.tmp",
        std::process::id()
    ))
}

fn exists_message(file: &OutputFile) -> anyhow::Error {
    anyhow::Error::new(bad_input(format!(
        "{} already exists; pass --force to overwrite it",
        file.path.display()
    )))
}

/// Starts writing `file`: refused at once when it exists and `--force`
/// was not given; else a temporary file beside it, which
/// [`Staged::commit`] moves to the final name.
pub fn create(file: &OutputFile) -> Result<Staged> {
    if !file.force && std::fs::symlink_metadata(&file.path).is_ok() {
        return Err(exists_message(file));
    }
    // Through a link, to the file it names (the link stays).
    let linked = std::fs::symlink_metadata(&file.path).is_ok_and(|m| m.file_type().is_symlink());
    let target = match linked {
        true => std::fs::canonicalize(&file.path).unwrap_or_else(|_| file.path.clone()),
        false => file.path.clone(),
    };
    let temporary = temporary(&target);
    // Listed before it exists: a signal between the two finds nothing to remove.
    PENDING
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(temporary.clone());
    let f = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temporary)
        .with_context(|| format!("cannot create {}", file.path.display()))
        .inspect_err(|_| settled(&temporary))?;
    Ok(Staged {
        writer: Some(BufWriter::new(f)),
        temporary,
        target,
        file: file.clone(),
    })
}

impl Staged {
    fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer.as_mut().expect("written before commit")
    }

    /// Flushes what was written and moves it to the final name: over the
    /// previous file with `--force` (keeping its permissions), else only
    /// if no file took the name meanwhile.
    pub fn commit(mut self) -> Result<()> {
        let writer = self.writer.take().expect("committed once");
        let moved = self.finish(writer);
        if moved.is_err() {
            let _ = std::fs::remove_file(&self.temporary);
        }
        settled(&self.temporary);
        moved
    }

    /// [`Staged::commit`]'s work; on an error the caller removes the
    /// temporary file.
    fn finish(&self, writer: BufWriter<File>) -> Result<()> {
        let shown = self.file.path.display().to_string();
        let f = writer
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("writing {shown}"))?;
        f.sync_all().with_context(|| format!("writing {shown}"))?;
        drop(f);
        if self.file.force {
            if let Ok(old) = std::fs::metadata(&self.target) {
                if old.is_file() {
                    let _ = std::fs::set_permissions(&self.temporary, old.permissions());
                }
            }
            std::fs::rename(&self.temporary, &self.target)
                .with_context(|| format!("cannot replace {shown}"))?;
        } else {
            match std::fs::hard_link(&self.temporary, &self.target) {
                Ok(()) => {
                    let _ = std::fs::remove_file(&self.temporary);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    return Err(exists_message(&self.file));
                }
                // No hard links here (some file systems): the check at
                // create() stands.
                Err(_) => std::fs::rename(&self.temporary, &self.target)
                    .with_context(|| format!("cannot create {shown}"))?,
            }
        }
        Ok(())
    }
}

impl Drop for Staged {
    /// Not committed: the temporary file goes, the final name is untouched.
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.temporary);
            settled(&self.temporary);
        }
    }
}

impl Write for Staged {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer().write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer().flush()
    }
}

impl Seek for Staged {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.writer().seek(pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the signal handler does: the temporary file of an output being
    /// written goes, the final name stays absent; a committed output is
    /// no longer pending and stays.
    #[test]
    fn an_interrupted_write_leaves_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("radcol-pending-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = |name: &str| OutputFile {
            path: dir.join(name),
            force: false,
            flag: "--out",
        };
        let mut done = create(&file("done.txt")).unwrap();
        done.write_all(b"whole").unwrap();
        done.commit().unwrap();
        let mut half = create(&file("half.txt")).unwrap();
        half.write_all(b"ha").unwrap();
        let temporary = half.temporary.clone();
        assert!(temporary.exists());
        remove_pending();
        assert!(!temporary.exists());
        assert!(!dir.join("half.txt").exists());
        assert_eq!(std::fs::read(dir.join("done.txt")).unwrap(), b"whole");
        drop(half);
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
