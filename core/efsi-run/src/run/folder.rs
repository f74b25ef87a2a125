//! The output folder before a run writes in it: its subfolders, an earlier run's outputs
//! (refused, or removed with `overwrite`), and the `probes.csv` header and append handle.

use crate::checkpoint::{self, CheckpointFile};
use crate::output::spec::ProbeSpec;
use crate::probes;
use efsi_core::Geometry;
use efsi_core::error::EfsiError;
use std::fs::{self, File, OpenOptions};
use std::path::{Path, PathBuf};

/// The files of a run's outputs present in `dir` (what makes it hold a run).
pub(super) fn earlier_outputs(dir: &Path) -> Result<Vec<PathBuf>, EfsiError> {
    let mut found: Vec<PathBuf> = ["run.json", "probes.csv", "fields.pvd", checkpoint::LATEST]
        .iter()
        .map(|f| dir.join(f))
        .filter(|p| p.is_file())
        .collect();
    for (sub, ext) in [
        ("fields", "vtr"),
        ("profiles", "csv"),
        ("slices", "vtr"),
        ("slices", "pvd"),
    ] {
        let d = dir.join(sub);
        // `slices/` exists only where a run wrote plane slices.
        if sub == "slices" && !d.is_dir() {
            continue;
        }
        for e in fs::read_dir(&d).map_err(|e| EfsiError::io(&d, e))? {
            let p = e.map_err(|e| EfsiError::io(&d, e))?.path();
            if p.extension().is_some_and(|x| x == ext) && p.is_file() {
                found.push(p);
            }
        }
    }
    Ok(found)
}

/// Refuse a folder holding an earlier run's outputs `old` (describing them), or remove them if
/// `overwrite`.
pub(super) fn replace_earlier_run(
    dir: &Path,
    old: &[PathBuf],
    overwrite: bool,
) -> Result<(), EfsiError> {
    if old.is_empty() {
        return Ok(());
    }
    if overwrite {
        for p in old {
            fs::remove_file(p).map_err(|e| EfsiError::io(p, e))?;
        }
        return Ok(());
    }
    let latest = dir.join(checkpoint::LATEST);
    let vtk = old
        .iter()
        .filter(|p| p.extension().is_some_and(|x| x == "vtr"))
        .count();
    let mut what: Vec<String> = ["run.json", "probes.csv", "fields.pvd"]
        .iter()
        .filter(|f| old.contains(&dir.join(f)))
        .map(|f| f.to_string())
        .collect();
    if vtk > 0 {
        what.push(format!("{vtk} VTK files"));
    }
    let resume = if old.contains(&latest) {
        let at = CheckpointFile::read(&latest).map_or(String::new(), |c| {
            format!(" at step {}, t = {:.6e}", c.record.step(), c.record.t())
        });
        what.push(format!("a checkpoint{at}"));
        format!("`efsi resume {}` continues it; ", dir.display())
    } else {
        String::new()
    };
    Err(EfsiError::Config {
        path: dir.to_path_buf(),
        field: "output folder".into(),
        message: format!(
            "holds the outputs of an earlier run ({}): {resume}--overwrite replaces them, --out \
             chooses another folder",
            what.join(", ")
        ),
    })
}

pub(super) fn probe_header(probes: &[ProbeSpec], geometry: Geometry, bodies: &[String]) -> String {
    let mut header = vec!["t".to_string()];
    for p in probes {
        header.extend(probes::columns(p, geometry, bodies));
    }
    header.join(",") + "\n"
}

/// Create the output folders; fails (naming the folder) if one cannot be made, e.g. a path
/// through a regular file.
pub(super) fn make_dirs(dir: &Path) -> Result<(), EfsiError> {
    for d in [
        dir.to_path_buf(),
        dir.join("fields"),
        dir.join("profiles"),
        dir.join("checkpoint"),
    ] {
        fs::create_dir_all(&d).map_err(|e| EfsiError::io(&d, e))?;
    }
    Ok(())
}

pub(super) fn open_append(path: &Path) -> Result<File, EfsiError> {
    OpenOptions::new()
        .append(true)
        .open(path)
        .map_err(|e| EfsiError::io(path, e))
}
