//! The scene's bodies: `solids: [ … ]`, several named solids, each of its own material, or the
//! single `solid:` as the shorthand for one body.
//!
//! ```ron
//! solids: [
//!     (name: "light", shape: Disk(center: (0.3, 0.7), radius: 0.1), density: 2.0),
//!     (name: "heavy", shape: Disk(center: (0.7, 0.7), radius: 0.1), density: 4.0,
//!      viscosity: 0.05, velocity: (0.0, -0.1)),
//! ],
//! ```
//!
//! A body has the settings of a [`Solid`] (`shape`, `density`, `viscosity`, `velocity`, `law`)
//! and a `name`, which names its probes and outputs. A scene writes `solid:` (one body, named
//! [`SINGLE`]) or `solids:`, never both. Read once into a [`Body`] list ([`SceneBodies`]); the
//! checks here are those of the list: names are non-empty, of
//! letters, digits, `_` and `-` (they become column names such as `a.solid_x`), and distinct;
//! the list is not empty. Each body's settings are checked as a [`Solid`]'s
//! ([`Solid::validate`]), the path naming the body (`solids[1].density`). The checks that need the grid — a body covers a cell, no two bodies
//! overlap at t = 0 — belong to the VOF stage's plugin, which turns shapes into cell fractions.

use super::Scene;
use super::solid::{SceneSolid, Solid, solid_settings};
use crate::validate::{Checked, err};

/// The name of the body of a scene that writes the single `solid:`.
pub const SINGLE: &str = "solid";

solid_settings! {
    /// One entry of `solids: [ … ]`: a named [`Solid`] (its settings, as [`Solid`]'s).
    pub struct BodySpec {
        /// The body's name, for its probes and outputs.
        pub name: String,
    }
}

/// A body of the scene: its name and its material and shape.
#[derive(Clone, Debug)]
pub struct Body {
    /// Its name ([`SINGLE`] for the single `solid:`).
    pub name: String,
    /// Its settings.
    pub solid: Solid,
}

impl From<BodySpec> for Body {
    fn from(b: BodySpec) -> Self {
        Body {
            name: b.name,
            solid: Solid {
                shape: b.shape,
                density: b.density,
                viscosity: b.viscosity,
                velocity: b.velocity,
                law: b.law,
            },
        }
    }
}

impl From<&Body> for BodySpec {
    fn from(b: &Body) -> Self {
        let s = b.solid.clone();
        BodySpec {
            name: b.name.clone(),
            shape: s.shape,
            density: s.density,
            viscosity: s.viscosity,
            velocity: s.velocity,
            law: s.law,
        }
    }
}

/// The bodies of a checked scene, in the order the scene lists them (one, named [`SINGLE`],
/// for a scene with `solid:`). Kept in the checked scene's [`Options`](super::Options) by the
/// plugin that checks the section.
#[derive(Clone, Debug)]
pub struct Bodies {
    /// The bodies.
    pub list: Vec<Body>,
    /// Whether the scene wrote them as `solids: [ … ]` (false: the single `solid:`).
    pub listed: bool,
}

impl Body {
    /// The path of this body's settings in the scene: `solid` for the single solid,
    /// `solids[k]` for the `k`-th entry of the list.
    pub fn path(listed: bool, k: usize) -> String {
        if listed {
            format!("solids[{k}]")
        } else {
            SINGLE.to_string()
        }
    }
}

/// Check the body names of a `solids` list: the list is not empty, each name is non-empty, of
/// letters, digits, `_` and `-`, and no two are equal.
pub fn check_names(bodies: &[Body]) -> Checked {
    if bodies.is_empty() {
        return err(
            "solids",
            "an empty list: give at least one body, or leave `solids` out",
        );
    }
    for (k, b) in bodies.iter().enumerate() {
        let at = format!("solids[{k}].name");
        if b.name.is_empty() {
            return err(
                &at,
                "empty: every body needs a name (its probes' and outputs')",
            );
        }
        if let Some(c) = b
            .name
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '-'))
        {
            return err(
                &at,
                format!(
                    "\"{}\" holds {c:?}: a name is letters, digits, `_` and `-` (it names probe columns such as `{}.solid_x`)",
                    b.name,
                    b.name.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
                ),
            );
        }
        if let Some(j) = bodies[..k].iter().position(|o| o.name == b.name) {
            return err(
                &at,
                format!(
                    "\"{}\" is also the name of solids[{j}]: names must differ",
                    b.name
                ),
            );
        }
    }
    Ok(())
}

/// The scene's `solid` or `solids` section as a list of [`Body`].
pub trait SceneBodies {
    /// The bodies of the scene, `None` without `solid` or `solids`; on error the path of the
    /// setting that does not read and the reader's message. Both `solid` and `solids`, an
    /// empty list, an empty, ill-formed or repeated name are errors ([`check_names`]).
    fn bodies_spec(&self) -> Result<Option<Bodies>, (String, String)>;
    /// Replace the `solids` section by `bodies`.
    fn set_bodies(&mut self, bodies: &[Body]);
    /// Whether the scene has a body (`solid` or `solids`).
    fn has_bodies(&self) -> bool;
}

impl SceneBodies for Scene {
    fn bodies_spec(&self) -> Result<Option<Bodies>, (String, String)> {
        match (&self.solid, &self.solids) {
            (Some(_), Some(_)) => err(
                "solids",
                "the scene has both `solid` and `solids`: write one body as `solid: ( … )` or \
                 every body in `solids: [ … ]`",
            ),
            (Some(_), None) => Ok(self.solid_spec()?.map(|solid| Bodies {
                list: vec![Body {
                    name: SINGLE.into(),
                    solid,
                }],
                listed: false,
            })),
            (None, Some(list)) => {
                let specs: Vec<BodySpec> = list.read("solids")?;
                let list: Vec<Body> = specs.into_iter().map(Body::from).collect();
                check_names(&list)?;
                Ok(Some(Bodies { list, listed: true }))
            }
            (None, None) => Ok(None),
        }
    }

    fn set_bodies(&mut self, bodies: &[Body]) {
        let specs: Vec<BodySpec> = bodies.iter().map(BodySpec::from).collect();
        self.solids =
            Some(super::Section::of(&specs).expect("the solids section serialises to RON"));
    }

    fn has_bodies(&self) -> bool {
        self.solid.is_some() || self.solids.is_some()
    }
}
