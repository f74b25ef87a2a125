//! FMU archives: deflated entries in the order they are added, each a regular file
//! (`rw-r--r--`) dated at the DOS epoch (1980-01-01 00:00), so the same content gives the same
//! archive. Written by the `zip` crate; read by fmpy, FMI tools and `unzip`.

use std::io::{Cursor, Write};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

/// An archive being written in memory.
pub struct Zip {
    writer: ZipWriter<Cursor<Vec<u8>>>,
}

impl Default for Zip {
    fn default() -> Self {
        Zip {
            writer: ZipWriter::new(Cursor::new(Vec::new())),
        }
    }
}

impl Zip {
    /// Add `data` as `name` (a relative path with `/` separators), deflated at the highest
    /// level.
    pub fn add(&mut self, name: &str, data: &[u8]) -> std::io::Result<()> {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .compression_level(Some(9))
            .last_modified_time(DateTime::default())
            .unix_permissions(0o644);
        self.writer.start_file(name, options)?;
        self.writer.write_all(data)
    }

    /// The archive's bytes.
    pub fn finish(self) -> std::io::Result<Vec<u8>> {
        Ok(self.writer.finish()?.into_inner())
    }
}
