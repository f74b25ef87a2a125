//! The scene: one RON file that describes everything a run needs.
//!
//! ```ron
//! Scene(
//!     name: "lid_driven_cavity_re100",
//!     geometry: Planar,
//!     domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
//!     grid: (nx: 64, ny: 64),
//!     time: (end: 30.0, cfl: 0.5, steady: 1e-8),
//!     fluid: (density: 1.0, viscosity: 0.01),
//!     boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
//!     output: (vtk_every: 5.0, profiles: [Line(name: "u_x0.5", from: (0.5, 0.0), to: (0.5, 1.0), points: 129, fields: ["u"])]),
//! )
//! ```
//!
//! Unknown fields are errors, and every error names the file, the line and column (syntax) or
//! the field (values out of range) and says what was expected. Optional values may be written
//! bare (`steady: 1e-8`) thanks to RON's `implicit_some` extension, which the loader enables.
//! In axisymmetric geometry `x` is the radius r and `y` the axis z; the aliases `r`, `z`,
//! `r_min`, `r_max`, `z_min`, `z_max` are accepted.

use crate::grid::Geometry;
pub use crate::interface::Shape;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

/// An error in a scene: where it is and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read scene: {source}")]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not valid RON, or does not match the scene schema.
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The scene file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A value is out of its allowed range or inconsistent with another.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// The offending field, as a path (`fluid.viscosity`).
        field: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// An override ([`crate::overrides`]: `efsi run --set`, `--refine`, [`Scene::set`]) that
    /// cannot be applied, or whose value the scene refuses.
    #[error("{path}: {setting}: {message}")]
    Override {
        /// The scene file (or `scene `name`` for a scene in memory).
        path: PathBuf,
        /// The override, as `set PATH=VALUE` or `refine F`.
        setting: String,
        /// What is wrong and what was expected.
        message: String,
    },
}

/// A complete scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name of the scene; the default output folder is `out/<name>/`.
    pub name: String,
    /// Planar or axisymmetric (default planar).
    #[serde(default = "default_geometry")]
    pub geometry: Geometry,
    /// Extents of the box.
    pub domain: Domain,
    /// Cell counts.
    pub grid: GridSpec,
    /// Time span and step control.
    pub time: TimeSpec,
    /// The fluid's material.
    pub fluid: Fluid,
    /// Gravity (acceleration vector; default zero). In axisymmetric geometry it must be along z.
    #[serde(default)]
    pub gravity: (f64, f64),
    /// Initial velocity of the fluid (default at rest).
    #[serde(default)]
    pub initial_velocity: InitialVelocity,
    /// The solid, if any: its shape at t = 0 and its material (one material; several bodies
    /// are a `Union` of shapes).
    #[serde(default)]
    pub solid: Option<Solid>,
    /// Boundary conditions per side.
    pub boundaries: Boundaries,
    /// Physics switches that cannot be inferred.
    #[serde(default)]
    pub physics: Physics,
    /// Numerical parameters of the solvers.
    #[serde(default)]
    pub numerics: Numerics,
    /// What to write and where.
    #[serde(default)]
    pub output: OutputSpec,
    /// The folder of the scene file (set by [`Scene::load`]; relative law paths start there).
    #[serde(skip)]
    pub source_dir: Option<PathBuf>,
    /// The overrides applied to the file's settings, in order ([`crate::overrides`]; set by
    /// [`Scene::load_with`], [`Scene::set`], …): the scene is the file's with these applied.
    #[serde(skip)]
    pub overrides: Vec<crate::overrides::Override>,
}

fn default_geometry() -> Geometry {
    Geometry::Planar
}

/// Extents of the box. `x` is r and `y` is z in axisymmetric geometry.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// `(min, max)` along x (r).
    #[serde(alias = "r")]
    pub x: (f64, f64),
    /// `(min, max)` along y (z).
    #[serde(alias = "z")]
    pub y: (f64, f64),
}

/// Cell counts.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Cells along x (r).
    #[serde(alias = "nr")]
    pub nx: usize,
    /// Cells along y (z).
    #[serde(alias = "nz")]
    pub ny: usize,
}

/// Time span and step control.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time (> 0).
    pub end: f64,
    /// Courant number on `Δt·(|u|/dx + |v|/dy)` (default 0.4, in (0, 1]; the advection scheme's
    /// sufficient TVD bound is 0.5, and the Re = 100 cavity shows limit-cycle noise from 0.45).
    #[serde(default = "default_cfl")]
    pub cfl: f64,
    /// Largest step allowed (default: no bound beyond the CFL and `end`).
    #[serde(default)]
    pub dt_max: Option<f64>,
    /// Smallest step allowed; a run that needs a smaller one stops with an error (default 1e-12·end).
    #[serde(default)]
    pub dt_min: Option<f64>,
    /// A fixed step instead of the CFL rule (still shortened to land on output times).
    #[serde(default)]
    pub fixed_dt: Option<f64>,
    /// Stop early at steady state: when `max|uⁿ⁺¹ − uⁿ|/Δt` falls below this (velocity/time units).
    #[serde(default)]
    pub steady: Option<f64>,
}

fn default_cfl() -> f64 {
    0.4
}

impl TimeSpec {
    /// The smallest step allowed: `dt_min`, else 1e-12·`end`. It also bounds the output and
    /// checkpoint intervals from below (a shorter interval would force shorter steps).
    pub fn dt_min_or_default(&self) -> f64 {
        self.dt_min.unwrap_or(1e-12 * self.end)
    }
}

/// A Newtonian fluid.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// Density ρ (kg/m³, > 0).
    pub density: f64,
    /// Dynamic viscosity μ (Pa·s, ≥ 0).
    pub viscosity: f64,
}

/// Initial velocity field.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum InitialVelocity {
    /// At rest.
    #[default]
    Rest,
    /// Uniform `(u, v)`.
    Uniform((f64, f64)),
    /// From the stream function `ψ = a·sin(kx·x)·sin(ky·y)`, `u = ∂ψ/∂y`, `v = −∂ψ/∂x`
    /// (sampled at cell corners, so the discrete field is exactly divergence-free).
    SinSinStream {
        /// Amplitude `a`.
        amplitude: f64,
        /// Wave numbers `(kx, ky)`.
        wavenumbers: (f64, f64),
    },
}

/// A solid body (or several, as a union of shapes) of one material.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solid {
    /// The region it occupies at t = 0 (x–y, or r–z in axisymmetric geometry).
    pub shape: Shape,
    /// Density ρ_s (kg/m³, > 0).
    pub density: f64,
    /// Viscosity μ_s (Pa·s, ≥ 0); default the seed's rule μ_s = μ_f ρ_s/ρ_f.
    #[serde(default)]
    pub viscosity: Option<f64>,
    /// Initial velocity of the solid (default: at rest).
    #[serde(default)]
    pub velocity: Option<(f64, f64)>,
    /// The hyperelastic law; without one the solid is a dense viscous body (no elastic stage).
    #[serde(default)]
    pub law: Option<LawSpec>,
}

/// A constitutive law named in a scene.
///
/// ```ron
/// law: (name: "neo_hookean", parameters: {"G": 0.18e6}),
/// law: (name: "plugins/my_law/target/release/libmy_law.so", parameters: {"k": 2.0}),
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawSpec {
    /// A shipped law's name (`neo_hookean`, `saint_venant_kirchhoff`, `mooney_rivlin`), or the
    /// path of a law library (relative paths are relative to the scene file's folder).
    pub name: String,
    /// Parameter values by name; the law declares which exist, their units, defaults and ranges.
    #[serde(default)]
    pub parameters: std::collections::BTreeMap<String, f64>,
}

impl Solid {
    /// μ_s: the scene's value, or the seed's rule μ_f ρ_s/ρ_f.
    pub fn viscosity(&self, fluid: &Fluid) -> f64 {
        self.viscosity
            .unwrap_or(fluid.viscosity * self.density / fluid.density)
    }
}

/// One of the four sides of the box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// x = x_min (r = r_min).
    #[serde(alias = "RMin")]
    XMin,
    /// x = x_max.
    #[serde(alias = "RMax")]
    XMax,
    /// y = y_min.
    #[serde(alias = "ZMin")]
    YMin,
    /// y = y_max.
    #[serde(alias = "ZMax")]
    YMax,
}

impl Side {
    /// All sides, in the order x_min, x_max, y_min, y_max.
    pub const ALL: [Side; 4] = [Side::XMin, Side::XMax, Side::YMin, Side::YMax];

    /// The scene field name of this side.
    pub fn field_name(self) -> &'static str {
        match self {
            Side::XMin => "x_min",
            Side::XMax => "x_max",
            Side::YMin => "y_min",
            Side::YMax => "y_max",
        }
    }

    /// The opposite side (the partner of a periodic pair).
    pub fn opposite(self) -> Side {
        match self {
            Side::XMin => Side::XMax,
            Side::XMax => Side::XMin,
            Side::YMin => Side::YMax,
            Side::YMax => Side::YMin,
        }
    }
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.field_name())
    }
}

/// Boundary conditions on the four sides.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boundaries {
    /// Side x = x_min (r_min; the axis when r_min = 0).
    #[serde(alias = "r_min")]
    pub x_min: Boundary,
    /// Side x = x_max.
    #[serde(alias = "r_max")]
    pub x_max: Boundary,
    /// Side y = y_min.
    #[serde(alias = "z_min")]
    pub y_min: Boundary,
    /// Side y = y_max.
    #[serde(alias = "z_max")]
    pub y_max: Boundary,
}

impl Boundaries {
    /// The condition on `side`.
    pub fn get(&self, side: Side) -> &Boundary {
        match side {
            Side::XMin => &self.x_min,
            Side::XMax => &self.x_max,
            Side::YMin => &self.y_min,
            Side::YMax => &self.y_max,
        }
    }
}

/// A boundary condition on one side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Boundary {
    /// Fixed wall: zero velocity.
    NoSlip,
    /// Wall moving in its own plane: zero normal velocity, tangential velocity
    /// `speed · profile(position) · motion(t)`.
    MovingWall {
        /// Peak tangential speed (m/s), along +x on y-sides and +y on x-sides.
        speed: f64,
        /// Shape along the wall (default uniform).
        #[serde(default)]
        profile: WallProfile,
        /// Dependence on time (default steady).
        #[serde(default)]
        motion: WallMotion,
    },
    /// Impermeable wall without friction: zero normal velocity and zero tangential stress.
    FreeSlip,
    /// The symmetry axis r = 0 of an axisymmetric domain (x_min only).
    Axis,
    /// Periodic: the opposite side must be periodic too.
    Periodic,
    /// Outflow: zero normal gradient of velocity, zero pressure.
    Outflow,
}

/// Shape of a moving wall's velocity along the wall.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum WallProfile {
    /// The same speed everywhere.
    #[default]
    Uniform,
    /// Seed Eq. (26): `sin²(π s / (2w))` over a ramp of width `w` at each end of the wall
    /// (s the distance from that end), 1 in between.
    Sin2Ramp {
        /// Width of each ramp (m).
        width: f64,
    },
}

/// Dependence of a moving wall's velocity on time.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum WallMotion {
    /// Constant in time.
    #[default]
    Steady,
    /// `sin(ω t)` (Stokes' oscillating plate; Sugiyama's oscillating Couette flow).
    Sin {
        /// Angular frequency ω (rad/s).
        omega: f64,
    },
    /// On for `t < t_off`, then stopped.
    Until {
        /// The time the wall stops (s).
        t_off: f64,
    },
}

impl WallProfile {
    /// Factor at distance `s` along a wall of length `len`.
    pub fn factor(&self, s: f64, len: f64) -> f64 {
        match *self {
            WallProfile::Uniform => 1.0,
            WallProfile::Sin2Ramp { width } => {
                let d = s.min(len - s).max(0.0);
                if d < width {
                    (std::f64::consts::PI * d / (2.0 * width)).sin().powi(2)
                } else {
                    1.0
                }
            }
        }
    }
}

impl WallMotion {
    /// Factor at time `t`.
    pub fn factor(&self, t: f64) -> f64 {
        match *self {
            WallMotion::Steady => 1.0,
            WallMotion::Sin { omega } => (omega * t).sin(),
            WallMotion::Until { t_off } => {
                if t < t_off {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }
}

/// Physics switches that the scene cannot imply.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Physics {
    /// Include the convective term (default true; false gives Stokes flow).
    #[serde(default = "yes")]
    pub advection: bool,
}

impl Default for Physics {
    fn default() -> Self {
        Physics { advection: true }
    }
}

fn yes() -> bool {
    true
}

/// Numerical parameters.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Numerics {
    /// A set of solver tolerances (default `Default`); `Strict` tightens each tolerance to at
    /// most its strict value — one setting for the strict run a check or a reference needs.
    #[serde(default)]
    pub preset: Preset,
    /// The pressure projection.
    #[serde(default)]
    pub projection: ProjectionParams,
    /// The implicit viscous step.
    #[serde(default)]
    pub viscous: ViscousParams,
    /// The elastic step.
    #[serde(default)]
    pub elastic: ElasticParams,
}

/// Solver-tolerance presets (`numerics.preset`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preset {
    /// The tolerances as set, or their defaults, chosen by the measured error/time trade
    /// (README, *Accuracy, speed and the defaults*).
    #[default]
    Default,
    /// Each tolerance at most its strict value: projection 1e-10, viscous 1e-9, elastic
    /// 1e-10 (the defaults before they were chosen by the trade); a tighter one set in the
    /// scene stays.
    Strict,
}

impl Numerics {
    /// Apply [`Preset::Strict`] to the tolerances (idempotent; nothing for `Default`). The
    /// scene loader and [`crate::Simulation::new`] call it, so the stages and `run.json` see
    /// the tolerances in force.
    pub fn apply_preset(&mut self) {
        if self.preset == Preset::Strict {
            self.projection.tolerance = self.projection.tolerance.min(1e-10);
            self.viscous.tolerance = self.viscous.tolerance.min(1e-9);
            self.elastic.tolerance = self.elastic.tolerance.min(1e-10);
        }
    }
}

/// Parameters of the elastic step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticParams {
    /// Treat the elastic stress implicitly (default true). `false` makes the elastic force
    /// explicit — stable only for `Δt ≲ h √(ρ/G)`; it exists to show what the implicit term buys.
    #[serde(default = "yes")]
    pub implicit: bool,
    /// Relative residual at which BiCGSTAB stops (default 1e-10).
    #[serde(default = "default_elastic_tol")]
    pub tolerance: f64,
    /// Iteration cap (default 5000).
    #[serde(default = "default_elastic_iter")]
    pub max_iterations: usize,
    /// Preconditioner of BiCGSTAB (default `Multigrid`).
    #[serde(default)]
    pub preconditioner: ElasticPreconditioner,
    /// The largest elastic-wave Courant number `Δt·c/h` a step may take (default and largest
    /// allowed: [`MAX_WAVE_COURANT`]), `c = √(G₀/ρ_s)` the solid's shear-wave speed at rest
    /// (`G₀` the law's stiffness at `B̃ = I`) and `h` the smaller cell side. The elastic step
    /// is implicit, but the pressure projection after it is not coupled to it: the strain its
    /// correction leaves in the solid is stored at stiffness G and given back at the next
    /// step, which pumps energy into stiff solids once `Δt·c/h` passes ≈ 5 (measured by the
    /// stability map, `cargo xtask bench-paper --case stability`). The time step is capped so;
    /// a `time.fixed_dt` above the cap is refused.
    #[serde(default = "default_wave_courant")]
    pub wave_courant: f64,
    /// How the elastic step and the pressure projection are coupled (default `Split`).
    #[serde(default)]
    pub coupling: ElasticCoupling,
    /// `Coupled` only: the coupled iteration stops once the residual of the divergence
    /// constraint (2-norm of the cells' net outfluxes) is this fraction of the one the elastic
    /// step left (default 1e-3); the projection stage removes the rest.
    #[serde(default = "default_coupling_tolerance")]
    pub coupling_tolerance: f64,
    /// The implicit weight θ of B's stretching over a step, `B^{n+1} = Bⁿ + Δt[(1 − θ) H(Vⁿ) +
    /// θ H(V^{n+1})] + …` (default: 0.5, Crank–Nicolson, with `Split`; 0.75 with `Coupled`).
    /// At an elastic-wave Courant number `s = kΔt√(G/ρ)` far above 1 the velocity's
    /// amplification per step tends to `−(1 − θ)/θ`: −1 (an undamped two-step oscillation) at
    /// 0.5, −1/3 at 0.75; above 0.5 the step is first order in time for the solid. (The
    /// coupled stability-map sphere at G = 1e9 Pa, CFL 0.5: at 0.5 the energy guard stops it
    /// in free flight, at 0.6 it gains 0.74 of its energy budget, at 0.75 nothing.)
    #[serde(default)]
    pub theta: Option<f64>,
    /// `Coupled` only: the most coupled iterations per step (default 50).
    #[serde(default = "default_coupling_iter")]
    pub coupling_iterations: usize,
}

/// How the implicit elastic step and the pressure projection share a time step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElasticCoupling {
    /// The elastic step, then the projection (seed Fig. 1): the projection's correction
    /// strains the solid without its stiffness answering within the step, which pumps energy
    /// into stiff solids above an elastic-wave Courant number of ≈ 5, so Δt is capped there
    /// (`wave_courant`).
    #[default]
    Split,
    /// Experimental. The elastic step solves its implicit system together with the
    /// divergence constraint (FGMRES on the pressure's Schur complement, preconditioned by the
    /// projection's Poisson operator plus the solid's effective viscosity — Cahouet–Chabard),
    /// so the pressure's correction meets the solid's implicit stiffness: no elastic-wave cap
    /// on Δt. The stability map's sphere at CFL 0.5 runs at G = 1e7 and 1e9 Pa in 31 and 30
    /// steps (split: 161, 1606) without gaining energy; it still gains at CFL 0.9 with
    /// G = 1e9 and at G = 1e11. Its B stretching is damped (`theta` 0.75), so an impact at
    /// the flow's step loses much of its rebound; ≈ 2.9× the split step's cost per step.
    Coupled,
}

impl ElasticParams {
    /// θ of B's stretching: the scene's, else 0.5 with `Split` and 0.75 with `Coupled`.
    pub fn stretch_theta(&self) -> f64 {
        self.theta.unwrap_or(match self.coupling {
            ElasticCoupling::Split => 0.5,
            ElasticCoupling::Coupled => 0.75,
        })
    }
}

fn default_coupling_tolerance() -> f64 {
    1e-3
}
fn default_coupling_iter() -> usize {
    50
}

/// The largest elastic-wave Courant number `Δt·c/h` allowed (see
/// [`ElasticParams::wave_courant`]): the largest at which every run of the stability map kept
/// its energy bounded.
pub const MAX_WAVE_COURANT: f64 = 4.0;

impl Default for ElasticParams {
    fn default() -> Self {
        ElasticParams {
            implicit: true,
            tolerance: default_elastic_tol(),
            max_iterations: default_elastic_iter(),
            preconditioner: ElasticPreconditioner::default(),
            wave_courant: default_wave_courant(),
            coupling: ElasticCoupling::default(),
            coupling_tolerance: default_coupling_tolerance(),
            coupling_iterations: default_coupling_iter(),
            theta: None,
        }
    }
}

/// Preconditioner of the elastic step's BiCGSTAB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElasticPreconditioner {
    /// The diagonal: cheapest per iteration; iterations grow like the elastic wave's Courant
    /// number `Δt √(G/ρ) / h`.
    Jacobi,
    /// Multigrid V-cycles on the u–u and v–v blocks of an SPD approximation of the system, the
    /// viscous operator with an effective viscosity `θΔt μ + (Δt/2) G_eff`.
    Multigrid,
    /// Multigrid, except in scenes with a periodic boundary, where Jacobi (the default): the
    /// red–black smoother keeps a flow uniform along a periodic direction uniform only to the
    /// solver's tolerance (a velocity of 1e-12 across a flat interface, solid fraction leaking
    /// into the fluid), where Jacobi keeps it exactly.
    #[default]
    Auto,
}

fn default_wave_courant() -> f64 {
    MAX_WAVE_COURANT
}

fn default_elastic_tol() -> f64 {
    1e-10
}
fn default_elastic_iter() -> usize {
    5000
}

/// Parameters of the pressure projection.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProjectionParams {
    /// Convergence criterion: after projection `max |∇·u|·Δt ≤ tolerance` — the largest
    /// fraction of its volume a cell may gain or lose in a step (dimensionless), reached after
    /// at least one iteration. Default 1e-6: on the axisymmetric drop at 128² (2,000 steps) the
    /// fall is the 1e-10 run's to seven digits and the drop's volume drifts by 5e-12, with 1.9
    /// multigrid-preconditioned iterations a step instead of 4.7; Basilisk's default is 1e-3
    /// in the same form. A strict setting is 1e-10.
    #[serde(default = "default_div_tol")]
    pub tolerance: f64,
    /// Iteration cap of the preconditioned conjugate gradient (default 10000).
    #[serde(default = "default_max_iter")]
    pub max_iterations: usize,
    /// The preconditioner of the conjugate gradient (default `Multigrid`).
    #[serde(default)]
    pub solver: PressureSolver,
    /// Incremental pressure correction: the last step's pressure gradient joins the predicted
    /// velocity before the viscous step, and the projection solves for the pressure's
    /// increment, so a viscous fluid at rest under gravity stays at rest (the seed's scheme
    /// sheared `gΔt` at no-slip side walls into a flow; `efsi_stages::projection`). `false` is the seed's scheme
    /// (Eqs. 11–23), the whole pressure found by the projection. Default (unset): incremental,
    /// except in a scene with an elastic solid, where the seed's scheme is kept — with the
    /// semi-implicit elastic step the incremental predictor pumped energy in (a Saint
    /// Venant–Kirchhoff sphere gained 16× its energy budget by step 151; the stability map's
    /// G = 1e9 sphere failed).
    #[serde(default)]
    pub incremental: Option<bool>,
}

impl Default for ProjectionParams {
    fn default() -> Self {
        ProjectionParams {
            tolerance: default_div_tol(),
            max_iterations: default_max_iter(),
            solver: PressureSolver::default(),
            incremental: None,
        }
    }
}

/// How the pressure equation is solved: conjugate gradient with one of two preconditioners.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PressureSolver {
    /// Geometric multigrid W-cycle (`efsi_linalg::Multigrid`): iterations independent
    /// of the grid size and of density ratios up to 1e4 (the default).
    #[default]
    Multigrid,
    /// Incomplete Cholesky IC(0), as the seed: the reference; iterations grow like the number
    /// of cells along a side.
    IncompleteCholesky,
}

fn default_div_tol() -> f64 {
    1e-6
}
fn default_max_iter() -> usize {
    10000
}

/// Parameters of the implicit viscous step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscousParams {
    /// Implicitness θ ∈ [0.5, 1]: 1 is backward Euler (the seed's Eq. 12, default), 0.5 is
    /// Crank–Nicolson.
    #[serde(default = "one")]
    pub theta: f64,
    /// Relative residual at which the conjugate gradient stops: `‖r‖ ≤ tolerance·‖b‖` with
    /// `b = Δt K(V*)`, so the viscous velocity increment of the step is solved to about this
    /// relative accuracy (default 1e-6). In a transient flow the error does not accumulate (the
    /// drop at 128² falls the same to seven digits at 1e-3 and 1e-9); at a steady state it
    /// biases the velocity by about `tolerance × U` (the Hagen–Poiseuille pipe: 3.7e-3 off at
    /// 1e-3 on 32 cells, the 1e-9 result to five digits at 1e-6). A strict setting is 1e-9.
    #[serde(default = "default_visc_tol")]
    pub tolerance: f64,
    /// Iteration cap (default 10000).
    #[serde(default = "default_max_iter")]
    pub max_iterations: usize,
    /// The preconditioner of the conjugate gradient (default `Jacobi`).
    #[serde(default)]
    pub preconditioner: ViscousPreconditioner,
}

impl Default for ViscousParams {
    fn default() -> Self {
        ViscousParams {
            theta: 1.0,
            tolerance: default_visc_tol(),
            max_iterations: default_max_iter(),
            preconditioner: ViscousPreconditioner::default(),
        }
    }
}

/// Preconditioner of the viscous step's conjugate gradient.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ViscousPreconditioner {
    /// Each step, `Multigrid` where the diffusion number makes Jacobi slow (the largest
    /// diagonal-to-mass ratio of the system above 40), else `Jacobi`.
    Auto,
    /// The diagonal (the default): cheapest per iteration; iterations grow like
    /// `√(1 + 8 μΔt/(ρh²))`. It keeps a flow that is uniform along a periodic direction
    /// exactly uniform, which the red–black smoother of `Multigrid` does only to the solver
    /// tolerance (the oscillating Couette flow then leaks solid fraction ~1e-7 into the fluid).
    #[default]
    Jacobi,
    /// Multigrid V-cycles on the u–u and v–v blocks (the u–v shear coupling left to CG):
    /// ≈ 16 iterations whatever the grid and the diffusion number, at about four times
    /// Jacobi's cost per iteration.
    Multigrid,
}

fn one() -> f64 {
    1.0
}
fn default_visc_tol() -> f64 {
    1e-6
}

/// What to write and where.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder (default `out/<name>/`; `efsi run --out` overrides).
    #[serde(default)]
    pub folder: Option<PathBuf>,
    /// Write VTK fields every this many seconds of simulated time (and at the start and end).
    #[serde(default)]
    pub vtk_every: Option<f64>,
    /// What the VTK files hold and how: fields, precision, compression, point data.
    #[serde(default)]
    pub vtk: VtkOptions,
    /// Sample the probes every this many seconds (default: every step).
    #[serde(default)]
    pub probe_every: Option<f64>,
    /// Probes: one or more columns each in `probes.csv`.
    #[serde(default)]
    pub probes: Vec<ProbeSpec>,
    /// Line profiles, written to `profiles/<name>_t<time>.csv`.
    #[serde(default)]
    pub profiles: Vec<ProfileSpec>,
}

/// The arrays a VTK file can hold, by name (`output.vtk.fields`): `velocity`, `pressure`,
/// `density`, `viscosity`, `divergence` always; `solid_fraction` with a solid; `B` (that is
/// B̃ = φ^{1/2} B) and `stress` (the elastic extra stress) with a solid that has a law. The
/// README's output section documents each one's location, components, meaning and unit.
pub const VTK_FIELDS: &[&str] = &[
    "velocity",
    "pressure",
    "density",
    "viscosity",
    "divergence",
    "solid_fraction",
    "B",
    "stress",
];

/// How the VTK field files are written (`output.vtk`); the defaults write every array as
/// `Float64` cell data, uncompressed (bit-exact values).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VtkOptions {
    /// The arrays to write, by name (see [`VTK_FIELDS`]); default: every array the scene has.
    #[serde(default)]
    pub fields: Option<Vec<String>>,
    /// The floating-point type of the arrays (coordinates and time stay `Float64`).
    #[serde(default)]
    pub precision: VtkPrecision,
    /// Compression of the appended binary data.
    #[serde(default)]
    pub compression: VtkCompression,
    /// Also write each array as point data, at the grid's nodes (each node the mean of the
    /// cells around it), beside the cell data — for smooth contours and surfaces.
    #[serde(default)]
    pub point_data: bool,
}

/// The floating-point type of VTK arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum VtkPrecision {
    /// 8 bytes per value, the simulation's values exactly.
    #[default]
    Float64,
    /// 4 bytes per value, rounded to single precision (≈ 7 significant digits).
    Float32,
}

/// Compression of VTK's appended binary data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum VtkCompression {
    /// Raw blocks.
    #[default]
    None,
    /// zlib (deflate), VTK's `vtkZLibDataCompressor`: every VTK/ParaView reader opens it.
    Zlib,
}

/// A probe: a time series written as columns of `probes.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ProbeSpec {
    /// A field sampled at a point (bilinear interpolation).
    Point {
        /// Column name.
        name: String,
        /// Field name (see [`FIELD_NAMES`]).
        field: String,
        /// Position.
        at: (f64, f64),
    },
    /// Kinetic energy ½∫ρ|u|² dV (per radian in axisymmetric geometry).
    KineticEnergy,
    /// Gravitational potential energy `−∫ρ g·x dV` of the scene's gravity, measured from the
    /// origin of coordinates (per radian in axisymmetric geometry); column `potential_energy`.
    /// With [`ProbeSpec::KineticEnergy`] and [`ProbeSpec::ElasticEnergy`] it makes the total
    /// mechanical energy, which only walls that move and the frame's acceleration can raise.
    PotentialEnergy,
    /// `max |∇·u|` over the cells.
    MaxDivergence,
    /// Maximum speed.
    MaxSpeed,
    /// Solid volume `∫φ_s dV` (per radian in axisymmetric geometry); column `solid_volume`.
    SolidVolume,
    /// Solid centroid `∫φ_s x dV / ∫φ_s dV`; columns `solid_x`, `solid_y`.
    SolidCentroid,
    /// Volume-weighted solid velocity `∫φ_s u dV / ∫φ_s dV`; columns `solid_u`, `solid_v`.
    SolidVelocity,
    /// Elastic (strain) energy stored in the solid, `∫ W(B̃) dV` from the law (per radian in
    /// axisymmetric geometry); column `elastic_energy`. Needs a solid with a law.
    ElasticEnergy,
    /// The normal force the solid presses on a wall with: `∫ (p − p_a − τ_nn) dA` over the
    /// wall's *contact cells*, per radian in axisymmetric geometry (×2π for the whole body);
    /// column `contact_force`. A contact cell is a cell of the first row along the wall that
    /// holds a solid fraction φ ≥ 1e-3 (the elastic stage's threshold: a cell holding less
    /// carries no deformation) and presses on the wall, `p − p_a − τ_nn > 0` — `p_a` the mean
    /// pressure of the row's other cells, `τ_nn` the elastic normal stress (the viscous one
    /// vanishes on a no-slip wall). The criterion is absolute: a trace of solid (φ ≈ 1e-18)
    /// left by the interface advection is no contact, and without a contact cell — before
    /// touch-down, after lift-off — the probe is exactly 0. A body pressed on a no-slip wall
    /// keeps a thin air film, thinner than a cell, under it: the film carries the load, so a
    /// partly filled cell counts.
    ContactForce {
        /// The wall (`YMin` is the substrate z = z_min in axisymmetric scenes).
        wall: Side,
    },
    /// The radius (half-width in planar geometry) of the loaded footprint on a wall: the
    /// distance along the wall from its start to the outer edge of the last contact cell (as
    /// defined at [`ProbeSpec::ContactForce`]: φ ≥ 1e-3 and pressing on the wall); exactly 0
    /// without one. Column `contact_radius`.
    ContactRadius {
        /// The wall.
        wall: Side,
    },
    /// The solid's extent along the vertical line `x = at` (the axis in axisymmetric scenes):
    /// the bottom and top of its longest run of cells holding solid, each placed by the end
    /// cell's solid fraction (a height function). Columns `solid_bottom`, `solid_top`.
    SolidExtent {
        /// The line's abscissa.
        at: f64,
    },
    /// Whether the solid stays in one piece: the cells holding more than 1e-3 of solid, joined
    /// through their faces, form connected regions; column `solid_pieces` counts the regions
    /// holding more than 1e-3 of the solid volume (smaller ones are VOF flotsam), and
    /// `solid_largest_piece` is the largest region's share of the solid volume (1 for a solid
    /// in one piece). Periodic sides are not wrapped: a solid crossing one counts as two.
    SolidPieces,
}

impl ProbeSpec {
    /// The probe's column names in `probes.csv`, in order.
    pub fn columns(&self) -> Vec<String> {
        match self {
            ProbeSpec::Point { name, .. } => vec![name.clone()],
            ProbeSpec::KineticEnergy => vec!["kinetic_energy".into()],
            ProbeSpec::PotentialEnergy => vec!["potential_energy".into()],
            ProbeSpec::MaxDivergence => vec!["max_divergence".into()],
            ProbeSpec::MaxSpeed => vec!["max_speed".into()],
            ProbeSpec::SolidVolume => vec!["solid_volume".into()],
            ProbeSpec::SolidCentroid => vec!["solid_x".into(), "solid_y".into()],
            ProbeSpec::SolidVelocity => vec!["solid_u".into(), "solid_v".into()],
            ProbeSpec::ElasticEnergy => vec!["elastic_energy".into()],
            ProbeSpec::ContactForce { .. } => vec!["contact_force".into()],
            ProbeSpec::ContactRadius { .. } => vec!["contact_radius".into()],
            ProbeSpec::SolidExtent { .. } => vec!["solid_bottom".into(), "solid_top".into()],
            ProbeSpec::SolidPieces => vec!["solid_pieces".into(), "solid_largest_piece".into()],
        }
    }

    /// Whether the probe needs a solid in the scene.
    pub fn needs_solid(&self) -> bool {
        matches!(
            self,
            ProbeSpec::SolidVolume
                | ProbeSpec::SolidCentroid
                | ProbeSpec::SolidVelocity
                | ProbeSpec::ElasticEnergy
                | ProbeSpec::ContactForce { .. }
                | ProbeSpec::ContactRadius { .. }
                | ProbeSpec::SolidExtent { .. }
                | ProbeSpec::SolidPieces
        )
    }
}

/// How deep values may nest in a scene file (RON's default, which keeps the reader off the
/// end of its stack).
pub const RECURSION_LIMIT: usize = 128;

/// The largest scene file read (4 MiB): a scene is a page of text; anything larger is not one.
pub const MAX_SCENE_BYTES: u64 = 4 << 20;

/// The most points a line profile may have: a 100 000-line CSV file per output time, finer
/// than any grid this solver runs (at most 1e4 cells across).
pub const MAX_PROFILE_POINTS: usize = 100_000;

/// A number for a message: plain where that is short, else in exponent form (`1e308`, not 309
/// digits).
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The largest diffusion number μ·time.end/(ρh²) a scene may reach (1e200): far beyond any
/// physical scene, and low enough that the viscous system's products stay finite.
pub const MAX_DIFFUSION_NUMBER: f64 = 1e200;

/// Field names that probes and profiles can sample.
pub const FIELD_NAMES: &[&str] = &[
    "u",
    "v",
    "p",
    "speed",
    "density",
    "viscosity",
    "solid_fraction",
];

/// A line profile: fields sampled at evenly spaced points of a segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ProfileSpec {
    /// The segment `from → to`.
    Line {
        /// File stem.
        name: String,
        /// Start point.
        from: (f64, f64),
        /// End point.
        to: (f64, f64),
        /// Number of points (≥ 2), both ends included.
        points: usize,
        /// Fields to sample (see [`FIELD_NAMES`]).
        fields: Vec<String>,
        /// Times at which to write it (default: only at the end of the run).
        #[serde(default)]
        at: Vec<f64>,
    },
}

impl ProfileSpec {
    /// The file stem.
    pub fn name(&self) -> &str {
        match self {
            ProfileSpec::Line { name, .. } => name,
        }
    }
}

impl Scene {
    /// Read and validate a scene file (with overrides: [`Scene::load_with`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::load_with(path, &[])
    }

    /// Parse and validate scene text; `path` is used in error messages only.
    pub fn from_str_at(text: &str, path: &Path) -> Result<Scene, SceneError> {
        Scene::from_str_with(text, path, &[])
    }

    /// Parse scene text without validating it (syntax and types only).
    pub(crate) fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let opts = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        // A byte-order mark some editors put first is not part of the scene.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut scene: Scene = opts.from_str(text).map_err(|e| SceneError::Syntax {
            path: path.to_path_buf(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: match e.code {
                ron::Error::ExceededRecursionLimit => format!(
                    "nested deeper than the scene reader allows ({RECURSION_LIMIT} levels): \
                     flatten the shape (e.g. one Union of many shapes rather than Unions of Unions)"
                ),
                code => code.to_string(),
            },
        })?;
        scene.numerics.apply_preset();
        Ok(scene)
    }

    /// The scene as RON text (what `run.json` and checkpoints record).
    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = r#"Scene(
        name: "t",
        domain: (x: (0.0, 1.0), y: (0.0, 1.0)),
        grid: (nx: 8, ny: 8),
        time: (end: 1.0),
        fluid: (density: 1.0, viscosity: 0.01),
        boundaries: (x_min: NoSlip, x_max: NoSlip, y_min: NoSlip, y_max: MovingWall(speed: 1.0)),
    )"#;

    fn load(s: &str) -> Result<Scene, SceneError> {
        Scene::from_str_at(s, Path::new("scene.ron"))
    }

    #[test]
    fn minimal_scene_loads_with_defaults() {
        let s = load(MIN).unwrap();
        assert_eq!(s.time.cfl, 0.4);
        assert!(s.physics.advection);
        assert_eq!(s.numerics.projection.tolerance, 1e-6);
        assert_eq!(s.numerics.projection.solver, PressureSolver::Multigrid);
    }

    /// `numerics.preset: Strict` tightens every tolerance to its strict value, keeps a tighter
    /// one set beside it, survives the round trip through RON, and `Default` changes nothing.
    #[test]
    fn strict_preset_tightens_each_tolerance() {
        let with = |n: &str| load(&MIN.replace("time:", &format!("numerics: {n}, time:"))).unwrap();
        let s = with("(preset: Strict)");
        let n = &s.numerics;
        assert_eq!(
            (
                n.projection.tolerance,
                n.viscous.tolerance,
                n.elastic.tolerance
            ),
            (1e-10, 1e-9, 1e-10)
        );
        let s =
            with("(preset: Strict, projection: (tolerance: 1e-12), viscous: (tolerance: 1e-3))");
        assert_eq!(s.numerics.projection.tolerance, 1e-12);
        assert_eq!(s.numerics.viscous.tolerance, 1e-9);
        let back = load(&s.to_ron()).unwrap();
        assert_eq!(back.numerics.preset, Preset::Strict);
        assert_eq!(back.numerics.projection.tolerance, 1e-12);
        let s = with("(preset: Default, viscous: (tolerance: 1e-3))");
        assert_eq!(s.numerics.viscous.tolerance, 1e-3);
        assert_eq!(s.numerics.projection.tolerance, 1e-6);
    }

    /// The elastic coupling: Split by default, Coupled by name (round trip); its tolerance,
    /// iteration cap and its need of the implicit step checked by field.
    #[test]
    fn elastic_coupling_is_a_scene_option_checked_by_field() {
        let with = |el: &str| {
            load(&MIN.replace(
                "time: (end: 1.0),",
                &format!("time: (end: 1.0), numerics: (elastic: {el}),"),
            ))
        };
        assert_eq!(
            load(MIN).unwrap().numerics.elastic.coupling,
            ElasticCoupling::Split
        );
        let s = with("(coupling: Coupled, coupling_tolerance: 1e-4)").unwrap();
        assert_eq!(s.numerics.elastic.coupling, ElasticCoupling::Coupled);
        assert_eq!(s.numerics.elastic.coupling_tolerance, 1e-4);
        assert_eq!(s.numerics.elastic.stretch_theta(), 0.75);
        assert_eq!(load(MIN).unwrap().numerics.elastic.stretch_theta(), 0.5);
        assert_eq!(
            with("(theta: 0.6)")
                .unwrap()
                .numerics
                .elastic
                .stretch_theta(),
            0.6
        );
        assert_eq!(
            load(&s.to_ron()).unwrap().numerics.elastic.coupling,
            ElasticCoupling::Coupled
        );
        for (el, needles) in [
            (
                "(coupling: Coupled, coupling_tolerance: 0.0)",
                &["numerics.elastic.coupling_tolerance", "(0, 1)"][..],
            ),
            (
                "(coupling_tolerance: 1.5)",
                &["numerics.elastic.coupling_tolerance"],
            ),
            (
                "(coupling: Coupled, coupling_iterations: 0)",
                &["numerics.elastic.coupling_iterations", "≥ 1"],
            ),
            (
                "(coupling: Coupled, implicit: false)",
                &["numerics.elastic.coupling", "implicit"],
            ),
            ("(theta: 0.4)", &["numerics.elastic.theta", "[0.5, 1]"]),
            ("(coupling: Monolithic)", &["Monolithic"]),
        ] {
            let e = with(el).unwrap_err().to_string();
            for n in needles {
                assert!(e.contains(n), "{el}: expected `{n}` in: {e}");
            }
        }
    }

    #[test]
    fn pressure_solver_is_a_scene_option() {
        let s = load(&MIN.replace(
            "time: (end: 1.0),",
            "time: (end: 1.0), numerics: (projection: (solver: IncompleteCholesky, tolerance: 1e-9)),",
        ))
        .unwrap();
        assert_eq!(
            s.numerics.projection.solver,
            PressureSolver::IncompleteCholesky
        );
        assert_eq!(s.numerics.projection.tolerance, 1e-9);
        let again = load(&s.to_ron()).unwrap();
        assert_eq!(
            again.numerics.projection.solver,
            PressureSolver::IncompleteCholesky
        );
        let e = load(&MIN.replace(
            "time: (end: 1.0),",
            "time: (end: 1.0), numerics: (projection: (solver: Jacobi)),",
        ))
        .unwrap_err();
        assert!(e.to_string().contains("Jacobi"), "{e}");
    }

    #[test]
    fn implicit_some_and_round_trip() {
        let s = load(&MIN.replace("end: 1.0", "end: 1.0, steady: 1e-6")).unwrap();
        assert_eq!(s.time.steady, Some(1e-6));
        let again = load(&s.to_ron()).unwrap();
        assert_eq!(again.time.steady, Some(1e-6));
    }

    #[test]
    fn unknown_field_names_line_and_column() {
        let e = load(&MIN.replace("density: 1.0,", "density: 1.0, colour: 3,")).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("scene.ron:6:"), "{msg}");
        assert!(msg.contains("colour"), "{msg}");
    }

    #[test]
    fn vtk_options_load_round_trip_and_are_checked_by_name() {
        let with = |vtk: &str| {
            load(&MIN.replace(
                "time: (end: 1.0),",
                &format!("time: (end: 1.0), output: (vtk_every: 0.5, vtk: {vtk}),"),
            ))
        };
        let s = with(r#"(fields: ["velocity", "pressure"], precision: Float32, compression: Zlib, point_data: true)"#)
            .unwrap();
        let v = &s.output.vtk;
        assert_eq!(
            v.fields.as_deref(),
            Some(&["velocity".to_string(), "pressure".to_string()][..])
        );
        assert_eq!(
            (v.precision, v.compression, v.point_data),
            (VtkPrecision::Float32, VtkCompression::Zlib, true)
        );
        assert_eq!(&load(&s.to_ron()).unwrap().output.vtk, v);
        // The defaults: every array, Float64, raw, cell data only.
        assert_eq!(load(MIN).unwrap().output.vtk, VtkOptions::default());
        for (vtk, needles) in [
            (
                r#"(fields: ["velocity", "temperature"])"#,
                &["output.vtk.fields[1]", "unknown field `temperature`"][..],
            ),
            (
                r#"(fields: ["pressure", "pressure"])"#,
                &["output.vtk.fields[1]", "listed twice"],
            ),
            (r#"(fields: [])"#, &["output.vtk.fields", "at least one"]),
            (
                r#"(fields: ["solid_fraction"])"#,
                &["output.vtk.fields[0]", "needs a solid"],
            ),
            (
                r#"(fields: ["B"])"#,
                &["output.vtk.fields[0]", "needs a solid with a law"],
            ),
            (r#"(precision: Float16)"#, &["Float16"]),
            (r#"(compression: Gzip)"#, &["Gzip"]),
        ] {
            let e = with(vtk).unwrap_err().to_string();
            for n in needles {
                assert!(e.contains(n), "{vtk}: expected `{n}` in: {e}");
            }
        }
    }

    #[test]
    fn sin2_ramp_matches_seed_eq26() {
        // Seed Eq. 26 on a 2-long lid: 0.5 sin²(πx/0.6) on [0, 0.3].
        let p = WallProfile::Sin2Ramp { width: 0.3 };
        let x: f64 = 0.1;
        assert!((p.factor(x, 2.0) - (std::f64::consts::PI * x / 0.6).sin().powi(2)).abs() < 1e-15);
        assert_eq!(p.factor(1.0, 2.0), 1.0);
        assert!(
            (p.factor(1.9, 2.0) - (std::f64::consts::PI * (1.9f64 - 2.0) / 0.6).sin().powi(2))
                .abs()
                < 1e-15
        );
    }
}
