//! Room kept on disk for the checkpoint and `run.json` that end a run.
//!
//! A run that stops because an output cannot be written — a full disk (`ENOSPC`), a file-size
//! limit (`EFBIG`, `ulimit -f`) — must still leave a checkpoint to resume from and a `run.json`
//! that says why it stopped; on a full disk neither could be written any more. So a run keeps a
//! file `checkpoint/room` of the size they need (a checkpoint of the run's state as encoded at
//! the start, with a quarter more for the bookkeeping that grows, plus `run.json` twice and
//! [`MARGIN`]), its blocks allocated (`posix_fallocate` where the system has it, else written),
//! and removes it — freeing that space — before it writes them after a failure, and when it
//! ends. The room grows when a checkpoint outgrows it. Under a file-size limit (`ulimit -f`)
//! smaller than the room none is kept: that limit is per file and takes no space from the disk.

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};

/// Bytes kept beyond the estimate (64 KiB).
pub(super) const MARGIN: u64 = 64 << 10;

/// The room file of a run (see the module docs); removed when dropped.
pub(super) struct Room {
    path: PathBuf,
    bytes: u64,
    held: bool,
}

impl Room {
    /// Keep `bytes` in `dir/checkpoint/room`. Under a file-size limit smaller than the room
    /// (`EFBIG`) no room is kept: such a limit is per file and takes no space from the disk,
    /// and the files the room is for are each smaller than it.
    pub(super) fn keep(dir: &Path, bytes: u64) -> io::Result<Room> {
        let mut room = Room {
            path: dir.join("checkpoint").join("room"),
            bytes: 0,
            held: false,
        };
        match room.grow(bytes) {
            Err(e) if is_file_size_limit(&e) => {
                room.release();
                room.bytes = u64::MAX;
                Ok(room)
            }
            Err(e) => {
                room.release();
                Err(e)
            }
            Ok(()) => Ok(room),
        }
    }

    /// The room needed for a checkpoint of `checkpoint` bytes and a `run.json` of `record`
    /// bytes (see the module docs).
    pub(super) fn needed(checkpoint: u64, record: u64) -> u64 {
        checkpoint + checkpoint / 4 + 2 * record + MARGIN
    }

    /// Make the room at least `bytes` (no-op once released, or where a file-size limit
    /// keeps it from being made).
    pub(super) fn grow(&mut self, bytes: u64) -> io::Result<()> {
        if bytes <= self.bytes || (self.bytes > 0 && !self.held) {
            return Ok(());
        }
        let file = File::options()
            .create(true)
            .write(true)
            .truncate(false)
            .open(&self.path)?;
        self.held = true;
        match allocate(&file, bytes) {
            Ok(()) => {
                self.bytes = bytes;
                Ok(())
            }
            // Past a file-size limit: the room keeps what it had (the limit takes no space).
            Err(e) if is_file_size_limit(&e) && self.bytes > 0 => {
                let _ = file.set_len(self.bytes);
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    /// Free the room (before the writes it was kept for).
    pub(super) fn release(&mut self) {
        if self.held {
            let _ = std::fs::remove_file(&self.path);
            self.held = false;
        }
    }
}

impl Drop for Room {
    fn drop(&mut self) {
        self.release();
    }
}

/// Whether `e` is a write past the process's file-size limit (`EFBIG`).
fn is_file_size_limit(e: &io::Error) -> bool {
    #[cfg(unix)]
    return e.raw_os_error() == Some(libc::EFBIG);
    #[cfg(not(unix))]
    return false;
}

/// Allocate the blocks of `file`'s first `bytes` bytes.
#[cfg(unix)]
fn allocate(file: &File, bytes: u64) -> io::Result<()> {
    use std::os::fd::AsRawFd as _;
    let len = libc::off_t::try_from(bytes).map_err(|_| io::Error::other("too large"))?;
    // SAFETY: a valid open descriptor; posix_fallocate touches nothing else.
    match unsafe { libc::posix_fallocate(file.as_raw_fd(), 0, len) } {
        0 => Ok(()),
        // A file system without the call: write the bytes instead.
        libc::EOPNOTSUPP | libc::EINVAL => write_zeros(file, bytes),
        e => Err(io::Error::from_raw_os_error(e)),
    }
}

#[cfg(not(unix))]
fn allocate(file: &File, bytes: u64) -> io::Result<()> {
    write_zeros(file, bytes)
}

/// Write zeros over `file`'s first `bytes` bytes.
fn write_zeros(mut file: &File, bytes: u64) -> io::Result<()> {
    use std::io::{Seek as _, Write as _};
    file.seek(io::SeekFrom::Start(0))?;
    let zeros = vec![0u8; 1 << 16];
    let mut left = bytes;
    while left > 0 {
        let n = left.min(zeros.len() as u64) as usize;
        file.write_all(&zeros[..n])?;
        left -= n as u64;
    }
    file.sync_data()
}
