//! TEMPORARY stub, replaced by the vtk branch.
#![allow(missing_docs)]
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = path.with_extension("tmp");
    let mut w = BufWriter::new(File::create(&tmp)?);
    write(&mut w)?;
    w.flush()?;
    std::fs::rename(tmp, path)
}
