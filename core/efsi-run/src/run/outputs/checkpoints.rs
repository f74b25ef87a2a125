//! The periodic checkpoint as an output: `checkpoint/latest.efsick` ([`crate::checkpoint`]),
//! written every `every` of simulated time at the end of the first step that reaches each
//! multiple ([`Schedule::Reached`]: checkpoints never change Δt, so a run with them is
//! bit-identical to one without).

use super::{RunAt, Schedule, Writer};
use crate::checkpoint::{self, Checkpoint, LawIdentity, OutputState};
use efsi_core::error::EfsiError;
use efsi_core::simulation::Simulation;
use std::path::{Path, PathBuf};

/// The writer of a run's periodic checkpoints.
pub struct Checkpoints {
    every: f64,
    law: Option<LawIdentity>,
}

impl Checkpoints {
    /// Checkpoints every `every` of simulated time, recording the law library `law`.
    pub fn new(every: f64, law: Option<LawIdentity>) -> Checkpoints {
        Checkpoints { every, law }
    }

    /// Their schedule, `count` checkpoints due so far.
    pub(super) fn schedule(&self, count: u64) -> Schedule {
        Schedule::Reached {
            every: self.every,
            count,
        }
    }
}

impl Writer for Checkpoints {
    fn label(&self) -> String {
        checkpoint::LATEST.to_string()
    }

    fn write(&mut self, run: &mut RunAt<'_>) -> Result<PathBuf, EfsiError> {
        let bookkeeping = run.bookkeeping.take().unwrap_or_default();
        save_checkpoint(run.sim, &self.law, bookkeeping, run.sim.snapshot(), run.dir)
    }

    fn save(&self, schedule: &Schedule, into: &mut OutputState) {
        into.checkpoint_every = Some(self.every);
        into.checkpoint_count = schedule.count();
    }

    fn is_checkpoint(&self) -> bool {
        true
    }
}

/// The checkpoint of `snapshot` with the output bookkeeping `outputs`.
pub(in crate::run) fn checkpoint_of(
    sim: &Simulation,
    law: &Option<LawIdentity>,
    outputs: OutputState,
    snapshot: efsi_core::Snapshot,
) -> Checkpoint {
    Checkpoint {
        efsi_version: env!("CARGO_PKG_VERSION").to_string(),
        scene_path: std::path::absolute(&sim.scene_path).unwrap_or(sim.scene_path.clone()),
        scene_ron: sim.scene.to_ron(),
        overrides: sim.scene.overrides.clone(),
        law: law.clone(),
        outputs,
        snapshot,
    }
}

/// Write the checkpoint of `snapshot` with the output bookkeeping `outputs` into the run's
/// folder `dir`; returns its path.
pub(in crate::run) fn save_checkpoint(
    sim: &Simulation,
    law: &Option<LawIdentity>,
    outputs: OutputState,
    snapshot: efsi_core::Snapshot,
    dir: &Path,
) -> Result<PathBuf, EfsiError> {
    let path = dir.join(checkpoint::LATEST);
    checkpoint_of(sim, law, outputs, snapshot).write(&path)?;
    Ok(path)
}
