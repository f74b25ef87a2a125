//! `efsi._efsi`: the extension module of the `efsi` Python package (the Python side,
//! `python/efsi/`, wraps it: numpy arrays, pandas, the exceptions, sweeps).
//!
//! **One implementation.** A scene is efsi-core's [`efsi_core::Scene`], changed through its
//! overrides (`set`, `refine`: the CLI's `--set` / `--refine` paths); a simulation is
//! [`efsi_core::Simulation`] with efsi-stages' built-in stages, stepped by
//! [`Simulation::advance_to`]; probes are efsi-run's ([`efsi_run::probes`]) and VTK files are
//! written by efsi-run's writer.
//!
//! **The same steps as `efsi run`.** `advance_to(t)` lands on every output time of the scene
//! (VTK, probe and profile times and the end, by the rule of efsi-run's run loop) on its way to
//! `t`, and records a probe row wherever `efsi run` writes one, so a simulation advanced to the
//! scene's end holds `probes.csv`'s rows bit for bit.
//!
//! **The GIL and Ctrl-C.** Stepping runs on a worker thread with the GIL released; the calling
//! thread waits for it, checking Python's signals every 20 ms. A `KeyboardInterrupt` (or any
//! exception a signal handler raises) sets the stop flag of `advance_to`: the worker stops at
//! the end of the step under way, and the exception is raised with the simulation at that step
//! boundary (a complete, consistent state that can be advanced further).
//!
//! **Errors.** Every efsi error is raised as one of the Python classes of `efsi.errors`
//! (`SceneError`, `UnstableError` with `stage`, `field` and `cell`, `EfsiError`), carrying
//! efsi's message; a panic inside efsi is caught at this boundary and raised as `EfsiError`
//! (`internal error: …`), never as a Rust panic crossing into Python.
//!
//! **A failed step is rolled back** (as `efsi run` and the FMU do): `advance_to` keeps the state
//! at the start of every step and puts it back when the step fails, so after an
//! `UnstableError` the simulation is at its last good state, which the message names. A
//! snapshot fits only a simulation of the same scene: `restore` refuses another scene's,
//! naming the settings that differ, as `resume` refuses another run's checkpoint.

use efsi_core::{
    Advance, AdvanceError, Advanced, EfsiError, Flow, Grid, OverrideValue, Rollback, Scene,
    Simulation, Snapshot, Stagger, StepInfo, StepStart, due,
};
use efsi_run::SceneOverrides;
use efsi_run::run::Schedule;
use efsi_run::{ProbeSpec, SceneOutput};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyFloat, PyInt, PyString};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, TryLockError};
use std::time::Duration;

mod errors;
use errors::{Failure, efsi_err, efsi_err_noted, guarded, panic_message};

/// The stop flag's value when a Python signal handler raised (SIGINT's number, as the CLI).
const STOPPED_BY_PYTHON: usize = 2;

/// A Python value as an override value: bool, int, float, or str taken as the command line's
/// RON text (`"(0.5, 0.5)"`, `"Disk(center: (0, 0), radius: 1)"`, `"None"`,
/// `"IncompleteCholesky"`; a string setting takes it unquoted, as `--set` does).
fn override_value(v: &Bound<'_, PyAny>) -> PyResult<OverrideValue> {
    if v.is_instance_of::<PyBool>() {
        return Ok(OverrideValue::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(OverrideValue::Int(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(OverrideValue::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(OverrideValue::Ron(v.extract()?));
    }
    // numpy scalars and other numbers.
    if let Ok(x) = v.extract::<f64>() {
        return Ok(OverrideValue::Float(x));
    }
    Err(PyTypeError::new_err(format!(
        "an override value must be a bool, int, float or str (RON text), got {}",
        v.get_type().name()?
    )))
}

fn value_to_py(py: Python<'_>, v: OverrideValue) -> PyResult<Py<PyAny>> {
    Ok(match v {
        OverrideValue::Bool(b) => PyBool::new(py, b).to_owned().into_any().unbind(),
        OverrideValue::Int(i) => i.into_pyobject(py)?.into_any().unbind(),
        OverrideValue::Float(x) => x.into_pyobject(py)?.into_any().unbind(),
        OverrideValue::Str(s) | OverrideValue::Ron(s) => s.into_pyobject(py)?.into_any().unbind(),
    })
}

/// A scene: a RON scene file's settings, changed by path (`set`) and refined (`refine`).
#[pyclass(module = "efsi._efsi", name = "Scene")]
#[derive(Clone)]
struct PyScene {
    scene: Scene,
    /// The file it was read from (messages, law libraries named by a relative path).
    path: PathBuf,
}

#[pymethods]
impl PyScene {
    /// Read a scene file (RON). Raises `efsi.SceneError` naming the file, line and column.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        guarded(py, || {
            let scene = Scene::load_with(&path, &[]).map_err(|e| efsi_err(py, e))?;
            Ok(PyScene { scene, path })
        })
    }

    /// A scene from RON text; `base` is the folder that law libraries named by a relative path
    /// are found in (default: the current folder).
    #[staticmethod]
    #[pyo3(signature = (text, base = None))]
    fn from_str(py: Python<'_>, text: &str, base: Option<PathBuf>) -> PyResult<PyScene> {
        guarded(py, || {
            let label = PathBuf::from("<string>");
            let mut scene = Scene::from_str_with(text, &label, &[]).map_err(|e| efsi_err(py, e))?;
            scene.source_dir = base;
            Ok(PyScene { scene, path: label })
        })
    }

    /// Set the setting at `path` (`"solid.law.parameters.G"`, `"grid.nx"`, …; the paths of
    /// `efsi run --set`) to `value`. Raises `efsi.SceneError` naming the override; the scene
    /// is then unchanged.
    fn set(&mut self, py: Python<'_>, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let value = override_value(value)?;
        guarded(py, || {
            self.scene.set(path, value).map_err(|e| efsi_err(py, e))
        })
    }

    /// Multiply every grid dimension by `factor` (rounded), keeping the domain.
    fn refine(&mut self, py: Python<'_>, factor: f64) -> PyResult<()> {
        guarded(py, || {
            self.scene.refine(factor).map_err(|e| efsi_err(py, e))
        })
    }

    /// The value of the setting at `path` (defaults filled in): a number, a str, a bool, or
    /// RON text for anything else.
    fn get(&self, py: Python<'_>, path: &str) -> PyResult<Py<PyAny>> {
        guarded(py, || {
            let v = self
                .scene
                .get_in_force(path, &efsi_stages::builtin())
                .map_err(|e| efsi_err(py, e))?;
            value_to_py(py, v)
        })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The overrides applied so far, as `efsi run` records them (`set PATH=VALUE`, `refine F`).
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.scene.overrides.iter().map(|o| o.to_string()).collect()
    }

    /// The effective scene as RON text.
    fn to_ron(&self) -> String {
        self.scene.to_ron()
    }

    /// A copy (scenes are changed in place by `set` and `refine`).
    fn copy(&self) -> PyScene {
        self.clone()
    }

    fn __copy__(&self) -> PyScene {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> PyScene {
        self.clone()
    }

    /// Pickling (Dask sends scenes to its workers): the effective scene's text, its folder and
    /// its overrides' record.
    fn __reduce__(&self, py: Python<'_>) -> PyResult<(Py<PyAny>, Py<PyAny>)> {
        let ctor = py
            .import("efsi._efsi")?
            .getattr("Scene")?
            .getattr("_restore")?
            .unbind();
        let args = (
            self.scene.to_ron(),
            self.scene.source_dir.clone(),
            self.path.clone(),
            self.overrides(),
        )
            .into_pyobject(py)?
            .into_any()
            .unbind();
        Ok((ctor, args))
    }

    /// The inverse of `__reduce__`.
    #[staticmethod]
    fn _restore(
        py: Python<'_>,
        text: &str,
        base: Option<PathBuf>,
        path: PathBuf,
        overrides: Vec<String>,
    ) -> PyResult<PyScene> {
        guarded(py, || {
            let mut scene = Scene::from_str_with(text, &path, &[]).map_err(|e| efsi_err(py, e))?;
            scene.source_dir = base;
            scene.overrides = overrides
                .iter()
                .filter_map(|o| restore_override(o))
                .collect();
            Ok(PyScene { scene, path })
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "efsi.Scene({:?}, {}×{} cells, overrides {:?})",
            self.scene.name,
            self.scene.grid.nx,
            self.scene.grid.ny,
            self.overrides()
        )
    }
}

/// An override from its record (`set PATH=VALUE`, `refine F`).
fn restore_override(text: &str) -> Option<efsi_core::Override> {
    if let Some(f) = text.strip_prefix("refine ") {
        return f.parse().ok().map(efsi_core::Override::Refine);
    }
    efsi_core::Override::parse(text.strip_prefix("set ")?).ok()
}

/// What `efsi run`'s outputs would do, without files: the output times it lands on and the
/// probe rows it writes (efsi-run's `Outputs` with their schedules, the probes' rows kept in
/// memory and nothing else written).
#[derive(Clone)]
struct Recorder {
    end: f64,
    /// The probes' schedule, then the VTK series' and each profile's.
    probe_schedule: Schedule,
    schedules: Vec<Schedule>,
    probes: Vec<ProbeSpec>,
    columns: Vec<String>,
    rows: Vec<f64>,
}

impl Recorder {
    fn new(sim: &Simulation) -> Recorder {
        // The section was checked when the simulation was built (`efsi_run::simulation`).
        let o = &sim.scene.output_spec().unwrap_or_default();
        let mut columns = vec!["t".to_string()];
        let bodies = efsi_run::probes::body_names(&sim.scene);
        for p in &o.probes {
            columns.extend(efsi_run::probes::columns(p, sim.grid.geometry, &bodies));
        }
        let vtk = o.vtk_every.map(|e| Schedule::every(Some(e)));
        let profiles = o.profiles.iter().map(|p| Schedule::times(p.times()));
        let mut r = Recorder {
            end: sim.scene.time.end,
            probe_schedule: Schedule::every(o.probe_every),
            schedules: vtk.into_iter().chain(profiles).collect(),
            probes: o.probes.clone(),
            columns,
            rows: Vec::new(),
        };
        r.emit(sim, false);
        r
    }

    /// The next output time after `t` (or the end), as efsi-run's `Outputs::next_event`.
    fn next_event(&self, t: f64) -> f64 {
        std::iter::once(&self.probe_schedule)
            .chain(&self.schedules)
            .filter_map(Schedule::next)
            .fold(self.end, f64::min)
            .max(t)
    }

    /// Record what is due at the simulation's time, as efsi-run's `Outputs::emit`: a probe row
    /// (also at the end, `last`), and the other outputs' times consumed (the simulation goes on
    /// after a `run`, so a profile's later times stay due).
    fn emit(&mut self, sim: &Simulation, last: bool) {
        let t = sim.state.t;
        if self.probe_schedule.take(t, last).write {
            self.rows.push(t);
            for p in &self.probes {
                efsi_run::probes::evaluate(
                    p,
                    &sim.grid,
                    &sim.state,
                    sim.scene.gravity,
                    sim.pipeline().outputs(),
                    &mut self.rows,
                );
            }
        }
        for s in &mut self.schedules {
            s.take(t, false);
        }
    }
}

/// A simulation with its recorder.
struct Driver {
    sim: Simulation,
    recorder: Recorder,
    steady: bool,
    /// The state at the start of the step under way, put back when the step fails (the run
    /// loop's rollback; reused from step to step).
    last_good: Option<StepStart>,
    /// Why the simulation cannot be used any more: a failed step whose state could not be put
    /// back (cleared by `restore`).
    broken: Option<String>,
}

/// Why [`Driver::advance`] failed: the error, and the step and time of the last good state the
/// simulation was put back to, when it was.
struct Failed {
    error: EfsiError,
    rolled_back: Option<(u64, f64)>,
}

impl From<EfsiError> for Failed {
    fn from(error: EfsiError) -> Failed {
        Failed {
            error,
            rolled_back: None,
        }
    }
}

impl Driver {
    /// Step to `target` landing on the scene's output times (the run loop's targets), recording
    /// probe rows; stops early on a steady flow or a non-zero `stop`. A step that fails puts
    /// the state at its start back (as `efsi run` and the FMU do): the simulation is then at
    /// its last good state, its time, step count and probe rows those of that state.
    fn advance(&mut self, target: f64, stop: &AtomicUsize) -> Result<Advanced, Failed> {
        let t0 = self.sim.state.t;
        if !target.is_finite() || !due(target, t0) {
            return Err(Failed::from(EfsiError::Target {
                target,
                t: t0,
                why: if target.is_finite() {
                    "it is before the simulation's time"
                } else {
                    "it is not a finite time"
                },
            }));
        }
        let end = self.recorder.end;
        while !due(self.sim.state.t, target) {
            let t = self.sim.state.t;
            let until = if due(t, end) {
                target
            } else {
                let until = self.recorder.next_event(t);
                let until = if due(t, until) {
                    end.min(self.recorder.next_event(t + 1e-9 * end))
                } else {
                    until
                };
                until.min(target)
            };
            let recorder = &mut self.recorder;
            let steady = &mut self.steady;
            let mut each = |sim: &mut Simulation, _: &StepInfo| -> Result<Flow, EfsiError> {
                *steady = sim.is_steady();
                let finished = due(sim.state.t, end) || *steady;
                if sim.state.t <= end * (1.0 + 1e-9) {
                    recorder.emit(sim, finished);
                }
                Ok(if *steady { Flow::Stop } else { Flow::Continue })
            };
            let control = Advance {
                stop: Some(stop),
                rollback: Rollback::Step(&mut self.last_good),
                on_step: Some(&mut each),
                ..Advance::default()
            };
            match self.sim.advance_to(until, control) {
                Ok(Advanced::Reached) => {}
                Ok(other) => return Ok(other),
                Err(AdvanceError::Refused(e)) | Err(AdvanceError::Hook(e)) => return Err(e.into()),
                Err(AdvanceError::Failed { error, good: true }) => {
                    let (step, t) = (self.sim.state.step, self.sim.state.t);
                    return Err(Failed {
                        error,
                        rolled_back: Some((step, t)),
                    });
                }
                Err(AdvanceError::Failed { error, good: false }) => {
                    self.broken = Some(error.to_string());
                    return Err(error.into());
                }
            }
        }
        Ok(Advanced::Reached)
    }
}

/// A state saved by `Simulation.snapshot()`, for `Simulation.restore()`.
#[pyclass(module = "efsi._efsi", name = "Snapshot", frozen)]
struct PySnapshot {
    snapshot: Snapshot,
    recorder: Recorder,
    steady: bool,
    /// The effective scene of the simulation it was taken from (a snapshot fits only a
    /// simulation of the same scene).
    scene: Scene,
}

#[pymethods]
impl PySnapshot {
    /// Simulated time of the snapshot.
    #[getter]
    fn time(&self) -> f64 {
        self.snapshot.t()
    }

    /// Step count of the snapshot.
    #[getter]
    fn steps(&self) -> u64 {
        self.snapshot.step()
    }

    fn __repr__(&self) -> String {
        format!(
            "efsi.Snapshot(t = {:e}, step {})",
            self.snapshot.t(),
            self.snapshot.step()
        )
    }
}

/// A grid coordinate along one axis by index: a face's ([`Grid::xf`]) or a cell centre's
/// ([`Grid::xc`]).
type Coordinate = fn(&Grid, isize) -> f64;

/// A field's values (little-endian f64 bytes), their shape (`[rows, columns]`, or
/// `[planes, rows, columns]` in three dimensions), and the x, y and z coordinates.
type FieldData<'py> = (
    Bound<'py, PyBytes>,
    Vec<usize>,
    Vec<f64>,
    Vec<f64>,
    Option<Vec<f64>>,
);

/// A running simulation of a scene (the stepping half of `efsi run`).
#[pyclass(module = "efsi._efsi", name = "Simulation", subclass)]
struct PySimulation {
    driver: Mutex<Driver>,
}

impl PySimulation {
    /// The simulation, unless `advance_to` is running on it in another Python thread (waiting
    /// for it while holding the GIL would deadlock: that call needs the GIL to return).
    fn lock(&self) -> PyResult<MutexGuard<'_, Driver>> {
        match self.driver.try_lock() {
            Ok(d) => Ok(d),
            // A panic is caught while the lock is held; the state is then still one of a
            // complete step or the failed step's, as after any error.
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
            Err(TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "the simulation is busy: advance_to is running on it in another thread",
            )),
        }
    }
}

#[pymethods]
impl PySimulation {
    /// Build the simulation of `scene` (the pipeline of stages it needs; the law library
    /// loaded). Raises `efsi.SceneError` when the scene cannot be run as it is.
    #[new]
    fn new(py: Python<'_>, scene: &PyScene) -> PyResult<PySimulation> {
        let (scene, path) = (scene.scene.clone(), scene.path.clone());
        guarded(py, || {
            let sim = py
                .detach(|| efsi_run::simulation(scene, &path, &efsi_stages::builtin()))
                .map_err(|e| efsi_err(py, e))?;
            let recorder = Recorder::new(&sim);
            Ok(PySimulation {
                driver: Mutex::new(Driver {
                    sim,
                    recorder,
                    steady: false,
                    last_good: None,
                    broken: None,
                }),
            })
        })
    }

    /// Step to time `t` (landing on it exactly, and on the scene's output times on the way).
    /// Returns `True` when `t` was reached, `False` when the flow became steady first
    /// (`time.steady`). Ctrl-C stops at the end of the step under way and raises
    /// `KeyboardInterrupt`; a failed step raises `efsi.UnstableError` with the simulation put
    /// back to the state at the start of that step (its last good state: time, step count,
    /// fields and probe rows), which the message names. A step whose state could not be put
    /// back leaves the simulation unusable: every later call raises `efsi.EfsiError` until
    /// `restore`.
    fn advance_to(&self, py: Python<'_>, t: f64) -> PyResult<bool> {
        let mut driver = self.lock()?;
        if let Some(why) = &driver.broken {
            return Err(broken_error(py, why));
        }
        let driver: &mut Driver = &mut driver;
        let stop = AtomicUsize::new(0);
        let mut raised: Option<PyErr> = None;
        let finished = (Mutex::new(false), Condvar::new());
        let outcome = std::thread::scope(|s| {
            let worker = s.spawn(|| {
                let r = catch_unwind(AssertUnwindSafe(|| driver.advance(t, &stop)));
                *finished.0.lock().unwrap_or_else(|p| p.into_inner()) = true;
                finished.1.notify_all();
                r
            });
            loop {
                let done = py.detach(|| {
                    let (lock, wake) = &finished;
                    let flag = lock.lock().unwrap_or_else(|p| p.into_inner());
                    let (flag, _) = wake
                        .wait_timeout_while(flag, Duration::from_millis(20), |f| !*f)
                        .unwrap_or_else(|p| p.into_inner());
                    *flag
                });
                if done {
                    break;
                }
                if raised.is_none()
                    && let Err(e) = py.check_signals()
                {
                    stop.store(STOPPED_BY_PYTHON, Ordering::SeqCst);
                    raised = Some(e);
                }
            }
            py.detach(|| worker.join())
        });
        let result = match outcome {
            Ok(Ok(r)) => r,
            Ok(Err(p)) | Err(p) => {
                // A panic inside a step: the state is neither that step's start nor its end.
                let message = panic_message(p.as_ref());
                driver.broken = Some(message.clone());
                return Err(Failure::Other(message).raise(py));
            }
        };
        match (result, raised) {
            (_, Some(e)) => Err(e),
            (Ok(Advanced::Reached), None) => Ok(true),
            (Ok(_), None) => Ok(false),
            (Err(Failed { error, rolled_back }), None) => Err(match rolled_back {
                Some((step, t)) => efsi_err_noted(
                    py,
                    error,
                    &format!(
                        "the simulation is back at its last good state (step {step}, t = {t:.6e}): fix the cause (e.g. a smaller time.cfl or time.dt_max) and advance again, or restore a snapshot"
                    ),
                ),
                None => efsi_err(py, error),
            }),
        }
    }

    /// Simulated time.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.lock()?.sim.state.t)
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> PyResult<u64> {
        Ok(self.lock()?.sim.state.step)
    }

    /// Whether the flow has become steady (`time.steady`).
    #[getter]
    fn steady(&self) -> PyResult<bool> {
        Ok(self.lock()?.steady)
    }

    /// The scene's end time.
    #[getter]
    fn end(&self) -> PyResult<f64> {
        Ok(self.lock()?.recorder.end)
    }

    /// The scene being run (a copy).
    #[getter]
    fn scene(&self) -> PyResult<PyScene> {
        let d = self.lock()?;
        Ok(PyScene {
            scene: d.sim.scene.clone(),
            path: d.sim.scene_path.clone(),
        })
    }

    /// A field's interior values: `(values, shape, x, y, z)` with `values` the little-endian
    /// f64 bytes of an array of `shape` — `[rows, columns]` (row `j` is y) on a
    /// two-dimensional grid, `[planes, rows, columns]` (plane `k` is z) on a three-dimensional
    /// one — and `x`, `y`, `z` the coordinates where they live (cell centres; faces for `u`
    /// along x, `v` along y and `w` along z; `z` is None on a two-dimensional grid).
    /// Names: `u`, `v`, `w` (three-dimensional grids), `p`, `density`, `viscosity`,
    /// `solid_fraction`.
    fn _field<'py>(&self, py: Python<'py>, name: &str) -> PyResult<FieldData<'py>> {
        let d = self.lock()?;
        let (grid, state) = (&d.sim.grid, &d.sim.state);
        let (field, stagger) = match name {
            "u" => (Some(&state.u), Stagger::XFace),
            "v" => (Some(&state.v), Stagger::YFace),
            "w" if grid.is_3d() => (state.w.as_ref(), Stagger::ZFace),
            "w" => {
                return Err(PyValueError::new_err(
                    "unknown field `w`: the scene is two-dimensional (w exists in Cartesian3D scenes)",
                ));
            }
            "p" => (Some(&state.p), Stagger::Cell),
            "density" => (Some(&state.rho), Stagger::Cell),
            "viscosity" => (Some(&state.mu), Stagger::Cell),
            "solid_fraction" => (state.phi.as_ref(), Stagger::Cell),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "unknown field `{name}`: expected one of u, v, w, p, density, viscosity, solid_fraction"
                )));
            }
        };
        let Some(field) = field else {
            return Err(PyValueError::new_err(format!(
                "field `{name}`: the scene has no solid"
            )));
        };
        let [ni, nj, nk] = stagger.extent3(grid);
        let [oi, oj, ok] = stagger.nodal();
        let mut bytes = Vec::with_capacity(8 * ni * nj * nk);
        for k in 0..nk as isize {
            for j in 0..nj as isize {
                for i in 0..ni as isize {
                    bytes.extend_from_slice(&field.data()[field.idx3([i, j, k])].to_le_bytes());
                }
            }
        }
        let axis = |n: usize, nodal: usize, face: Coordinate, centre: Coordinate| {
            let at = if nodal == 1 { face } else { centre };
            (0..n as isize).map(|i| at(grid, i)).collect::<Vec<f64>>()
        };
        let x = axis(ni, oi, Grid::xf, Grid::xc);
        let y = axis(nj, oj, Grid::yf, Grid::yc);
        let (shape, z) = if grid.is_3d() {
            (vec![nk, nj, ni], Some(axis(nk, ok, Grid::zf, Grid::zc)))
        } else {
            (vec![nj, ni], None)
        };
        Ok((PyBytes::new(py, &bytes), shape, x, y, z))
    }

    /// The probe rows recorded so far (those `efsi run` writes to `probes.csv`): the column
    /// names and the rows' values, row after row.
    fn _probes(&self) -> PyResult<(Vec<String>, Vec<f64>)> {
        let d = self.lock()?;
        Ok((d.recorder.columns.clone(), d.recorder.rows.clone()))
    }

    /// Save the state (and the probe rows recorded so far) to come back to with `restore`.
    fn snapshot(&self, py: Python<'_>) -> PyResult<PySnapshot> {
        let d = self.lock()?;
        if let Some(why) = &d.broken {
            return Err(broken_error(py, why));
        }
        Ok(PySnapshot {
            snapshot: d.sim.snapshot(),
            recorder: d.recorder.clone(),
            steady: d.steady,
            scene: d.sim.scene.clone(),
        })
    }

    /// Go back to a snapshot of a simulation of the same scene: its state, time and probe rows.
    /// Raises `efsi.SceneError` naming the settings that differ when the snapshot is of another
    /// scene (as a checkpoint of another run is refused), the simulation then unchanged.
    fn restore(&self, py: Python<'_>, snapshot: &PySnapshot) -> PyResult<()> {
        guarded(py, || {
            let mut d = self.lock()?;
            let diffs = efsi_run::checkpoint::scene_differences(&snapshot.scene, &d.sim.scene);
            if !diffs.is_empty() {
                return Err(Failure::Scene(format!(
                    "the snapshot is of another scene ({}): {}",
                    snapshot.scene.name,
                    diffs.join("; ")
                ))
                .raise(py));
            }
            d.sim
                .restore(&snapshot.snapshot)
                .map_err(|e| efsi_err(py, e))?;
            d.recorder = snapshot.recorder.clone();
            d.steady = snapshot.steady;
            d.broken = None;
            Ok(())
        })
    }

    /// Write the current state with efsi run's writer into the folder `dir`:
    /// `fields/<name>_<step>.vtr` (velocity, divergence, pressure, density, viscosity, solid
    /// fraction, B and stress) listed in `fields.pvd`, and `probes.csv` with the current row.
    /// A folder holding earlier outputs is refused (`efsi.SceneError`, as `efsi run` refuses
    /// it) unless `overwrite`, which replaces them. Returns the `.vtr` file's path.
    #[pyo3(signature = (dir, overwrite = false))]
    fn write_vtk(&self, py: Python<'_>, dir: PathBuf, overwrite: bool) -> PyResult<PathBuf> {
        guarded(py, || {
            let mut d = self.lock()?;
            let sim = &mut d.sim;
            let keep = sim.scene.output.clone();
            let once = sim.scene.update_output(|o| {
                o.vtk_every = Some(f64::MAX);
                o.profiles.clear();
            });
            let path = sim.scene_path.clone();
            let config = |message| efsi_core::EfsiError::Config {
                path,
                field: "output".into(),
                message,
            };
            once.map_err(|m| efsi_err(py, config(m)))?;
            let written = write_now(sim, &dir, overwrite);
            sim.scene.output = keep;
            written.map_err(|e| efsi_err(py, e))
        })
    }

    fn __repr__(&self) -> String {
        match self.lock() {
            Ok(d) => format!(
                "efsi.Simulation({:?}, t = {:e}, step {})",
                d.sim.scene.name, d.sim.state.t, d.sim.state.step
            ),
            Err(_) => "efsi.Simulation(advancing)".into(),
        }
    }
}

/// The error of a simulation left unusable by a failed step whose state could not be put back.
fn broken_error(py: Python<'_>, why: &str) -> PyErr {
    Failure::Other(format!(
        "the simulation cannot be used: a failed step left it in the failing stage's state and it could not be put back ({why}); restore a snapshot or build a new Simulation"
    ))
    .raise(py)
}

/// Write the current state of `sim` into `dir` with efsi-run's outputs (the scene's output
/// settings already made to write VTK now).
fn write_now(sim: &Simulation, dir: &Path, overwrite: bool) -> Result<PathBuf, EfsiError> {
    let mut out = efsi_run::run::Outputs::new(sim, dir, None, overwrite)?;
    out.emit(sim, false)?;
    let file = dir
        .join("fields")
        .join(format!("{}_{:06}.vtr", sim.scene.name, sim.state.step));
    Ok(file)
}

/// The extension module.
#[pymodule]
fn _efsi(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PySimulation>()?;
    m.add_class::<PySnapshot>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
