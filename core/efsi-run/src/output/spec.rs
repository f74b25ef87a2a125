//! The scene's `output` section: what a run writes and where — VTK fields, probes and profiles
//! — and its checks.
//!
//! The core keeps the section as RON text it does not read ([`efsi_core::scene::Section`]);
//! this crate owns its type ([`OutputSpec`]) and checks it: [`crate::simulation`] builds a
//! simulation and checks the section against the scene and the scheduled stages' outputs
//! (every failure naming the setting's path, or the override that set it), then keeps the
//! settings in force in the scene, so that checkpoints record its defaults too. Code reads and
//! changes it through [`SceneOutput`].

use efsi_core::Geometry;
use efsi_core::error::EfsiError;
use efsi_core::scene::bodies::SceneBodies;
use efsi_core::scene::solid::Axis;
use efsi_core::scene::{MAX_EVENTS, Scene, Section, Side, TimeSpec, Vector, num};
use efsi_core::validate::{Checked, err, positive};
use efsi_core::{OutputKind, Pipeline};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

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
    /// Plane slices of a Cartesian3D run, written to `slices/<name>_<step>.vtr` with their
    /// collection `slices/<name>.pvd`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slices: Vec<SliceSpec>,
}

/// A plane slice of a Cartesian3D run (`output.slices`): the plane `x_normal = at`, its cells
/// the grid's in-plane cells, each array of the VTK files interpolated to it
/// ([`crate::output::slice`]), written as a `.vtr` file of the plane (flat along the normal)
/// every `every` of simulated time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SliceSpec {
    /// File stem (default: the normal's letter and the position, e.g. `z0.5`).
    #[serde(default)]
    pub name: Option<String>,
    /// The axis the plane is normal to.
    pub normal: Axis,
    /// The plane's position along the normal, inside the box.
    pub at: f64,
    /// Write it every this much simulated time (and at the start and end); default
    /// `output.vtk_every`; without either, at the start and the end only.
    #[serde(default)]
    pub every: Option<f64>,
    /// The arrays (names of `output.vtk.fields`); default: every array the VTK files hold.
    #[serde(default)]
    pub fields: Option<Vec<String>>,
}

impl SliceSpec {
    /// The file stem: `name`, or the normal's letter and the position (`z0.5`).
    pub fn stem(&self) -> String {
        self.name.clone().unwrap_or_else(|| {
            format!(
                "{}{}",
                crate::output::slice::axis_name(self.normal.index()),
                num(self.at)
            )
        })
    }

    /// Its interval: `every`, else `output.vtk_every` (`vtk_every`).
    pub fn interval(&self, vtk_every: Option<f64>) -> Option<f64> {
        self.every.or(vtk_every)
    }
}

/// The arrays of the shared fields a VTK file can hold, by name (`output.vtk.fields`):
/// `velocity`, `pressure`, `density`, `viscosity`, `divergence` always; `solid_fraction` with a
/// solid. The scheduled stages add theirs ([`efsi_core::StagePlugin::outputs`]: the elastic stage's
/// `B` and `stress`). `docs/outputs.md` documents each one's location, components, meaning
/// and unit.
pub const VTK_FIELDS: &[&str] = &[
    "velocity",
    "pressure",
    "density",
    "viscosity",
    "divergence",
    "solid_fraction",
];

/// How the VTK field files are written (`output.vtk`); the defaults write every array as
/// `Float64` cell data, uncompressed (bit-exact values).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VtkOptions {
    /// The arrays to write, by name (see [`VTK_FIELDS`], and the stages' arrays); default:
    /// every array the scene has.
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
    /// A field sampled at a point (bilinear interpolation; trilinear in three dimensions).
    Point {
        /// Column name.
        name: String,
        /// Field name (see [`FIELD_NAMES`], and the stages' fields).
        field: String,
        /// Position: `(x, y)`, or `(x, y, z)` in a Cartesian3D scene.
        at: Vector,
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
    /// axisymmetric geometry); column `elastic_energy`. Needs a solid with a law (a body with
    /// one, among several). In a scene of several bodies, each body's own
    /// (`<body>.elastic_energy`; 0 for a body without a law).
    ElasticEnergy,
    /// The normal force the solid presses on a wall with: `∫ (p − p_a − τ_nn) dA` over the
    /// wall's *contact cells*, per radian in axisymmetric geometry (×2π for the whole body);
    /// column `contact_force`. A contact cell is a cell of the first row (layer, in a
    /// Cartesian3D scene, on any of its six sides) along the wall that holds a solid fraction
    /// φ ≥ 1e-3 (the elastic stage's threshold: a cell holding less carries no deformation)
    /// and presses on the wall, `p − p_a − τ_nn > 0` — `p_a` the mean pressure of the row's
    /// other cells, `τ_nn` the elastic normal stress (0 for a solid without a law; the viscous
    /// one vanishes on a no-slip wall). The criterion is absolute: a trace of solid
    /// (φ ≈ 1e-18) left by the interface advection is no contact, and without a contact cell — before
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
    /// without one. In a Cartesian3D scene, how far the contact cells reach from the wall's
    /// corner (the lower end of both axes along it: the axis of a body on a quarter of the box
    /// between two symmetry planes), each cell's farthest point along the direction from the
    /// corner to its centre. Column `contact_radius`.
    ContactRadius {
        /// The wall.
        wall: Side,
    },
    /// The solid's extent along the vertical line `x = at` (the axis in axisymmetric scenes;
    /// the line `x = at`, `z = z` along y in a Cartesian3D scene): the bottom and top of its
    /// longest run of cells holding solid, each placed by the end cell's solid fraction (a
    /// height function). Columns `solid_bottom`, `solid_top`.
    SolidExtent {
        /// The line's abscissa.
        at: f64,
        /// The line's z, in a Cartesian3D scene only (where it is required).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        z: Option<f64>,
    },
    /// Whether the solid stays in one piece: the cells holding more than 1e-3 of solid, joined
    /// through their faces, form connected regions; column `solid_pieces` counts the regions
    /// holding more than 1e-3 of the solid volume (smaller ones are VOF flotsam), and
    /// `solid_largest_piece` is the largest region's share of the solid volume (1 for a solid
    /// in one piece). Periodic sides are not wrapped: a solid crossing one counts as two.
    SolidPieces,
    /// The solid's angular velocity: the rigid rotation about its centroid that fits its
    /// velocity best in the least-squares sense (`I ω = ∫φ r × u dV`, `I` the solid's inertia
    /// tensor about the centroid per unit density; exact for a rigid rotation). Column
    /// `solid_spin` (ω about z) in a planar scene, `solid_spin_x`, `solid_spin_y`,
    /// `solid_spin_z` in a Cartesian3D one; refused in an axisymmetric scene, whose bodies
    /// turn about no out-of-plane axis.
    SolidSpin,
    /// Whether bodies overlap: column `max_solid_fraction_sum`, the largest solid fraction of a
    /// cell, `max Σ_k φ_k` over the bodies' fractions (at most 1 while no two bodies overlap; the
    /// largest φ for one body), and `solid_overlap_volume`, the volume in excess of full cells,
    /// `∫ max(0, Σ_k φ_k − 1) dV` (0 while none overlap). Of the whole scene.
    SolidOverlap,
    /// Whether two bodies of a scene of several meet: for each pair `(a, b)` in the scene's
    /// order (`a` listed before `b`), `a.b.shared_volume`, `∫ min(φ_a, φ_b) dV` (0 while a cell
    /// of fluid, at least, parts them), and `a.b.shared_cells`, the number of cells where both
    /// fractions exceed 1e-3. Needs a scene of two bodies or more.
    BodyContact,
    /// A quantity by name: the framework's ([`crate::probes::QUANTITIES`]: the variants above
    /// that take no argument, by their column's name, `solid_centroid`, `solid_velocity`,
    /// `solid_pieces` and `solid_spin` for the ones of several columns) or one a scheduled stage reports
    /// ([`efsi_core::StagePlugin::outputs`]: `elastic_energy`), whose column is named after it.
    Quantity(String),
}

impl ProbeSpec {
    /// The name of the quantity the probe reports, for a probe of a quantity (every variant
    /// but `Point`, `ContactForce`, `ContactRadius` and `SolidExtent`, which take arguments):
    /// the framework's ([`crate::probes::QUANTITIES`]) or a stage's, found by this name.
    pub fn quantity(&self) -> Option<&str> {
        Some(match self {
            ProbeSpec::KineticEnergy => "kinetic_energy",
            ProbeSpec::PotentialEnergy => "potential_energy",
            ProbeSpec::MaxDivergence => "max_divergence",
            ProbeSpec::MaxSpeed => "max_speed",
            ProbeSpec::SolidVolume => "solid_volume",
            ProbeSpec::SolidCentroid => "solid_centroid",
            ProbeSpec::SolidVelocity => "solid_velocity",
            ProbeSpec::ElasticEnergy => "elastic_energy",
            ProbeSpec::SolidPieces => "solid_pieces",
            ProbeSpec::SolidSpin => "solid_spin",
            ProbeSpec::SolidOverlap => "solid_overlap",
            ProbeSpec::Quantity(name) => name,
            ProbeSpec::BodyContact
            | ProbeSpec::Point { .. }
            | ProbeSpec::ContactForce { .. }
            | ProbeSpec::ContactRadius { .. }
            | ProbeSpec::SolidExtent { .. } => return None,
        })
    }

    /// The probe's column names in `probes.csv` of a scene of `geometry`, in order: a
    /// quantity's columns (one named after a stage's quantity), or the probe's own.
    pub fn columns(&self, geometry: Geometry) -> Vec<String> {
        if let Some(name) = self.quantity() {
            return match crate::probes::framework_quantity(name) {
                Some(q) => q
                    .columns_in(geometry)
                    .iter()
                    .map(|c| c.to_string())
                    .collect(),
                None => vec![name.to_string()],
            };
        }
        match self {
            ProbeSpec::Point { name, .. } => vec![name.clone()],
            ProbeSpec::ContactForce { .. } => vec!["contact_force".into()],
            ProbeSpec::ContactRadius { .. } => vec!["contact_radius".into()],
            ProbeSpec::SolidExtent { .. } => vec!["solid_bottom".into(), "solid_top".into()],
            _ => Vec::new(),
        }
    }

    /// Whether the probe is a property of one body ([`crate::probes::evaluate`] evaluates it
    /// per body in a scene of several): the solid's volume, centroid, velocity, pieces, spin,
    /// contact force and radius, extent, and strain energy (`ElasticEnergy`: each body's own,
    /// 0 for a body without a law). Not the whole scene's quantities, nor another stage's, nor
    /// a point's value.
    pub fn per_body(&self) -> bool {
        match self {
            ProbeSpec::ElasticEnergy
            | ProbeSpec::ContactForce { .. }
            | ProbeSpec::ContactRadius { .. }
            | ProbeSpec::SolidExtent { .. } => true,
            p => p
                .quantity()
                .and_then(crate::probes::framework_quantity)
                .is_some_and(|q| q.per_body),
        }
    }

    /// The probe's column names in a scene of `geometry` whose bodies are named `bodies` (the
    /// `solids: [ … ]` list's names; none for the single `solid:`). **Naming:** a probe of one
    /// body ([`Self::per_body`]) has its [`columns`](Self::columns) once per body, each
    /// prefixed with the body's name and a dot, bodies in the scene's order
    /// (`light.solid_x, light.solid_y, heavy.solid_x, …`; `light.contact_force`); a
    /// [`ProbeSpec::BodyContact`] has `a.b.shared_volume, a.b.shared_cells` per pair;
    /// every other probe, and every probe of a scene of the single `solid:`, the unprefixed
    /// columns.
    pub fn columns_for(&self, geometry: Geometry, bodies: &[String]) -> Vec<String> {
        if *self == ProbeSpec::BodyContact {
            let mut out = Vec::new();
            for (k, a) in bodies.iter().enumerate() {
                for b in &bodies[k + 1..] {
                    out.push(format!("{a}.{b}.shared_volume"));
                    out.push(format!("{a}.{b}.shared_cells"));
                }
            }
            return out;
        }
        let own = self.columns(geometry);
        if bodies.is_empty() || !self.per_body() {
            return own;
        }
        bodies
            .iter()
            .flat_map(|b| own.iter().map(move |c| format!("{b}.{c}")))
            .collect()
    }

    /// Why the probe cannot run in a scene of `geometry`, if it cannot: a quantity without
    /// columns there (the spin in an axisymmetric scene). Every other probe runs in every
    /// geometry.
    pub fn refused_in(&self, geometry: Geometry) -> Option<&'static str> {
        self.quantity()
            .and_then(crate::probes::framework_quantity)
            .filter(|q| q.columns_in(geometry).is_empty())
            .map(|_| {
                "SolidSpin is the turn about an axis out of the plane, which an \
                 axisymmetric scene's bodies have not: it is refused there"
            })
    }

    /// Whether the probe needs a solid in the scene.
    pub fn needs_solid(&self) -> bool {
        match self {
            ProbeSpec::ElasticEnergy
            | ProbeSpec::BodyContact
            | ProbeSpec::ContactForce { .. }
            | ProbeSpec::ContactRadius { .. }
            | ProbeSpec::SolidExtent { .. } => true,
            p => p
                .quantity()
                .and_then(crate::probes::framework_quantity)
                .is_some_and(|q| q.needs_solid),
        }
    }
}

/// The most points a line profile may have: a 100 000-line CSV file per output time, finer
/// than any grid this solver runs (at most 1e4 cells across).
pub const MAX_PROFILE_POINTS: usize = 100_000;

/// The shared fields' names that probes and profiles can sample; the scheduled stages add
/// theirs ([`efsi_core::OutputKind::Field`]). `w`, the velocity along z, exists in Cartesian3D
/// scenes only.
pub const FIELD_NAMES: &[&str] = &[
    "u",
    "v",
    "w",
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
        /// Start point: `(x, y)`, or `(x, y, z)` in a Cartesian3D scene.
        from: Vector,
        /// End point, likewise.
        to: Vector,
        /// Number of points (≥ 2), both ends included.
        points: usize,
        /// Fields to sample (see [`FIELD_NAMES`], and the stages' fields).
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

    /// The times at which to write it, as the scene lists them (none: only at the end).
    pub fn times(&self) -> &[f64] {
        match self {
            ProfileSpec::Line { at, .. } => at,
        }
    }
}

/// A point as the scene writes it: `(x, y)` or `(x, y, z)`.
fn show(p: Vector) -> String {
    match p.2 {
        Some(z) => format!("({:?}, {:?}, {z:?})", p.0, p.1),
        None => format!("({:?}, {:?})", p.0, p.1),
    }
}

/// Reading and changing a scene's `output` section ([`OutputSpec`]).
pub trait SceneOutput {
    /// The section's settings, defaults filled in; on error the setting (`output`) and the
    /// reader's message (with the line and column in the scene file where known).
    fn output_spec(&self) -> Result<OutputSpec, (String, String)>;
    /// Replace the section by `spec`.
    fn set_output(&mut self, spec: &OutputSpec);
    /// Change the section in place: read it, apply `change`, write it back.
    fn update_output(&mut self, change: impl FnOnce(&mut OutputSpec)) -> Result<(), String> {
        let mut spec = self.output_spec().map_err(|(f, m)| format!("{f}: {m}"))?;
        change(&mut spec);
        self.set_output(&spec);
        Ok(())
    }
}

impl SceneOutput for Scene {
    fn output_spec(&self) -> Result<OutputSpec, (String, String)> {
        self.output.get().map_err(|m| ("output".to_string(), m))
    }

    fn set_output(&mut self, spec: &OutputSpec) {
        self.output = Section::of(spec).expect("the output section serialises to RON");
    }
}

/// Read the `output` section of `scene` (the scene read from `path`) and check it against the
/// scene and against the outputs `pipeline`'s stages provide; an error an override caused
/// names the override.
pub fn check(scene: &Scene, path: &Path, pipeline: &Pipeline) -> Result<OutputSpec, EfsiError> {
    let checked = scene.output_spec().and_then(|o| {
        validate(&o, scene)?;
        check_names(&o, pipeline)?;
        Ok(o)
    });
    checked.map_err(|(field, message)| {
        efsi_core::overrides::attribute(path, &scene.overrides, field, message).into()
    })
}

/// The `output` section of `scene` as JSON, what records hold: its settings, defaults filled
/// in (the section's RON text where it does not read as one).
pub fn json(scene: &Scene) -> serde_json::Value {
    match scene.output_spec() {
        Ok(o) => serde_json::to_value(o).unwrap_or_default(),
        Err(_) => serde_json::Value::String(scene.output.text().to_string()),
    }
}

/// Why `every` cannot be an interval of outputs or checkpoints in a run timed by `time`, if it
/// cannot: shorter than the smallest step (`time.dt_min`), or than `time.end /`
/// [`MAX_EVENTS`] ([`TimeSpec::shortest_interval`]).
pub fn interval(time: &TimeSpec, every: f64) -> Result<(), String> {
    let dt_min = time.dt_min_or_default();
    if every < dt_min {
        return Err(format!(
            "must be at least time.dt_min = {dt_min:e} (the smallest step; by default \
             1e-12·time.end), got {every:e}: shorter intervals would force shorter steps"
        ));
    }
    let floor = time.shortest_interval();
    if every < floor {
        return Err(format!(
            "must be at least time.end/{} = {}, got {}: a run has at most {} outputs of \
             one kind",
            num(MAX_EVENTS),
            num(floor),
            num(every),
            num(MAX_EVENTS)
        ));
    }
    Ok(())
}

/// The section's ranges and consistency with the scene: intervals, VTK options, probes and
/// profiles.
fn validate(o: &OutputSpec, scene: &Scene) -> Checked {
    validate_intervals_and_vtk(o, scene)?;
    let space = Space {
        scene,
        three: scene.geometry == Geometry::Cartesian3D,
    };
    validate_probes(o, scene, &space)?;
    validate_profiles(o, scene, &space)?;
    validate_slices(o, scene)
}

/// The output intervals and the VTK field list.
fn validate_intervals_and_vtk(o: &OutputSpec, scene: &Scene) -> Checked {
    for (f, v) in [
        ("output.vtk_every", o.vtk_every),
        ("output.probe_every", o.probe_every),
    ] {
        if let Some(v) = v {
            positive(f, v)?;
            interval(&scene.time, v).or_else(|m| err(f, m))?;
        }
    }
    if let Some(fields) = &o.vtk.fields {
        check_array_list("output.vtk.fields", fields, scene)?;
    }
    Ok(())
}

/// The scene's box, for the points probes and profiles name.
struct Space<'a> {
    scene: &'a Scene,
    /// Whether the scene is three-dimensional (points have three coordinates).
    three: bool,
}

impl Space<'_> {
    /// Whether `p` lies in the domain (z checked when both have one).
    fn inside(&self, p: Vector) -> bool {
        let d = &self.scene.domain;
        p.0 >= d.x.0
            && p.0 <= d.x.1
            && p.1 >= d.y.0
            && p.1 <= d.y.1
            && match (p.2, d.z) {
                (Some(z), Some((lo, hi))) => z >= lo && z <= hi,
                _ => true,
            }
    }

    /// A point has as many coordinates as the scene has axes; `f` names the field.
    fn dimension(&self, f: &str, p: Vector) -> Checked {
        match (self.three, p.2.is_some()) {
            (true, false) => err(
                f,
                format!(
                    "{} has two coordinates: a point of a Cartesian3D scene is (x, y, z)",
                    show(p)
                ),
            ),
            (false, true) => err(
                f,
                format!(
                    "{} has three coordinates: a point of a {:?} scene is (x, y)",
                    show(p),
                    self.scene.geometry
                ),
            ),
            _ => Ok(()),
        }
    }
}

/// The probes: each one the scene can evaluate, its columns named once, its points inside.
fn validate_probes(o: &OutputSpec, scene: &Scene, space: &Space<'_>) -> Checked {
    // Every column of probes.csv is named once, `t` first, and a name is one CSV field.
    let mut columns: std::collections::HashMap<String, usize> =
        [("t".to_string(), usize::MAX)].into_iter().collect();
    let bodies = crate::probes::body_names(scene);
    let has_law = scene
        .bodies_spec()
        .is_ok_and(|b| b.is_some_and(|b| b.list.iter().any(|b| b.solid.law.is_some())));
    for (k, probe) in o.probes.iter().enumerate() {
        let f = format!("output.probes[{k}]");
        if let Some(why) = probe.refused_in(scene.geometry) {
            return err(&f, why);
        }
        if probe.needs_solid() && !scene.has_bodies() {
            return err(
                &f,
                format!("{probe:?} needs a solid, and the scene has none"),
            );
        }
        if *probe == ProbeSpec::ElasticEnergy && !has_law {
            return err(
                &f,
                "ElasticEnergy needs a solid with a law (solid.law), and this solid has none",
            );
        }
        if let ProbeSpec::SolidExtent { at, z } = probe {
            solid_extent_line(&f, scene, *at, *z)?;
        }
        if *probe == ProbeSpec::BodyContact && bodies.len() < 2 {
            return err(
                &f,
                "BodyContact measures pairs of bodies: it needs a scene of two bodies or more \
                 (`solids: [ … ]`)",
            );
        }
        claim_columns(probe, scene.geometry, &bodies, k, &f, &mut columns)?;
        if let ProbeSpec::Point { field, at, .. } = probe {
            if field == "solid_fraction" && !scene.has_bodies() {
                return err(
                    &format!("{f}.field"),
                    "solid_fraction needs a solid, and the scene has none",
                );
            }
            if field == "w" && !space.three {
                return err(
                    &format!("{f}.field"),
                    "`w` is the velocity along z, which only a Cartesian3D scene has",
                );
            }
            space.dimension(&format!("{f}.at"), *at)?;
            if !space.inside(*at) {
                return err(
                    &format!("{f}.at"),
                    format!("{} is outside the domain", show(*at)),
                );
            }
        }
    }
    Ok(())
}

/// The line of a `SolidExtent` probe `f`: `x = at` inside the domain, and `z` given, inside,
/// in a Cartesian3D scene only.
fn solid_extent_line(f: &str, scene: &Scene, at: f64, z: Option<f64>) -> Checked {
    let inside = |v: f64, (lo, hi): (f64, f64)| v.is_finite() && v >= lo && v <= hi;
    let outside = |name: &str, v: f64, (lo, hi): (f64, f64)| {
        format!(
            "{name} = {} is outside the domain's [{}, {}]",
            num(v),
            num(lo),
            num(hi)
        )
    };
    if !inside(at, scene.domain.x) {
        return err(&format!("{f}.at"), outside("x", at, scene.domain.x));
    }
    match (
        z,
        scene
            .domain
            .z
            .filter(|_| scene.geometry == Geometry::Cartesian3D),
    ) {
        (None, Some(_)) => err(
            &format!("{f}.z"),
            "a Cartesian3D scene's line needs its z: SolidExtent(at: x, z: z)",
        ),
        (Some(_), None) => err(
            &format!("{f}.z"),
            format!(
                "a {:?} scene's line is x = at; z is for a Cartesian3D scene",
                scene.geometry
            ),
        ),
        (Some(z), Some(d)) if !inside(z, d) => err(&format!("{f}.z"), outside("z", z, d)),
        _ => Ok(()),
    }
}

/// Claim probe `k`'s columns of probes.csv in `columns` (column → the probe that has it,
/// `usize::MAX` for the time): each a CSV field, none already claimed. `f` names the probe.
fn claim_columns(
    probe: &ProbeSpec,
    geometry: Geometry,
    bodies: &[String],
    k: usize,
    f: &str,
    columns: &mut std::collections::HashMap<String, usize>,
) -> Checked {
    for c in probe.columns_for(geometry, bodies) {
        if c.is_empty() || c.contains([',', '"']) || c.chars().any(char::is_control) {
            return err(
                &format!("{f}.name"),
                format!(
                    "must be a non-empty CSV column name without commas, quotes or \
                     control characters, got {c:?}"
                ),
            );
        }
        if let Some(&other) = columns.get(&c) {
            let first = if other == usize::MAX {
                "the time column".to_string()
            } else {
                format!("output.probes[{other}]")
            };
            return err(
                f,
                format!(
                    "its column `{c}` is already {first}'s: every column of probes.csv needs its own name"
                ),
            );
        }
        columns.insert(c, k);
    }
    Ok(())
}

/// The profiles: unique names, point counts, segments inside the domain, fields, times.
fn validate_profiles(o: &OutputSpec, scene: &Scene, space: &Space<'_>) -> Checked {
    let mut pnames = std::collections::HashSet::new();
    for (k, prof) in o.profiles.iter().enumerate() {
        let ProfileSpec::Line {
            name,
            from,
            to,
            points,
            fields,
            at,
        } = prof;
        let f = format!("output.profiles[{k}]");
        if name.is_empty() || name.contains(['/', '\\']) || !pnames.insert(name.clone()) {
            return err(
                &format!("{f}.name"),
                format!("must be a unique file stem, got `{name}`"),
            );
        }
        if !(2..=MAX_PROFILE_POINTS).contains(points) {
            return err(
                &format!("{f}.points"),
                format!("must be in [2, {MAX_PROFILE_POINTS}], got {points}"),
            );
        }
        space.dimension(&format!("{f}.from"), *from)?;
        space.dimension(&format!("{f}.to"), *to)?;
        if !space.inside(*from) || !space.inside(*to) {
            return err(
                &f,
                format!("segment {} → {} leaves the domain", show(*from), show(*to)),
            );
        }
        for (j, field) in fields.iter().enumerate() {
            if field == "w" && !space.three {
                return err(
                    &format!("{f}.fields[{j}]"),
                    "`w` is the velocity along z, which only a Cartesian3D scene has",
                );
            }
            if field == "solid_fraction" && !scene.has_bodies() {
                return err(
                    &format!("{f}.fields"),
                    "solid_fraction needs a solid, and the scene has none",
                );
            }
            // Each is a column of the profile's CSV: a repeated one would repeat a header name.
            if fields[..j].contains(field) {
                return err(
                    &format!("{f}.fields[{j}]"),
                    format!("`{field}` is listed twice (each field is one column of the CSV)"),
                );
            }
        }
        if fields.is_empty() {
            return err(&format!("{f}.fields"), "must name at least one field");
        }
        for t in at {
            if !(t.is_finite() && *t >= 0.0 && *t <= scene.time.end) {
                return err(
                    &format!("{f}.at"),
                    format!("time {} is outside [0, time.end]", num(*t)),
                );
            }
        }
    }
    Ok(())
}

/// The plane slices: a Cartesian3D scene's, each plane inside the box, unique names, their
/// intervals and field lists.
fn validate_slices(o: &OutputSpec, scene: &Scene) -> Checked {
    let mut names = std::collections::HashSet::new();
    for (k, s) in o.slices.iter().enumerate() {
        let f = format!("output.slices[{k}]");
        let Some(z) = scene
            .domain
            .z
            .filter(|_| scene.geometry == Geometry::Cartesian3D)
        else {
            return err(
                &f,
                format!(
                    "a plane slice cuts a three-dimensional box, and this scene is {:?}: its \
                     VTK files (output.vtk_every) are its one plane already",
                    scene.geometry
                ),
            );
        };
        let d = &scene.domain;
        let a = s.normal.index();
        let (lo, hi) = [d.x, d.y, z][a];
        if !(s.at.is_finite() && s.at >= lo && s.at <= hi) {
            return err(
                &format!("{f}.at"),
                format!(
                    "{} = {} is outside the box's [{}, {}]",
                    crate::output::slice::axis_name(a),
                    num(s.at),
                    num(lo),
                    num(hi)
                ),
            );
        }
        let name = s.stem();
        if name.is_empty() || name.contains(['/', '\\']) || !names.insert(name.clone()) {
            return err(
                &format!("{f}.name"),
                format!("must be a unique file stem, got `{name}`"),
            );
        }
        if let Some(every) = s.every {
            positive(&format!("{f}.every"), every)?;
            interval(&scene.time, every).or_else(|m| err(&format!("{f}.every"), m))?;
        }
        if let Some(fields) = &s.fields {
            check_array_list(&format!("{f}.fields"), fields, scene)?;
        }
    }
    Ok(())
}

/// A list of VTK array names (`output.vtk.fields`, a slice's `fields`) named `at`: at least one,
/// each once, `solid_fraction` only with a solid (the names themselves are checked against the
/// stages by [`check_names`]).
fn check_array_list(at: &str, fields: &[String], scene: &Scene) -> Checked {
    if fields.is_empty() {
        return err(
            at,
            "must name at least one field (leave it out for all of them)",
        );
    }
    for (k, f) in fields.iter().enumerate() {
        let at = format!("{at}[{k}]");
        if fields[..k].contains(f) {
            return err(&at, format!("`{f}` is listed twice"));
        }
        if f == "solid_fraction" && !scene.has_bodies() {
            return err(
                &at,
                "`solid_fraction` needs a solid, and the scene has none",
            );
        }
    }
    Ok(())
}

/// The outputs the stages provide, checked once the pipeline is built: every array of `output.vtk.fields` is a shared field's
/// ([`VTK_FIELDS`]) or one a scheduled stage contributes, every field a `Point` probe or a
/// profile samples a shared one ([`FIELD_NAMES`]) or a stage's
/// ([`OutputKind::Field`]), every `Quantity` probe one a scheduled
/// stage reports; an unknown one is named with the ones there are.
fn check_names(o: &OutputSpec, pipeline: &Pipeline) -> Checked {
    let stage = |array: bool| {
        pipeline
            .outputs()
            .iter()
            .filter(move |o| o.is_array() == array)
            .map(|o| o.name)
    };
    let fields: Vec<&str> = FIELD_NAMES
        .iter()
        .copied()
        .chain(pipeline.outputs().iter().filter_map(|o| match o.kind {
            OutputKind::Field(_) => Some(o.name),
            _ => None,
        }))
        .collect();
    let sampled = |at: String, f: &String| {
        if fields.contains(&f.as_str()) {
            Ok(())
        } else {
            err(
                &at,
                format!("unknown field `{f}`: this scene's fields and stages provide {fields:?}"),
            )
        }
    };
    for (k, p) in o.probes.iter().enumerate() {
        if let ProbeSpec::Point { field, .. } = p {
            sampled(format!("output.probes[{k}].field"), field)?;
        }
    }
    for (k, ProfileSpec::Line { fields, .. }) in o.profiles.iter().enumerate() {
        for f in fields {
            sampled(format!("output.profiles[{k}].fields"), f)?;
        }
    }
    let arrays: Vec<&str> = VTK_FIELDS.iter().copied().chain(stage(true)).collect();
    let lists = std::iter::once(("output.vtk.fields".to_string(), &o.vtk.fields)).chain(
        o.slices
            .iter()
            .enumerate()
            .map(|(k, s)| (format!("output.slices[{k}].fields"), &s.fields)),
    );
    for (at, list) in lists {
        for (k, f) in list.iter().flatten().enumerate() {
            if !arrays.contains(&f.as_str()) {
                return err(
                    &format!("{at}[{k}]"),
                    format!(
                        "unknown field `{f}`: this scene's fields and stages provide {arrays:?}"
                    ),
                );
            }
        }
    }
    for (k, p) in o.probes.iter().enumerate() {
        if let ProbeSpec::Quantity(q) = p {
            let quantities: Vec<&str> = stage(false).collect();
            let framework = crate::probes::framework_quantity(q).is_some();
            if !framework && !quantities.contains(&q.as_str()) {
                return err(
                    &format!("output.probes[{k}]"),
                    if quantities.is_empty() {
                        format!("unknown quantity `{q}`: no stage of this scene reports one")
                    } else {
                        format!("unknown quantity `{q}`: this scene's stages report {quantities:?}")
                    },
                );
            }
        }
    }
    Ok(())
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

    /// Plane slices: a Cartesian3D scene's, inside the box, with unique names and valid field
    /// lists; each refusal names the setting.
    #[test]
    fn slices_are_checked_by_name() {
        let cube = MIN
            .replace(
                "domain: (x: (0.0, 1.0), y: (0.0, 1.0)),",
                "geometry: Cartesian3D, domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (-1.0, 2.0)),",
            )
            .replace("grid: (nx: 8, ny: 8),", "grid: (nx: 8, ny: 8, nz: 8),")
            .replace(
                "y_max: MovingWall(speed: 1.0)",
                "y_max: MovingWall(speed: 1.0), z_min: NoSlip, z_max: NoSlip",
            );
        let with = |base: &str, slices: &str| {
            let text = base.replace(
                "time: (end: 1.0),",
                &format!("time: (end: 1.0), output: (vtk_every: 0.5, slices: {slices}),"),
            );
            let scene = Scene::from_str_at(&text, Path::new("scene.ron")).unwrap();
            let o = scene.output_spec()?;
            validate(&o, &scene).map(|()| o)
        };
        let o = with(&cube, "[(normal: Z, at: 2.0), (name: \"side\", normal: X, at: 0.3, every: 0.25, fields: [\"pressure\"])]").unwrap();
        assert_eq!(o.slices[0].stem(), "z2");
        assert_eq!(o.slices[0].interval(o.vtk_every), Some(0.5));
        assert_eq!(o.slices[1].stem(), "side");
        assert_eq!(o.slices[1].interval(o.vtk_every), Some(0.25));
        for (base, slices, needles) in [
            (
                MIN,
                "[(normal: Z, at: 0.5)]",
                &["output.slices[0]", "three-dimensional box", "Planar"][..],
            ),
            (
                &cube,
                "[(normal: Z, at: 2.5)]",
                &[
                    "output.slices[0].at",
                    "z = 2.5 is outside the box's [-1, 2]",
                ],
            ),
            (
                &cube,
                "[(normal: Y, at: -0.1)]",
                &["output.slices[0].at", "y = -0.1"],
            ),
            (
                &cube,
                "[(normal: X, at: 0.5), (normal: X, at: 0.5)]",
                &["output.slices[1].name", "unique", "x0.5"],
            ),
            (
                &cube,
                "[(normal: X, at: 0.5, every: 0.0)]",
                &["output.slices[0].every"],
            ),
            (
                &cube,
                "[(normal: X, at: 0.5, fields: [])]",
                &["output.slices[0].fields", "at least one"],
            ),
            (
                &cube,
                "[(normal: X, at: 0.5, fields: [\"pressure\", \"pressure\"])]",
                &["output.slices[0].fields[1]", "twice"],
            ),
            (
                &cube,
                "[(normal: X, at: 0.5, fields: [\"solid_fraction\"])]",
                &["output.slices[0].fields[0]", "needs a solid"],
            ),
            (&cube, "[(normal: W, at: 0.5)]", &["W"]),
        ] {
            let (f, m) = with(base, slices).unwrap_err();
            let e = format!("{f}: {m}");
            for n in needles {
                assert!(e.contains(n), "{slices}: expected `{n}` in: {e}");
            }
        }
    }

    /// The solid probes run in a Cartesian3D scene (the extent's line needs its z there and
    /// only there), `ElasticEnergy` with a law; `SolidSpin` is refused in an axisymmetric
    /// scene by name.
    #[test]
    fn the_solid_probes_are_checked_per_geometry_by_name() {
        let solid = "solid: (shape: Sphere(center: (0.5, 0.5, 0.5), radius: 0.2), density: 2.0, viscosity: 0.1),";
        let cube = MIN
            .replace(
                "domain: (x: (0.0, 1.0), y: (0.0, 1.0)),",
                "geometry: Cartesian3D, domain: (x: (0.0, 1.0), y: (0.0, 1.0), z: (0.0, 1.0)),",
            )
            .replace(
                "grid: (nx: 8, ny: 8),",
                &format!("grid: (nx: 8, ny: 8, nz: 8), {solid}"),
            )
            .replace(
                "y_max: MovingWall(speed: 1.0)",
                "y_max: MovingWall(speed: 1.0), z_min: NoSlip, z_max: NoSlip",
            );
        let axi = MIN
            .replace("domain: (x: (0.0, 1.0), y: (0.0, 1.0)),", "geometry: Axisymmetric, domain: (r: (0.0, 1.0), z: (0.0, 1.0)),")
            .replace("grid: (nx: 8, ny: 8),", "grid: (nr: 8, nz: 8), solid: (shape: Disk(center: (0.0, 0.5), radius: 0.2), density: 2.0, viscosity: 0.1),")
            .replace("boundaries: (x_min: NoSlip,", "boundaries: (x_min: Axis,");
        let with = |base: &str, probes: &str| {
            let text = base.replace(
                "time: (end: 1.0),",
                &format!("time: (end: 1.0), output: (probes: [{probes}]),"),
            );
            let scene = Scene::from_str_at(&text, Path::new("scene.ron")).unwrap();
            let o = scene.output_spec()?;
            validate(&o, &scene).map(|()| o)
        };
        let o = with(
            &cube,
            "SolidPieces, SolidSpin, SolidExtent(at: 0.5, z: 0.25), ContactForce(wall: ZMin), ContactRadius(wall: YMin)",
        )
        .unwrap();
        let columns: Vec<String> = o
            .probes
            .iter()
            .flat_map(|p| p.columns(Geometry::Cartesian3D))
            .collect();
        assert_eq!(
            columns,
            [
                "solid_pieces",
                "solid_largest_piece",
                "solid_spin_x",
                "solid_spin_y",
                "solid_spin_z",
                "solid_bottom",
                "solid_top",
                "contact_force",
                "contact_radius"
            ]
        );
        assert_eq!(
            ProbeSpec::SolidSpin.columns(Geometry::Planar),
            ["solid_spin"]
        );
        assert!(with(&axi, "SolidExtent(at: 0.0), SolidPieces").is_ok());
        let elastic = cube.replace(
            "viscosity: 0.1),",
            "viscosity: 0.1, law: (name: \"neo_hookean\", parameters: {\"G\": 1.0})),",
        );
        let o = with(&elastic, "MaxSpeed, ElasticEnergy").unwrap();
        assert_eq!(
            o.probes[1].columns(Geometry::Cartesian3D),
            ["elastic_energy"]
        );
        for (base, probes, needles) in [
            (
                &cube,
                "SolidExtent(at: 0.5)",
                &["output.probes[0].z", "needs its z"][..],
            ),
            (
                &cube,
                "SolidExtent(at: 0.5, z: 1.5)",
                &["output.probes[0].z", "z = 1.5"],
            ),
            (
                &axi,
                "SolidExtent(at: 0.0, z: 0.5)",
                &["output.probes[0].z", "Axisymmetric"],
            ),
            (
                &cube,
                "MaxSpeed, ElasticEnergy",
                &["output.probes[1]", "needs a solid with a law"],
            ),
            (
                &axi,
                "SolidSpin",
                &["output.probes[0]", "SolidSpin", "axisymmetric"],
            ),
            (
                &axi,
                "Quantity(\"solid_spin\")",
                &["output.probes[0]", "SolidSpin"],
            ),
        ] {
            let (f, m) = with(base, probes).unwrap_err();
            let e = format!("{f}: {m}");
            for n in needles {
                assert!(e.contains(n), "{probes}: expected `{n}` in: {e}");
            }
        }
    }

    #[test]
    fn vtk_options_load_round_trip_and_are_checked_by_name() {
        let load = |text: &str| {
            let scene = Scene::from_str_at(text, Path::new("scene.ron")).unwrap();
            let o = scene.output_spec()?;
            validate(&o, &scene).map(|()| o)
        };
        let with = |vtk: &str| {
            load(&MIN.replace(
                "time: (end: 1.0),",
                &format!("time: (end: 1.0), output: (vtk_every: 0.5, vtk: {vtk}),"),
            ))
        };
        let s = with(r#"(fields: ["velocity", "pressure"], precision: Float32, compression: Zlib, point_data: true)"#)
                .unwrap();
        let v = &s.vtk;
        assert_eq!(
            v.fields.as_deref(),
            Some(&["velocity".to_string(), "pressure".to_string()][..])
        );
        assert_eq!(
            (v.precision, v.compression, v.point_data),
            (VtkPrecision::Float32, VtkCompression::Zlib, true)
        );
        let mut scene = Scene::from_str_at(MIN, Path::new("scene.ron")).unwrap();
        scene.set_output(&s);
        assert_eq!(&load(&scene.to_ron()).unwrap().vtk, v);
        // The defaults: every array, Float64, raw, cell data only.
        assert_eq!(load(MIN).unwrap().vtk, VtkOptions::default());
        // Names are checked against the shared fields and the scheduled stages' outputs when the
        // pipeline is built (tests/tests/elastic.rs, tests/tests/own_field.rs); the loader checks
        // the list's form.
        for (vtk, needles) in [
            (
                r#"(fields: ["pressure", "pressure"])"#,
                &["output.vtk.fields[1]", "listed twice"][..],
            ),
            (r#"(fields: [])"#, &["output.vtk.fields", "at least one"]),
            (
                r#"(fields: ["solid_fraction"])"#,
                &["output.vtk.fields[0]", "needs a solid"],
            ),
            (r#"(precision: Float16)"#, &["Float16"]),
            (r#"(compression: Gzip)"#, &["Gzip"]),
        ] {
            let (f, m) = with(vtk).unwrap_err();
            let e = format!("{f}: {m}");
            for n in needles {
                assert!(e.contains(n), "{vtk}: expected `{n}` in: {e}");
            }
        }
    }
}
