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

use crate::params::Params;
use efsi_core::scene::Side;
use efsi_core::{Scene, Simulation, Snapshot};
use efsi_laws_host::loader::{describe, library_file_name};
use efsi_run::checkpoint::{LawIdentity, law_identity};
use efsi_run::probes;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The label standing for the scene file in messages and serialised states (the scene is
/// generated from the parameters, it has no file).
pub const SCENE_LABEL: &str = "<sphere_impact FMU parameters>";

/// The outputs at the current time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs {
    /// Centroid height (m).
    pub height: f64,
    /// Axial velocity (m/s).
    pub velocity: f64,
    /// Contact force, whole body (N).
    pub contact_force: f64,
    /// Contact radius (m).
    pub contact_radius: f64,
    /// Largest compression so far (m).
    pub max_compression: f64,
    /// Kinetic energy, whole domain (J).
    pub kinetic_energy: f64,
    /// Elastic energy, whole body (J).
    pub elastic_energy: f64,
    /// Solver steps.
    pub steps: u64,
}

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
    /// The largest compression so far (m).
    pub max_compression: f64,
    /// The outputs of the current state.
    pub outputs: Outputs,
    /// The parameters it was built from.
    pub params: Params,
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

/// Check the law and its parameter against the library in the FMU's binaries folder: it must
/// be there, declare the parameter as a modulus in Pa and accept the value. Messages name the
/// FMU parameter. Returns the library's file name.
fn check_law(p: &Params, dir: &Path) -> Result<String, String> {
    let file = library_file_name(&p.law);
    let path = dir.join(&file);
    if !path.is_file() {
        return Err(format!(
            "parameter `law` = \"{}\": no such law in the FMU (its binaries folder has: {})",
            p.law,
            shipped_laws().join(", ")
        ));
    }
    let info = describe(&path).map_err(|e| {
        format!(
            "parameter `law` = \"{}\": the library is unusable: {e}",
            p.law
        )
    })?;
    let Some(param) = info.parameters.iter().find(|q| q.name == p.law_parameter) else {
        return Err(format!(
            "parameter `law_parameter` = \"{}\": the law `{}` has no such parameter; it has: {}",
            p.law_parameter,
            info.name,
            info.parameters
                .iter()
                .map(|q| q.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    };
    if param.unit != "Pa" {
        return Err(format!(
            "parameter `law_parameter` = \"{}\": the law `{}`'s parameter is in `{}`, but law_parameter_value is in Pa (name a modulus)",
            p.law_parameter,
            info.name,
            if param.unit.is_empty() {
                "no unit"
            } else {
                &param.unit
            }
        ));
    }
    if !param.contains(p.law_parameter_value) {
        return Err(format!(
            "parameter `law_parameter_value` = {} Pa: out of the range {} of the law `{}`'s parameter `{}`",
            p.law_parameter_value,
            param.range_text(),
            info.name,
            param.name,
        ));
    }
    Ok(file)
}

impl Run {
    /// Check `params`, build their scene and its simulation from `start` (the scene ends at
    /// `end`), with the frame acceleration `base_acceleration`.
    pub fn build(
        params: &Params,
        start: f64,
        end: f64,
        base_acceleration: f64,
    ) -> Result<Run, String> {
        params.check()?;
        let dir = law_dir()?;
        let file = check_law(params, &dir)?;
        let text = params.scene_ron(&file, end - start, 0.001);
        let label = Path::new(SCENE_LABEL);
        let mut scene = Scene::from_str_at(&text, label)
            .map_err(|e| format!("the parameters make an invalid scene: {e}\n{text}"))?;
        // The law is a file name, resolved in the FMU's binaries folder.
        scene.source_dir = Some(dir);
        let mut sim = Simulation::new(scene, label, &efsi_stages::builtin())
            .map_err(|e| format!("the simulation could not be set up: {e}"))?;
        sim.set_frame_acceleration((0.0, base_acceleration))
            .map_err(|e| format!("input `base_acceleration`: {e}"))?;
        sim.state.t = start;
        let mut law = law_identity(&sim.scene).map_err(|e| e.to_string())?;
        if let Some(l) = &mut law {
            l.library = file;
        }
        let identity = Arc::new(RunIdentity {
            scene_ron: sim.scene.to_ron(),
            law,
        });
        let mut run = Run {
            sim,
            max_compression: 0.0,
            outputs: Outputs::default(),
            params: params.clone(),
            identity,
            start: None,
            rebuilt: None,
        };
        run.track_compression();
        run.outputs = run.evaluate();
        Ok(run)
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
        // The importer's clock is the reference: absorb round-off between the two.
        self.sim.state.t = t;
        match &mut self.start {
            Some(s) => self.sim.snapshot_into(s),
            None => self.start = Some(self.sim.snapshot()),
        }
        let compression = self.max_compression;
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
            Err(e) => {
                self.max_compression = compression;
                match self.recover() {
                    Ok(()) => Err(StepFailure::Discarded(format!(
                        "{e}; the instance is back at t = {t} exactly, its state before this call"
                    ))),
                    Err(r) => Err(StepFailure::Broken(format!(
                        "{e}; and the state at t = {t} could not be put back ({r})"
                    ))),
                }
            }
        }
    }

    /// The solver steps of one communication step (the bound checked before and during).
    fn solver_steps(&mut self, target: f64, max_steps: u64) -> Result<(), String> {
        let t = self.sim.state.t;
        let dt = self
            .sim
            .next_dt(target)
            .map_err(|e| format!("the solver cannot step from t = {t}: {e}"))?;
        let needed = ((target - t) / dt).round();
        if needed > max_steps as f64 {
            return Err(format!(
                "the communication step from t = {t} to {target} needs about {needed} solver steps of {dt:.3e} s, more than max_solver_steps_per_step = {max_steps}: take shorter communication steps or raise max_solver_steps_per_step"
            ));
        }
        let mut taken = 0u64;
        while !crate::model::due(self.sim.state.t, target) {
            if taken == max_steps {
                return Err(format!(
                    "the communication step from t = {t} to {target} took max_solver_steps_per_step = {max_steps} solver steps and reached only t = {}: take shorter communication steps or raise max_solver_steps_per_step",
                    self.sim.state.t
                ));
            }
            let result = self.sim.next_dt(target).and_then(|dt| self.sim.step(dt));
            if let Err(e) = result {
                return Err(format!(
                    "the solver failed between t = {t} and {target}: {e}"
                ));
            }
            taken += 1;
            self.sim.snap_time(target);
            self.track_compression();
        }
        Ok(())
    }

    /// Put the state of the current communication step's start back: into this simulation, or
    /// into one rebuilt from its scene when this one does not take it.
    fn recover(&mut self) -> Result<(), String> {
        let Some(start) = &self.start else {
            return Err("no state was kept".into());
        };
        if let Err(e) = self.sim.restore(start) {
            self.rebuilt = Some(e.to_string());
            let mut fresh = Simulation::new(
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

    /// Include the current state in the maximum compression: the loss of the sphere's axial
    /// height, `2R − (top − bottom)` on the axis — the approach of Hertz's theory. (The
    /// centroid's drop below R is smaller: the flattened bottom lifts the centroid; at 35 cells
    /// per radius 2.56 mm against a compression of 3.56 mm.)
    pub fn track_compression(&mut self) {
        let g = &self.sim.grid;
        let (bottom, top) = probes::solid_extent(g, &self.sim.state, g.x0 + 0.5 * g.dx);
        let c = 2.0 * self.params.radius - (top - bottom);
        if c > self.max_compression {
            self.max_compression = c;
        }
    }

    /// The outputs of the current state (whole-body values: efsi's per-radian ones × 2π).
    pub fn evaluate(&self) -> Outputs {
        let (grid, state) = (&self.sim.grid, &self.sim.state);
        let m = state
            .phi
            .as_ref()
            .map(|phi| probes::solid_moments(grid, state, phi));
        Outputs {
            height: m.map_or(f64::NAN, |m| m.centroid.1),
            velocity: m.map_or(f64::NAN, |m| m.velocity.1),
            contact_force: TAU * probes::contact_force(grid, state, Side::YMin),
            contact_radius: probes::contact_radius(grid, state, Side::YMin),
            max_compression: self.max_compression,
            kinetic_energy: TAU
                * efsi_core::ops::kinetic_energy(grid, &state.u, &state.v, &state.rho),
            elastic_energy: TAU
                * state
                    .deformation
                    .as_ref()
                    .map_or(f64::NAN, |d| d.elastic_energy),
            steps: state.step,
        }
    }
}
