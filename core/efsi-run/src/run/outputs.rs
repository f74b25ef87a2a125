//! The writers of one run ([`Outputs`]) and their schedule: which outputs are due at a time
//! (VTK files, probe rows, profiles, periodic checkpoints), writing them, and the bookkeeping a
//! checkpoint records so that a resumed run neither repeats nor loses any.

use super::folder::{earlier_outputs, make_dirs, open_append, probe_header, replace_earlier_run};
use super::record::new_run_id;
use super::time_label;
use crate::checkpoint::OutputState;
use crate::lock::FolderLock;
use crate::output::spec::{ProbeSpec, ProfileSpec};
use crate::output::vtk::{CellArray, PvdCollection, VtrFormat, write_vtr_with};
use crate::probes;
use efsi_core::due;
use efsi_core::error::EfsiError;
use efsi_core::grid::Grid;
use efsi_core::simulation::Simulation;
use efsi_core::state::State;
use std::fs::{self, File};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// The writers of one run.
pub struct Outputs {
    pub(super) dir: PathBuf,
    pub(super) vtk_every: Option<f64>,
    pub(super) vtk: crate::output::spec::VtkOptions,
    vtk_count: u64,
    pvd: PvdCollection,
    probe_every: Option<f64>,
    probe_count: u64,
    probes: Vec<ProbeSpec>,
    /// The scheduled stages' outputs (their VTK arrays and probe quantities).
    pub(super) outputs: Vec<efsi_core::OutputDecl>,
    probe_path: PathBuf,
    probe_file: File,
    probe_bytes: u64,
    /// XXH3 of `probes.csv`'s `probe_bytes` bytes, fed as rows are appended (its digest is
    /// [`OutputState::probes_hash`]).
    probes_hash: Xxh3,
    row: Vec<f64>,
    profiles: Vec<(ProfileSpec, Vec<f64>)>,
    end: f64,
    checkpoint_every: Option<f64>,
    checkpoint_count: u64,
    pub(super) warnings: Vec<String>,
    pub(super) run_id: String,
    /// The bookkeeping at the start of the latest [`Outputs::emit`] (see [`Outputs::state_before_emit`]).
    mark: Mark,
    /// The room kept for the last checkpoint and `run.json` ([`super::room`]), once made.
    pub(super) room: Option<super::room::Room>,
    _lock: FolderLock,
}

/// What [`Outputs::emit`] changes, as it was before the call: what a checkpoint of the state
/// before the step must record.
#[derive(Default)]
struct Mark {
    vtk_count: u64,
    probe_count: u64,
    probe_bytes: u64,
    probes_hash: u64,
    pvd_len: usize,
    checkpoint_count: u64,
    /// Profile times written by the call: (profile, time).
    popped: Vec<(usize, f64)>,
}

/// The number of events of period `every` due by time `t` ([`due`]), at least `count`: the
/// smallest `n ≥ count` whose event `n·every` is not yet due. Computed, not counted, so that a
/// period tiny against `t` costs nothing: whatever the arguments, a bounded number of steps.
fn events_due(t: f64, every: f64, count: u64) -> u64 {
    // `due(t, x)` holds for x ≤ t / (1 − 1e-9) when x ≥ 1e-12, and for x ≤ t + 1e-21 below
    // (its absolute floor): start past the latest such x, then correct the rounding by single
    // steps. The start is capped at 2⁵³, where n·every stops being exact.
    const EXACT: f64 = 9_007_199_254_740_992.0;
    let reach = (t / (1.0 - 1e-9)).max((t + 1e-21).min(1e-12));
    let start = (reach / every).floor() + 1.0;
    let mut n = if start >= 0.0 {
        start.min(EXACT) as u64
    } else {
        0
    }
    .max(count);
    for _ in 0..64 {
        if n > count && !due(t, (n - 1) as f64 * every) {
            n -= 1;
        } else {
            break;
        }
    }
    for _ in 0..64 {
        if due(t, n as f64 * every) {
            n = n.saturating_add(1);
        } else {
            break;
        }
    }
    n
}

impl Outputs {
    /// Create the output folder and open the writers (fails before any step if it cannot).
    /// Checkpoints are due every `checkpoint_every` of simulated time, if given.
    pub fn new(
        sim: &Simulation,
        dir: &Path,
        checkpoint_every: Option<f64>,
        overwrite: bool,
    ) -> Result<Outputs, EfsiError> {
        let o = &crate::output::spec::check(&sim.scene, &sim.scene_path, sim.pipeline())?;
        make_dirs(dir)?;
        let lock = FolderLock::acquire(dir)?;
        replace_earlier_run(dir, &earlier_outputs(dir)?, overwrite)?;
        let probe_path = dir.join("probes.csv");
        let header = probe_header(&o.probes);
        crate::output::atomic::write_bytes_atomically(&probe_path, header.as_bytes())
            .map_err(|e| EfsiError::io(&probe_path, e))?;
        let profiles = o
            .profiles
            .iter()
            .map(|p| {
                let ProfileSpec::Line { at, .. } = p;
                let mut times = at.clone();
                times.sort_by(f64::total_cmp);
                (p.clone(), times)
            })
            .collect();
        // The collection starts empty: a stale one from an earlier run in this folder goes.
        let pvd = PvdCollection::new(dir.join("fields.pvd"));
        if o.vtk_every.is_some() {
            pvd.write()
                .map_err(|e| EfsiError::io(dir.join("fields.pvd"), e))?;
        }
        Ok(Outputs {
            dir: dir.to_path_buf(),
            vtk_every: o.vtk_every,
            vtk: o.vtk.clone(),
            vtk_count: 0,
            pvd,
            probe_every: o.probe_every,
            probe_count: 0,
            probes: o.probes.clone(),
            outputs: sim.pipeline().outputs().to_vec(),
            probe_file: open_append(&probe_path)?,
            probe_path,
            probe_bytes: header.len() as u64,
            probes_hash: hasher_of(header.as_bytes()),
            row: Vec::new(),
            profiles,
            end: sim.scene.time.end,
            checkpoint_every,
            checkpoint_count: 1,
            warnings: Vec::new(),
            run_id: new_run_id(dir),
            mark: Mark::default(),
            room: None,
            _lock: lock,
        })
    }

    /// Reopen the writers of a run that stopped at a checkpoint with bookkeeping `state`:
    /// `probes.csv` is truncated to its length at the checkpoint (its header must match the
    /// scene's probes) and `fields.pvd` rewritten with the checkpoint's entries, so what the
    /// resumed run writes neither duplicates nor loses rows.
    pub fn resume(
        sim: &Simulation,
        dir: &Path,
        state: &OutputState,
        checkpoint_every: Option<f64>,
        lock: FolderLock,
    ) -> Result<Outputs, EfsiError> {
        let o = &crate::output::spec::check(&sim.scene, &sim.scene_path, sim.pipeline())?;
        make_dirs(dir)?;
        let probe_path = dir.join("probes.csv");
        let header = probe_header(&o.probes);
        let fail = |message: String| EfsiError::Checkpoint {
            what: probe_path.display().to_string(),
            message,
        };
        let mut head = Vec::new();
        File::open(&probe_path)
            .and_then(|f| f.take(header.len() as u64).read_to_end(&mut head))
            .map_err(|e| EfsiError::io(&probe_path, e))?;
        if head != header.as_bytes() {
            return Err(fail(format!(
                "its header is not the scene's `{}`",
                header.trim_end()
            )));
        }
        let len = fs::metadata(&probe_path)
            .map_err(|e| EfsiError::io(&probe_path, e))?
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
        File::open(&probe_path)
            .and_then(|f| f.take(state.probe_bytes).read_to_end(&mut kept))
            .map_err(|e| EfsiError::io(&probe_path, e))?;
        let probes_hash = hasher_of(&kept);
        if probes_hash.digest() != state.probes_hash {
            return Err(fail(format!(
                "its first {} bytes are not the rows the checkpoint's run wrote: the checkpoint \
                 belongs to another run's folder; resume in the folder it was written in",
                state.probe_bytes
            )));
        }
        let file = open_append(&probe_path)?;
        file.set_len(state.probe_bytes)
            .map_err(|e| EfsiError::io(&probe_path, e))?;
        if state.profile_times.len() != o.profiles.len() {
            return Err(fail(format!(
                "the checkpoint records {} profiles, the scene has {}",
                state.profile_times.len(),
                o.profiles.len()
            )));
        }
        let profiles = o
            .profiles
            .iter()
            .cloned()
            .zip(state.profile_times.iter().cloned())
            .collect();
        let pvd = PvdCollection::with_entries(dir.join("fields.pvd"), state.pvd.clone());
        if o.vtk_every.is_some() {
            pvd.write()
                .map_err(|e| EfsiError::io(dir.join("fields.pvd"), e))?;
        }
        Ok(Outputs {
            dir: dir.to_path_buf(),
            vtk_every: o.vtk_every,
            vtk: o.vtk.clone(),
            vtk_count: state.vtk_count,
            pvd,
            probe_every: o.probe_every,
            probe_count: state.probe_count,
            probes: o.probes.clone(),
            outputs: sim.pipeline().outputs().to_vec(),
            probe_file: file,
            probe_path,
            probe_bytes: state.probe_bytes,
            probes_hash,
            row: Vec::new(),
            profiles,
            end: sim.scene.time.end,
            checkpoint_every,
            checkpoint_count: state.checkpoint_count,
            warnings: Vec::new(),
            run_id: state.run_id.clone(),
            mark: Mark::default(),
            room: None,
            _lock: lock,
        })
    }

    /// The bookkeeping a checkpoint records (see [`Outputs::resume`]).
    pub fn state(&self) -> OutputState {
        OutputState {
            vtk_count: self.vtk_count,
            probe_count: self.probe_count,
            probe_bytes: self.probe_bytes,
            pvd: self.pvd.entries().to_vec(),
            profile_times: self.profiles.iter().map(|(_, t)| t.clone()).collect(),
            checkpoint_every: self.checkpoint_every,
            checkpoint_count: self.checkpoint_count,
            run_id: self.run_id.clone(),
            probes_hash: self.probes_hash.digest(),
        }
    }

    /// The bookkeeping as it was before the latest [`Outputs::emit`]: what a checkpoint of the
    /// state at the start of the latest step records (its outputs are written again on resume).
    pub fn state_before_emit(&self) -> OutputState {
        let m = &self.mark;
        let mut s = self.state();
        s.vtk_count = m.vtk_count;
        s.probe_count = m.probe_count;
        s.probe_bytes = m.probe_bytes;
        s.probes_hash = m.probes_hash;
        s.pvd.truncate(m.pvd_len);
        s.checkpoint_count = m.checkpoint_count;
        for &(k, t) in m.popped.iter().rev() {
            s.profile_times[k].insert(0, t);
        }
        s
    }

    /// Whether a periodic checkpoint is due at `t`; if so, counts it.
    pub(super) fn checkpoint_due(&mut self, t: f64) -> bool {
        let Some(e) = self.checkpoint_every else {
            return false;
        };
        if !due(t, self.checkpoint_count as f64 * e) {
            return false;
        }
        self.checkpoint_count = events_due(t, e, self.checkpoint_count);
        true
    }

    /// The next time an output is due after `t` (or the end).
    pub fn next_event(&self, t: f64) -> f64 {
        let mut next = self.end;
        if let Some(e) = self.vtk_every {
            next = next.min(self.vtk_count as f64 * e);
        }
        if let Some(e) = self.probe_every {
            next = next.min(self.probe_count as f64 * e);
        }
        for (_, times) in &self.profiles {
            if let Some(&tt) = times.first() {
                next = next.min(tt);
            }
        }
        next.max(t)
    }

    /// Write whatever is due at the simulation's current time (everything, if `last`).
    pub fn emit(&mut self, sim: &Simulation, last: bool) -> Result<(), EfsiError> {
        let t = sim.state.t;
        self.mark.vtk_count = self.vtk_count;
        self.mark.probe_count = self.probe_count;
        self.mark.probe_bytes = self.probe_bytes;
        self.mark.probes_hash = self.probes_hash.digest();
        self.mark.pvd_len = self.pvd.entries().len();
        self.mark.checkpoint_count = self.checkpoint_count;
        self.mark.popped.clear();
        let probe_due = match self.probe_every {
            Some(e) => due(t, self.probe_count as f64 * e),
            None => true,
        };
        if probe_due || last {
            self.row.clear();
            self.row.push(t);
            for p in &self.probes {
                probes::evaluate(
                    p,
                    &sim.grid,
                    &sim.state,
                    sim.scene.gravity,
                    &self.outputs,
                    &mut self.row,
                );
            }
            let line: Vec<String> = self.row.iter().map(|v| format!("{v:.17e}")).collect();
            let line = line.join(",") + "\n";
            // One write of a complete line: a reader never sees half a row. A write that fails
            // part-way (a full disk, a file size limit) is undone to the last whole row.
            if let Err(e) = self.probe_file.write_all(line.as_bytes()) {
                let undone = self.probe_file.set_len(self.probe_bytes).map_or_else(
                    |u| format!("; removing the partial row failed too: {u}"),
                    |_| {
                        format!(
                            "; the file ends with its last whole row ({} bytes)",
                            self.probe_bytes
                        )
                    },
                );
                return Err(EfsiError::io(
                    &self.probe_path,
                    std::io::Error::new(e.kind(), format!("{e}{undone}")),
                ));
            }
            self.probe_bytes += line.len() as u64;
            self.probes_hash.update(line.as_bytes());
            if let Some(e) = self.probe_every {
                self.probe_count = events_due(t, e, self.probe_count);
            }
        }
        let vtk_due = self
            .vtk_every
            .is_some_and(|e| due(t, self.vtk_count as f64 * e));
        if vtk_due || (last && self.vtk_every.is_some()) {
            self.write_fields(&sim.grid, &sim.state, &sim.scene.name, "")?;
            if let Some(e) = self.vtk_every {
                self.vtk_count = events_due(t, e, self.vtk_count);
            }
        }
        for k in 0..self.profiles.len() {
            let is_due = self.profiles[k].1.first().is_some_and(|&tt| due(t, tt));
            let at_end = last && self.profiles[k].1.is_empty();
            if is_due || at_end {
                self.write_profile(k, sim)?;
                while self.profiles[k].1.first().is_some_and(|&tt| due(t, tt)) {
                    let tt = self.profiles[k].1.remove(0);
                    self.mark.popped.push((k, tt));
                }
            }
            // The run ends (at its end time or a steady state) before some of the profile's
            // times: the profile is written now instead, and the run says so.
            if last && !self.profiles[k].1.is_empty() {
                let missed = std::mem::take(&mut self.profiles[k].1);
                self.mark.popped.extend(missed.iter().map(|&tt| (k, tt)));
                let file = self.write_profile(k, sim)?;
                let ProfileSpec::Line { name, .. } = &self.profiles[k].0;
                let times: Vec<String> = missed.iter().map(|&x| time_label(x)).collect();
                self.warnings.push(format!(
                    "profile `{name}`: the run ended at t = {} before its time(s) {}; written at the end instead: {}",
                    time_label(t),
                    times.join(", "),
                    file.display()
                ));
            }
        }
        Ok(())
    }

    /// Write `state` as `fields/<name>_<step><suffix>.vtr` and add it to the collection;
    /// returns the file's path.
    pub(super) fn write_fields(
        &mut self,
        grid: &Grid,
        state: &State,
        name: &str,
        suffix: &str,
    ) -> Result<PathBuf, EfsiError> {
        let options = &self.vtk;
        let data = crate::output::fields::arrays(grid, state, options, &self.outputs);
        let arrays: Vec<CellArray> = data
            .iter()
            .map(|(name, components, values)| CellArray {
                name,
                components: *components,
                values,
            })
            .collect();
        let format = VtrFormat {
            precision: options.precision,
            compression: options.compression,
            point_data: options.point_data,
        };
        let notes = crate::output::fields::notes(grid.geometry);
        let file = format!("{name}_{:06}{suffix}.vtr", state.step);
        let path = self.dir.join("fields").join(&file);
        write_vtr_with(&path, grid, state.t, &arrays, &format, &notes)
            .map_err(|e| EfsiError::io(&path, e))?;
        let rel = format!("fields/{file}");
        self.pvd
            .add(state.t, &rel)
            .map_err(|e| EfsiError::io(self.dir.join("fields.pvd"), e))?;
        Ok(path)
    }

    /// Write profile `k` at the simulation's time; returns the file's path.
    fn write_profile(&mut self, k: usize, sim: &Simulation) -> Result<PathBuf, EfsiError> {
        let ProfileSpec::Line {
            name,
            from,
            to,
            points,
            fields,
            ..
        } = &self.profiles[k].0;
        let path = self
            .dir
            .join("profiles")
            .join(format!("{name}_t{}.csv", time_label(sim.state.t)));
        let len = (to.0 - from.0).hypot(to.1 - from.1);
        let mut text = format!("s,x,y,{}\n", fields.join(","));
        for q in 0..*points {
            let f = q as f64 / (*points - 1) as f64;
            let p = (from.0 + f * (to.0 - from.0), from.1 + f * (to.1 - from.1));
            text.push_str(&format!("{:.17e},{:.17e},{:.17e}", f * len, p.0, p.1));
            for fl in fields {
                text.push_str(&format!(
                    ",{:.17e}",
                    probes::sample_in(&sim.grid, &sim.state, &self.outputs, fl, p)
                ));
            }
            text.push('\n');
        }
        crate::output::atomic::write_bytes_atomically(&path, text.as_bytes())
            .map_err(|e| EfsiError::io(&path, e))?;
        Ok(path)
    }

    /// Free the room kept for the last checkpoint and `run.json` (before writing them after a
    /// failure, or at the end).
    pub(super) fn release_room(&mut self) {
        if let Some(r) = &mut self.room {
            r.release();
        }
    }

    /// What the outputs have to tell the user about this run (a profile written at the end
    /// instead of at its times), in the order it happened; also in `run.json`'s `warnings`.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// An XXH3 hasher fed with `bytes` (a streamed hash equals the one-shot hash of all it was fed).
fn hasher_of(bytes: &[u8]) -> Xxh3 {
    let mut h = Xxh3::new();
    h.update(bytes);
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    /// The counter as the loop `while due(t, n·e) { n += 1 }` would leave it.
    fn counted(t: f64, e: f64, mut n: u64) -> u64 {
        while due(t, n as f64 * e) {
            n += 1;
        }
        n
    }

    #[test]
    fn events_due_equals_counting_and_costs_nothing_for_tiny_periods() {
        for (t, e, n) in [
            (0.0, 0.1, 0),
            (0.0, 0.1, 1),
            (0.3, 0.1, 1),
            (0.30000000000000004, 0.1, 2),
            (0.29999999999, 0.1, 1),
            (1.0, 0.25, 3),
            (40.0, 2.0, 0),
            (1e-3, 1e-7, 5),
            (7.0, 3.0, 9),
        ] {
            assert_eq!(
                events_due(t, e, n),
                counted(t, e, n),
                "t = {t}, e = {e}, n = {n}"
            );
        }
        // 1e12 events due at once: computed, not counted.
        let t0 = Instant::now();
        let n = events_due(1.0, 1e-12, 1);
        assert!(t0.elapsed().as_secs_f64() < 0.01);
        assert!(due(1.0, (n - 1) as f64 * 1e-12) && !due(1.0, n as f64 * 1e-12));
        // Periods under `due`'s absolute floor (1e-21) at t = 0, periods of 1e-300 at any time,
        // NaN: a bounded number of steps, at least the count.
        for (t, e) in [(0.0, 1e-300), (1e-12, 1e-300), (1.0, 1e-300)] {
            let n = events_due(t, e, 1);
            assert!(
                n > 1 << 53 && due(t, (n - 1) as f64 * e),
                "t = {t}, e = {e}"
            );
        }
        assert_eq!(events_due(1.0, f64::NAN, 7), 7);
        assert_eq!(events_due(0.0, 1e-22, 0), counted(0.0, 1e-22, 0));
    }
}
