//! `probes.csv` as an output: header `t,<columns…>`, one row per sample of the scene's probes
//! ([`crate::probes`]), every `output.probe_every` of simulated time (every step without one)
//! and at the end.
//!
//! The file grows by appends — rewriting it whole for every row would cost time quadratic in
//! its length — each row one `write` of a complete line (a write that fails part-way is cut
//! back to the last whole row); its header is written atomically. A checkpoint records its
//! length and the XXH3 hash of its bytes: a resumed run truncates it to that length, after
//! checking that those bytes are the ones the checkpoint's run wrote.

use super::{RunAt, Schedule, Writer};
use crate::checkpoint::OutputState;
use crate::output::spec::ProbeSpec;
use crate::probes;
use crate::run::folder::{open_append, probe_header};
use efsi_core::Geometry;
use efsi_core::error::EfsiError;
use std::fs::{self, File};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// The writer of `probes.csv`.
pub struct ProbesCsv {
    path: PathBuf,
    file: File,
    probes: Vec<ProbeSpec>,
    /// The file's length in bytes.
    bytes: u64,
    /// XXH3 of the file's `bytes` bytes, fed as rows are appended (its digest is
    /// [`OutputState::probes_hash`]).
    hash: Xxh3,
    row: Vec<f64>,
}

impl ProbesCsv {
    /// A new `probes.csv` in `dir`, its header naming the columns of `probes` in a scene of
    /// `geometry` whose bodies are named `bodies` ([`probes::body_names`]).
    pub fn create(
        dir: &Path,
        probes: &[ProbeSpec],
        geometry: Geometry,
        bodies: &[String],
    ) -> Result<ProbesCsv, EfsiError> {
        let path = dir.join("probes.csv");
        let header = probe_header(probes, geometry, bodies);
        crate::output::atomic::write_bytes_atomically(&path, header.as_bytes())
            .map_err(|e| EfsiError::io(&path, e))?;
        Ok(ProbesCsv {
            file: open_append(&path)?,
            path,
            probes: probes.to_vec(),
            bytes: header.len() as u64,
            hash: hasher_of(header.as_bytes()),
            row: Vec::new(),
        })
    }

    /// The `probes.csv` of a run in `dir` that stopped at a checkpoint with bookkeeping
    /// `state`, truncated to its length then; refused if its header is not `probes`' (in a
    /// scene with `bodies`, as [`Self::create`]) or its rows are not the ones the checkpoint's
    /// run wrote.
    pub fn reopen(
        dir: &Path,
        probes: &[ProbeSpec],
        (geometry, bodies): (Geometry, &[String]),
        state: &OutputState,
    ) -> Result<ProbesCsv, EfsiError> {
        let path = dir.join("probes.csv");
        let header = probe_header(probes, geometry, bodies);
        let fail = |message: String| EfsiError::Checkpoint {
            what: path.display().to_string(),
            message,
        };
        let mut head = Vec::new();
        File::open(&path)
            .and_then(|f| f.take(header.len() as u64).read_to_end(&mut head))
            .map_err(|e| EfsiError::io(&path, e))?;
        if head != header.as_bytes() {
            return Err(fail(format!(
                "its header is not the scene's `{}`",
                header.trim_end()
            )));
        }
        let len = fs::metadata(&path)
            .map_err(|e| EfsiError::io(&path, e))?
            .len();
        if len < state.probe_bytes {
            return Err(fail(format!(
                "it has {len} bytes, fewer than the {} it had at the checkpoint: rows were lost",
                state.probe_bytes
            )));
        }
        // The rows the checkpoint's run wrote must be this file's: a checkpoint carried into
        // another run's folder (its run.json edited to match) continues nothing here.
        let mut kept = Vec::new();
        File::open(&path)
            .and_then(|f| f.take(state.probe_bytes).read_to_end(&mut kept))
            .map_err(|e| EfsiError::io(&path, e))?;
        let hash = hasher_of(&kept);
        if hash.digest() != state.probes_hash {
            return Err(fail(format!(
                "its first {} bytes are not the rows the checkpoint's run wrote: the checkpoint \
                 belongs to another run's folder; resume in the folder it was written in",
                state.probe_bytes
            )));
        }
        let file = open_append(&path)?;
        file.set_len(state.probe_bytes)
            .map_err(|e| EfsiError::io(&path, e))?;
        Ok(ProbesCsv {
            path,
            file,
            probes: probes.to_vec(),
            bytes: state.probe_bytes,
            hash,
            row: Vec::new(),
        })
    }
}

impl Writer for ProbesCsv {
    fn label(&self) -> String {
        "probes.csv".to_string()
    }

    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError> {
        let sim = run.sim;
        self.row.clear();
        self.row.push(sim.state.t);
        for p in &self.probes {
            probes::evaluate(
                p,
                &sim.grid,
                &sim.state,
                sim.scene.gravity,
                sim.pipeline().outputs(),
                &mut self.row,
            );
        }
        let line: Vec<String> = self.row.iter().map(|v| format!("{v:.17e}")).collect();
        let line = line.join(",") + "\n";
        // One write of a complete line: a reader never sees half a row. A write that fails
        // part-way (a full disk, a file size limit) is undone to the last whole row.
        if let Err(e) = self.file.write_all(line.as_bytes()) {
            let undone = self.file.set_len(self.bytes).map_or_else(
                |u| format!("; removing the partial row failed too: {u}"),
                |_| {
                    format!(
                        "; the file ends with its last whole row ({} bytes)",
                        self.bytes
                    )
                },
            );
            return Err(EfsiError::io(
                &self.path,
                std::io::Error::new(e.kind(), format!("{e}{undone}")),
            ));
        }
        self.bytes += line.len() as u64;
        self.hash.update(line.as_bytes());
        Ok(self.path.clone())
    }

    fn save(&self, schedule: &Schedule, into: &mut OutputState) {
        into.probe_count = schedule.count();
        into.probe_bytes = self.bytes;
        into.probes_hash = self.hash.digest();
    }
}

/// An XXH3 hasher fed with `bytes` (a streamed hash equals the one-shot hash of all it was fed).
fn hasher_of(bytes: &[u8]) -> Xxh3 {
    let mut h = Xxh3::new();
    h.update(bytes);
    h
}
