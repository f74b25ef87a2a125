//! The outputs of one run ([`Outputs`]): `(schedule, writer)` pairs. A [`Schedule`] says when
//! (and which times Δt lands on), a [`Writer`] what is written; the VTK series
//! ([`vtk::VtkSeries`]), `probes.csv` ([`probes::ProbesCsv`]), each plane slice
//! ([`slices::SliceSeries`]), each line profile ([`profiles::Profile`]) and the periodic checkpoint ([`checkpoints::Checkpoints`]) are the
//! writers a run has. A new kind of output is one file: a [`Writer`], and its pair in
//! [`Outputs::new`] / [`Outputs::resume`]. Each writer records in a checkpoint's
//! [`OutputState`] what a resumed run needs to continue its files, so that a resumed run
//! neither repeats nor loses any.

pub mod checkpoints;
pub mod probes;
pub mod profiles;
pub mod slices;
pub mod vtk;

pub use crate::output::schedule::{Due, Schedule};

use super::folder::{earlier_outputs, make_dirs, replace_earlier_run};
use super::record::new_run_id;
use super::time_label;
use crate::checkpoint::OutputState;
use crate::lock::FolderLock;
use crate::output::spec::{OutputSpec, SliceSpec, VtkOptions};
use efsi_core::error::EfsiError;
use efsi_core::simulation::Simulation;
use efsi_core::state::State;
use std::path::{Path, PathBuf};

pub use checkpoints::Checkpoints;

/// What a writer writes for: the simulation at the time its schedule is due, in the run's
/// output folder.
pub struct RunAt<'a> {
    /// The simulation.
    pub sim: &'a Simulation,
    /// The output folder.
    pub dir: &'a Path,
    /// The bookkeeping of every output of the run after the writers before this one wrote
    /// (what a checkpoint records), given to a writer that [`Writer::is_checkpoint`].
    pub bookkeeping: Option<OutputState>,
}

/// What an output writes, and what it keeps to continue after a resume.
pub trait Writer: Send {
    /// What it writes, in messages (`probes.csv`, ``profile `centre` ``).
    fn label(&self) -> String;
    /// Write the simulation's current state; returns the file written.
    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError>;
    /// Record in `into` what a resumed run needs to continue this output, with its
    /// `schedule`'s progress.
    fn save(&self, _schedule: &Schedule, _into: &mut OutputState) {}
    /// Write `state`, the last good state of a run whose step failed, if this writer keeps
    /// such states (the VTK series); returns the file.
    fn write_last_good(
        &mut self,
        _run: &mut RunAt<'_>,
        _state: &State,
    ) -> Result<Option<PathBuf>, EfsiError> {
        Ok(None)
    }
    /// Whether it writes the run's checkpoint: it is given the run's bookkeeping
    /// ([`RunAt::bookkeeping`]), and the room the run keeps on disk grows to its file.
    fn is_checkpoint(&self) -> bool {
        false
    }
}

/// An output: a schedule and a writer.
pub struct Output {
    /// When it is written.
    pub schedule: Schedule,
    /// What is written.
    pub writer: Box<dyn Writer>,
}

impl Output {
    /// The pair of `schedule` and `writer`.
    pub fn new(schedule: Schedule, writer: impl Writer + 'static) -> Output {
        Output {
            schedule,
            writer: Box::new(writer),
        }
    }
}

/// The plane slices of `o`, each one's interval resolved ([`SliceSpec::interval`]).
fn resolved_slices(o: &OutputSpec) -> Vec<SliceSpec> {
    o.slices
        .iter()
        .map(|s| SliceSpec {
            every: s.interval(o.vtk_every),
            ..s.clone()
        })
        .collect()
}

/// The outputs of one run, in the order they are written after a step, in its folder.
pub struct Outputs {
    pub(super) dir: PathBuf,
    /// The `output.vtk` settings (what `run.json` describes of the VTK arrays).
    pub(super) vtk: VtkOptions,
    /// The plane slices, their intervals resolved (what `run.json` describes of them).
    pub(super) slices: Vec<SliceSpec>,
    list: Vec<Output>,
    end: f64,
    /// The checkpoint count a run without periodic checkpoints records (the one it was
    /// resumed with).
    checkpoint_idle: u64,
    /// The latest periodic checkpoint written.
    latest: Option<PathBuf>,
    pub(super) warnings: Vec<String>,
    pub(super) run_id: String,
    /// The bookkeeping at the start of the latest [`Outputs::emit`] (see
    /// [`Outputs::state_before_emit`]).
    mark: OutputState,
    /// The room kept for the last checkpoint and `run.json` ([`super::room`]), once made.
    pub(super) room: Option<super::room::Room>,
    _lock: FolderLock,
}

impl Outputs {
    /// Create the output folder and open the writers (fails before any step if it cannot).
    /// Checkpoints are written as `checkpoints` says, if given.
    pub fn new(
        sim: &Simulation,
        dir: &Path,
        checkpoints: Option<Checkpoints>,
        overwrite: bool,
    ) -> Result<Outputs, EfsiError> {
        let o = &crate::output::spec::check(&sim.scene, &sim.scene_path, sim.pipeline())?;
        make_dirs(dir)?;
        let lock = FolderLock::acquire(dir)?;
        replace_earlier_run(dir, &earlier_outputs(dir)?, overwrite)?;
        let mut list = vec![Output::new(
            Schedule::every(o.probe_every),
            probes::ProbesCsv::create(
                dir,
                &o.probes,
                sim.grid.geometry,
                &crate::probes::body_names(&sim.scene),
            )?,
        )];
        if let Some(every) = o.vtk_every {
            let writer = vtk::VtkSeries::create(dir, &o.vtk, Vec::new())?;
            list.push(Output::new(Schedule::every(Some(every)), writer));
        }
        let slices = resolved_slices(o);
        for s in &slices {
            let writer = slices::SliceSeries::create(dir, s, &o.vtk, &[])?;
            list.push(Output::new(writer.schedule(), writer));
        }
        for p in &o.profiles {
            list.push(Output::new(
                Schedule::times(p.times()),
                profiles::Profile::new(dir, p),
            ));
        }
        if let Some(c) = checkpoints {
            list.push(Output::new(c.schedule(1), c));
        }
        let mut outputs = Outputs {
            dir: dir.to_path_buf(),
            vtk: o.vtk.clone(),
            slices,
            list,
            end: sim.scene.time.end,
            checkpoint_idle: 1,
            latest: None,
            warnings: Vec::new(),
            run_id: new_run_id(dir),
            mark: OutputState::default(),
            room: None,
            _lock: lock,
        };
        outputs.mark = outputs.state();
        Ok(outputs)
    }

    /// Reopen the writers of a run that stopped at a checkpoint with bookkeeping `state`:
    /// `probes.csv` is truncated to its length at the checkpoint (its header must match the
    /// scene's probes) and `fields.pvd` rewritten with the checkpoint's entries, so what the
    /// resumed run writes neither duplicates nor loses rows.
    pub fn resume(
        sim: &Simulation,
        dir: &Path,
        state: &OutputState,
        checkpoints: Option<Checkpoints>,
        lock: FolderLock,
    ) -> Result<Outputs, EfsiError> {
        let o = &crate::output::spec::check(&sim.scene, &sim.scene_path, sim.pipeline())?;
        make_dirs(dir)?;
        let mut probe_schedule = Schedule::every(o.probe_every);
        if let Schedule::Every { count, .. } = &mut probe_schedule {
            *count = state.probe_count;
        }
        let mut list = vec![Output::new(
            probe_schedule,
            probes::ProbesCsv::reopen(
                dir,
                &o.probes,
                (sim.grid.geometry, &crate::probes::body_names(&sim.scene)),
                state,
            )?,
        )];
        if state.profile_times.len() != o.profiles.len() {
            return Err(EfsiError::Checkpoint {
                what: dir.join("probes.csv").display().to_string(),
                message: format!(
                    "the checkpoint records {} profiles, the scene has {}",
                    state.profile_times.len(),
                    o.profiles.len()
                ),
            });
        }
        if let Some(every) = o.vtk_every {
            let fields = state.pvd.iter().filter(|e| !e.1.starts_with("slices/"));
            let writer = vtk::VtkSeries::create(dir, &o.vtk, fields.cloned().collect())?;
            let schedule = Schedule::Every {
                every,
                count: state.vtk_count,
            };
            list.push(Output::new(schedule, writer));
        }
        let slices = resolved_slices(o);
        for s in &slices {
            let writer = slices::SliceSeries::create(dir, s, &o.vtk, &state.pvd)?;
            list.push(Output::new(writer.schedule(), writer));
        }
        for (p, times) in o.profiles.iter().zip(&state.profile_times) {
            let schedule = Schedule::Times(times.clone());
            list.push(Output::new(schedule, profiles::Profile::new(dir, p)));
        }
        if let Some(c) = checkpoints {
            list.push(Output::new(c.schedule(state.checkpoint_count), c));
        }
        let mut outputs = Outputs {
            dir: dir.to_path_buf(),
            vtk: o.vtk.clone(),
            slices,
            list,
            end: sim.scene.time.end,
            checkpoint_idle: state.checkpoint_count,
            latest: None,
            warnings: Vec::new(),
            run_id: state.run_id.clone(),
            mark: OutputState::default(),
            room: None,
            _lock: lock,
        };
        outputs.mark = outputs.state();
        Ok(outputs)
    }

    /// The bookkeeping a checkpoint records (see [`Outputs::resume`]): each writer's, with
    /// its schedule's progress.
    pub fn state(&self) -> OutputState {
        let mut s = OutputState {
            checkpoint_count: self.checkpoint_idle,
            run_id: self.run_id.clone(),
            ..OutputState::default()
        };
        for o in &self.list {
            o.writer.save(&o.schedule, &mut s);
        }
        s
    }

    /// The bookkeeping as it was before the latest [`Outputs::emit`]: what a checkpoint of the
    /// state at the start of the latest step records (its outputs are written again on resume).
    pub fn state_before_emit(&self) -> OutputState {
        self.mark.clone()
    }

    /// The next time an output is due after `t` (or the end): the time Δt lands on.
    pub fn next_event(&self, t: f64) -> f64 {
        self.list
            .iter()
            .filter_map(|o| o.schedule.next())
            .fold(self.end, f64::min)
            .max(t)
    }

    /// Write whatever is due at the simulation's current time (everything, if `last`), in
    /// order.
    pub fn emit(&mut self, sim: &Simulation, last: bool) -> Result<(), EfsiError> {
        let t = sim.state.t;
        self.mark = self.state();
        for k in 0..self.list.len() {
            let Due { write, missed } = self.list[k].schedule.take(t, last);
            if !write {
                continue;
            }
            let checkpoint = self.list[k].writer.is_checkpoint();
            let mut run = RunAt {
                sim,
                dir: &self.dir,
                bookkeeping: checkpoint.then(|| self.state()),
            };
            let file = self.list[k].writer.write(&mut run)?;
            // The run ends (at its end time or a steady state) before some of the output's
            // times: it is written now instead, and the run says so.
            if !missed.is_empty() {
                let times: Vec<String> = missed.iter().map(|&x| time_label(x)).collect();
                self.warnings.push(format!(
                    "{}: the run ended at t = {} before its time(s) {}; written at the end instead: {}",
                    self.list[k].writer.label(),
                    time_label(t),
                    times.join(", "),
                    file.display()
                ));
            }
            if checkpoint {
                self.grow_room(&file)?;
                self.latest = Some(file);
            }
        }
        Ok(())
    }

    /// The latest periodic checkpoint written, if any.
    pub fn latest_checkpoint(&self) -> Option<&PathBuf> {
        self.latest.as_ref()
    }

    /// Write `state`, the last good state of a run whose step failed, with the writers that
    /// keep such states (the VTK series, if the scene writes VTK); returns the file.
    pub(super) fn write_last_good(
        &mut self,
        sim: &Simulation,
        state: &State,
    ) -> Result<Option<PathBuf>, EfsiError> {
        let mut file = None;
        for o in &mut self.list {
            let mut run = RunAt {
                sim,
                dir: &self.dir,
                bookkeeping: None,
            };
            if let Some(f) = o.writer.write_last_good(&mut run, state)? {
                file.get_or_insert(f);
            }
        }
        Ok(file)
    }

    /// Grow the room after a checkpoint of `path` was written, if the checkpoint outgrew it.
    fn grow_room(&mut self, path: &Path) -> Result<(), EfsiError> {
        let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
        let record = std::fs::metadata(self.dir.join("run.json")).map_or(0, |m| m.len());
        if let Some(room) = &mut self.room {
            room.grow(super::room::Room::needed(bytes, record))
                .map_err(|e| EfsiError::io(self.dir.join("checkpoint").join("room"), e))?;
        }
        Ok(())
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
