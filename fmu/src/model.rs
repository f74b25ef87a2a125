//! The sphere-impact model both FMI interfaces drive: its life cycle, parameters and input,
//! outputs, communication steps and FMU states.
//!
//! **No second implementation of physics.** The parameters ([`crate::params`]) fill in a RON
//! scene that is parsed and validated by efsi's scene loader and run by the same
//! [`efsi_core::Simulation`] and stage plugins as `efsi run` ([`crate::stepping`]); `efsi run`
//! of the scene [`Params::scene_ron`] writes (see `fmu/sphere_impact.ron` for the defaults)
//! gives the FMU's outputs bit for bit at the communication points.
//!
//! **The input** `base_acceleration` a is the substrate's (the grid frame's) acceleration along
//! z, positive upwards, set with [`efsi_core::Simulation::set_frame_acceleration`]: the body
//! force becomes `gravity − a`, so a table accelerating upwards at a acts like a gravity
//! stronger by a.
//!
//! **Refusals.** A call that cannot be carried out returns a [`Fault`]: `Discard` when nothing
//! changed and the importer may go on (a value outside its declared range; a communication
//! step refused or failed with the state of its start put back), `Error` otherwise (an
//! illegal argument — a NaN or negative step, a communication point that is not the model's
//! time, a step past the stop time — or a state that could not be put back), after which the
//! instance is in the `Error` mode ([`crate::machine`]).

use crate::log::Status;
use crate::machine::Mode;
use crate::params::{Causality, Kind, Params, variable, vr};
use crate::state::{FmuState, Simulated, restore_into};
use crate::stepping::{Outputs, Run, StepFailure};

/// The scene's end time when the importer gives no stop time (s); it only sets the smallest
/// step allowed (10⁻¹² of it).
pub const DEFAULT_END: f64 = 0.07;

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

/// `t` has reached `event` (the run loop's rule, to land on communication points the same way).
pub fn due(t: f64, event: f64) -> bool {
    t >= event - 1e-9 * event.abs().max(1e-12)
}

/// The model behind one FMU instance.
pub struct Model {
    /// The parameters (settable until initialisation ends).
    pub params: Params,
    base_acceleration: f64,
    mode: Mode,
    start_time: f64,
    stop_time: Option<f64>,
    run: Option<Run>,
    /// Informational messages for the importer's log (drained by the FMI layer).
    pub notes: Vec<String>,
}

impl Default for Model {
    fn default() -> Self {
        Self::new()
    }
}

fn unknown(vr: u32, kind: &str) -> Fault {
    Fault::error(match variable(vr) {
        Some(v) => format!(
            "`{}` (value reference {vr}) is not a {kind} variable",
            v.name
        ),
        None => format!("no {kind} variable has the value reference {vr}"),
    })
}

impl Model {
    /// A model with the default parameters, not yet initialised.
    pub fn new() -> Self {
        Model {
            params: Params::default(),
            base_acceleration: 0.0,
            mode: Mode::Instantiated,
            start_time: 0.0,
            stop_time: None,
            run: None,
            notes: Vec::new(),
        }
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

    /// Back to the state after instantiation (default parameters, no simulation).
    pub fn reset(&mut self) {
        *self = Model::new();
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
        if !self.run.as_ref().is_some_and(|r| r.params == self.params) {
            let end = self.stop_time.unwrap_or(self.start_time + DEFAULT_END);
            let run = Run::build(&self.params, self.start_time, end, self.base_acceleration)?;
            let (nr, nz) = self.params.grid();
            self.notes.push(format!(
                "sphere_impact: grid {nr} x {nz}, law {}, stages {}",
                self.params.law,
                run.sim.pipeline().stage_names().join(", ")
            ));
            self.run = Some(run);
        }
        self.run
            .as_mut()
            .ok_or_else(|| Fault::error("no simulation"))
    }

    /// Leave initialisation mode: check the parameters and build the simulation. A refused
    /// parameter is named in the error.
    pub fn exit_initialization(&mut self) -> Result<(), Fault> {
        self.ensure_run()?;
        self.mode = Mode::Step;
        Ok(())
    }

    /// Advance from `t` (the importer's current communication point, which must be this
    /// model's time) by `h > 0`, landing exactly on `t + h` (see [`crate::stepping`]).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), Fault> {
        let stop = self.stop_time;
        let max_steps = self.params.max_solver_steps_per_step.max(1) as u64;
        let run = self
            .run
            .as_mut()
            .ok_or_else(|| Fault::error("no simulation: initialise the instance first"))?;
        let now = run.sim.state.t;
        if !t.is_finite() {
            return Err(Fault::error(format!(
                "the communication point {t} is not a finite number (the model's time is {now})"
            )));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(Fault::error(format!(
                "the communication step size {h} must be a finite number > 0"
            )));
        }
        if (t - now).abs() > 1e-9 * t.abs().max(h) {
            return Err(Fault::error(format!(
                "the communication point {t} is not the model's time {now}"
            )));
        }
        let target = t + h;
        if let Some(stop) = stop
            && target - stop > 1e-9 * stop.abs().max(h)
        {
            return Err(Fault::error(format!(
                "a step from t = {t} by {h} ends at {target}, past the stop time {stop} given at initialisation"
            )));
        }
        let smallest = run.smallest_step();
        if due(t, target) || h < smallest {
            return Err(Fault::discard(format!(
                "the communication step size {h} s is too small to resolve at t = {t} s (the smallest is {:e} s: the solver's smallest step, and 1e-9 of the time); the instance stays at t = {t}",
                smallest.max(1e-9 * t.abs())
            )));
        }
        let result = run.advance(t, h, max_steps);
        if let Some(why) = run.rebuilt.take() {
            self.notes.push(format!(
                "the simulation did not take back the state of t = {t} ({why}): it was rebuilt from its scene and given that state"
            ));
        }
        match result {
            Ok(n) => {
                self.notes
                    .push(format!("doStep t = {t} h = {h}: {n} solver steps"));
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

    /// The outputs: computed from the parameters before initialisation ends.
    fn outputs(&mut self) -> Result<Outputs, Fault> {
        match self.mode {
            Mode::Instantiated | Mode::Initialization => Ok(self.ensure_run()?.outputs),
            _ => self.run.as_ref().map(|r| r.outputs).ok_or_else(|| {
                Fault::error("no outputs: the simulation failed and could not be put back")
            }),
        }
    }

    /// A real variable's value.
    pub fn get_real(&mut self, vr: u32) -> Result<f64, Fault> {
        let o = match variable(vr) {
            Some(v) if v.causality == Causality::Output && v.kind == Kind::Real => {
                self.outputs()?
            }
            _ => Outputs::default(),
        };
        let p = &mut self.params;
        Ok(match vr {
            vr::TIME => return Ok(self.time()),
            vr::BASE_ACCELERATION => self.base_acceleration,
            vr::HEIGHT => o.height,
            vr::VELOCITY => o.velocity,
            vr::CONTACT_FORCE => o.contact_force,
            vr::CONTACT_RADIUS => o.contact_radius,
            vr::MAX_COMPRESSION => o.max_compression,
            vr::KINETIC_ENERGY => o.kinetic_energy,
            vr::ELASTIC_ENERGY => o.elastic_energy,
            _ => *p.real_mut(vr).ok_or_else(|| unknown(vr, "real"))?,
        })
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

    /// Set a real parameter (before initialisation ends) or the input (any time). A value
    /// outside the variable's range is refused (`Discard`: nothing changes).
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<(), Fault> {
        let v = variable(vr)
            .filter(|v| v.kind == Kind::Real)
            .ok_or_else(|| unknown(vr, "real"))?;
        match v.causality {
            Causality::Input => {
                v.check_range(value).map_err(Fault::discard)?;
                if let Some(run) = &mut self.run {
                    run.sim
                        .set_frame_acceleration((0.0, value))
                        .map_err(|e| Fault::error(e.to_string()))?;
                }
                self.base_acceleration = value;
                Ok(())
            }
            Causality::Parameter => {
                self.configurable(v.name)?;
                v.check_range(value).map_err(Fault::discard)?;
                *self
                    .params
                    .real_mut(vr)
                    .ok_or_else(|| unknown(vr, "real"))? = value;
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
        if vr == vr::STEPS {
            return Ok(self.outputs()?.steps as i64);
        }
        self.params
            .integer_mut(vr)
            .map(|x| *x as i64)
            .ok_or_else(|| unknown(vr, "integer"))
    }

    /// Set an integer parameter (before initialisation ends); out of range: `Discard`.
    pub fn set_integer(&mut self, vr: u32, value: i64) -> Result<(), Fault> {
        let v = variable(vr).ok_or_else(|| unknown(vr, "integer"))?;
        if v.causality != Causality::Parameter {
            return Err(Fault::error(format!(
                "`{}` is an output: it cannot be set",
                v.name
            )));
        }
        self.configurable(v.name)?;
        v.check_range(value as f64).map_err(Fault::discard)?;
        let slot = self
            .params
            .integer_mut(vr)
            .ok_or_else(|| unknown(vr, "integer"))?;
        *slot = i32::try_from(value).map_err(|_| {
            Fault::discard(format!(
                "parameter `{}` = {value}: out of the 32-bit range",
                v.name
            ))
        })?;
        Ok(())
    }

    /// A string variable's value.
    pub fn get_string(&mut self, vr: u32) -> Result<String, Fault> {
        self.params
            .string_mut(vr)
            .map(|s| s.clone())
            .ok_or_else(|| unknown(vr, "string"))
    }

    /// Set a string parameter (before initialisation ends).
    pub fn set_string(&mut self, vr: u32, value: &str) -> Result<(), Fault> {
        let name = variable(vr).map_or("?", |v| v.name);
        if self.params.string_mut(vr).is_none() {
            return Err(unknown(vr, "string"));
        }
        self.configurable(name)?;
        if let Some(slot) = self.params.string_mut(vr) {
            *slot = value.to_string();
        }
        Ok(())
    }

    /// A copy of the current state (in any mode but `Error`).
    pub fn get_state(&self) -> Result<FmuState, Fault> {
        let simulated = self.simulated()?;
        Ok(FmuState {
            mode: self.mode,
            start_time: self.start_time,
            stop_time: self.stop_time,
            params: self.params.clone(),
            base_acceleration: self.base_acceleration,
            max_compression: self.run.as_ref().map_or(0.0, |r| r.max_compression),
            simulated,
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
        into.params.clone_from(&self.params);
        into.base_acceleration = self.base_acceleration;
        into.max_compression = self.run.as_ref().map_or(0.0, |r| r.max_compression);
        into.serialized = None;
        Ok(())
    }

    /// Put a state back, in any mode (see [`crate::state`]): its parameters, input, mode and
    /// simulation; the instance keeps its own stop time if it has one. On failure nothing
    /// changes.
    pub fn set_state(&mut self, s: &FmuState) -> Result<(), Fault> {
        let stop = self.stop_time.or(s.stop_time);
        match &s.simulated {
            None => self.run = None,
            Some(simulated) => {
                let reuse = self.run.as_ref().is_some_and(|r| r.params == s.params);
                let mut run = match self.run.take() {
                    Some(r) if reuse => r,
                    other => {
                        self.run = other;
                        let end = stop.unwrap_or(s.start_time + DEFAULT_END);
                        Run::build(&s.params, s.start_time, end, s.base_acceleration)
                            .map_err(|e| format!("the state's parameters: {e}"))?
                    }
                };
                if let Err(e) = restore_into(&mut run, simulated) {
                    if reuse {
                        self.run = Some(run);
                    }
                    return Err(Fault::error(e));
                }
                run.max_compression = s.max_compression;
                run.outputs = run.evaluate();
                self.run = Some(run);
            }
        }
        self.params.clone_from(&s.params);
        self.base_acceleration = s.base_acceleration;
        self.mode = s.mode;
        self.start_time = s.start_time;
        self.stop_time = stop;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::VARIABLES;
    use efsi_core::Scene;
    use std::path::Path;

    #[test]
    fn start_values_are_the_defaults() {
        let mut m = Model::new();
        for v in VARIABLES {
            let Some(start) = v.start else { continue };
            match v.kind {
                Kind::Real => assert_eq!(
                    m.get_real(v.vr).unwrap(),
                    start.parse::<f64>().unwrap(),
                    "{}",
                    v.name
                ),
                Kind::Int32 | Kind::Int64 => assert_eq!(
                    m.get_integer(v.vr).unwrap(),
                    start.parse::<i64>().unwrap(),
                    "{}",
                    v.name
                ),
                Kind::String => assert_eq!(m.get_string(v.vr).unwrap(), start, "{}", v.name),
            }
            if let (Some(lo), Some(hi), Kind::Real) = (v.min, v.max, v.kind) {
                let x: f64 = start.parse().unwrap();
                assert!(lo <= x && x <= hi, "{}", v.name);
            }
        }
    }

    #[test]
    fn value_references_are_unique() {
        for (k, a) in VARIABLES.iter().enumerate() {
            assert!(
                VARIABLES[k + 1..]
                    .iter()
                    .all(|b| b.vr != a.vr && b.name != a.name),
                "{}",
                a.name
            );
        }
    }

    #[test]
    fn default_grid_is_the_seed_scene_at_ten_cells_per_radius() {
        assert_eq!(Params::default().grid(), (23, 47));
        let p = Params {
            cells_per_radius: 6,
            ..Params::default()
        };
        assert_eq!(p.grid(), (14, 28));
    }

    /// `fmu/sphere_impact.ron` is the scene of the default parameters, for `efsi run`.
    #[test]
    fn shipped_scene_is_the_default_parameters_scene() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("sphere_impact.ron");
        let shipped = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            shipped,
            Params::default().scene_ron("neo_hookean", 0.07, 0.001)
        );
        Scene::from_str_at(&shipped, &path).unwrap();
    }

    #[test]
    fn bad_parameters_are_named() {
        type Change = fn(&mut Params);
        let cases: [(Change, &str); 9] = [
            (|p| p.radius = -0.01, "`radius`"),
            (|p| p.cells_per_radius = 0, "`cells_per_radius`"),
            (|p| p.initial_height = 0.01, "`initial_height`"),
            (|p| p.gravity = 0.0, "`gravity`"),
            (|p| p.cfl = 1.5, "`cfl`"),
            (|p| p.fluid_viscosity = f64::NAN, "`fluid_viscosity`"),
            (
                |p| p.initial_velocity = -1220.0,
                "`initial_velocity` = -1220 m/s: outside its range [-100, 100] m/s",
            ),
            (|p| p.law = "/tmp/libefsi_law_x.so".into(), "`law`"),
            (
                |p| p.max_solver_steps_per_step = 0,
                "`max_solver_steps_per_step`",
            ),
        ];
        for (change, name) in cases {
            let mut p = Params::default();
            change(&mut p);
            let e = p.check().unwrap_err();
            assert!(e.contains(name), "{e}");
        }
        assert_eq!(Params::default().check(), Ok(()));
    }

    #[test]
    fn out_of_range_values_are_discarded_and_change_nothing() {
        let mut m = Model::new();
        let e = m.set_real(vr::BASE_ACCELERATION, 1e12).unwrap_err();
        assert_eq!(e.status, Status::Discard);
        assert!(
            e.message
                .contains("input `base_acceleration` = 1000000000000 m/s2: outside its range [-1000, 1000] m/s2"),
            "{}",
            e.message
        );
        assert_eq!(m.get_real(vr::BASE_ACCELERATION).unwrap(), 0.0);
        let e = m.set_real(vr::INITIAL_VELOCITY, -1220.0).unwrap_err();
        assert_eq!(e.status, Status::Discard);
        assert_eq!(m.params.initial_velocity, -1.22);
        assert_eq!(
            m.set_real(vr::HEIGHT, 1.0).unwrap_err().status,
            Status::Error
        );
    }
}
