//! The run loop and its outputs: `(schedule, writer)` pairs kept apart from the model
//! (STYLE.md §5). Δt is shortened to land exactly on every output time.
//!
//! A run writes into its output folder:
//! - `fields/<name>_<step>.vtr` and `fields.pvd` (VTK XML for ParaView; the collection is
//!   rewritten after each file, so it is valid at every moment of the run);
//! - `probes.csv`: header `t,<columns…>`, one row per sample;
//! - `profiles/<name>_t<time>.csv`: the coordinate along the line `s`, `x`, `y`, then the fields,
//!   at each of the profile's `at` times, or at the end if it has none; a run that ends (end
//!   time or steady state) before some of them writes the profile at its end instead and says
//!   so ([`RunOutcome::warnings`], `run.json`'s `warnings`);
//! - `run.json`: the effective scene (the file's with the overrides applied) and the
//!   overrides (`set PATH=VALUE`, `refine F`), efsi version, steps, wall time, wall time per
//!   stage, warnings;
//! - `checkpoint/latest.efsick`: the latest checkpoint ([`crate::checkpoint`]), written every
//!   [`RunOptions::checkpoint_every`] of simulated time (at the end of the first step that
//!   reaches each multiple: checkpoints never change Δt, so a run with them is bit-identical to
//!   one without), when a stop is requested ([`RunOptions::stop`], set by the CLI on SIGINT /
//!   SIGTERM) and when a step fails.
//!
//! **Nothing half-written.** Every file but `probes.csv` is written to a temporary name and
//! renamed ([`crate::output::atomic`]). `probes.csv` grows by appends — rewriting it whole for
//! every row would cost time quadratic in its length — each row one `write` of a complete
//! line; its header is written atomically, and a resumed run first truncates it to the length
//! recorded in the checkpoint, so rows are neither duplicated nor lost.
//!
//! **A failed step** (a stage error such as a NaN/Inf found after a stage, a solver that did not
//! converge, a collapsing Δt) stops the run with the error; before that the state at the start
//! of the failed step — the last good one, kept in memory every step
//! ([`RunOptions::save_last_good`]) — is written as `fields/<name>_<step>_last_good.vtr` (with a
//! `.pvd` entry at its time) and as the checkpoint ([`EfsiError::Saved`]).
//!
//! **An output that cannot be written** (a full disk, a path blocked) after a good step stops the
//! run the same way: the state at the start of that step is saved as the checkpoint, with the
//! output bookkeeping as it was before that step's outputs, so a resume writes them again. A
//! `probes.csv` append that fails part-way is cut back to the last whole row. Every failure is
//! recorded in `run.json` (`"stop": {"Failed": {"error", "exit_code"}}`). Room for that last
//! checkpoint and `run.json` is kept on disk from the start of the run (`room`:
//! `checkpoint/room`, freed before they are written), so a full disk or a file-size limit
//! (`EFBIG`; the CLI ignores SIGXFSZ so that such a write fails rather than killing it) still
//! leaves a run that can be resumed and a record of why it stopped.
//!
//! **One run per folder.** A run holds the folder's lock ([`crate::lock`]) while it writes;
//! `run.json` is written at the start (`"stop": "Running"`) with the run's identity (`run_id`),
//! which its checkpoints record too. A folder holding an earlier run's outputs is refused unless
//! [`RunOptions::overwrite`].
//!
//! **Intervals.** Output and checkpoint intervals are at least `time.dt_min` and at least
//! `time.end / 1e12` (validated; [`efsi_core::scene::TimeSpec::shortest_interval`]), and the
//! number of events due at a time is computed, not counted one period at a time.
//!
//! [`resume`] continues a run from its latest checkpoint, appending to the same outputs, after
//! checking that the checkpoint's run is the folder's (its `run.json`).

use crate::SceneOverrides;
use crate::checkpoint::{self, CheckpointFile};
use crate::lock::FolderLock;
use efsi_core::error::EfsiError;
use efsi_core::scene::Scene;
use efsi_core::schedule::StagePlugin;
use efsi_core::simulation::Simulation;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;
use std::time::Instant;

mod drive;
mod folder;
mod outputs;
mod record;
mod room;

use drive::drive;
pub use outputs::{Checkpoints, Output, Outputs, RunAt, Schedule, Writer};
use record::recorded_run_id;

/// What the progress display is told after each step.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Simulated time.
    pub t: f64,
    /// End time.
    pub end: f64,
    /// Steps done.
    pub step: u64,
    /// Last Δt.
    pub dt: f64,
    /// Wall seconds since the start.
    pub wall: f64,
}

/// Why a run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum StopReason {
    /// Reached `time.end`.
    EndTime,
    /// The flow became steady (`time.steady`).
    Steady,
    /// A stop was requested ([`RunOptions::stop`]; the CLI's SIGINT / SIGTERM): the run ended
    /// after a complete step and wrote a checkpoint to resume from.
    Interrupted {
        /// The signal number that was stored in the stop flag.
        signal: usize,
    },
}

/// How a run is driven besides its scene.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Write a checkpoint every this much simulated time (default: none; a checkpoint is still
    /// written when the run is stopped or a step fails).
    pub checkpoint_every: Option<f64>,
    /// A flag checked after every step: when it holds a non-zero value (a signal number) the run
    /// writes a checkpoint and stops with [`StopReason::Interrupted`] (default: none).
    pub stop: Option<Arc<AtomicUsize>>,
    /// Keep a copy of the state at the start of every step, to save it if the step fails
    /// (default: true; one copy of the fields per step, a small fraction of a step's work).
    pub save_last_good: bool,
    /// Replace the outputs of an earlier run in the output folder (default: false — a folder
    /// that holds a run's outputs is refused, see [`run_with`]).
    pub overwrite: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            checkpoint_every: None,
            stop: None,
            save_last_good: true,
            overwrite: false,
        }
    }
}

/// Summary of a finished run.
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// Steps taken.
    pub steps: u64,
    /// Final time.
    pub t: f64,
    /// Wall time (s).
    pub wall_seconds: f64,
    /// Why it stopped.
    pub stop: StopReason,
    /// The output folder.
    pub out_dir: PathBuf,
    /// Steps taken in this process (fewer than `steps` after a resume).
    pub steps_this_run: u64,
    /// The checkpoint this run resumed from: its step, time and the efsi version that wrote it.
    pub resumed_from: Option<(u64, f64, String)>,
    /// The latest checkpoint written, if any.
    pub checkpoint: Option<PathBuf>,
    /// What the user should know about the outputs ([`Outputs::warnings`]).
    pub warnings: Vec<String>,
}

/// Format a time for file names: shortest decimal, e.g. `0.5`, `30`, `2.8`.
pub fn time_label(t: f64) -> String {
    let s = format!("{:.6}", t);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Run `sim` to its end time (or steady state), writing outputs into `dir`, with the default
/// [`RunOptions`].
pub fn run(
    sim: &mut Simulation,
    dir: &Path,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome, EfsiError> {
    run_with(sim, dir, &RunOptions::default(), progress)
}

/// Run `sim` to its end time (or steady state, or a stop request), writing outputs into `dir`.
///
/// The folder belongs to this run while it writes there ([`crate::lock`]): another process
/// writing a run in it is refused. A folder that holds an earlier run's outputs (`run.json`,
/// `probes.csv`, `fields.pvd`, VTK files, profiles, a checkpoint) is refused too, naming them,
/// unless [`RunOptions::overwrite`], which removes them first. `run.json` is written at the
/// start (`"stop": "Running"`) with the run's identity, which its checkpoints record too.
pub fn run_with(
    sim: &mut Simulation,
    dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome, EfsiError> {
    let start = Instant::now();
    check_checkpoint_every(sim, options.checkpoint_every)?;
    let law = checkpoint::law_identity(&sim.scene, sim.options())?;
    let checkpoints = options
        .checkpoint_every
        .map(|every| Checkpoints::new(every, law.clone()));
    let mut out = Outputs::new(sim, dir, checkpoints, options.overwrite)?;
    out.write_run_json(sim, serde_json::json!("Running"), 0, None, 0.0)?;
    drive::make_room(sim, &law, &mut out)?;
    out.emit(sim, false)?;
    drive(sim, &mut out, &law, options, progress, start, None)
}

/// A checkpoint interval is bounded as an output interval is
/// ([`crate::output::spec::interval`]): at least the scene's smallest step (`time.dt_min`,
/// default 1e-12·`time.end`; below it, checkpoints could not be told apart from one step to the
/// next) and at least `time.end / 1e12`.
fn check_checkpoint_every(sim: &Simulation, every: Option<f64>) -> Result<(), EfsiError> {
    let Some(e) = every else { return Ok(()) };
    let checked = if e.is_finite() {
        crate::output::spec::interval(&sim.scene.time, e)
    } else {
        Err(format!(
            "must be a finite time, got {}",
            efsi_core::scene::num(e)
        ))
    };
    checked.map_err(|message| EfsiError::Config {
        path: PathBuf::from("--checkpoint-every"),
        field: "checkpoint_every".into(),
        message,
    })
}

/// Continue the run in `dir` from its latest checkpoint (`dir/checkpoint/latest.efsick`),
/// appending to its outputs. The scene is read again from the file the run was started with,
/// with the overrides it was started with applied again, and must be unchanged except for `time.end`, which may move past the checkpoint (to
/// continue a run), and so must the law library; otherwise the error lists what differs. `options.checkpoint_every` defaults to the interrupted run's. Returns the
/// simulation (for its timings) and the outcome.
pub fn resume(
    dir: &Path,
    plugins: &[&dyn StagePlugin],
    options: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<(Simulation, RunOutcome), EfsiError> {
    let start = Instant::now();
    let path = dir.join(checkpoint::LATEST);
    let what = path.display().to_string();
    let lock = if dir.is_dir() {
        Some(FolderLock::acquire(dir)?)
    } else {
        None
    };
    if !path.is_file() {
        return Err(EfsiError::Checkpoint {
            what,
            message: format!(
                "no checkpoint to resume from in {} (a run writes one with --checkpoint-every T, when stopped by SIGINT/SIGTERM, or when a step fails)",
                dir.display()
            ),
        });
    }
    let file = CheckpointFile::read(&path)?;
    match recorded_run_id(dir) {
        Ok(id) if id == file.outputs.run_id => {}
        recorded => {
            let folder = match recorded {
                Ok(id) => format!("this folder's run.json is of run {id}"),
                Err(why) => why,
            };
            return Err(EfsiError::Checkpoint {
                what,
                message: format!(
                    "cannot resume: the checkpoint was written by run {} and {folder}, so the \
                     outputs here are not the ones it continues (a checkpoint copied from \
                     another run's folder?); resume in the folder it was written in",
                    if file.outputs.run_id.is_empty() {
                        "(none)"
                    } else {
                        &file.outputs.run_id
                    }
                ),
            });
        }
    }
    let mut scene = Scene::load_with(&file.scene_path, &file.overrides)?;
    // The recorded scene holds the stages' options in force: compare it with this one's.
    let checked = scene.check_options(&file.scene_path, plugins)?;
    checkpoint::check_resumable(&file, &scene, &what, plugins)?;
    let law = checkpoint::law_identity(&scene, &checked)?;
    let mut sim = crate::setup::simulation_with(scene, Some(checked), &file.scene_path, plugins)?;
    let snapshot = file.record.clone().into_snapshot(sim.snapshot(), &what)?;
    sim.restore(&snapshot)?;
    let mut options = options.clone();
    options.checkpoint_every = options.checkpoint_every.or(file.outputs.checkpoint_every);
    check_checkpoint_every(&sim, options.checkpoint_every)?;
    let Some(lock) = lock else {
        return Err(EfsiError::io(dir, std::io::ErrorKind::NotFound.into()));
    };
    let checkpoints = options
        .checkpoint_every
        .map(|every| Checkpoints::new(every, law.clone()));
    let mut out = Outputs::resume(&sim, dir, &file.outputs, checkpoints, lock)?;
    let from = Some((snapshot.step(), snapshot.t(), file.efsi_version.clone()));
    out.write_run_json(
        &sim,
        serde_json::json!("Running"),
        0,
        Some(snapshot.step()),
        0.0,
    )?;
    drive::make_room(&sim, &law, &mut out)?;
    let outcome = drive(&mut sim, &mut out, &law, &options, progress, start, from)?;
    Ok((sim, outcome))
}
