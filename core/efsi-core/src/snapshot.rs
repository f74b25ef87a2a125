//! In-memory snapshots of a simulation: everything that determines the steps after a given one.
//!
//! [`Snapshot`] is the copy of a [`Simulation`]'s evolving data taken with
//! [`Simulation::snapshot`] (or [`Simulation::snapshot_into`], allocation-free) and put back with
//! [`Simulation::restore`]. It is what an FMU's get/set FMU state needs, what a failed run saves as
//! its last good state (the run loop keeps less of the start of every step, only what the step
//! can change: [`crate::StepStart`]) and what a checkpoint file stores (crate `efsi-run`). It holds: every [`State`] array with its ghosts
//! (velocity, pressure — the projection's warm start —, density, viscosity, the solid fraction and
//! the deformation tensors), time, step count and previous Δt; the simulation's private
//! stepping data (the last rate of change, which decides steadiness, and the velocity scale of
//! the first step); and each stage's carried-over data ([`crate::schedule::Stage::save`], e.g.
//! the viscous stage's last increments; the VOF stage's previous velocity is the state's own
//! between steps, taken back from it, [`crate::schedule::Stage::restored`]); each step check's record ([`crate::simulation::StepCheck`],
//! e.g. efsi-run's energy guard's baseline). The simulation's `previous` velocity is not in it: every
//! step overwrites it before reading it. Restoring a snapshot into a simulation built from the
//! same scene continues the run **bit for bit** as if it had never stopped.

use crate::error::EfsiError;
use crate::simulation::Simulation;
use crate::state::State;

/// The evolving data of a [`Simulation`], in memory (see the module docs for what it holds).
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Time, step count, Δt of the previous step and every field, ghosts included.
    pub state: State,
    /// `max |uⁿ⁺¹ − uⁿ|/Δt` of the last step (decides steadiness).
    pub last_change: f64,
    /// The velocity scale that bounds a step when nothing else does.
    pub velocity_scale: f64,
    /// Each stage's carried-over data, by stage name, in pipeline order.
    pub stages: Vec<(String, Vec<f64>)>,
    /// Each step check's record ([`crate::simulation::StepCheck::save_into`]), by check name,
    /// in the order the checks were added: a restored run is judged by them as the run it
    /// continues (e.g. energy growth against the same start).
    pub checks: Vec<(&'static str, Vec<f64>)>,
}

impl Snapshot {
    /// Simulated time of the snapshot.
    pub fn t(&self) -> f64 {
        self.state.t
    }

    /// Steps completed at the snapshot.
    pub fn step(&self) -> u64 {
        self.state.step
    }

    /// The data a stage saved ([`crate::schedule::Stage::save`]), by stage name (None for a
    /// stage not in the pipeline; empty for a stage that keeps nothing between steps).
    pub fn stage_data(&self, stage: &str) -> Option<&[f64]> {
        self.stages
            .iter()
            .find(|(n, _)| n == stage)
            .map(|(_, d)| d.as_slice())
    }

    /// Bytes the snapshot occupies in a checkpoint file (its arrays and stage data).
    pub fn size_bytes(&self) -> usize {
        let arrays: usize = self
            .state
            .arrays()
            .iter()
            .map(|(_, f)| 8 * f.data().len())
            .sum();
        arrays + self.stages.iter().map(|(_, d)| 8 * d.len()).sum::<usize>()
    }
}

impl Simulation {
    /// A copy of everything that determines the steps after this one (see [`Snapshot`]).
    pub fn snapshot(&self) -> Snapshot {
        let (last_change, velocity_scale) = self.stepping();
        let mut checks = Vec::new();
        self.save_checks_into(&mut checks);
        Snapshot {
            state: self.state.clone(),
            last_change,
            velocity_scale,
            stages: self.pipeline().save_stages(),
            checks,
        }
    }

    /// [`snapshot`](Self::snapshot) into an existing snapshot of this simulation, reusing its
    /// storage (what the run loop does before every step).
    pub fn snapshot_into(&self, snap: &mut Snapshot) {
        if !snap.state.copy_from(&self.state) {
            snap.state = self.state.clone();
        }
        (snap.last_change, snap.velocity_scale) = self.stepping();
        self.pipeline().save_stages_into(&mut snap.stages);
        self.save_checks_into(&mut snap.checks);
    }

    /// Each step check's record into `out`, reusing its storage when it holds the same checks.
    pub(crate) fn save_checks_into(&self, out: &mut Vec<(&'static str, Vec<f64>)>) {
        let names = self.checks().iter().map(|c| c.name());
        if !out.iter().map(|(n, _)| *n).eq(names) {
            *out = self
                .checks()
                .iter()
                .map(|c| (c.name(), Vec::new()))
                .collect();
        }
        for (c, (_, record)) in self.checks().iter().zip(out) {
            c.save_into(record);
        }
    }

    /// Put a snapshot back: the simulation continues exactly as the one it was taken from
    /// would have. The snapshot must come from a simulation of the same scene (same fields,
    /// grid and stages); otherwise nothing changes and the error says what does not fit.
    pub fn restore(&mut self, snap: &Snapshot) -> Result<(), EfsiError> {
        let fail = |message: String| EfsiError::Checkpoint {
            what: "snapshot".into(),
            message,
        };
        let names: Vec<String> = self.state.arrays().into_iter().map(|(n, _)| n).collect();
        let theirs: Vec<String> = snap.state.arrays().into_iter().map(|(n, _)| n).collect();
        if names != theirs {
            return Err(fail(format!(
                "it holds the fields [{}], this simulation [{}]",
                theirs.join(", "),
                names.join(", ")
            )));
        }
        // The resources' arrays may change shape during a run (a body's window): they take
        // the snapshot's with their values.
        let same_shape = self
            .state
            .field_arrays()
            .iter()
            .zip(snap.state.field_arrays())
            .all(|((_, f), (_, g))| f.data().len() == g.data().len());
        if !same_shape {
            return Err(fail(
                "its fields are shaped for another grid than this simulation's".into(),
            ));
        }
        // A stage that refuses its data leaves the others as they were.
        let before = self.pipeline().save_stages();
        if let Err(e) = self.pipeline_mut().restore_stages(&snap.stages) {
            let _ = self.pipeline_mut().restore_stages(&before);
            return Err(fail(e.to_string()));
        }
        self.state.copy_from(&snap.state);
        self.stages_restored();
        self.set_stepping(snap.last_change, snap.velocity_scale);
        self.restore_checks(&snap.checks);
        Ok(())
    }

    /// Give each step check its record in `checks` (by name; none: an empty one).
    pub(crate) fn restore_checks(&mut self, checks: &[(&'static str, Vec<f64>)]) {
        for c in self.checks_mut() {
            let record = checks.iter().find(|(n, _)| *n == c.name());
            c.restore(record.map_or(&[], |(_, r)| r.as_slice()));
        }
    }
}
