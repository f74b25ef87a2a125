//! A running simulation and its communication steps: from `t` to `t + h` with the solver's own
//! steps, shortened the way `efsi run` shortens them to land on an output time
//! ([`Simulation::next_dt`]), so that any communication step lands exactly and `efsi run` of
//! the same scene with its outputs at the communication points gives the same numbers.
//!
//! **A bounded, all-or-nothing step.** A communication step takes at most
//! `max_solver_steps_per_step` solver steps: one that would need more (judged before the first
//! step from the step size the solver would take, and counted while stepping) is refused. A
//! refused or failed step — the bound, a solver that fails (a law returning NaN, a solver that
//! does not converge, a collapsing Δt), even a panic inside the solver — puts back the state of
//! its start, bit for bit: into the same simulation when it takes it back,
//! else into one rebuilt from the same scene. Only when neither works is the instance broken.
//!
//! **The scene** is the packaged one with the parameters' values applied as overrides; its law
//! is looked up by name in the FMU's binaries folder and nowhere else; the inputs are given to
//! the simulation after it is built and after every restore (they are not part of a snapshot
//! for the wall speeds). The outputs are the scene's probes, evaluated as `efsi run` evaluates
//! them for `probes.csv`.

use crate::spec::{InputTarget, Spec, input_target};
use efsi_core::overrides::OverrideValue;
use efsi_core::{Advance, AdvanceError, EfsiError, Simulation, Snapshot};
use efsi_laws_host::loader::{describe, library_file_name};
use efsi_run::SceneOutput;
use efsi_run::checkpoint::{LawIdentity, law_identity};
use efsi_stages::body_force::FrameAcceleration;
use efsi_stages::solid::SceneSolid;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The label standing for the scene file in messages and serialised states.
pub const SCENE_LABEL: &str = "resources/scene.ron";

/// What a run's scene is, for serialised states: the scene as RON (no absolute path in it: the
/// law is a library file name relative to the FMU's binaries folder) and the law library's
/// identity (name, ABI, parameter table, size and content hash; its `library` is the file
/// name only).
#[derive(Clone, Debug)]
pub struct RunIdentity {
    /// The scene, canonical RON.
    pub scene_ron: String,
    /// The law library.
    pub law: Option<LawIdentity>,
}

/// An initialised simulation and the model's running values.
pub struct Run {
    /// The simulation.
    pub sim: Simulation,
    /// The outputs of the current state (the spec's outputs, in order).
    pub outputs: Vec<f64>,
    /// The parameter values it was built from.
    pub params: Vec<OverrideValue>,
    /// The scene's probes.
    probes: Vec<efsi_run::ProbeSpec>,
    /// For each output, its column among the scene's probe columns.
    columns: Vec<usize>,
    /// The probe row (reused).
    row: Vec<f64>,
    /// The scene and law, for serialised states.
    pub identity: Arc<RunIdentity>,
    /// The state at the start of the current communication step (reused storage).
    start: Option<Snapshot>,
    /// Why the last recovery had to rebuild the simulation, if it did (for the log).
    pub rebuilt: Option<String>,
}

/// Why a communication step did not complete.
#[derive(Debug)]
pub enum StepFailure {
    /// Refused or failed, and the state of its start is back, exactly.
    Discarded(String),
    /// Failed, and the state could not be put back: the run is unusable.
    Broken(String),
}

/// The folder of the library this code was loaded from (the FMU's `binaries/<platform>/`), via
/// `dladdr` on one of its own functions.
pub fn library_dir() -> Option<PathBuf> {
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    let here = library_dir as *const () as *const libc::c_void;
    // SAFETY: dladdr only reads the address and fills `info`.
    let found = unsafe { libc::dladdr(here, &mut info) };
    if found == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: dli_fname is a NUL-terminated string owned by the dynamic loader.
    let name = unsafe { std::ffi::CStr::from_ptr(info.dli_fname) };
    use std::os::unix::ffi::OsStrExt;
    let path = PathBuf::from(std::ffi::OsStr::from_bytes(name.to_bytes()));
    let path = std::fs::canonicalize(&path).unwrap_or(path);
    path.parent().map(Path::to_path_buf)
}

/// The names of the laws whose libraries are in the FMU's binaries folder.
pub fn shipped_laws() -> Vec<String> {
    let file = library_file_name("*");
    let Some((prefix, suffix)) = file.split_once('*') else {
        return Vec::new();
    };
    let mut names: Vec<String> = library_dir()
        .and_then(|d| std::fs::read_dir(d).ok())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            Some(name.strip_prefix(prefix)?.strip_suffix(suffix)?.to_string())
        })
        .collect();
    names.sort();
    names
}

/// The folder the law libraries are looked up in: the FMU's binaries folder, and nowhere else.
fn law_dir() -> Result<PathBuf, String> {
    library_dir().ok_or_else(|| {
        "the FMU library cannot find its own folder (dladdr failed), so it cannot find the laws packaged beside it".to_string()
    })
}

/// Point the scene's law at its library in the FMU's binaries folder (`dir`), and nowhere
/// else: the scene names a law by its name; its library `libefsi_law_<name>.so` must be in
/// `dir`. Returns the library's file name.
fn law_in_fmu(scene: &mut efsi_core::Scene, dir: &Path) -> Result<Option<String>, String> {
    let Some(mut solid) = scene.solid_spec().map_err(|(f, m)| format!("{f}: {m}"))? else {
        return Ok(None);
    };
    let Some(law) = solid.law.as_mut() else {
        return Ok(None);
    };
    let plain = !law.name.is_empty()
        && law
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if !plain {
        return Err(format!(
            "solid.law.name = \"{}\": must be a plain law name (letters, digits, `_`, `-`): laws are looked up by name in the FMU's binaries folder only (it has: {})",
            law.name,
            shipped_laws().join(", ")
        ));
    }
    let file = library_file_name(&law.name);
    if !dir.join(&file).is_file() {
        return Err(format!(
            "solid.law.name = \"{}\": no such law in the FMU (its binaries folder has: {})",
            law.name,
            shipped_laws().join(", ")
        ));
    }
    describe(&dir.join(&file)).map_err(|e| format!("solid.law.name = \"{}\": {e}", law.name))?;
    law.name = file.clone();
    scene.set_solid(&solid);
    scene.source_dir = Some(dir.to_path_buf());
    Ok(Some(file))
}

impl Run {
    /// Build the scene of `spec` with the parameter values `params` and its simulation from
    /// `start`, with the inputs' values. (The scene keeps its own end time: it sets only the
    /// solver's smallest step; the importer's stop time is checked by the model.)
    pub fn build(
        spec: &Spec,
        params: &[OverrideValue],
        start: f64,
        inputs: &[f64],
    ) -> Result<Run, String> {
        let values: Vec<(String, OverrideValue)> = spec
            .parameters
            .iter()
            .map(|p| p.name.clone())
            .zip(params.iter().cloned())
            .collect();
        let mut scene = spec.scene_with(&values)?;
        let file = law_in_fmu(&mut scene, &law_dir()?)?;
        let label = Path::new(SCENE_LABEL);
        let sim = efsi_run::simulation(scene, label, &efsi_stages::builtin())
            .map_err(|e| format!("the simulation could not be set up: {e}"))?;
        let mut law = law_identity(&sim.scene, sim.options()).map_err(|e| e.to_string())?;
        if let (Some(l), Some(f)) = (&mut law, file) {
            l.library = f;
        }
        let identity = Arc::new(RunIdentity {
            scene_ron: sim.scene.to_ron(),
            law,
        });
        let all = crate::spec::probe_columns(&sim.scene)?;
        let probes = sim
            .scene
            .output_spec()
            .map(|o| o.probes)
            .unwrap_or_default();
        let columns = spec
            .outputs
            .iter()
            .map(|o| {
                all.iter()
                    .position(|c| *c == o.name)
                    .ok_or_else(|| format!("output `{}`: no such probe column", o.name))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut run = Run {
            sim,
            outputs: Vec::new(),
            params: params.to_vec(),
            probes,
            columns,
            row: Vec::new(),
            identity,
            start: None,
            rebuilt: None,
        };
        run.sim.state.t = start;
        run.apply_inputs(spec, inputs)?;
        run.outputs = run.evaluate();
        Ok(run)
    }

    /// Give the simulation the inputs' values (after a build or a restore).
    pub fn apply_inputs(&mut self, spec: &Spec, inputs: &[f64]) -> Result<(), String> {
        for (port, &value) in spec.inputs.iter().zip(inputs) {
            self.apply_input(&port.name, value)?;
        }
        Ok(())
    }

    /// Give the simulation one input's value.
    pub fn apply_input(&mut self, name: &str, value: f64) -> Result<(), String> {
        match input_target(name) {
            Some(InputTarget::BaseAcceleration) => self
                .sim
                .set_frame_acceleration((0.0, value))
                .map_err(|e| format!("input `{name}`: {e}")),
            Some(InputTarget::WallSpeed(side)) => self
                .sim
                .set_wall_speed(side, value)
                .map_err(|e| format!("input `{name}`: {e}")),
            None => Err(format!("`{name}` is not an input")),
        }
    }

    /// The smallest solver step the scene allows (`time.dt_min`, by default 10⁻¹² of its end).
    pub fn smallest_step(&self) -> f64 {
        let t = &self.sim.scene.time;
        t.dt_min.unwrap_or(1e-12 * t.end)
    }

    /// Advance from `t` (the model's time, up to round-off) to `t + h`: solver steps shortened
    /// to land on `t + h`, at most `max_steps` of them. Returns the solver steps taken. On
    /// failure the state of `t` is back ([`StepFailure::Discarded`]) unless it cannot be put
    /// back ([`StepFailure::Broken`]).
    pub fn advance(&mut self, t: f64, h: f64, max_steps: u64) -> Result<u64, StepFailure> {
        let target = t + h;
        let t_ = crate::model::Num(t);
        // The importer's clock is the reference: absorb round-off between the two.
        self.sim.state.t = t;
        match &mut self.start {
            Some(s) => self.sim.snapshot_into(s),
            None => self.start = Some(self.sim.snapshot()),
        }
        let first = self.sim.state.step;
        let result = crate::log::guard(
            || self.solver_steps(target, max_steps),
            |panic| Err(format!("internal error in the solver (a panic: {panic})")),
        );
        match result {
            Ok(()) => {
                self.outputs = self.evaluate();
                Ok(self.sim.state.step - first)
            }
            Err(e) => match self.recover() {
                Ok(()) => Err(StepFailure::Discarded(format!(
                    "{e}; the instance is back at t = {t_} exactly, its state before this call"
                ))),
                Err(r) => Err(StepFailure::Broken(format!(
                    "{e}; and the state at t = {t_} could not be put back ({r})"
                ))),
            },
        }
    }

    /// The solver steps of one communication step: [`Simulation::advance_to`] with the bound
    /// (judged first from the step size the solver would take); the rollback is
    /// [`advance`](Self::advance)'s, which kept the call's start before anything ran.
    fn solver_steps(&mut self, target: f64, max_steps: u64) -> Result<(), String> {
        let t = self.sim.state.t;
        let (t_, target_) = (crate::model::Num(t), crate::model::Num(target));
        let dt = self
            .sim
            .next_dt(target)
            .map_err(|e| format!("the solver cannot step from t = {t_}: {e}"))?;
        let needed = ((target - t) / dt).round();
        let needed_ = crate::model::Num(needed);
        if needed > max_steps as f64 {
            return Err(format!(
                "the communication step from t = {t_} to {target_} needs about {needed_} solver steps of {dt:.3e} s, more than max_solver_steps_per_step = {max_steps}: take shorter communication steps or raise max_solver_steps_per_step"
            ));
        }
        let control = Advance {
            max_steps: Some(max_steps),
            ..Advance::default()
        };
        match self.sim.advance_to(target, control) {
            Ok(_) => Ok(()),
            Err(AdvanceError::Failed {
                error: EfsiError::StepBudget { .. },
                ..
            }) => Err(format!(
                "the communication step from t = {t_} to {target_} took max_solver_steps_per_step = {max_steps} solver steps and reached only t = {}: take shorter communication steps or raise max_solver_steps_per_step",
                self.sim.state.t
            )),
            Err(e) => Err(format!(
                "the solver failed between t = {t_} and {target_}: {e}"
            )),
        }
    }

    /// Put the state of the current communication step's start back: into this simulation, or
    /// into one rebuilt from its scene when this one does not take it.
    fn recover(&mut self) -> Result<(), String> {
        let Some(start) = &self.start else {
            return Err("no state was kept".into());
        };
        if let Err(e) = self.sim.restore(start) {
            self.rebuilt = Some(e.to_string());
            let mut fresh = efsi_run::simulation(
                self.sim.scene.clone(),
                &self.sim.scene_path,
                &efsi_stages::builtin(),
            )
            .map_err(|e| format!("rebuilding the simulation failed: {e}"))?;
            fresh.restore(start).map_err(|e| e.to_string())?;
            self.sim = fresh;
        }
        self.outputs = self.evaluate();
        Ok(())
    }

    /// The outputs of the current state: the scene's probes, the spec's columns of them.
    pub fn evaluate(&mut self) -> Vec<f64> {
        self.row.clear();
        for p in &self.probes {
            efsi_run::probes::evaluate(
                p,
                &self.sim.grid,
                &self.sim.state,
                self.sim.scene.gravity,
                self.sim.pipeline().outputs(),
                &mut self.row,
            );
        }
        self.columns.iter().map(|&k| self.row[k]).collect()
    }
}
