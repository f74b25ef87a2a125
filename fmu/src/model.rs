//! The model both FMI interfaces drive: a scene FMU's life cycle, parameters and inputs,
//! outputs, communication steps and FMU states.
//!
//! **No second implementation of physics.** The packaged scene, with the parameters' values
//! applied as overrides ([`crate::spec`]), is parsed and validated by efsi's scene loader and
//! run by the same [`efsi_core::Simulation`] and stage plugins as `efsi run`
//! ([`crate::stepping`]); the outputs are its probes. `efsi run` of the same scene, with its
//! probes at the communication points, gives the FMU's outputs bit for bit.
//!
//! **Refusals.** A call that cannot be carried out returns a [`Fault`]: `Discard` when nothing
//! changed and the importer may go on (a value outside its declared range; a communication
//! step refused or failed with the state of its start put back), `Error` otherwise (an
//! illegal argument — a NaN or negative step, a communication point that is not the model's
//! time, a step past the stop time — or a state that could not be put back), after which the
//! instance is in the `Error` mode ([`crate::machine`]).

use crate::log::Status;
use crate::machine::Mode;
use crate::spec::{Causality, Kind, Spec, VR_MAX_STEPS, VR_STEPS, VR_TIME, Variable};
use crate::state::{FmuState, Simulated, restore_into};
use crate::stepping::{Run, StepFailure};
use efsi_core::due;
use efsi_core::overrides::OverrideValue;
use std::sync::Arc;

/// A number in a message or a log line: compact ([`efsi_core::scene::num`]: `5e-324`, never
/// 324 digits).
pub(crate) struct Num(pub(crate) f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&efsi_core::scene::num(self.0))
    }
}

/// A refused call: its status (`Discard` or `Error`) and what to tell the importer.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    /// `Discard` (nothing changed, the importer may go on) or `Error`.
    pub status: Status,
    /// The message.
    pub message: String,
}

impl Fault {
    /// An `Error`.
    pub fn error(message: impl Into<String>) -> Self {
        Fault {
            status: Status::Error,
            message: message.into(),
        }
    }

    /// A `Discard`: the call changed nothing.
    pub fn discard(message: impl Into<String>) -> Self {
        Fault {
            status: Status::Discard,
            message: message.into(),
        }
    }
}

impl From<String> for Fault {
    fn from(message: String) -> Self {
        Fault::error(message)
    }
}

impl From<&str> for Fault {
    fn from(message: &str) -> Self {
        Fault::error(message)
    }
}

/// The values an importer sets: the parameters (in the spec's order), the step bound and the
/// inputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Values {
    /// The parameters' values.
    pub params: Vec<OverrideValue>,
    /// `max_solver_steps_per_step`.
    pub max_steps: i64,
    /// The inputs' values.
    pub inputs: Vec<f64>,
}

/// The model behind one FMU instance.
pub struct Model {
    spec: Arc<Spec>,
    vars: Arc<Vec<Variable>>,
    start_values: Values,
    values: Values,
    mode: Mode,
    start_time: f64,
    stop_time: Option<f64>,
    run: Option<Run>,
    /// Informational messages for the importer's log (drained by the FMI layer).
    pub notes: Vec<String>,
}

/// Where a value reference points.
enum Slot {
    Time,
    MaxSteps,
    Parameter(usize),
    Input(usize),
    Output(usize),
    Steps,
}

impl Model {
    /// A model of `spec` with its start values, not yet initialised.
    pub fn new(spec: Arc<Spec>) -> Result<Self, String> {
        let vars = Arc::new(spec.variables()?);
        let start = |v: &Variable| -> OverrideValue {
            let s = v.start.clone().unwrap_or_default();
            match v.kind {
                Kind::Real => OverrideValue::Float(s.parse().unwrap_or(f64::NAN)),
                Kind::Int32 | Kind::Int64 => OverrideValue::Int(s.parse().unwrap_or(0)),
                Kind::String => OverrideValue::Str(s),
            }
        };
        let params = vars
            .iter()
            .filter(|v| v.causality == Causality::Parameter && v.vr != VR_MAX_STEPS)
            .map(start)
            .collect();
        let inputs = vars
            .iter()
            .filter(|v| v.causality == Causality::Input)
            .map(|v| {
                v.start
                    .as_deref()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(0.0)
            })
            .collect();
        let start_values = Values {
            params,
            max_steps: crate::spec::DEFAULT_MAX_SOLVER_STEPS as i64,
            inputs,
        };
        Ok(Model {
            spec,
            vars,
            values: start_values.clone(),
            start_values,
            mode: Mode::Instantiated,
            start_time: 0.0,
            stop_time: None,
            run: None,
            notes: Vec::new(),
        })
    }

    /// The spec.
    pub fn spec(&self) -> &Spec {
        &self.spec
    }

    /// The variable with value reference `vr`.
    pub fn variable(&self, vr: u32) -> Option<&Variable> {
        self.vars.iter().find(|v| v.vr == vr)
    }

    fn slot(&self, vr: u32) -> Option<Slot> {
        let v = self.variable(vr)?;
        let k = |c: Causality| {
            self.vars
                .iter()
                .filter(|w| w.causality == c && w.vr != VR_MAX_STEPS && w.vr != VR_STEPS)
                .position(|w| w.vr == vr)
        };
        Some(match (vr, v.causality) {
            (VR_TIME, _) => Slot::Time,
            (VR_MAX_STEPS, _) => Slot::MaxSteps,
            (VR_STEPS, _) => Slot::Steps,
            (_, Causality::Parameter) => Slot::Parameter(k(Causality::Parameter)?),
            (_, Causality::Input) => Slot::Input(k(Causality::Input)?),
            (_, Causality::Output) => Slot::Output(k(Causality::Output)?),
            _ => return None,
        })
    }

    /// The life-cycle mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Enter the `Error` mode (after a call returned `Error`).
    pub fn enter_error(&mut self) {
        self.mode = Mode::Error;
    }

    /// FMI 2.0: a discarded `fmi2DoStep` leaves the instance in *stepFailed*.
    pub fn enter_step_discarded(&mut self) {
        self.mode = Mode::StepDiscarded;
    }

    /// Back to the state after instantiation (start values, no simulation).
    pub fn reset(&mut self) {
        self.values = self.start_values.clone();
        self.mode = Mode::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.run = None;
    }

    /// Record the experiment's start and optional stop time.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), Fault> {
        if !start.is_finite() {
            return Err(Fault::error(format!(
                "the start time {start} is not finite"
            )));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s > start)
        {
            return Err(Fault::error(format!(
                "the stop time {s} is not after the start time {start}"
            )));
        }
        self.start_time = start;
        self.stop_time = stop;
        Ok(())
    }

    /// Enter initialisation mode.
    pub fn enter_initialization(&mut self) {
        self.mode = Mode::Initialization;
    }

    /// The simulation of the current parameters, built if there is none for them (before
    /// initialisation ends, to compute outputs on request, and when it ends).
    fn ensure_run(&mut self) -> Result<&mut Run, Fault> {
        if !self
            .run
            .as_ref()
            .is_some_and(|r| r.params == self.values.params)
        {
            let run = Run::build(
                &self.spec,
                &self.values.params,
                self.start_time,
                &self.values.inputs,
            )?;
            self.notes.push(format!(
                "{}: grid {} x {}, stages {}",
                self.spec.name,
                run.sim.grid.nx,
                run.sim.grid.ny,
                run.sim.pipeline().stage_names().join(", ")
            ));
            self.run = Some(run);
        }
        self.run
            .as_mut()
            .ok_or_else(|| Fault::error("no simulation"))
    }

    /// Leave initialisation mode: apply the parameters to the scene and build the simulation.
    /// A refused parameter is named in the error.
    pub fn exit_initialization(&mut self) -> Result<(), Fault> {
        self.ensure_run()?;
        self.mode = Mode::Step;
        Ok(())
    }

    /// Advance from `t` (the importer's current communication point, which must be this
    /// model's time) by `h > 0`, landing exactly on `t + h` (see [`crate::stepping`]).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), Fault> {
        let stop = self.stop_time;
        let max_steps = self.values.max_steps.max(1) as u64;
        let run = self
            .run
            .as_mut()
            .ok_or_else(|| Fault::error("no simulation: initialise the instance first"))?;
        let now = run.sim.state.t;
        // Numbers in messages and logs: compact (`5e-324`, never 324 digits).
        let (t_, h_, now_) = (Num(t), Num(h), Num(now));
        if !t.is_finite() {
            return Err(Fault::error(format!(
                "the communication point {t_} is not a finite number (the model's time is {now_})"
            )));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(Fault::error(format!(
                "the communication step size {h_} must be a finite number > 0"
            )));
        }
        if (t - now).abs() > 1e-9 * t.abs().max(h) {
            return Err(Fault::error(format!(
                "the communication point {t_} is not the model's time {now_}"
            )));
        }
        let target = t + h;
        let target_ = Num(target);
        if let Some(stop) = stop
            && target - stop > 1e-9 * stop.abs().max(h)
        {
            let stop_ = Num(stop);
            return Err(Fault::error(format!(
                "a step from t = {t_} by {h_} ends at {target_}, past the stop time {stop_} given at initialisation"
            )));
        }
        let smallest = run.smallest_step();
        if due(t, target) || h < smallest {
            return Err(Fault::discard(format!(
                "the communication step size {h_} s is too small to resolve at t = {t_} s (the smallest is {:e} s: the solver's smallest step, and 1e-9 of the time); the instance stays at t = {t_}",
                smallest.max(1e-9 * t.abs())
            )));
        }
        let result = run.advance(t, h, max_steps);
        if let Some(why) = run.rebuilt.take() {
            self.notes.push(format!(
                "the simulation did not take back the state of t = {t_} ({why}): it was rebuilt from its scene and given that state"
            ));
            // A rebuilt simulation has the scene's wall speeds: give it the inputs again.
            run.apply_inputs(&self.spec, &self.values.inputs)?;
        }
        match result {
            Ok(n) => {
                self.notes
                    .push(format!("doStep t = {t_} h = {h_}: {n} solver steps"));
                Ok(())
            }
            Err(StepFailure::Discarded(m)) => Err(Fault::discard(m)),
            Err(StepFailure::Broken(m)) => {
                self.run = None;
                Err(Fault::error(format!(
                    "{m}; the instance is in the Error state: set an FMU state or reset it"
                )))
            }
        }
    }

    /// Terminate.
    pub fn terminate(&mut self) {
        self.mode = Mode::Terminated;
    }

    /// The current time.
    pub fn time(&self) -> f64 {
        match (&self.run, self.mode) {
            (Some(r), Mode::Step | Mode::StepDiscarded | Mode::Terminated | Mode::Error) => {
                r.sim.state.t
            }
            _ => self.start_time,
        }
    }

    /// The run whose outputs are read: built from the parameters before initialisation ends.
    fn outputs_run(&mut self) -> Result<&mut Run, Fault> {
        match self.mode {
            Mode::Instantiated | Mode::Initialization => self.ensure_run(),
            _ => self.run.as_mut().ok_or_else(|| {
                Fault::error("no outputs: the simulation failed and could not be put back")
            }),
        }
    }

    fn unknown(&self, vr: u32, kind: &str) -> Fault {
        Fault::error(match self.variable(vr) {
            Some(v) => format!(
                "`{}` (value reference {vr}) is not a {kind} variable",
                v.name
            ),
            None => format!("no {kind} variable has the value reference {vr}"),
        })
    }

    /// A real variable's value.
    pub fn get_real(&mut self, vr: u32) -> Result<f64, Fault> {
        match self.slot(vr) {
            Some(Slot::Time) => Ok(self.time()),
            Some(Slot::Parameter(k)) => match &self.values.params[k] {
                OverrideValue::Float(x) => Ok(*x),
                _ => Err(self.unknown(vr, "real")),
            },
            Some(Slot::Input(k)) => Ok(self.values.inputs[k]),
            Some(Slot::Output(k)) => Ok(self.outputs_run()?.outputs[k]),
            _ => Err(self.unknown(vr, "real")),
        }
    }

    /// A parameter may be set only before initialisation ends.
    fn configurable(&self, name: &str) -> Result<(), Fault> {
        match self.mode {
            Mode::Instantiated | Mode::Initialization => Ok(()),
            _ => Err(Fault::error(format!(
                "`{name}` is a fixed parameter: it can be set only before initialisation ends"
            ))),
        }
    }

    /// Set a real parameter (before initialisation ends) or an input (any time). A value
    /// outside the variable's range is refused (`Discard`: nothing changes).
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<(), Fault> {
        let v = self
            .variable(vr)
            .filter(|v| v.kind == Kind::Real)
            .cloned()
            .ok_or_else(|| self.unknown(vr, "real"))?;
        match self.slot(vr) {
            Some(Slot::Input(k)) => {
                v.check_range(value).map_err(Fault::discard)?;
                if let Some(run) = &mut self.run {
                    run.apply_input(&v.name, value)?;
                }
                self.values.inputs[k] = value;
                Ok(())
            }
            Some(Slot::Parameter(k)) => {
                self.configurable(&v.name)?;
                v.check_range(value).map_err(Fault::discard)?;
                self.values.params[k] = OverrideValue::Float(value);
                Ok(())
            }
            _ => Err(Fault::error(format!(
                "`{}` is {}: it cannot be set",
                v.name,
                if v.causality == Causality::Output {
                    "an output"
                } else {
                    "the independent variable"
                }
            ))),
        }
    }

    /// An integer variable's value.
    pub fn get_integer(&mut self, vr: u32) -> Result<i64, Fault> {
        match self.slot(vr) {
            Some(Slot::Steps) => Ok(self.outputs_run()?.sim.state.step as i64),
            Some(Slot::MaxSteps) => Ok(self.values.max_steps),
            Some(Slot::Parameter(k)) => match &self.values.params[k] {
                OverrideValue::Int(i) => Ok(*i),
                _ => Err(self.unknown(vr, "integer")),
            },
            _ => Err(self.unknown(vr, "integer")),
        }
    }

    /// Set an integer parameter (before initialisation ends); out of range: `Discard`.
    pub fn set_integer(&mut self, vr: u32, value: i64) -> Result<(), Fault> {
        let v = self
            .variable(vr)
            .cloned()
            .ok_or_else(|| self.unknown(vr, "integer"))?;
        if v.causality != Causality::Parameter || v.kind != Kind::Int32 {
            return Err(if v.causality == Causality::Output {
                Fault::error(format!("`{}` is an output: it cannot be set", v.name))
            } else {
                self.unknown(vr, "integer")
            });
        }
        self.configurable(&v.name)?;
        v.check_range(value as f64).map_err(Fault::discard)?;
        if i32::try_from(value).is_err() {
            return Err(Fault::discard(format!(
                "parameter `{}` = {value}: out of the 32-bit range",
                v.name
            )));
        }
        match self.slot(vr) {
            Some(Slot::MaxSteps) => self.values.max_steps = value,
            Some(Slot::Parameter(k)) => self.values.params[k] = OverrideValue::Int(value),
            _ => return Err(self.unknown(vr, "integer")),
        }
        Ok(())
    }

    /// A string variable's value.
    pub fn get_string(&mut self, vr: u32) -> Result<String, Fault> {
        match self.slot(vr) {
            Some(Slot::Parameter(k)) => match &self.values.params[k] {
                OverrideValue::Str(s) => Ok(s.clone()),
                _ => Err(self.unknown(vr, "string")),
            },
            _ => Err(self.unknown(vr, "string")),
        }
    }

    /// Set a string parameter (before initialisation ends).
    pub fn set_string(&mut self, vr: u32, value: &str) -> Result<(), Fault> {
        let Some(Slot::Parameter(k)) = self.slot(vr) else {
            return Err(self.unknown(vr, "string"));
        };
        if !matches!(self.values.params[k], OverrideValue::Str(_)) {
            return Err(self.unknown(vr, "string"));
        }
        let name = self
            .vars
            .iter()
            .find(|v| v.vr == vr)
            .map(|v| v.name.clone());
        self.configurable(&name.unwrap_or_default())?;
        self.values.params[k] = OverrideValue::Str(value.to_string());
        Ok(())
    }

    /// A copy of the current state (in any mode but `Error`).
    pub fn get_state(&self) -> Result<FmuState, Fault> {
        Ok(FmuState {
            mode: self.mode,
            start_time: self.start_time,
            stop_time: self.stop_time,
            values: self.values.clone(),
            simulated: self.simulated()?,
            serialized: None,
        })
    }

    /// The simulation part of a state taken now.
    fn simulated(&self) -> Result<Option<Simulated>, Fault> {
        match (self.mode, &self.run) {
            (Mode::Error, _) => Err(Fault::error(
                "the instance is in the Error state: its state cannot be taken (set an FMU state or reset it)",
            )),
            (Mode::Instantiated | Mode::Initialization, _) => Ok(None),
            (_, Some(run)) => Ok(Some(Simulated::Live {
                snapshot: Box::new(run.sim.snapshot()),
                identity: run.identity.clone(),
            })),
            (_, None) => Err(Fault::error("no simulation")),
        }
    }

    /// Overwrite `into` with the current state, reusing its snapshot's storage.
    pub fn get_state_into(&self, into: &mut FmuState) -> Result<(), Fault> {
        match (&mut into.simulated, self.mode, &self.run) {
            (
                Some(Simulated::Live { snapshot, identity }),
                Mode::Step | Mode::StepDiscarded | Mode::Terminated,
                Some(run),
            ) => {
                run.sim.snapshot_into(snapshot);
                *identity = run.identity.clone();
            }
            _ => into.simulated = self.simulated()?,
        }
        into.mode = self.mode;
        into.start_time = self.start_time;
        into.stop_time = self.stop_time;
        into.values.clone_from(&self.values);
        into.serialized = None;
        Ok(())
    }

    /// Put a state back, in any mode (see [`crate::state`]): its values, mode and simulation;
    /// the instance keeps its own stop time if it has one. On failure nothing changes.
    pub fn set_state(&mut self, s: &FmuState) -> Result<(), Fault> {
        if s.values.params.len() != self.values.params.len()
            || s.values.inputs.len() != self.values.inputs.len()
        {
            return Err(Fault::error("the state belongs to another FMU"));
        }
        let stop = self.stop_time.or(s.stop_time);
        match &s.simulated {
            None => self.run = None,
            Some(simulated) => {
                let reuse = self
                    .run
                    .as_ref()
                    .is_some_and(|r| r.params == s.values.params);
                let mut run = match self.run.take() {
                    Some(r) if reuse => r,
                    other => {
                        self.run = other;
                        Run::build(&self.spec, &s.values.params, s.start_time, &s.values.inputs)
                            .map_err(|e| format!("the state's parameters: {e}"))?
                    }
                };
                let restored = restore_into(&mut run, simulated)
                    .and_then(|_| run.apply_inputs(&self.spec, &s.values.inputs));
                if let Err(e) = restored {
                    if reuse {
                        self.run = Some(run);
                    }
                    return Err(Fault::error(e));
                }
                run.outputs = run.evaluate();
                self.run = Some(run);
            }
        }
        self.values.clone_from(&s.values);
        self.mode = s.mode;
        self.start_time = s.start_time;
        self.stop_time = stop;
        Ok(())
    }
}
