//! The scene's `solid` section: the solid body (or several, as a union of shapes) of one
//! material, and the checks of its settings.
//!
//! ```ron
//! solid: (
//!     shape: Disk(center: (0.0, 0.0573), radius: 0.0192),
//!     density: 1106.0,
//!     velocity: (0.0, -1.22),
//!     law: (name: "neo_hookean", parameters: {"G": 0.18e6}),
//! ),
//! ```
//!
//! Part of the scene model: the scene keeps the section as RON text ([`Section`]), which
//! overrides edit; [`SceneSolid`] reads it as a [`Solid`]. What the section means for a time
//! step belongs to the stage plugins: the VOF stage turns the shape into cell fractions and
//! checks that it covers a cell, the elastic stage loads the law the section names. A plugin
//! reads the section once when a simulation is built and keeps the [`Solid`] in the checked
//! scene's [`Options`](super::Options), from which every stage that needs it reads it.

use super::{Fluid, Scene, Section, Vector};
use crate::grid::Geometry;
use crate::validate::{Checked, err, finite, positive};
use serde::{Deserialize, Serialize};

pub use super::shape::{Axis, Shape};

/// A struct of a body's settings: the fields given (a `solids` entry's `name`), then those of a
/// [`Solid`] — `shape`, `density`, `viscosity`, `velocity`, `law` — with unknown fields refused.
/// The one list of a body's settings, for [`Solid`] and for an entry of `solids: [ … ]`
/// (`bodies::BodySpec`): serde's `flatten` cannot be combined with `deny_unknown_fields`.
macro_rules! solid_settings {
    (
        $(#[$attr:meta])*
        pub struct $name:ident { $($(#[$fattr:meta])* pub $field:ident: $ty:ty,)* }
    ) => {
        $(#[$attr])*
        #[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $($(#[$fattr])* pub $field: $ty,)*
            /// The region it occupies at t = 0 (x–y, or r–z in axisymmetric geometry; a
            /// three-dimensional shape in a three-dimensional scene).
            pub shape: $crate::scene::solid::Shape,
            /// Density ρ_s (kg/m³, > 0).
            pub density: f64,
            /// Viscosity μ_s (Pa·s, ≥ 0); default the seed's rule μ_s = μ_f ρ_s/ρ_f.
            #[serde(default)]
            pub viscosity: Option<f64>,
            /// Initial velocity (default: at rest): `(vx, vy)` in a two-dimensional scene
            /// (`(0, v_z)` when axisymmetric), `(vx, vy, vz)` in a Cartesian3D one.
            #[serde(default)]
            pub velocity: Option<$crate::scene::Vector>,
            /// The hyperelastic law; without one the body is a dense viscous body (no elastic
            /// stage).
            #[serde(default)]
            pub law: Option<$crate::scene::solid::LawSpec>,
        }
    };
}
pub(super) use solid_settings;

solid_settings! {
    /// A solid body (or several, as a union of shapes) of one material.
    pub struct Solid {}
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

    /// Check the solid against `scene`: its shape, density (and the density ratio), viscosity
    /// and velocity; on failure the setting's path and what was expected.
    pub fn validate(&self, scene: &Scene) -> Checked {
        let dims = if scene.geometry == Geometry::Cartesian3D {
            3
        } else {
            2
        };
        self.check_shape(scene, dims)?;
        self.check_density(scene)?;
        if let Some(mu) = self.viscosity {
            if !(mu.is_finite() && mu >= 0.0) {
                return err(
                    "solid.viscosity",
                    format!("must be a finite number ≥ 0, got {}", crate::scene::num(mu)),
                );
            }
            scene.check_diffusion("solid.viscosity", mu, self.density)?;
        }
        if let Some(v) = self.velocity {
            check_velocity(v, scene.geometry, dims)?;
        }
        Ok(())
    }

    /// The shape is valid and has the scene's `dims` axes.
    fn check_shape(&self, scene: &Scene, dims: usize) -> Checked {
        self.shape
            .check()
            .map_err(|(at, m)| (format!("solid.shape{at}"), m))?;
        if self.shape.dims() == dims {
            return Ok(());
        }
        err(
            "solid.shape",
            format!(
                "a {}-D shape in a {dims}-D scene (geometry {:?}): the shapes of a \
                 {dims}-D scene are {}",
                self.shape.dims(),
                scene.geometry,
                if dims == 3 {
                    "Sphere, Ellipsoid, Box, Cylinder, HalfSpace and their combinations"
                } else {
                    "Disk, Rectangle, HalfPlane and their combinations"
                }
            ),
        )
    }

    /// The density is positive and within [1e-6, 1e6] of the fluid's: far beyond the ratios
    /// the scheme is meant for (DESIGN: up to 1e4), the pressure equation's coefficients 1/ρ
    /// span more than floating point resolves.
    fn check_density(&self, scene: &Scene) -> Checked {
        positive("solid.density", self.density)?;
        let ratio = self.density / scene.fluid.density;
        if !(1e-6..=1e6).contains(&ratio) {
            return err(
                "solid.density",
                format!(
                    "the density ratio solid/fluid {ratio:e} is outside [1e-6, 1e6] (solid {} kg/m³, fluid {} kg/m³)",
                    crate::scene::num(self.density),
                    crate::scene::num(scene.fluid.density)
                ),
            );
        }
        Ok(())
    }
}

/// The initial velocity `v` of a solid in a scene of `geometry` with `dims` axes: finite, one
/// component per axis, along the axis only when axisymmetric.
fn check_velocity(v: Vector, geometry: Geometry, dims: usize) -> Checked {
    let [x, y, z] = v.xyz();
    finite("solid.velocity", (x, y))?;
    finite("solid.velocity", (z, 0.0))?;
    match (dims, v.2.is_some()) {
        (3, false) => {
            return err(
                "solid.velocity",
                "a Cartesian3D scene's solid velocity has three components (vx, vy, vz), \
                 got two",
            );
        }
        (2, true) => {
            return err(
                "solid.velocity",
                format!(
                    "a {geometry:?} scene has two axes: the solid velocity is (vx, vy), got \
                     three components",
                ),
            );
        }
        _ => {}
    }
    if geometry == Geometry::Axisymmetric && v.0 != 0.0 {
        return err(
            "solid.velocity",
            "an axisymmetric body can only move along the axis: (0, v_z)",
        );
    }
    Ok(())
}

/// The `solid` section of a scene as a [`Solid`].
pub trait SceneSolid {
    /// The solid, if the scene has one; on error the path of the setting that does not read
    /// (`solid.law.parameters.G`) and the reader's message (with the line and column in the
    /// scene file where known).
    fn solid_spec(&self) -> Result<Option<Solid>, (String, String)>;
    /// Replace the section by `solid`.
    fn set_solid(&mut self, solid: &Solid);
    /// Change the solid in place: read it, apply `change`, write it back. An error if the
    /// scene has no solid or its section does not read as one.
    fn update_solid(&mut self, change: impl FnOnce(&mut Solid)) -> Result<(), String> {
        let mut solid = self
            .solid_spec()
            .map_err(|(f, m)| format!("{f}: {m}"))?
            .ok_or("the scene has no solid")?;
        change(&mut solid);
        self.set_solid(&solid);
        Ok(())
    }
}

impl SceneSolid for Scene {
    fn solid_spec(&self) -> Result<Option<Solid>, (String, String)> {
        self.solid.as_ref().map(|s| s.read("solid")).transpose()
    }

    fn set_solid(&mut self, solid: &Solid) {
        self.solid = Some(Section::of(solid).expect("the solid section serialises to RON"));
    }
}

/// The `solid` section of `scene` as JSON, what records hold (`run.json`, a checkpoint's
/// comparison of scenes): its settings, defaults filled in; the section's RON text where it
/// does not read as a [`Solid`]; null without a solid.
pub fn json(scene: &Scene) -> serde_json::Value {
    match scene.solid_spec() {
        Ok(solid) => serde_json::to_value(solid).unwrap_or_default(),
        Err(_) => serde_json::Value::String(
            scene
                .solid
                .as_ref()
                .map(|s| s.text().to_string())
                .unwrap_or_default(),
        ),
    }
}

/// The solid of a checked scene (`options`, as the plugin that checks the section read it) as JSON, what `run.json`
/// records: its settings, defaults filled in; null without a solid.
pub fn checked_json(options: &super::Options) -> serde_json::Value {
    options.get::<Solid>().map_or(serde_json::Value::Null, |s| {
        serde_json::to_value(s).unwrap_or_default()
    })
}
