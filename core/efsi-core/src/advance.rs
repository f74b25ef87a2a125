//! Stepping to a target time: [`Simulation::advance_to`], the one place that lands a simulation
//! exactly on a time — an output time of the run loop, an FMU's communication point, the time a
//! Python caller asks for.
//!
//! **Landing.** Each step takes the Δt of [`Simulation::next_dt`] with the target as its bound,
//! which splits what remains into equal steps no larger than the stable one, and the time is
//! set exactly to the target once it is within round-off of it ([`due`], the rule every caller
//! shares). Two drivers that advance to the same targets therefore take the same steps: an FMU
//! stepped on a communication grid gives `efsi run`'s numbers with output times on that grid,
//! bit for bit.
//!
//! **Control** ([`Advance`], every part optional):
//! - a stop flag checked at every step boundary (the CLI's SIGINT / SIGTERM, a Python
//!   `KeyboardInterrupt`): the call returns [`Advanced::Stopped`] at the boundary, the state
//!   that of a complete step;
//! - a bound on the solver steps of one call: one more is [`EfsiError::StepBudget`], at a step
//!   boundary (an importer's communication step that would run for minutes);
//! - a hook after every step (outputs, progress, a checkpoint, a co-simulation output tracked
//!   at every solver step), which may end the call ([`Flow::Stop`]);
//! - a rollback: the state at the start of every step, or of the call, kept in a slot the
//!   caller owns (reused, so no allocation after the first step), and put back when a step
//!   fails, the error returned with it ([`AdvanceError::Failed`]). The start of every step is
//!   kept as a [`StepStart`]: only what a step can change — the fields the pipeline's stages
//!   write (a scene of one fluid does not change its density and viscosity), the part of each
//!   stage's carried-over data a step overwrites ([`crate::Stage::keep_into`]) — so the copy
//!   taken before every step is no larger than undoing the step needs; the start of the call
//!   is a whole [`Snapshot`].
//!
//! A target that is not a finite time at or after the current one is refused before anything
//! changes ([`AdvanceError::Refused`]).

use crate::error::EfsiError;
use crate::field::Field;
use crate::schedule::FieldId;
use crate::simulation::Simulation;
use crate::snapshot::Snapshot;
use crate::state::StateResources;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Whether time `t` has reached `event`: it is at most 1e-9 of the event's size before it (the
/// rule by which [`Simulation::advance_to`], the run loop's output times and the FMU's
/// communication points are landed on).
pub fn due(t: f64, event: f64) -> bool {
    t >= event - 1e-9 * event.abs().max(1e-12)
}

/// Which state a failed step puts back (see the module docs).
#[derive(Debug, Default)]
pub enum Rollback<'a> {
    /// None: a failed step leaves the state as the failing stage left it (no copy is kept).
    #[default]
    None,
    /// The state at the start of the failed step (the run loop's last good state), kept in the
    /// slot before every step.
    Step(&'a mut Option<StepStart>),
    /// The state at the start of the call (an FMU's communication point), kept in the slot once.
    Call(&'a mut Option<Snapshot>),
}

/// The start of a step, as far as undoing the step needs it ([`Rollback::Step`]): time, step
/// count, previous Δt and the simulation's stepping data; a copy of each field a stage of the
/// pipeline writes ([`crate::schedule::Pipeline::written`]; the others do not change in a
/// step); the stages' resources if a stage writes a field of theirs; each stage's data as the
/// step finds it ([`crate::Stage::keep_into`]) and each step check's record. Taken with
/// [`Simulation::keep_step_start`] (into the same slot step after step: no allocation after the
/// first) and put back with [`Simulation::rewind`].
#[derive(Debug, Default)]
pub struct StepStart {
    t: f64,
    step: u64,
    dt_prev: f64,
    frame_acceleration: (f64, f64),
    last_change: f64,
    velocity_scale: f64,
    fields: Vec<(FieldId, Field)>,
    resources: Option<StateResources>,
    stages: Vec<(String, Vec<f64>)>,
    checks: Vec<(&'static str, Vec<f64>)>,
}

impl StepStart {
    /// Simulated time at the start of the step.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Steps completed at the start of the step.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// The velocity the step started from, one field per component (`None` for `w` on a
    /// two-dimensional grid), if the pipeline writes every component (else it is the state's).
    fn velocity(&self) -> Option<[Option<&Field>; 3]> {
        let get = |id| self.fields.iter().find(|(f, _)| *f == id).map(|(_, f)| f);
        let (u, v, w) = (
            get(FieldId::VelocityX)?,
            get(FieldId::VelocityY)?,
            get(FieldId::VelocityZ),
        );
        Some([Some(u), Some(v), w])
    }
}

/// What the hook tells [`Simulation::advance_to`] after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Go on to the target.
    Continue,
    /// Return now with [`Advanced::Halted`] (e.g. the flow became steady).
    Stop,
}

/// What the hook sees of the step just taken (the simulation itself is passed beside it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// The step's Δt.
    pub dt: f64,
    /// The call's target time.
    pub target: f64,
    /// Steps taken in this call so far, this one included.
    pub steps: u64,
}

/// The per-step hook: called after every successful step with the simulation and the step.
pub type StepHook<'a> = dyn FnMut(&mut Simulation, &StepInfo) -> Result<Flow, EfsiError> + 'a;

/// How [`Simulation::advance_to`] is driven (the default: no stop flag, no bound, no hook, no
/// rollback).
#[derive(Default)]
pub struct Advance<'a> {
    /// Checked before every step: a non-zero value (e.g. a signal number) stops the call at that
    /// step boundary with [`Advanced::Stopped`] carrying it.
    pub stop: Option<&'a AtomicUsize>,
    /// The most solver steps this call may take; reaching the bound before the target is
    /// [`EfsiError::StepBudget`] (state of a complete step, nothing rolled back).
    pub max_steps: Option<u64>,
    /// Which state a failed step puts back.
    pub rollback: Rollback<'a>,
    /// Called after every step.
    pub on_step: Option<&'a mut StepHook<'a>>,
}

/// How a call of [`Simulation::advance_to`] ended, the target reached or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Advanced {
    /// At the target exactly.
    Reached,
    /// The stop flag held this value at a step boundary.
    Stopped {
        /// The flag's value (the CLI stores the signal number).
        signal: usize,
    },
    /// The hook returned [`Flow::Stop`].
    Halted,
}

/// Why [`Simulation::advance_to`] failed.
#[derive(Debug, thiserror::Error)]
pub enum AdvanceError {
    /// The target was refused; nothing changed.
    #[error("{0}")]
    Refused(EfsiError),
    /// A step could not be taken or failed ([`EfsiError::Stage`], [`EfsiError::Unstable`],
    /// [`EfsiError::EnergyGrowth`], [`EfsiError::StepBudget`], …).
    #[error("{error}")]
    Failed {
        /// Why.
        error: EfsiError,
        /// Whether the simulation is at a good state — the failure came before the step changed
        /// anything, or the rollback put the state back — rather than where the failing stage
        /// left it.
        good: bool,
    },
    /// The hook returned this error (after a successful step).
    #[error("{0}")]
    Hook(EfsiError),
}

impl From<AdvanceError> for EfsiError {
    fn from(e: AdvanceError) -> EfsiError {
        match e {
            AdvanceError::Refused(e) | AdvanceError::Failed { error: e, .. } => e,
            AdvanceError::Hook(e) => e,
        }
    }
}

impl Simulation {
    /// Step to time `target`, landing on it exactly, under `control` (see the module docs).
    pub fn advance_to(
        &mut self,
        target: f64,
        control: Advance<'_>,
    ) -> Result<Advanced, AdvanceError> {
        let t = self.state.t;
        if !target.is_finite() || !due(target, t) {
            return Err(AdvanceError::Refused(EfsiError::Target {
                target,
                t,
                why: if target.is_finite() {
                    "it is before the simulation's time"
                } else {
                    "it is not a finite time"
                },
            }));
        }
        let Advance {
            stop,
            max_steps,
            mut rollback,
            mut on_step,
        } = control;
        if let Rollback::Call(slot) = &mut rollback {
            self.keep(slot);
        }
        let mut steps = 0u64;
        while !due(self.state.t, target) {
            if let Some(signal) = stop.map(|s| s.load(Ordering::SeqCst))
                && signal != 0
            {
                return Ok(Advanced::Stopped { signal });
            }
            if max_steps.is_some_and(|m| steps >= m) {
                let error = EfsiError::StepBudget {
                    steps,
                    t: self.state.t,
                    target,
                };
                return Err(AdvanceError::Failed { error, good: true });
            }
            // Nothing has changed yet if Δt cannot be chosen: the state is good.
            let dt = self
                .next_dt(target)
                .map_err(|error| AdvanceError::Failed { error, good: true })?;
            if let Rollback::Step(slot) = &mut rollback {
                self.keep_step_start(slot);
            }
            // The velocity just kept is the one the step starts from.
            let start = match &rollback {
                Rollback::Step(Some(s)) => s.velocity(),
                _ => None,
            };
            if let Err(error) = self.step_from(dt, start) {
                let good = match &rollback {
                    Rollback::Step(Some(s)) => self.rewind(s).is_ok(),
                    Rollback::Call(Some(s)) => {
                        self.put_back(s);
                        true
                    }
                    _ => false,
                };
                return Err(AdvanceError::Failed { error, good });
            }
            self.snap_time(target);
            steps += 1;
            if let Some(hook) = on_step.as_deref_mut() {
                let info = StepInfo { dt, target, steps };
                if hook(self, &info).map_err(AdvanceError::Hook)? == Flow::Stop {
                    return Ok(Advanced::Halted);
                }
            }
        }
        Ok(Advanced::Reached)
    }

    /// Keep the start of the next step in `slot` ([`StepStart`]; reusing its storage once it
    /// holds one of this simulation).
    pub fn keep_step_start(&self, slot: &mut Option<StepStart>) {
        let s = slot.get_or_insert_with(StepStart::default);
        let written = || self.pipeline().written();
        if s.fields.is_empty() {
            s.fields = (written().into_iter())
                .filter_map(|id| self.state.field(id).map(|f| (id, f.clone())))
                .collect();
            s.resources = written()
                .iter()
                .any(|id| matches!(id, FieldId::Stage(_)))
                .then(|| self.state.resources.clone());
        } else {
            for (id, f) in &mut s.fields {
                if let Some(now) = self.state.field(*id) {
                    f.copy_from(now);
                }
            }
            if let Some(r) = &mut s.resources
                && !r.copy_from(&self.state.resources)
            {
                *r = self.state.resources.clone();
            }
        }
        (s.t, s.step, s.dt_prev) = (self.state.t, self.state.step, self.state.dt_prev);
        s.frame_acceleration = self.state.frame_acceleration;
        (s.last_change, s.velocity_scale) = self.stepping();
        self.pipeline().keep_stages_into(&mut s.stages);
        self.save_checks_into(&mut s.checks);
    }

    /// Put the start of a step, kept by [`keep_step_start`](Self::keep_step_start) before it,
    /// back: the simulation is then as it was before the step (after a failed step, or a step
    /// whose outputs could not be written), bit for bit — as a [`Snapshot`] taken then would
    /// have put it back. The error (a stage that refuses the data it kept, which only a bug
    /// in the stage makes happen) names the stage; the state is then not a good one.
    pub fn rewind(&mut self, s: &StepStart) -> Result<(), EfsiError> {
        for (id, f) in &s.fields {
            match self.state.field_mut(*id) {
                Some(now) if now.data().len() == f.data().len() => now.copy_from(f),
                _ => self.state.put_field(*id, f.clone()),
            }
        }
        if let Some(r) = &s.resources
            && !self.state.resources.copy_from(r)
        {
            self.state.resources = r.clone();
        }
        (self.state.t, self.state.step) = (s.t, s.step);
        self.state.dt_prev = s.dt_prev;
        self.state.frame_acceleration = s.frame_acceleration;
        self.pipeline_mut()
            .undo_stages(&s.stages)
            .map_err(EfsiError::Stage)?;
        self.stages_restored();
        self.set_stepping(s.last_change, s.velocity_scale);
        self.restore_checks(&s.checks);
        Ok(())
    }

    /// Copy the current state into `slot` (reusing its storage once it holds one).
    fn keep(&self, slot: &mut Option<Snapshot>) {
        match slot {
            Some(s) => self.snapshot_into(s),
            None => *slot = Some(self.snapshot()),
        }
    }

    /// Put `snap`, taken from this simulation, back — also when a failed stage left the state
    /// without a field it had taken out (then the state is copied whole).
    fn put_back(&mut self, snap: &Snapshot) {
        if self.restore(snap).is_err() {
            self.state = snap.state.clone();
            let _ = self.restore(snap);
        }
    }
}
