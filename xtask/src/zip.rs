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

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn archive() -> Vec<u8> {
        let mut z = Zip::default();
        z.add("modelDescription.xml", b"<fmiModelDescription/>")
            .unwrap();
        z.add("binaries/linux64/m.so", &[7u8; 5000]).unwrap();
        z.finish().unwrap()
    }

    #[test]
    fn entries_read_back_deflated_dated_and_reproducible() {
        let bytes = archive();
        assert_eq!(bytes, archive());
        let mut a = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
        assert_eq!(a.len(), 2);
        let mut f = a.by_name("binaries/linux64/m.so").unwrap();
        assert_eq!(f.compression(), CompressionMethod::Deflated);
        assert_eq!(f.unix_mode(), Some(0o100644));
        assert!(f.compressed_size() < 100, "{}", f.compressed_size());
        let d = f.last_modified().unwrap();
        assert_eq!((d.year(), d.month(), d.day(), d.hour()), (1980, 1, 1, 0));
        let mut data = Vec::new();
        f.read_to_end(&mut data).unwrap();
        assert_eq!(data, [7u8; 5000]);
        drop(f);
        let mut text = String::new();
        a.by_index(0).unwrap().read_to_string(&mut text).unwrap();
        assert_eq!(text, "<fmiModelDescription/>");
    }
}
