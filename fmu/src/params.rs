//! The sphere-impact model's variables and parameters: the one variable table both model
//! descriptions are generated from, the parameters with their checks, and the efsi scene they
//! describe.
//!
//! **The scene.** The seed's §5.1 impact, axisymmetric: the domain is fixed at
//! r ∈ [0, 0.045] m, z ∈ [0, 0.09] m (axis at r = 0, no-slip walls elsewhere; the substrate is
//! z = 0); a sphere of radius R centred on the axis at `initial_height`, moving axially at
//! `initial_velocity`; gravity along z. `cells_per_radius` n sets the cell size h = R/n and the
//! grid `round(0.045/h) × round(0.09/h)` (so the cells are nearly, not exactly, square, and a
//! larger sphere gets a coarser grid of the same domain).
//!
//! **Ranges.** Every real and integer parameter and the input declare the range the model
//! accepts (`min`/`max` in the model description): the geometric limits of the fixed domain,
//! and physical plausibility limits for the rest — speeds at which the air stays
//! incompressible (|v| ≤ 100 m/s, Mach 0.3), accelerations a shaker table produces
//! (|a| ≤ 1000 m/s², about 100 g), densities and viscosities of real materials. A value
//! outside its range is refused with a message naming the variable and the range.

/// Radial extent of the domain (m).
pub const DOMAIN_R: f64 = 0.045;
/// Axial extent of the domain (m).
pub const DOMAIN_Z: f64 = 0.09;
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
    /// The smallest value accepted (inclusive), if bounded below.
    pub min: Option<f64>,
    /// The largest value accepted (inclusive), if bounded above.
    pub max: Option<f64>,
    /// Description.
    pub description: &'static str,
}

impl Variable {
    /// Refuse `value` outside `[min, max]` (or not finite): the message names the variable,
    /// the value and the range.
    pub fn check_range(&self, value: f64) -> Result<(), String> {
        let inside = value.is_finite()
            && self.min.is_none_or(|m| value >= m)
            && self.max.is_none_or(|m| value <= m);
        if inside {
            return Ok(());
        }
        let unit = self.unit.map_or(String::new(), |u| format!(" {u}"));
        let bound = |b: Option<f64>| b.map_or("unbounded".to_string(), |b| format!("{b}"));
        Err(format!(
            "{} `{}` = {value}{unit}: outside its range [{}, {}]{unit}",
            match self.causality {
                Causality::Input => "input",
                _ => "parameter",
            },
            self.name,
            bound(self.min),
            bound(self.max),
        ))
    }
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
    /// The bound on solver steps per communication step.
    pub const MAX_SOLVER_STEPS_PER_STEP: u32 = 13;
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

#[allow(clippy::too_many_arguments)]
const fn var(
    vr: u32,
    name: &'static str,
    kind: Kind,
    causality: Causality,
    unit: Option<&'static str>,
    start: Option<&'static str>,
    range: (Option<f64>, Option<f64>),
    description: &'static str,
) -> Variable {
    Variable {
        vr,
        name,
        kind,
        causality,
        unit,
        start,
        min: range.0,
        max: range.1,
        description,
    }
}

use Causality::{Independent, Input, Output, Parameter};
use Kind::{Int32, Int64, Real};

const NONE: (Option<f64>, Option<f64>) = (None, None);

/// The default bound on solver steps per communication step (`max_solver_steps_per_step`).
pub const DEFAULT_MAX_SOLVER_STEPS: i32 = 10_000;

/// Every variable, in model-description order. The start values are [`Params::default`]'s
/// (a unit test checks it).
#[rustfmt::skip]
pub const VARIABLES: &[Variable] = &[
    var(vr::TIME, "time", Real, Independent, Some("s"), None, NONE, "Simulation time"),
    var(vr::RADIUS, "radius", Real, Parameter, Some("m"), Some("0.0192"), (Some(0.0), Some(DOMAIN_R)),
        "Sphere radius R, > 0 (the sphere must fit in the fixed 0.045 m x 0.09 m domain)"),
    var(vr::SOLID_DENSITY, "solid_density", Real, Parameter, Some("kg/m3"), Some("1106"),
        (Some(1.0), Some(25000.0)), "Sphere density"),
    var(vr::LAW, "law", Kind::String, Parameter, None, Some("neo_hookean"), NONE,
        "Hyperelastic law: the name of a law whose library is in the FMU's binaries folder (neo_hookean, saint_venant_kirchhoff, mooney_rivlin)"),
    var(vr::LAW_PARAMETER, "law_parameter", Kind::String, Parameter, None, Some("G"), NONE,
        "Name of the law parameter (a modulus in Pa) that law_parameter_value sets; the law's other parameters keep their defaults"),
    var(vr::LAW_PARAMETER_VALUE, "law_parameter_value", Real, Parameter, Some("Pa"), Some("180000"),
        (Some(-1e10), Some(1e10)),
        "Value of the law parameter named by law_parameter (default: the neo-Hookean shear modulus G); the law's own range applies too"),
    var(vr::INITIAL_HEIGHT, "initial_height", Real, Parameter, Some("m"), Some("0.0573"),
        (Some(0.0), Some(DOMAIN_Z)),
        "Initial height of the sphere's centre above the substrate (radius <= height <= 0.09 m - radius)"),
    var(vr::INITIAL_VELOCITY, "initial_velocity", Real, Parameter, Some("m/s"), Some("-1.22"),
        (Some(-100.0), Some(100.0)),
        "Initial axial velocity of the sphere (negative: towards the substrate); |v| <= 100 m/s keeps the air incompressible (Mach 0.3)"),
    var(vr::FLUID_DENSITY, "fluid_density", Real, Parameter, Some("kg/m3"), Some("1.2"),
        (Some(0.01), Some(25000.0)), "Density of the surrounding fluid"),
    var(vr::FLUID_VISCOSITY, "fluid_viscosity", Real, Parameter, Some("Pa.s"), Some("1.8e-05"),
        (Some(0.0), Some(1e4)), "Dynamic viscosity of the surrounding fluid"),
    var(vr::GRAVITY, "gravity", Real, Parameter, Some("m/s2"), Some("-9.81"),
        (Some(-100.0), Some(100.0)),
        "Gravity along z, non-zero (the base acceleration acts through the body-force stage)"),
    var(vr::CELLS_PER_RADIUS, "cells_per_radius", Int32, Parameter, None, Some("10"),
        (Some(2.0), Some(300.0)),
        "Grid cells per sphere radius, the speed/accuracy knob: cell size h = radius/cells_per_radius, grid round(0.045/h) x round(0.09/h), at most 1e6 cells"),
    var(vr::CFL, "cfl", Real, Parameter, None, Some("0.4"), (Some(0.0), Some(1.0)),
        "Courant number of the solver's internal steps, in (0, 1]"),
    var(vr::MAX_SOLVER_STEPS_PER_STEP, "max_solver_steps_per_step", Int32, Parameter, None,
        Some("10000"), (Some(1.0), Some(1e9)),
        "The most solver steps one communication step may take; a step that needs more is refused (Discard) with the state of its start kept"),
    var(vr::BASE_ACCELERATION, "base_acceleration", Real, Input, Some("m/s2"), Some("0"),
        (Some(-1000.0), Some(1000.0)),
        "Acceleration of the substrate (the grid's frame) along z, positive upwards: the body force is gravity - base_acceleration; |a| <= 1000 m/s2 (about 100 g)"),
    var(vr::HEIGHT, "height", Real, Output, Some("m"), None, NONE,
        "Height of the sphere's centroid above the substrate"),
    var(vr::VELOCITY, "velocity", Real, Output, Some("m/s"), None, NONE,
        "Axial velocity of the sphere (volume average)"),
    var(vr::CONTACT_FORCE, "contact_force", Real, Output, Some("N"), None, NONE,
        "Normal force of the sphere on the substrate, whole body (2 pi times efsi's per-radian contact_force probe)"),
    var(vr::CONTACT_RADIUS, "contact_radius", Real, Output, Some("m"), None, NONE,
        "Radius of the sphere's footprint on the substrate (0 without contact)"),
    var(vr::MAX_COMPRESSION, "max_compression", Real, Output, Some("m"), None, NONE,
        "Largest loss of the sphere's axial height so far, 2 radius - (top - bottom) on the axis, over every solver step, at least 0"),
    var(vr::KINETIC_ENERGY, "kinetic_energy", Real, Output, Some("J"), None, NONE,
        "Kinetic energy of fluid and sphere in the whole domain (2 pi times efsi's per-radian probe)"),
    var(vr::ELASTIC_ENERGY, "elastic_energy", Real, Output, Some("J"), None, NONE,
        "Elastic energy stored in the sphere, whole body (2 pi times efsi's per-radian probe)"),
    var(vr::STEPS, "steps", Int64, Output, None, None, NONE,
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
    /// The law's name: its library is in the FMU's binaries folder (default `neo_hookean`).
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
    /// The most solver steps one communication step may take (default 10 000).
    pub max_solver_steps_per_step: i32,
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
            max_solver_steps_per_step: DEFAULT_MAX_SOLVER_STEPS,
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

    /// The real parameter with value reference `vr`, for reading or writing.
    pub fn real_mut(&mut self, vr: u32) -> Option<&mut f64> {
        Some(match vr {
            vr::RADIUS => &mut self.radius,
            vr::SOLID_DENSITY => &mut self.solid_density,
            vr::LAW_PARAMETER_VALUE => &mut self.law_parameter_value,
            vr::INITIAL_HEIGHT => &mut self.initial_height,
            vr::INITIAL_VELOCITY => &mut self.initial_velocity,
            vr::FLUID_DENSITY => &mut self.fluid_density,
            vr::FLUID_VISCOSITY => &mut self.fluid_viscosity,
            vr::GRAVITY => &mut self.gravity,
            vr::CFL => &mut self.cfl,
            _ => return None,
        })
    }

    /// The integer parameter with value reference `vr`, for reading or writing.
    pub fn integer_mut(&mut self, vr: u32) -> Option<&mut i32> {
        Some(match vr {
            vr::CELLS_PER_RADIUS => &mut self.cells_per_radius,
            vr::MAX_SOLVER_STEPS_PER_STEP => &mut self.max_solver_steps_per_step,
            _ => return None,
        })
    }

    /// The string parameter with value reference `vr`, for reading or writing.
    pub fn string_mut(&mut self, vr: u32) -> Option<&mut String> {
        Some(match vr {
            vr::LAW => &mut self.law,
            vr::LAW_PARAMETER => &mut self.law_parameter,
            _ => return None,
        })
    }

    /// Check the parameters; the message names the first bad one, its value and what is
    /// allowed. (The law and its parameter are checked against the library by the model.)
    pub fn check(&self) -> Result<(), String> {
        let bad = |name: &str, value: String, why: &str| {
            Err(format!("parameter `{name}` = {value}: {why}"))
        };
        let mut copy = self.clone();
        for v in VARIABLES
            .iter()
            .filter(|v| v.causality == Causality::Parameter)
        {
            let value = match v.kind {
                Kind::Real => copy.real_mut(v.vr).map(|x| *x),
                Kind::Int32 | Kind::Int64 => copy.integer_mut(v.vr).map(|x| *x as f64),
                Kind::String => None,
            };
            if let Some(x) = value {
                v.check_range(x)?;
            }
        }
        // Exclusive bounds and rules across parameters.
        if self.radius <= 0.0 || self.radius >= DOMAIN_R {
            return bad(
                "radius",
                format!("{} m", self.radius),
                "the sphere must fit in the domain: 0 < radius < 0.045 m",
            );
        }
        if self.cfl <= 0.0 {
            return bad("cfl", self.cfl.to_string(), "must be in (0, 1]");
        }
        if self.gravity == 0.0 {
            return bad(
                "gravity",
                format!("{} m/s2", self.gravity),
                "must be non-zero (the base acceleration acts through the body force, which runs only with gravity)",
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
            let plain = !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !plain {
                return bad(
                    name,
                    format!("{s:?}"),
                    "must be a plain name (letters, digits, `_`, `-`): laws are looked up by name in the FMU's binaries folder only",
                );
            }
        }
        Ok(())
    }

    /// The scene these parameters describe, as RON text: `law` is the law's name as the scene
    /// gives it (the FMU gives the library file in its binaries folder), `end` the end time and
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
