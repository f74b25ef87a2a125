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
//! `nr`, `nz`, `r_min`, `r_max`, `z_min`, `z_max` are accepted.
//!
//! # Three dimensions
//!
//! `geometry: Cartesian3D` is a box in x, y and z: `domain: (x: …, y: …, z: …)`,
//! `grid: (nx: …, ny: …, nz: …)`, six `boundaries` (`x_min` … `z_max`) and `gravity: (gx, gy,
//! gz)`. There `z`, `nz`, `z_min` and `z_max` name the third axis; in a two-dimensional scene
//! they are the axisymmetric spellings of `y`, `ny`, `y_min` and `y_max`, allowed only where
//! the `y` key itself is not written. A scene that mixes the two readings is refused, naming
//! the key: a two-dimensional scene with a third axis (`z` beside `y`, `nz` beside `ny`,
//! `z_min` beside `y_min`, a third gravity component), and a Cartesian3D scene without one
//! (no `z`, `nz`, `z_min` or `z_max`, two gravity components) or with the axisymmetric
//! spellings `r`, `nr`, `r_min`, `r_max` ([`Scene::validate`]).

use crate::grid::Geometry;
pub use numerics::{Numerics, OptionsDecl, Preset, StageOptions};
pub use section::Section;
pub use typed::Options;

pub mod bodies;
mod numerics;
mod section;
mod shape;
pub mod solid;
mod typed;
pub mod options {
    //! What a stage plugin needs to declare its `numerics` section.
    pub use super::numerics::{OptionsDecl, Preset, StageOptions, check_sections};
    pub use super::typed::Options;
    pub use crate::validate::{Checked, check_iterations, check_tolerance};
}
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
    /// An override ([`crate::overrides`]: `efsi run --set`, `--refine`, `Scene::set`) that
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
    /// Gravity (acceleration vector; default zero): `(gx, gy)` in two dimensions, `(gx, gy,
    /// gz)` in Cartesian3D. In axisymmetric geometry it must be along z.
    #[serde(default)]
    pub gravity: Vector,
    /// Initial velocity of the fluid (default at rest).
    #[serde(default)]
    pub initial_velocity: InitialVelocity,
    /// The solid, if any: its shape at t = 0 and its material (one material; several bodies
    /// are a `Union` of shapes). A [`Section`], read as a [`solid::Solid`]
    /// ([`solid::SceneSolid`]).
    #[serde(default)]
    pub solid: Option<Section>,
    /// Several named bodies ([`bodies`]); a scene writes `solid` or `solids`, not both.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solids: Option<Section>,
    /// Boundary conditions per side.
    pub boundaries: Boundaries,
    /// Physics switches that cannot be inferred.
    #[serde(default)]
    pub physics: Physics,
    /// Numerical parameters of the solvers.
    #[serde(default)]
    pub numerics: Numerics,
    /// What a run writes and where: a [`Section`] whose type and checks the run crate owns
    /// (`efsi-run`'s `OutputSpec`).
    #[serde(default)]
    pub output: Section,
    /// The folder of the scene file (set by `efsi_run::SceneOverrides::load`; relative law paths start
    /// there).
    #[serde(skip)]
    pub source_dir: Option<PathBuf>,
    /// The overrides applied to the file's settings, in order ([`crate::overrides`]; set by
    /// `efsi_run::SceneOverrides`): the scene is the file's with these applied.
    #[serde(skip)]
    pub overrides: Vec<crate::overrides::Override>,
}

fn default_geometry() -> Geometry {
    Geometry::Planar
}

/// Extents of the box. `x` is r and `y` is z in axisymmetric geometry; `z` is the third axis
/// of a Cartesian3D box (see the module's "Three dimensions").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "keys::Domain")]
pub struct Domain {
    /// `(min, max)` along x (r).
    pub x: (f64, f64),
    /// `(min, max)` along y (z in axisymmetric geometry).
    pub y: (f64, f64),
    /// `(min, max)` along the third axis z (Cartesian3D only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<(f64, f64)>,
    /// The axisymmetric spellings the file used (`r`, `z` for y), which a Cartesian3D scene
    /// refuses.
    #[serde(skip)]
    pub aliases: Vec<&'static str>,
}

impl Domain {
    /// A two-dimensional box `x × y`.
    pub fn planar(x: (f64, f64), y: (f64, f64)) -> Self {
        Domain {
            x,
            y,
            z: None,
            aliases: Vec::new(),
        }
    }
}

/// Cell counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "keys::GridSpec")]
pub struct GridSpec {
    /// Cells along x (r).
    pub nx: usize,
    /// Cells along y (z in axisymmetric geometry).
    pub ny: usize,
    /// Cells along the third axis z (Cartesian3D only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nz: Option<usize>,
    /// The axisymmetric spellings the file used (`nr`, `nz` for ny).
    #[serde(skip)]
    pub aliases: Vec<&'static str>,
}

impl GridSpec {
    /// A two-dimensional grid of `nx × ny` cells.
    pub fn planar(nx: usize, ny: usize) -> Self {
        GridSpec {
            nx,
            ny,
            nz: None,
            aliases: Vec::new(),
        }
    }

    /// Cells along each axis, `[nx, ny, nz]` (`nz` = 1 in two dimensions).
    pub fn n(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz.unwrap_or(1)]
    }
}

/// A vector setting (gravity): two components `(x, y)` in a two-dimensional scene, three
/// `(x, y, z)` in a Cartesian3D one; the third is `None` where the file wrote two.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vector(pub f64, pub f64, pub Option<f64>);

impl Vector {
    /// The in-plane components `(x, y)`.
    pub fn planar(self) -> (f64, f64) {
        (self.0, self.1)
    }

    /// All three components, z = 0 where none was written.
    pub fn xyz(self) -> [f64; 3] {
        [self.0, self.1, self.2.unwrap_or(0.0)]
    }

    /// The Euclidean length.
    pub fn norm(self) -> f64 {
        let [a, b, c] = self.xyz();
        a.hypot(b).hypot(c)
    }
}

impl From<(f64, f64)> for Vector {
    fn from((x, y): (f64, f64)) -> Self {
        Vector(x, y, None)
    }
}

/// A two-component vector equals `(x, y)` when its third component is absent or zero.
impl PartialEq<(f64, f64)> for Vector {
    fn eq(&self, other: &(f64, f64)) -> bool {
        self.2.unwrap_or(0.0) == 0.0 && (self.0, self.1) == *other
    }
}

impl Serialize for Vector {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(if self.2.is_some() { 3 } else { 2 })?;
        t.serialize_element(&self.0)?;
        t.serialize_element(&self.1)?;
        if let Some(z) = self.2 {
            t.serialize_element(&z)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Vector {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Vector;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a vector of two (x, y) or three (x, y, z) numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<Vector, A::Error> {
                use serde::de::Error;
                let x = a
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(0, &self))?;
                let y = a
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(1, &self))?;
                let z = a.next_element()?;
                if a.next_element::<f64>()?.is_some() {
                    return Err(A::Error::invalid_length(4, &self));
                }
                Ok(Vector(x, y, z))
            }
        }
        d.deserialize_tuple(3, V)
    }
}

/// Time span and step control.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time (> 0).
    pub end: f64,
    /// Courant number on `Δt·(|u|/dx + |v|/dy)` (default 0.4, in (0, 1]; the advection scheme's
    /// sufficient TVD bound is 0.5, and the cavities reach their steady states up to 1.0).
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

    /// The shortest output or checkpoint interval: [`dt_min_or_default`](Self::dt_min_or_default)
    /// (a shorter interval would force shorter steps), and at least `end /`
    /// [`MAX_EVENTS`]: a run has at most that many events of one kind, so that an event's time
    /// `n·interval` is exact in `f64` and its count fits in any integer the run keeps — a
    /// `dt_min` set far below the default must not let an interval of 1e-300 ask for 1e300
    /// outputs.
    pub fn shortest_interval(&self) -> f64 {
        self.dt_min_or_default().max(self.end / MAX_EVENTS)
    }
}

/// The most outputs (or checkpoints) of one kind a run may schedule over `time.end`: output and
/// checkpoint intervals are at least `time.end / MAX_EVENTS` ([`TimeSpec::shortest_interval`]).
pub const MAX_EVENTS: f64 = 1e12;

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

/// One of the sides of the box: four in two dimensions, six in three.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// x = x_min (r = r_min).
    #[serde(alias = "RMin")]
    XMin,
    /// x = x_max.
    #[serde(alias = "RMax")]
    XMax,
    /// y = y_min.
    YMin,
    /// y = y_max.
    YMax,
    /// z = z_min (Cartesian3D).
    ZMin,
    /// z = z_max (Cartesian3D).
    ZMax,
}

impl Side {
    /// The four sides of a two-dimensional box, in the order x_min, x_max, y_min, y_max.
    pub const ALL: [Side; 4] = [Side::XMin, Side::XMax, Side::YMin, Side::YMax];

    /// The six sides of a three-dimensional box: [`Side::ALL`], then z_min, z_max.
    pub const ALL3: [Side; 6] = [
        Side::XMin,
        Side::XMax,
        Side::YMin,
        Side::YMax,
        Side::ZMin,
        Side::ZMax,
    ];

    /// The sides of a box with `dims` axes (2 or 3): [`Side::ALL`] or [`Side::ALL3`].
    pub fn of(dims: usize) -> &'static [Side] {
        if dims == 3 { &Side::ALL3 } else { &Side::ALL }
    }

    /// The side normal to `axis` (0, 1, 2) at its lower (`hi = false`) or upper end.
    pub fn normal_to(axis: usize, hi: bool) -> Side {
        Side::ALL3[2 * axis + hi as usize]
    }

    /// The axis this side is normal to (0 for x, 1 for y, 2 for z).
    pub fn axis(self) -> usize {
        self as usize / 2
    }

    /// Whether this is the upper side along its axis.
    pub fn is_upper(self) -> bool {
        self as usize % 2 == 1
    }

    /// The scene field name of this side.
    pub fn field_name(self) -> &'static str {
        match self {
            Side::XMin => "x_min",
            Side::XMax => "x_max",
            Side::YMin => "y_min",
            Side::YMax => "y_max",
            Side::ZMin => "z_min",
            Side::ZMax => "z_max",
        }
    }

    /// The opposite side (the partner of a periodic pair).
    pub fn opposite(self) -> Side {
        Side::normal_to(self.axis(), !self.is_upper())
    }
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.field_name())
    }
}

/// Boundary conditions on the four sides of a two-dimensional box or the six of a
/// three-dimensional one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "keys::Boundaries")]
pub struct Boundaries {
    /// Side x = x_min (r_min; the axis when r_min = 0).
    pub x_min: Boundary,
    /// Side x = x_max.
    pub x_max: Boundary,
    /// Side y = y_min (z_min in axisymmetric geometry).
    pub y_min: Boundary,
    /// Side y = y_max.
    pub y_max: Boundary,
    /// Side z = z_min (Cartesian3D only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z_min: Option<Boundary>,
    /// Side z = z_max (Cartesian3D only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z_max: Option<Boundary>,
    /// The axisymmetric spellings the file used (`r_min`, `r_max`, and `z_min`/`z_max` for
    /// y_min/y_max).
    #[serde(skip)]
    pub aliases: Vec<&'static str>,
}

impl Boundaries {
    /// The four sides of a two-dimensional box.
    pub fn planar(x_min: Boundary, x_max: Boundary, y_min: Boundary, y_max: Boundary) -> Self {
        Boundaries {
            x_min,
            x_max,
            y_min,
            y_max,
            z_min: None,
            z_max: None,
            aliases: Vec::new(),
        }
    }

    /// The condition on `side`, if the scene has that side (the z sides exist in Cartesian3D
    /// only).
    pub fn side(&self, side: Side) -> Option<&Boundary> {
        match side {
            Side::XMin => Some(&self.x_min),
            Side::XMax => Some(&self.x_max),
            Side::YMin => Some(&self.y_min),
            Side::YMax => Some(&self.y_max),
            Side::ZMin => self.z_min.as_ref(),
            Side::ZMax => self.z_max.as_ref(),
        }
    }

    /// The condition on `side`.
    ///
    /// # Panics
    ///
    /// On a z side the scene does not have (a two-dimensional scene: iterate
    /// [`Side::of`] the grid's dimensions, or use [`side`](Self::side)).
    pub fn get(&self, side: Side) -> &Boundary {
        self.side(side)
            .unwrap_or_else(|| panic!("boundaries.{side}: a two-dimensional scene has no z sides"))
    }
}

/// The scene's keys as written, before they are read by geometry: the axisymmetric spellings
/// and the third axis share `z`, `nz`, `z_min`, `z_max`.
mod keys {
    use super::Boundary;
    use serde::Deserialize;

    /// `x` or `r`, and the spellings used.
    fn either<T>(
        a: Option<T>,
        b: Option<T>,
        names: [&'static str; 2],
        aliases: &mut Vec<&'static str>,
    ) -> Result<T, String> {
        match (a, b) {
            (Some(a), None) => Ok(a),
            (None, Some(b)) => {
                aliases.push(names[1]);
                Ok(b)
            }
            (Some(_), Some(_)) => Err(format!(
                "`{}` and its axisymmetric spelling `{}` are both given: write one",
                names[0], names[1]
            )),
            (None, None) => Err(format!("missing field `{}`", names[0])),
        }
    }

    /// `y` or, where `y` is not written, `z` read as its axisymmetric spelling; else `z` is
    /// the third axis.
    fn second<T>(
        y: Option<T>,
        z: Option<T>,
        names: [&'static str; 2],
        aliases: &mut Vec<&'static str>,
    ) -> Result<(T, Option<T>), String> {
        match (y, z) {
            (Some(y), z) => Ok((y, z)),
            (None, Some(z)) => {
                aliases.push(names[1]);
                Ok((z, None))
            }
            (None, None) => Err(format!("missing field `{}`", names[0])),
        }
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Domain {
        x: Option<(f64, f64)>,
        r: Option<(f64, f64)>,
        y: Option<(f64, f64)>,
        z: Option<(f64, f64)>,
    }

    impl TryFrom<Domain> for super::Domain {
        type Error = String;
        fn try_from(k: Domain) -> Result<Self, String> {
            let mut aliases = Vec::new();
            let x = either(k.x, k.r, ["x", "r"], &mut aliases)?;
            let (y, z) = second(k.y, k.z, ["y", "z"], &mut aliases)?;
            Ok(super::Domain { x, y, z, aliases })
        }
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct GridSpec {
        nx: Option<usize>,
        nr: Option<usize>,
        ny: Option<usize>,
        nz: Option<usize>,
    }

    impl TryFrom<GridSpec> for super::GridSpec {
        type Error = String;
        fn try_from(k: GridSpec) -> Result<Self, String> {
            let mut aliases = Vec::new();
            let nx = either(k.nx, k.nr, ["nx", "nr"], &mut aliases)?;
            let (ny, nz) = second(k.ny, k.nz, ["ny", "nz"], &mut aliases)?;
            Ok(super::GridSpec {
                nx,
                ny,
                nz,
                aliases,
            })
        }
    }

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Boundaries {
        x_min: Option<Boundary>,
        r_min: Option<Boundary>,
        x_max: Option<Boundary>,
        r_max: Option<Boundary>,
        y_min: Option<Boundary>,
        y_max: Option<Boundary>,
        z_min: Option<Boundary>,
        z_max: Option<Boundary>,
    }

    impl TryFrom<Boundaries> for super::Boundaries {
        type Error = String;
        fn try_from(k: Boundaries) -> Result<Self, String> {
            let mut aliases = Vec::new();
            let x_min = either(k.x_min, k.r_min, ["x_min", "r_min"], &mut aliases)?;
            let x_max = either(k.x_max, k.r_max, ["x_max", "r_max"], &mut aliases)?;
            let (y_min, z_min) = second(k.y_min, k.z_min, ["y_min", "z_min"], &mut aliases)?;
            let (y_max, z_max) = second(k.y_max, k.z_max, ["y_max", "z_max"], &mut aliases)?;
            Ok(super::Boundaries {
                x_min,
                x_max,
                y_min,
                y_max,
                z_min,
                z_max,
                aliases,
            })
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
        /// Peak tangential speed (m/s), along +x on y- and z-sides and +y on x-sides (the
        /// other tangential component is zero, as at a fixed wall), or along `direction`.
        speed: f64,
        /// Shape along the wall (default uniform).
        #[serde(default)]
        profile: WallProfile,
        /// Dependence on time (default steady).
        #[serde(default)]
        motion: WallMotion,
        /// The direction of the motion in the wall's plane, `(x, y, z)` (normalised; its
        /// component normal to the wall zero, and `z` zero in two dimensions). Default: the
        /// axis `speed` is along. Each tangential component is `speed` times its share.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        direction: Option<(f64, f64, f64)>,
    },
    /// Impermeable wall without friction: zero normal velocity and zero tangential stress.
    FreeSlip,
    /// A mirror plane: zero normal velocity, zero normal gradient of the tangential velocity
    /// and of every cell scalar (the pressure included) — the ghost rule of
    /// [`Boundary::FreeSlip`], named for a plane of symmetry of the flow. Any side, any
    /// geometry.
    Symmetry,
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

/// How deep values may nest in a scene file (RON's default, which keeps the reader off the
/// end of its stack).
pub const RECURSION_LIMIT: usize = 128;

/// A number for a message: plain where that is short, else in exponent form (`1e308`, not 309
/// digits).
pub fn num(v: f64) -> String {
    efsi_ron_edit::number(v)
}

/// The largest diffusion number μ·time.end/(ρh²) a scene may reach (1e200): far beyond any
/// physical scene, and low enough that the viscous system's products stay finite.
pub const MAX_DIFFUSION_NUMBER: f64 = 1e200;

impl Scene {
    /// Parse and validate scene text; `path` is used in error messages only.
    pub fn from_str_at(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let scene = Scene::parse(text, path)?;
        scene
            .validate()
            .map_err(|(field, message)| crate::overrides::attribute(path, &[], field, message))?;
        Ok(scene)
    }

    /// Parse scene text without validating it (syntax and types only).
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
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
        scene.locate_sections_in(text);
        Ok(scene)
    }

    /// Record where the opaque sections ([`Section`]) start in `text`, the file the scene was
    /// read from (no position where an override rewrote one).
    pub fn locate_sections_in(&mut self, text: &str) {
        self.numerics.locate_in(text);
        self.output.locate_in(text);
        for solid in [&mut self.solid, &mut self.solids].into_iter().flatten() {
            solid.locate_in(text);
        }
    }

    /// The scene as RON text (what `run.json` and checkpoints record).
    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests;
