//! TEMPORARY stub, replaced by the vtk branch.
#![allow(missing_docs)]
use crate::grid::Grid;
use std::path::{Path, PathBuf};
pub struct CellArray<'a> {
    pub name: &'a str,
    pub components: usize,
    pub values: &'a [f64],
}
pub fn write_vtr(
    _path: &Path,
    _grid: &Grid,
    _time: f64,
    _arrays: &[CellArray],
) -> std::io::Result<()> {
    Ok(())
}
pub struct PvdCollection {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}
impl PvdCollection {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        PvdCollection {
            path: path.into(),
            entries: vec![],
        }
    }
    pub fn add(&mut self, time: f64, file: &str) -> std::io::Result<()> {
        let _ = &self.path;
        self.entries.push((time, file.into()));
        Ok(())
    }
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }
}
