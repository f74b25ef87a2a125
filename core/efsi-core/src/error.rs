//! The error type of a run, with the process exit code each kind maps to.

use crate::scene::SceneError;
use crate::schedule::{ScheduleError, StageError};
use std::path::PathBuf;

/// Anything that stops a run.
#[derive(Debug, thiserror::Error)]
pub enum EfsiError {
    /// The scene is malformed or out of range.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene is valid on its own but cannot be run as it is (names the setting).
    #[error("{path}: {field}: {message}")]
    Config {
        /// The scene file.
        path: PathBuf,
        /// The setting to change.
        field: String,
        /// Why.
        message: String,
    },
    /// The pipeline could not be assembled.
    #[error("{0}")]
    Schedule(#[from] ScheduleError),
    /// A stage failed during the run (non-convergence, non-finite values).
    #[error("{0}")]
    Stage(#[from] StageError),
    /// The step size collapsed below `time.dt_min`.
    #[error(
        "unstable run: Δt = {dt:.3e} fell below time.dt_min = {dt_min:.3e} at t = {t:.6e} (step {step}); {cause}"
    )]
    Unstable {
        /// The step size wanted.
        dt: f64,
        /// The floor.
        dt_min: f64,
        /// Which limit set Δt, what it depends on, and what to change.
        cause: String,
        /// Time reached.
        t: f64,
        /// Step reached.
        step: u64,
    },
    /// The motion gained energy that nothing supplied: the scheme is pumping it in (the
    /// verdict of efsi-run's energy guard, a [`crate::StepCheck`]; `limit` is its
    /// `ENERGY_GUARD`).
    #[error(
        "unstable run: at t = {t:.6e} (step {step}) the kinetic + potential energy is {gain:.3e} above its start, more than {limit}× the {supplied:.3e} that the initial motion, the initial strain and gravity can have supplied (energies per radian in axisymmetric geometry): the scheme is pumping energy in — lower time.cfl or numerics.elastic.wave_courant, refine the grid, or check the solid's law (one whose stiffness turns negative, as Saint Venant–Kirchhoff's does in compression, does this)"
    )]
    EnergyGrowth {
        /// Time reached.
        t: f64,
        /// Step reached.
        step: u64,
        /// Kinetic + potential energy above its start.
        gain: f64,
        /// What can have been supplied.
        supplied: f64,
        /// The allowed multiple of `supplied`.
        limit: f64,
    },
    /// A time to advance to was refused (not finite, or before the simulation's time); nothing
    /// changed.
    #[error("cannot advance to t = {target:e}: {why} (the simulation is at t = {t:.6e})")]
    Target {
        /// The time asked for.
        target: f64,
        /// The simulation's time.
        t: f64,
        /// Why it was refused.
        why: &'static str,
    },
    /// A call of [`crate::Simulation::advance_to`] took as many solver steps as it was allowed
    /// without reaching its target.
    #[error(
        "the step budget of the call ran out: {steps} solver steps reached t = {t:.6e}, short of the target t = {target:.6e}"
    )]
    StepBudget {
        /// The steps taken (the budget).
        steps: u64,
        /// Time reached.
        t: f64,
        /// The target.
        target: f64,
    },
    /// A checkpoint cannot be read or resumed (corrupt, another format version, written for a
    /// different scene or law), or a snapshot does not fit the simulation it is restored into.
    /// `what` is the file (or `snapshot`); the message says what differs.
    #[error("{what}: {message}")]
    Checkpoint {
        /// The checkpoint file, or `snapshot` for an in-memory one.
        what: String,
        /// What is wrong or what differs.
        message: String,
    },
    /// A step failed; the state at the start of that step (the last good one) was saved.
    #[error(
        "{error}\nthe last good state (step {step}, t = {t:.6e}) was saved {}to the checkpoint {}",
        vtk.as_ref().map_or(String::new(), |v| format!("to {} and ", v.display())),
        checkpoint.display()
    )]
    Saved {
        /// What stopped the run.
        error: Box<EfsiError>,
        /// Step count of the saved state.
        step: u64,
        /// Time of the saved state.
        t: f64,
        /// The VTK file of the saved state (None when the scene writes no VTK).
        vtk: Option<PathBuf>,
        /// The checkpoint file.
        checkpoint: PathBuf,
    },
    /// An output could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl EfsiError {
    /// Process exit code: 2 for bad input (also a checkpoint that cannot be resumed), 3 for a
    /// run that failed numerically, 1 for I/O. (The CLI exits with 130 / 143 after SIGINT /
    /// SIGTERM; those are not errors.)
    pub fn exit_code(&self) -> i32 {
        match self {
            EfsiError::Scene(_) | EfsiError::Config { .. } | EfsiError::Schedule(_) => 2,
            EfsiError::Stage(_) | EfsiError::Unstable { .. } | EfsiError::EnergyGrowth { .. } => 3,
            EfsiError::Io { .. } => 1,
            EfsiError::Checkpoint { .. } | EfsiError::Target { .. } => 2,
            EfsiError::StepBudget { .. } => 3,
            EfsiError::Saved { error, .. } => error.exit_code(),
        }
    }

    /// Wrap an I/O error with its path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        EfsiError::Io {
            path: path.into(),
            source,
        }
    }
}
