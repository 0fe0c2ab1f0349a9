//! The ranks of `mpirun -np P radcol solve …` (feature `mpi`): every rank
//! runs the same command on the same inputs, stores its share of the
//! compressed operator's rows and takes part in GMRES; rank 0 alone shows
//! progress, writes the outputs and prints the report. A failure ends
//! every rank with one error line: when every rank fails alike (bad input
//! is the same on all of them) rank 0 reports it and all exit with its
//! code; when one fails alone, the others waiting for it in a collective
//! operation, it reports it (naming its rank) and ends the world
//! (MPI_Abort). Without the feature, or started without mpirun, there is
//! one rank.

use radcol_core::run::Ranks;
use std::sync::{Arc, OnceLock};

/// The world's ranks, when more than one runs this command.
static RANKS: OnceLock<Arc<dyn Ranks>> = OnceLock::new();

/// How long a failing rank waits for the others to fail alike before it
/// ends the world itself.
#[cfg(feature = "mpi")]
const WAIT_FOR_THE_OTHERS: std::time::Duration = std::time::Duration::from_secs(3);

/// MPI for the life of the process, when the command was built with it.
#[derive(Debug)]
pub struct Session {
    #[cfg(feature = "mpi")]
    mpi: radcol_core::run::MpiSession,
}

impl Session {
    /// Starts MPI (a world of one without mpirun); without the feature,
    /// nothing.
    ///
    /// # Errors
    /// One line when MPI cannot start.
    pub fn start() -> Result<Self, String> {
        #[cfg(feature = "mpi")]
        {
            let mpi = radcol_core::run::MpiSession::start()?;
            let world = mpi.world();
            if world.size() > 1 {
                let _ = RANKS.set(world);
            }
            Ok(Self { mpi })
        }
        #[cfg(not(feature = "mpi"))]
        Ok(Self {})
    }

    /// Ranks on this machine (1 without MPI).
    pub fn local_size(&self) -> usize {
        #[cfg(feature = "mpi")]
        return self.mpi.local_size();
        #[cfg(not(feature = "mpi"))]
        1
    }

    /// Reports `line` once for the whole world and ends every rank with
    /// `code`; returns only in a single process (the caller then exits).
    pub fn fail(&self, line: &str, code: u8) {
        let Some(ranks) = current() else {
            eprintln!("error: {line}");
            return;
        };
        #[cfg(feature = "mpi")]
        {
            if self.mpi.all_here(WAIT_FOR_THE_OTHERS) {
                if ranks.rank() == 0 {
                    eprintln!("error: {line}");
                }
                return;
            }
            if ranks.rank() != 0 {
                eprintln!("error: rank {} of {}: {line}", ranks.rank(), ranks.size());
            } else {
                eprintln!("error: {line}");
            }
            use std::io::Write;
            let _ = std::io::stderr().flush();
            let _ = std::io::stdout().flush();
            self.mpi.abort(code.into());
        }
        #[cfg(not(feature = "mpi"))]
        {
            let _ = (ranks, code);
            eprintln!("error: {line}");
        }
    }
}

/// The world's ranks, when more than one runs this command.
pub fn current() -> Option<Arc<dyn Ranks>> {
    RANKS.get().cloned()
}

/// Whether this process shows progress, writes outputs and prints the
/// report: rank 0, or the only process.
pub fn lead() -> bool {
    current().is_none_or(|r| r.rank() == 0)
}
