//! One process per output folder: an advisory lock held while a run or a resume writes there.
//!
//! The lock is an exclusive `flock` on the file [`LOCK_FILE`] in the output folder, taken
//! without waiting by [`crate::run::run_with`] and [`crate::run::resume`] before they touch any
//! output, and released when the [`FolderLock`] is dropped — also when the process dies, since
//! the operating system drops the locks of a closed file. A second `efsi run` or `efsi resume`
//! in the same folder is therefore refused (naming the process that holds it) instead of
//! rewriting `probes.csv` under the first or appending the same rows twice. The file holds the
//! holder's process id, for that message only; the lock, not the file's presence, is what
//! counts, so a file left by a killed process does not block anything.

use efsi_core::error::EfsiError;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The lock file, relative to the output folder.
pub const LOCK_FILE: &str = ".efsi.lock";

/// An exclusive lock on an output folder, held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    file: File,
    path: PathBuf,
}

impl FolderLock {
    /// Take the lock of the folder `dir` (which must exist) without waiting. Refused, naming
    /// the holder's process id, when another process holds it (exit code 2).
    pub fn acquire(dir: &Path) -> Result<FolderLock, EfsiError> {
        let path = dir.join(LOCK_FILE);
        let io = |e| EfsiError::io(&path, e);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let holder = holder.trim();
                let who = if holder.is_empty() {
                    "another efsi process".to_string()
                } else {
                    format!("another efsi process (pid {holder})")
                };
                return Err(EfsiError::Config {
                    path: dir.to_path_buf(),
                    field: "output folder".into(),
                    message: format!(
                        "{who} is writing a run in this folder; wait for it to end or stop it \
                         (a stopped run continues with `efsi resume`), or choose another folder \
                         with --out"
                    ),
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        file.set_len(0)
            .and_then(|_| file.rewind())
            .and_then(|_| writeln!(file, "{}", std::process::id()))
            .map_err(io)?;
        Ok(FolderLock { file, path })
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_on_the_folder_is_refused_until_the_first_is_dropped() {
        let dir = std::env::temp_dir().join(format!("efsi-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let first = FolderLock::acquire(&dir).unwrap();
        let e = FolderLock::acquire(&dir).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let m = e.to_string();
        assert!(
            m.contains(&format!(
                "another efsi process (pid {})",
                std::process::id()
            )) && m.contains("output folder"),
            "{m}"
        );
        drop(first);
        let again = FolderLock::acquire(&dir).unwrap();
        assert!(again.path().ends_with(LOCK_FILE));
        drop(again);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
