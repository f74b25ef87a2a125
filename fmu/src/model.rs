//! The sphere-impact model both FMI interfaces drive: parameters, the scene built from them, the
//! stepping to communication points, the outputs and the FMU state.
//!
//! **No second implementation of physics.** The parameters fill in a RON scene
//! ([`Params::scene_ron`]) that is parsed and validated by efsi's scene loader and run by the
//! same [`Simulation`] and stage plugins as `efsi run`; `efsi run` of the scene written by
//! [`Params::scene_ron`] (see `fmu/sphere_impact.ron` for the defaults) gives the FMU's outputs
//! bit for bit at the communication points.
//!
//! **The scene.** The seed's §5.1 impact, axisymmetric: the domain is fixed at
//! r ∈ [0, 0.045] m, z ∈ [0, 0.09] m (axis at r = 0, no-slip walls elsewhere; the substrate is
//! z = 0); a sphere of radius R centred on the axis at `initial_height`, moving axially at
//! `initial_velocity`; gravity along z. `cells_per_radius` n sets the cell size h = R/n and the
//! grid `round(0.045/h) × round(0.09/h)` (so the cells are nearly, not exactly, square, and a
//! larger sphere gets a coarser grid of the same domain).
//!
//! **The input** `base_acceleration` a is the substrate's (the grid frame's) acceleration along
//! z, positive upwards, set with [`Simulation::set_frame_acceleration`]: the body force becomes
//! `gravity − a`, so a table accelerating upwards at a acts like a gravity stronger by a.
//!
//! **Stepping.** [`Model::do_step`] advances from t to t + h with
//! [`Simulation::advance_to`], the stepping `efsi run` lands on its output times with, so any
//! communication step lands exactly and a communication grid gives the numbers of `efsi run`
//! with output times on that grid.

use efsi_core::scene::Side;
use efsi_core::{Advance, Flow, Rollback, Scene, Simulation, Snapshot, StepInfo};
use efsi_laws_host::loader::{describe, library_file_name, resolve_law};
use efsi_run::checkpoint::{self, Checkpoint, OutputState};
use efsi_run::probes;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// Radial extent of the domain (m).
pub const DOMAIN_R: f64 = 0.045;
/// Axial extent of the domain (m).
pub const DOMAIN_Z: f64 = 0.09;
/// The scene's end time when the importer gives no stop time (s); it only sets the smallest
/// step allowed (10⁻¹² of it).
pub const DEFAULT_END: f64 = 0.07;
/// The most cells a grid may have (a guard against a mistyped `cells_per_radius`).
pub const MAX_CELLS: usize = 1_000_000;

/// The type of a model variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A real number (FMI 2.0 `Real`, FMI 3.0 `Float64`).
    Real,
    /// A 32-bit integer (FMI 2.0 `Integer`, FMI 3.0 `Int32`).
    Int32,
    /// A count (FMI 2.0 `Integer`, saturated; FMI 3.0 `Int64`).
    Int64,
    /// A string.
    String,
}

/// The causality of a model variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// Time.
    Independent,
    /// Set before initialisation, fixed afterwards.
    Parameter,
    /// Set by the importer at any time.
    Input,
    /// Computed by the model.
    Output,
}

/// One variable of the model description.
#[derive(Clone, Copy, Debug)]
pub struct Variable {
    /// Value reference.
    pub vr: u32,
    /// Name.
    pub name: &'static str,
    /// Type.
    pub kind: Kind,
    /// Causality.
    pub causality: Causality,
    /// Unit, if any.
    pub unit: Option<&'static str>,
    /// Start value as written in the model description (parameters and inputs).
    pub start: Option<&'static str>,
    /// Description.
    pub description: &'static str,
}

/// Value references.
pub mod vr {
    /// Time.
    pub const TIME: u32 = 0;
    /// Sphere radius.
    pub const RADIUS: u32 = 1;
    /// Solid density.
    pub const SOLID_DENSITY: u32 = 2;
    /// Law name.
    pub const LAW: u32 = 3;
    /// Name of the law parameter set by `law_parameter_value`.
    pub const LAW_PARAMETER: u32 = 4;
    /// Its value.
    pub const LAW_PARAMETER_VALUE: u32 = 5;
    /// Initial centre height.
    pub const INITIAL_HEIGHT: u32 = 6;
    /// Initial axial velocity.
    pub const INITIAL_VELOCITY: u32 = 7;
    /// Fluid density.
    pub const FLUID_DENSITY: u32 = 8;
    /// Fluid viscosity.
    pub const FLUID_VISCOSITY: u32 = 9;
    /// Gravity.
    pub const GRAVITY: u32 = 10;
    /// Cells per radius.
    pub const CELLS_PER_RADIUS: u32 = 11;
    /// Courant number.
    pub const CFL: u32 = 12;
    /// Base acceleration (input).
    pub const BASE_ACCELERATION: u32 = 100;
    /// Centroid height.
    pub const HEIGHT: u32 = 200;
    /// Axial velocity.
    pub const VELOCITY: u32 = 201;
    /// Contact force.
    pub const CONTACT_FORCE: u32 = 202;
    /// Contact radius.
    pub const CONTACT_RADIUS: u32 = 203;
    /// Maximum compression.
    pub const MAX_COMPRESSION: u32 = 204;
    /// Kinetic energy.
    pub const KINETIC_ENERGY: u32 = 205;
    /// Elastic energy.
    pub const ELASTIC_ENERGY: u32 = 206;
    /// Solver steps.
    pub const STEPS: u32 = 207;
}

const fn var(
    vr: u32,
    name: &'static str,
    kind: Kind,
    causality: Causality,
    unit: Option<&'static str>,
    start: Option<&'static str>,
    description: &'static str,
) -> Variable {
    Variable {
        vr,
        name,
        kind,
        causality,
        unit,
        start,
        description,
    }
}

use Causality::{Independent, Input, Output, Parameter};
use Kind::{Int32, Int64, Real};

/// Every variable, in model-description order. The start values are [`Params::default`]'s
/// (a unit test checks it).
#[rustfmt::skip]
pub const VARIABLES: &[Variable] = &[
    var(vr::TIME, "time", Real, Independent, Some("s"), None, "Simulation time"),
    var(vr::RADIUS, "radius", Real, Parameter, Some("m"), Some("0.0192"),
        "Sphere radius R (the sphere must fit in the fixed 0.045 m x 0.09 m domain)"),
    var(vr::SOLID_DENSITY, "solid_density", Real, Parameter, Some("kg/m3"), Some("1106"),
        "Sphere density"),
    var(vr::LAW, "law", Kind::String, Parameter, None, Some("neo_hookean"),
        "Hyperelastic law: a shipped law's name (neo_hookean, saint_venant_kirchhoff, mooney_rivlin; their libraries are in binaries/) or a law library's path"),
    var(vr::LAW_PARAMETER, "law_parameter", Kind::String, Parameter, None, Some("G"),
        "Name of the law parameter that law_parameter_value sets (the law's other parameters keep their defaults)"),
    var(vr::LAW_PARAMETER_VALUE, "law_parameter_value", Real, Parameter, None, Some("180000"),
        "Value of the law parameter named by law_parameter (default: the neo-Hookean shear modulus G in Pa)"),
    var(vr::INITIAL_HEIGHT, "initial_height", Real, Parameter, Some("m"), Some("0.0573"),
        "Initial height of the sphere's centre above the substrate"),
    var(vr::INITIAL_VELOCITY, "initial_velocity", Real, Parameter, Some("m/s"), Some("-1.22"),
        "Initial axial velocity of the sphere (negative: towards the substrate)"),
    var(vr::FLUID_DENSITY, "fluid_density", Real, Parameter, Some("kg/m3"), Some("1.2"),
        "Density of the surrounding fluid"),
    var(vr::FLUID_VISCOSITY, "fluid_viscosity", Real, Parameter, Some("Pa.s"), Some("1.8e-05"),
        "Dynamic viscosity of the surrounding fluid"),
    var(vr::GRAVITY, "gravity", Real, Parameter, Some("m/s2"), Some("-9.81"),
        "Gravity along z (non-zero: the base acceleration acts through the body-force stage)"),
    var(vr::CELLS_PER_RADIUS, "cells_per_radius", Int32, Parameter, None, Some("10"),
        "Grid cells per sphere radius, the speed/accuracy knob: cell size h = radius/cells_per_radius, grid round(0.045/h) x round(0.09/h)"),
    var(vr::CFL, "cfl", Real, Parameter, None, Some("0.4"),
        "Courant number of the solver's internal steps, in (0, 1]"),
    var(vr::BASE_ACCELERATION, "base_acceleration", Real, Input, Some("m/s2"), Some("0"),
        "Acceleration of the substrate (the grid's frame) along z, positive upwards: the body force is gravity - base_acceleration"),
    var(vr::HEIGHT, "height", Real, Output, Some("m"), None,
        "Height of the sphere's centroid above the substrate"),
    var(vr::VELOCITY, "velocity", Real, Output, Some("m/s"), None,
        "Axial velocity of the sphere (volume average)"),
    var(vr::CONTACT_FORCE, "contact_force", Real, Output, Some("N"), None,
        "Normal force of the sphere on the substrate, whole body (2 pi times efsi's per-radian contact_force probe)"),
    var(vr::CONTACT_RADIUS, "contact_radius", Real, Output, Some("m"), None,
        "Radius of the sphere's footprint on the substrate (0 without contact)"),
    var(vr::MAX_COMPRESSION, "max_compression", Real, Output, Some("m"), None,
        "Largest loss of the sphere's axial height so far, 2 radius - (top - bottom) on the axis, over every solver step, at least 0"),
    var(vr::KINETIC_ENERGY, "kinetic_energy", Real, Output, Some("J"), None,
        "Kinetic energy of fluid and sphere in the whole domain (2 pi times efsi's per-radian probe)"),
    var(vr::ELASTIC_ENERGY, "elastic_energy", Real, Output, Some("J"), None,
        "Elastic energy stored in the sphere, whole body (2 pi times efsi's per-radian probe)"),
    var(vr::STEPS, "steps", Int64, Output, None, None,
        "Solver steps taken since the start"),
];

/// The variable with value reference `vr`.
pub fn variable(vr: u32) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.vr == vr)
}

/// The model's parameters (each field's default is the seed's §5.1 value).
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Sphere radius R (m; default 0.0192).
    pub radius: f64,
    /// Sphere density (kg/m³; default 1106).
    pub solid_density: f64,
    /// Law name or library path (default `neo_hookean`).
    pub law: String,
    /// The law parameter [`law_parameter_value`](Self::law_parameter_value) sets (default `G`).
    pub law_parameter: String,
    /// Its value (default 0.18e6, G in Pa).
    pub law_parameter_value: f64,
    /// Initial centre height (m; default 0.0573).
    pub initial_height: f64,
    /// Initial axial velocity (m/s; default −1.22).
    pub initial_velocity: f64,
    /// Fluid density (kg/m³; default 1.2).
    pub fluid_density: f64,
    /// Fluid viscosity (Pa·s; default 1.8e-5).
    pub fluid_viscosity: f64,
    /// Gravity along z (m/s²; default −9.81).
    pub gravity: f64,
    /// Cells per radius (default 10).
    pub cells_per_radius: i32,
    /// Courant number (default 0.4).
    pub cfl: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            radius: 0.0192,
            solid_density: 1106.0,
            law: "neo_hookean".into(),
            law_parameter: "G".into(),
            law_parameter_value: 0.18e6,
            initial_height: 0.0573,
            initial_velocity: -1.22,
            fluid_density: 1.2,
            fluid_viscosity: 1.8e-5,
            gravity: -9.81,
            cells_per_radius: 10,
            cfl: 0.4,
        }
    }
}

impl Params {
    /// The grid `(nr, nz)` for these parameters (see the module docs).
    pub fn grid(&self) -> (usize, usize) {
        let h = self.radius / self.cells_per_radius as f64;
        (
            (DOMAIN_R / h).round().max(1.0) as usize,
            (DOMAIN_Z / h).round().max(1.0) as usize,
        )
    }

    /// Check the parameters; the message names the first bad one, its value and what is
    /// allowed. (The law and its parameter are checked by [`Model`] against the library.)
    pub fn check(&self) -> Result<(), String> {
        let bad = |name: &str, value: String, why: &str| {
            Err(format!("parameter `{name}` = {value}: {why}"))
        };
        let positive = [
            ("radius", self.radius, "m"),
            ("solid_density", self.solid_density, "kg/m3"),
            ("fluid_density", self.fluid_density, "kg/m3"),
        ];
        for (name, v, unit) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("{v} {unit}"), "must be a finite number > 0");
            }
        }
        for (name, v) in [
            ("initial_height", self.initial_height),
            ("initial_velocity", self.initial_velocity),
            ("law_parameter_value", self.law_parameter_value),
        ] {
            if !v.is_finite() {
                return bad(name, v.to_string(), "must be finite");
            }
        }
        if !(self.fluid_viscosity.is_finite() && self.fluid_viscosity >= 0.0) {
            return bad(
                "fluid_viscosity",
                format!("{} Pa.s", self.fluid_viscosity),
                "must be a finite number >= 0",
            );
        }
        if !(self.gravity.is_finite() && self.gravity != 0.0) {
            return bad(
                "gravity",
                format!("{} m/s2", self.gravity),
                "must be finite and non-zero (the base acceleration acts through the body force, which runs only with gravity)",
            );
        }
        if !(self.cfl.is_finite() && self.cfl > 0.0 && self.cfl <= 1.0) {
            return bad("cfl", self.cfl.to_string(), "must be in (0, 1]");
        }
        if self.cells_per_radius < 2 {
            return bad(
                "cells_per_radius",
                self.cells_per_radius.to_string(),
                "must be at least 2",
            );
        }
        if self.radius >= DOMAIN_R {
            return bad(
                "radius",
                format!("{} m", self.radius),
                "the sphere must fit in the domain: radius < 0.045 m",
            );
        }
        if self.initial_height < self.radius {
            return bad(
                "initial_height",
                format!("{} m", self.initial_height),
                &format!(
                    "the sphere would start inside the substrate: initial_height >= radius = {} m",
                    self.radius
                ),
            );
        }
        if self.initial_height + self.radius > DOMAIN_Z {
            return bad(
                "initial_height",
                format!("{} m", self.initial_height),
                &format!(
                    "the sphere must fit in the domain: initial_height + radius <= 0.09 m (radius = {} m)",
                    self.radius
                ),
            );
        }
        let (nr, nz) = self.grid();
        if nr * nz > MAX_CELLS {
            return bad(
                "cells_per_radius",
                self.cells_per_radius.to_string(),
                &format!("the grid would have {nr} x {nz} cells, more than {MAX_CELLS}"),
            );
        }
        for (name, s) in [("law", &self.law), ("law_parameter", &self.law_parameter)] {
            if s.trim().is_empty() || s.contains('"') || s.contains('\\') {
                return bad(
                    name,
                    format!("{s:?}"),
                    "must be a non-empty name without quotes or backslashes",
                );
            }
        }
        Ok(())
    }

    /// The scene these parameters describe, as RON text: `law` is the law's name as the scene
    /// gives it (the FMU passes the library it found next to itself), `end` the end time and
    /// `probe_every` the probe interval (the probes are the outputs' sources, for `efsi run`).
    pub fn scene_ron(&self, law: &str, end: f64, probe_every: f64) -> String {
        let (nr, nz) = self.grid();
        format!(
            r#"// The sphere-impact scene of the efsi FMU (generated from its parameters).
Scene(
    name: "sphere_impact",
    geometry: Axisymmetric,
    domain: (r: (0.0, {dr:?}), z: (0.0, {dz:?})),
    grid: (nr: {nr}, nz: {nz}),
    time: (end: {end:?}, cfl: {cfl:?}),
    fluid: (density: {rho_f:?}, viscosity: {mu_f:?}),
    gravity: (0.0, {g:?}),
    solid: (
        shape: Disk(center: (0.0, {z0:?}), radius: {r:?}),
        density: {rho_s:?},
        velocity: (0.0, {w0:?}),
        law: (name: "{law}", parameters: {{"{pname}": {pval:?}}}),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (
        probe_every: {probe_every:?},
        probes: [SolidCentroid, SolidVelocity, ContactForce(wall: YMin), ContactRadius(wall: YMin),
                 KineticEnergy, ElasticEnergy],
    ),
)
"#,
            dr = DOMAIN_R,
            dz = DOMAIN_Z,
            cfl = self.cfl,
            rho_f = self.fluid_density,
            mu_f = self.fluid_viscosity,
            g = self.gravity,
            z0 = self.initial_height,
            r = self.radius,
            rho_s = self.solid_density,
            w0 = self.initial_velocity,
            pname = self.law_parameter,
            pval = self.law_parameter_value,
        )
    }
}

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

/// Where the model is in the FMI life cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Instantiated: parameters may be set.
    Instantiated,
    /// In initialisation mode: parameters may still be set.
    Initialization,
    /// Initialised: stepping.
    Stepping,
    /// Terminated.
    Terminated,
    /// A call failed in a way that leaves the model unusable until reset or a state is set.
    Failed,
}

/// A saved FMU state: the simulation's snapshot and the model's own running values.
#[derive(Clone, Debug)]
pub struct FmuState {
    snapshot: Snapshot,
    max_compression: f64,
    base_acceleration: f64,
    /// The serialised form, computed on demand (FMI asks for the size, then the bytes).
    serialized: Option<Vec<u8>>,
}

struct Run {
    sim: Simulation,
    max_compression: f64,
    outputs: Outputs,
    /// The state at the start of the current communication step, put back if a step fails.
    start: Option<Snapshot>,
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

/// The names of the laws whose libraries are next to this library.
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

    /// Back to the state after instantiation (default parameters, no simulation).
    pub fn reset(&mut self) {
        *self = Model::new();
    }

    /// Record the experiment's start and stop time (before initialisation).
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), String> {
        self.require_configurable("set up the experiment")?;
        if !start.is_finite() {
            return Err(format!("the start time {start} is not finite"));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s > start)
        {
            return Err(format!(
                "the stop time {s} is not after the start time {start}"
            ));
        }
        self.start_time = start;
        self.stop_time = stop;
        Ok(())
    }

    /// Enter initialisation mode.
    pub fn enter_initialization(&mut self) -> Result<(), String> {
        if self.mode != Mode::Instantiated {
            return Err(format!(
                "cannot enter initialisation mode from {:?} mode",
                self.mode
            ));
        }
        self.mode = Mode::Initialization;
        Ok(())
    }

    fn require_configurable(&self, what: &str) -> Result<(), String> {
        match self.mode {
            Mode::Instantiated | Mode::Initialization => Ok(()),
            m => Err(format!(
                "cannot {what} in {m:?} mode: only before initialisation ends"
            )),
        }
    }

    /// The law's name as the scene should give it: a shipped law's library next to this
    /// library (the FMU's `binaries/<platform>/`) by absolute path when it is there, else the
    /// name itself (efsi's search path: `$EFSI_LAW_PATH`, the executable's folder, the build's
    /// target folders).
    pub fn law_in_scene(&self) -> String {
        let law = &self.params.law;
        let is_path =
            law.contains('/') || [".so", ".dylib", ".dll"].iter().any(|e| law.ends_with(e));
        if !is_path && let Some(dir) = library_dir() {
            let candidate = dir.join(library_file_name(law));
            if candidate.is_file() {
                return candidate.display().to_string();
            }
        }
        law.clone()
    }

    /// Check the law and its parameter against the library: it must exist, declare the
    /// parameter and accept the value. Messages name the FMU parameter.
    fn check_law(&self, law: &str) -> Result<(), String> {
        let p = &self.params;
        let path = resolve_law(law, Path::new(".")).map_err(|e| {
            format!(
                "parameter `law` = \"{}\": no such law (the FMU ships {}): {e}",
                p.law,
                shipped_laws().join(", ")
            )
        })?;
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
        if !param.contains(p.law_parameter_value) {
            return Err(format!(
                "parameter `law_parameter_value` = {}: out of the range {} of the law `{}`'s parameter `{}`{}",
                p.law_parameter_value,
                param.range_text(),
                info.name,
                param.name,
                if param.unit.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", param.unit)
                }
            ));
        }
        Ok(())
    }

    /// Leave initialisation mode: check the parameters, build the scene and the simulation.
    /// A refused parameter is named in the error.
    pub fn exit_initialization(&mut self) -> Result<(), String> {
        if self.mode != Mode::Initialization {
            return Err(format!(
                "cannot exit initialisation mode from {:?} mode",
                self.mode
            ));
        }
        self.params.check()?;
        let law = self.law_in_scene();
        self.check_law(&law)?;
        let end = self.stop_time.unwrap_or(self.start_time + DEFAULT_END);
        let text = self
            .params
            .scene_ron(&law, end - self.start_time, DEFAULT_END / 70.0);
        let path = Path::new("<sphere_impact FMU parameters>");
        let scene = Scene::from_str_at(&text, path)
            .map_err(|e| format!("the parameters make an invalid scene: {e}\n{text}"))?;
        let mut sim = Simulation::new(scene, path, &efsi_stages::builtin())
            .map_err(|e| format!("the simulation could not be set up: {e}"))?;
        sim.set_frame_acceleration((0.0, self.base_acceleration))
            .map_err(|e| format!("input `base_acceleration`: {e}"))?;
        sim.state.t = self.start_time;
        let (nr, nz) = self.params.grid();
        self.notes.push(format!(
            "sphere_impact: grid {nr} x {nz}, law {law}, stages {}",
            sim.pipeline().stage_names().join(", ")
        ));
        let mut run = Run {
            sim,
            max_compression: 0.0,
            outputs: Outputs::default(),
            start: None,
        };
        run.track_compression(self.params.radius);
        run.outputs = run.evaluate();
        self.run = Some(run);
        self.mode = Mode::Stepping;
        Ok(())
    }

    /// Advance from `t` (the importer's current communication point, which must be this
    /// model's time) by `h > 0`, landing exactly on `t + h`. On a failed solver step the state
    /// of `t` is put back and the error says why.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), String> {
        if self.mode != Mode::Stepping {
            return Err(format!("cannot step in {:?} mode", self.mode));
        }
        let radius = self.params.radius;
        let Some(run) = &mut self.run else {
            return Err("not initialised".into());
        };
        if !(h.is_finite() && h > 0.0) {
            return Err(format!("the communication step size {h} must be > 0"));
        }
        let now = run.sim.state.t;
        if (t - now).abs() > 1e-9 * t.abs().max(h) {
            return Err(format!(
                "the communication point {t} is not the model's time {now}"
            ));
        }
        // The importer's clock is the reference: absorb round-off between the two.
        run.sim.state.t = t;
        let compression = run.max_compression;
        let target = t + h;
        let steps = run.sim.state.step;
        let max_compression = &mut run.max_compression;
        let mut track = |sim: &mut Simulation, _: &StepInfo| {
            raise(max_compression, compression_of(sim, radius));
            Ok(Flow::Continue)
        };
        let control = Advance {
            rollback: Rollback::Call(&mut run.start),
            on_step: Some(&mut track),
            ..Advance::default()
        };
        if let Err(e) = run.sim.advance_to(target, control) {
            run.max_compression = compression;
            return Err(format!(
                "the solver failed between t = {t} and {target}: {e} (the state at t = {t} was put back)"
            ));
        }
        run.outputs = run.evaluate();
        self.notes.push(format!(
            "doStep t = {t} h = {h}: {} solver steps",
            run.sim.state.step - steps
        ));
        Ok(())
    }

    /// Terminate.
    pub fn terminate(&mut self) -> Result<(), String> {
        self.mode = Mode::Terminated;
        Ok(())
    }

    /// The current time.
    pub fn time(&self) -> f64 {
        self.run.as_ref().map_or(self.start_time, |r| r.sim.state.t)
    }

    /// The outputs (zeros before initialisation ends).
    pub fn outputs(&self) -> Outputs {
        self.run
            .as_ref()
            .map_or_else(Outputs::default, |r| r.outputs)
    }

    /// The simulation, once initialised.
    pub fn simulation(&self) -> Option<&Simulation> {
        self.run.as_ref().map(|r| &r.sim)
    }

    /// A real variable's value.
    pub fn get_real(&self, vr: u32) -> Result<f64, String> {
        let p = &self.params;
        let o = self.outputs();
        Ok(match vr {
            vr::TIME => self.time(),
            vr::RADIUS => p.radius,
            vr::SOLID_DENSITY => p.solid_density,
            vr::LAW_PARAMETER_VALUE => p.law_parameter_value,
            vr::INITIAL_HEIGHT => p.initial_height,
            vr::INITIAL_VELOCITY => p.initial_velocity,
            vr::FLUID_DENSITY => p.fluid_density,
            vr::FLUID_VISCOSITY => p.fluid_viscosity,
            vr::GRAVITY => p.gravity,
            vr::CFL => p.cfl,
            vr::BASE_ACCELERATION => self.base_acceleration,
            vr::HEIGHT => o.height,
            vr::VELOCITY => o.velocity,
            vr::CONTACT_FORCE => o.contact_force,
            vr::CONTACT_RADIUS => o.contact_radius,
            vr::MAX_COMPRESSION => o.max_compression,
            vr::KINETIC_ENERGY => o.kinetic_energy,
            vr::ELASTIC_ENERGY => o.elastic_energy,
            _ => return Err(unknown(vr, "real")),
        })
    }

    /// Set a real parameter (before initialisation ends) or the input (any time).
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        if vr == vr::BASE_ACCELERATION {
            if !value.is_finite() {
                return Err(format!(
                    "input `base_acceleration` = {value}: must be finite"
                ));
            }
            if let Some(run) = &mut self.run {
                run.sim
                    .set_frame_acceleration((0.0, value))
                    .map_err(|e| e.to_string())?;
            }
            self.base_acceleration = value;
            return Ok(());
        }
        let name = variable(vr)
            .filter(|v| v.kind == Kind::Real)
            .map(|v| v.name)
            .ok_or_else(|| unknown(vr, "real"))?;
        if !matches!(
            variable(vr).map(|v| v.causality),
            Some(Causality::Parameter)
        ) {
            return Err(format!(
                "`{name}` cannot be set: it is not a parameter or input"
            ));
        }
        self.require_configurable(&format!("set the parameter `{name}`"))?;
        let p = &mut self.params;
        let slot = match vr {
            vr::RADIUS => &mut p.radius,
            vr::SOLID_DENSITY => &mut p.solid_density,
            vr::LAW_PARAMETER_VALUE => &mut p.law_parameter_value,
            vr::INITIAL_HEIGHT => &mut p.initial_height,
            vr::INITIAL_VELOCITY => &mut p.initial_velocity,
            vr::FLUID_DENSITY => &mut p.fluid_density,
            vr::FLUID_VISCOSITY => &mut p.fluid_viscosity,
            vr::GRAVITY => &mut p.gravity,
            vr::CFL => &mut p.cfl,
            _ => return Err(unknown(vr, "real")),
        };
        *slot = value;
        Ok(())
    }

    /// An integer variable's value.
    pub fn get_integer(&self, vr: u32) -> Result<i64, String> {
        match vr {
            vr::CELLS_PER_RADIUS => Ok(self.params.cells_per_radius as i64),
            vr::STEPS => Ok(self.outputs().steps as i64),
            _ => Err(unknown(vr, "integer")),
        }
    }

    /// Set an integer parameter (before initialisation ends).
    pub fn set_integer(&mut self, vr: u32, value: i64) -> Result<(), String> {
        match vr {
            vr::CELLS_PER_RADIUS => {
                self.require_configurable("set the parameter `cells_per_radius`")?;
                self.params.cells_per_radius = i32::try_from(value).map_err(|_| {
                    format!("parameter `cells_per_radius` = {value}: out of the 32-bit range")
                })?;
                Ok(())
            }
            vr::STEPS => Err("`steps` is an output: it cannot be set".into()),
            _ => Err(unknown(vr, "integer")),
        }
    }

    /// A string variable's value.
    pub fn get_string(&self, vr: u32) -> Result<&str, String> {
        match vr {
            vr::LAW => Ok(&self.params.law),
            vr::LAW_PARAMETER => Ok(&self.params.law_parameter),
            _ => Err(unknown(vr, "string")),
        }
    }

    /// Set a string parameter (before initialisation ends).
    pub fn set_string(&mut self, vr: u32, value: &str) -> Result<(), String> {
        let slot = match vr {
            vr::LAW => &mut self.params.law,
            vr::LAW_PARAMETER => &mut self.params.law_parameter,
            _ => return Err(unknown(vr, "string")),
        };
        let name = variable(vr).map_or("?", |v| v.name);
        match self.mode {
            Mode::Instantiated | Mode::Initialization => {
                *slot = value.to_string();
                Ok(())
            }
            m => Err(format!(
                "cannot set the parameter `{name}` in {m:?} mode: only before initialisation ends"
            )),
        }
    }

    /// A copy of the current state (after initialisation).
    pub fn get_state(&self) -> Result<FmuState, String> {
        let run = self
            .run
            .as_ref()
            .ok_or("the FMU state can be taken only after initialisation")?;
        Ok(FmuState {
            snapshot: run.sim.snapshot(),
            max_compression: run.max_compression,
            base_acceleration: self.base_acceleration,
            serialized: None,
        })
    }

    /// Overwrite `into` with the current state, reusing its storage.
    pub fn get_state_into(&self, into: &mut FmuState) -> Result<(), String> {
        let run = self
            .run
            .as_ref()
            .ok_or("the FMU state can be taken only after initialisation")?;
        run.sim.snapshot_into(&mut into.snapshot);
        into.max_compression = run.max_compression;
        into.base_acceleration = self.base_acceleration;
        into.serialized = None;
        Ok(())
    }

    /// Go back to a state taken from this model (or one with the same parameters).
    pub fn set_state(&mut self, state: &FmuState) -> Result<(), String> {
        let run = self
            .run
            .as_mut()
            .ok_or("an FMU state can be set only after initialisation")?;
        run.sim
            .restore(&state.snapshot)
            .map_err(|e| e.to_string())?;
        run.max_compression = state.max_compression;
        run.outputs = run.evaluate();
        self.base_acceleration = state.base_acceleration;
        if matches!(self.mode, Mode::Failed | Mode::Terminated) {
            self.mode = Mode::Stepping;
        }
        Ok(())
    }

    /// The state as bytes: a small header (magic `EFSIFMU1`, max compression, base
    /// acceleration) and the snapshot in efsi's checkpoint format, which records the scene so
    /// that [`deserialize`](Self::deserialize) refuses a state of other parameters.
    pub fn serialize<'a>(&self, state: &'a mut FmuState) -> Result<&'a [u8], String> {
        let run = self
            .run
            .as_ref()
            .ok_or("an FMU state can be serialised only after initialisation")?;
        if state.serialized.is_none() {
            let c = Checkpoint {
                efsi_version: env!("CARGO_PKG_VERSION").to_string(),
                scene_path: run.sim.scene_path.clone(),
                scene_ron: run.sim.scene.to_ron(),
                overrides: run.sim.scene.overrides.clone(),
                law: None,
                outputs: OutputState::default(),
                snapshot: state.snapshot.clone(),
            };
            let mut bytes = Vec::new();
            bytes.extend_from_slice(SERIAL_MAGIC);
            bytes.extend_from_slice(&state.max_compression.to_le_bytes());
            bytes.extend_from_slice(&state.base_acceleration.to_le_bytes());
            bytes.extend_from_slice(&checkpoint::encode(&c));
            state.serialized = Some(bytes);
        }
        Ok(state.serialized.as_deref().unwrap_or_default())
    }

    /// A state from [`serialize`](Self::serialize)'s bytes.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<FmuState, String> {
        let run = self
            .run
            .as_ref()
            .ok_or("an FMU state can be deserialised only after initialisation")?;
        let head = SERIAL_MAGIC.len() + 16;
        if bytes.len() < head || &bytes[..SERIAL_MAGIC.len()] != SERIAL_MAGIC {
            return Err("not a serialised sphere_impact FMU state".into());
        }
        let f = |k: usize| {
            let at = SERIAL_MAGIC.len() + 8 * k;
            f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or([0; 8]))
        };
        let what = "serialised FMU state";
        let file = checkpoint::decode(&bytes[head..], what).map_err(|e| e.to_string())?;
        if file.scene_ron != run.sim.scene.to_ron() {
            let theirs = file.scene().map_err(|e| e.to_string())?;
            return Err(format!(
                "the serialised state belongs to a model with other parameters: {}",
                checkpoint::scene_differences(&theirs, &run.sim.scene).join("; ")
            ));
        }
        let snapshot = file
            .record
            .into_snapshot(run.sim.snapshot(), what)
            .map_err(|e| e.to_string())?;
        Ok(FmuState {
            snapshot,
            max_compression: f(0),
            base_acceleration: f(1),
            serialized: None,
        })
    }

    /// Mark the model unusable (after a panic) until it is reset or a state is set.
    pub fn fail(&mut self) {
        self.mode = Mode::Failed;
    }
}

const SERIAL_MAGIC: &[u8; 8] = b"EFSIFMU1";

/// The compression of the sphere of radius `radius` in `sim`: the loss of its axial height,
/// `2R − (top − bottom)` on the axis — the approach of Hertz's theory. (The centroid's drop
/// below R is smaller: the flattened bottom lifts the centroid; at 35 cells per radius 2.56 mm
/// against a compression of 3.56 mm.)
fn compression_of(sim: &Simulation, radius: f64) -> f64 {
    let g = &sim.grid;
    let (bottom, top) = probes::solid_extent(g, &sim.state, g.x0 + 0.5 * g.dx);
    2.0 * radius - (top - bottom)
}

/// `max = c` if `c` is larger (a NaN compression changes nothing).
fn raise(max: &mut f64, c: f64) {
    if c > *max {
        *max = c;
    }
}

fn unknown(vr: u32, kind: &str) -> String {
    match variable(vr) {
        Some(v) => format!(
            "`{}` (value reference {vr}) is not a {kind} variable",
            v.name
        ),
        None => format!("no {kind} variable has the value reference {vr}"),
    }
}

impl Run {
    /// Include the current state in the maximum compression ([`compression_of`]).
    fn track_compression(&mut self, radius: f64) {
        raise(&mut self.max_compression, compression_of(&self.sim, radius));
    }

    /// The outputs of the current state (whole-body values: efsi's per-radian ones × 2π).
    fn evaluate(&self) -> Outputs {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_values_are_the_defaults() {
        let m = Model::new();
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
        let cases: [(Change, &str); 6] = [
            (|p| p.radius = -0.01, "`radius`"),
            (|p| p.cells_per_radius = 0, "`cells_per_radius`"),
            (|p| p.initial_height = 0.01, "`initial_height`"),
            (|p| p.gravity = 0.0, "`gravity`"),
            (|p| p.cfl = 1.5, "`cfl`"),
            (|p| p.fluid_viscosity = f64::NAN, "`fluid_viscosity`"),
        ];
        for (change, name) in cases {
            let mut p = Params::default();
            change(&mut p);
            let e = p.check().unwrap_err();
            assert!(e.contains(name), "{e}");
        }
        assert_eq!(Params::default().check(), Ok(()));
    }
}
