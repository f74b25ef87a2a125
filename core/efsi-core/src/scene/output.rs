//! What a run writes: VTK fields, probes and profiles (the `output` section).

use super::Side;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

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

/// The arrays of the shared fields a VTK file can hold, by name (`output.vtk.fields`):
/// `velocity`, `pressure`, `density`, `viscosity`, `divergence` always; `solid_fraction` with a
/// solid. The scheduled stages add theirs ([`crate::StagePlugin::outputs`]: the elastic stage's
/// `B` and `stress`). The README's output section documents each one's location, components,
/// meaning and unit.
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
    /// A field sampled at a point (bilinear interpolation).
    Point {
        /// Column name.
        name: String,
        /// Field name (see [`FIELD_NAMES`], and the stages' fields).
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
    /// A quantity a scheduled stage reports ([`crate::StagePlugin::outputs`]), by name; the
    /// column is named after it.
    Quantity(String),
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
            ProbeSpec::Quantity(name) => vec![name.clone()],
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

/// The most points a line profile may have: a 100 000-line CSV file per output time, finer
/// than any grid this solver runs (at most 1e4 cells across).
pub const MAX_PROFILE_POINTS: usize = 100_000;

/// The shared fields' names that probes and profiles can sample; the scheduled stages add
/// theirs ([`crate::OutputKind::Field`]).
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
}
