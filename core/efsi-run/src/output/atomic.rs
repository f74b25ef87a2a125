//! Atomic file replacement: write to a temporary file in the target's folder, then rename.
//!
//! A reader (ParaView polling a `.pvd`, a script tailing the output folder) therefore sees either
//! the previous complete file or the new complete file, never a half-written one. The rename is
//! atomic on POSIX file systems when source and target are in the same folder, which is why the
//! temporary file lives next to the target.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Capacity of the buffered writer handed to the caller (64 KiB: writes reach the file in large
/// pieces, and a field file streamed through it adds little to a run's memory).
const BUFFER_BYTES: usize = 1 << 16;

/// The temporary name used while `path` is being written: `.name.tmp` in the same folder.
pub fn temporary_path(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write {}: the path names no file", path.display()),
        )
    })?;
    let mut tmp = std::ffi::OsString::from(".");
    tmp.push(name);
    tmp.push(".tmp");
    Ok(path.with_file_name(tmp))
}

/// Write `path` atomically: `write` fills a buffered temporary file in the same folder, which is
/// flushed and then renamed over `path`.
///
/// If `write` (or the flush, or the rename) fails, the temporary file is removed, `path` is left
/// as it was and the error is returned with the file name added to its message. The data is
/// flushed to the operating system before the rename but not `fsync`ed: readers never see a
/// partial file, though a power loss right after the call may still lose it.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    write_through(path, BUFFER_BYTES, write)
}

/// [`write_atomically`] for data already in memory: `bytes` go to the temporary file in one
/// write, without a buffer (for `run.json`, a few kB, it would be the largest allocation of the
/// run's end).
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_through(path, 0, |w| w.write_all(bytes))
}

/// [`write_atomically`] with a buffer of `capacity` bytes (0: every write goes straight to the
/// file).
fn write_through(
    path: &Path,
    capacity: usize,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = temporary_path(path)?;
    let result = (|| {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(capacity, file);
        write(&mut w)?;
        w.flush()?;
        // Surface any error the buffered writer still holds and close the file before renaming.
        let file = w.into_inner().map_err(|e| e.into_error())?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(io::Error::new(
            e.kind(),
            format!("cannot write {}: {e}", path.display()),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("efsi-atomic-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn writes_and_leaves_no_temporary() {
        let dir = scratch("ok");
        let path = dir.join("a.txt");
        write_atomically(&path, |w| w.write_all(b"first")).unwrap();
        write_atomically(&path, |w| w.write_all(b"second")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failure_keeps_old_file_and_removes_temporary() {
        let dir = scratch("fail");
        let path = dir.join("a.txt");
        write_atomically(&path, |w| w.write_all(b"old")).unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("a.txt") && err.to_string().contains("boom"));
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert!(!temporary_path(&path).unwrap().exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporary_is_hidden_sibling() {
        let t = temporary_path(Path::new("out/run.pvd")).unwrap();
        assert_eq!(t, Path::new("out/.run.pvd.tmp"));
        assert!(temporary_path(Path::new("/")).is_err());
    }
}
