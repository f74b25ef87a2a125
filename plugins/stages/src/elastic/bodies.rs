//! Per-body deformation: every elastic body of a scene of several keeps its own B, its own law
//! and its own interface weights.
//!
//! # Rule
//!
//! A scene of several bodies (`solids: [ … ]`) transports each body's fraction `φ_k` on its own
//! (the VOF stage's `bodies` module). Each body `k` with a law keeps its own left Cauchy–Green
//! tensor `B_k` and its rates (a [`Deformation`]), transported by the upper-convected law of the
//! module docs of [`super`] with the weights `w_k = φ_k^{1/2}` of its own fraction — B̃ of the
//! body is `B̃_k = φ_k^{1/2} B_k` — and reset to the identity outside it ("Pure fluid"). The
//! law of body `k` (its own library and parameters) is evaluated on `B_k` only, so two bodies
//! that meet never mix their deformation histories. The stress in a cell is the mixture
//!
//! ```text
//!   τ = Σ_k w_k (τ_k(B_k) − τ_k(I)),     (shear on the edges: Σ_k (1/κ_k) τ_k,ab(B_k))
//! ```
//!
//! each term as the single body's ("The interface"), the other bodies counting as fluid in the
//! series closure of its interface edges (`μ_s` of the body, `μ_f` of the fluid). The
//! implicit system sees the sum of the bodies' tangents, `K_J δ = Σ_k vol ∇·[J_k : H(δ; B_kⁿ)]`,
//! each body's increment stretched by its own `B_kⁿ`; the block multigrid's effective viscosity
//! and the Jacobi diagonal take the sum of the bodies' stiffnesses; the coupled step uses the
//! same operator. The strain energy is `Σ_k ∫ w_k W_k(B_k) dV`, each body's kept for its probe.
//!
//! # Storage
//!
//! Each elastic body has its own kernels (weights, batches, gradients) and deformation on the
//! whole grid; the work of each is restricted to its own solid's window (`Kernels::solid_c`,
//! `near_c`), so a step costs the bodies' extent, but the storage is the grid's per elastic
//! body. A scene of one body keeps the single [`Deformation`] resource (checkpoint names
//! `B.<part>.<c>`) and runs the same arithmetic as before, bit for bit; a scene of several
//! keeps [`BodyDeformations`] (names `B.<body>.<part>.<c>`).
//!
//! # Limits
//!
//! The bodies' fractions come from the state's [`BodyFractions`], which the VOF stage sets at
//! its initialisation, after every step and when a snapshot or checkpoint is restored
//! ([`efsi_core::Stage::restored`]); the elastic step refuses a state that holds none. Two
//! bodies sharing a cell add their stresses as two materials in parallel; a body's
//! interface edge counts the other body's part of it as fluid. Keeping the bodies a film apart
//! is the contact's job, not this module's.

use super::Deformation;
use efsi_core::body_fractions::BodyFractions;
use efsi_core::scene::Options;
use efsi_core::{BoundarySet, Field, Grid, Scene, State, StateResource};

/// An elastic body of the scene: its index among the scene's bodies (`None` for the single
/// solid of a scene of one body, whose fraction is the state's) and its settings.
#[derive(Clone, Debug)]
pub(super) struct ElasticBody {
    pub(super) index: Option<usize>,
    pub(super) name: String,
    pub(super) solid: crate::solid::Solid,
    /// The path of its settings in the scene (`solid`, `solids[1]`), for messages.
    pub(super) path: String,
}

/// The elastic bodies of a checked scene: the single solid (with its law), or every body of a
/// scene of several that has a law, in the scene's order.
pub(super) fn elastic_bodies(options: &Options) -> Result<Vec<ElasticBody>, String> {
    if let Ok(s) = crate::solid::solid(options) {
        return Ok(vec![ElasticBody {
            index: None,
            name: efsi_core::scene::bodies::SINGLE.to_string(),
            solid: s.clone(),
            path: "solid".to_string(),
        }]);
    }
    let bodies = crate::solid::bodies(options)?;
    Ok(bodies
        .list
        .iter()
        .enumerate()
        .filter(|(_, b)| b.solid.law.is_some())
        .map(|(k, b)| ElasticBody {
            index: Some(k),
            name: b.name.clone(),
            solid: b.solid.clone(),
            path: crate::solid::Body::path(true, k),
        })
        .collect())
}

/// Whether a checked scene has an elastic body: a solid with a law, or a body with a law among
/// several.
pub(crate) fn any_elastic(options: &Options) -> bool {
    match crate::solid::solid(options) {
        Ok(s) => s.law.is_some(),
        Err(_) => crate::solid::bodies(options)
            .is_ok_and(|b| b.list.iter().any(|b| b.solid.law.is_some())),
    }
}

/// The fluid's and body `b`'s viscosities, for its interface edges.
pub(super) fn viscosities_of(scene: &Scene, b: &ElasticBody) -> (f64, f64) {
    (scene.fluid.viscosity, b.solid.viscosity(&scene.fluid))
}

/// The deformations of the elastic bodies of a scene of several (the bodies with a law, in the
/// scene's order): each body's [`Deformation`] with its name, saved in checkpoints and snapshots
/// under the names `B.<body>.<part>.<c>`.
#[derive(Clone, Debug)]
pub struct BodyDeformations {
    /// The bodies' names.
    pub names: Vec<String>,
    /// Their deformations.
    pub bodies: Vec<Deformation>,
}

impl StateResource for BodyDeformations {
    fn arrays(&self) -> Vec<(String, &Field)> {
        let mut out = Vec::new();
        for (name, d) in self.names.iter().zip(&self.bodies) {
            for (a, f) in d.arrays() {
                out.push((format!("B.{name}{}", &a[1..]), f));
            }
        }
        out
    }

    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        let mut out = Vec::new();
        for (name, d) in self.names.iter().zip(&mut self.bodies) {
            for (a, f) in d.arrays_mut() {
                out.push((format!("B.{name}{}", &a[1..]), f));
            }
        }
        out
    }

    fn clone_box(&self) -> Box<dyn StateResource> {
        Box::new(self.clone())
    }

    fn copy_from(&mut self, other: &dyn StateResource) -> bool {
        let Some(other) = (other as &dyn std::any::Any).downcast_ref::<BodyDeformations>() else {
            return false;
        };
        if self.names != other.names || self.bodies.len() != other.bodies.len() {
            return false;
        }
        // The bodies' deformations are shaped alike (one grid): the first fits if all do, and
        // a body that does not fit copies nothing.
        self.bodies
            .iter_mut()
            .zip(&other.bodies)
            .all(|(a, b)| a.copy_from(b))
    }

    fn first_non_finite(&self, nx: usize, ny: usize) -> Option<(String, (usize, usize))> {
        self.names.iter().zip(&self.bodies).find_map(|(name, d)| {
            d.first_non_finite(nx, ny)
                .map(|(c, at)| (format!("{name}.B{c}"), at))
        })
    }

    /// The bodies' strain energies summed.
    fn stored_energy(&self) -> f64 {
        self.bodies.iter().map(|d| d.elastic_energy).sum()
    }
}

/// The elastic bodies' deformations taken out of the state for a sub-step (put them back with
/// [`Held::put`]).
pub(super) enum Held {
    One(Box<Deformation>),
    Many(Box<BodyDeformations>),
}

impl Held {
    /// The deformations of the state, `None` if it holds none.
    pub(super) fn take(state: &mut State) -> Option<Held> {
        if let Some(d) = state.resources.take::<Deformation>() {
            return Some(Held::One(d));
        }
        state.resources.take::<BodyDeformations>().map(Held::Many)
    }

    /// Back into the state.
    pub(super) fn put(self, state: &mut State) {
        match self {
            Held::One(d) => state.resources.put(d),
            Held::Many(d) => state.resources.put(d),
        }
    }

    /// One deformation per elastic body.
    pub(super) fn all(&mut self) -> &mut [Deformation] {
        match self {
            Held::One(d) => std::slice::from_mut(&mut **d),
            Held::Many(d) => &mut d.bodies,
        }
    }
}

/// The deformations of a state, one per elastic body (none if it holds none).
pub(super) fn deformations(state: &State) -> &[Deformation] {
    if let Some(d) = state.resources.get::<Deformation>() {
        return std::slice::from_ref(d);
    }
    state
        .resources
        .get::<BodyDeformations>()
        .map_or(&[], |d| &d.bodies[..])
}

/// Add the deformation resource for `bodies` to the state, if it has none: the single
/// [`Deformation`] for the single solid, [`BodyDeformations`] for the bodies of a scene of
/// several.
pub(super) fn init_state(bodies: &[ElasticBody], grid: &Grid, state: &mut State) {
    let single = bodies.len() == 1 && bodies[0].index.is_none();
    if single {
        if state.resources.get::<Deformation>().is_none() {
            state.resources.insert(Deformation::zeros(grid));
        }
    } else if state.resources.get::<BodyDeformations>().is_none() {
        state.resources.insert(BodyDeformations {
            names: bodies.iter().map(|b| b.name.clone()).collect(),
            bodies: bodies.iter().map(|_| Deformation::zeros(grid)).collect(),
        });
    }
}

/// Each elastic body's fraction as a field of the grid with its ghosts filled: the state's
/// solid fraction for the single solid, else the body's `φ_k` from the state's
/// [`BodyFractions`] (the VOF stage's copy of its windows).
pub(super) struct Fractions {
    fields: Vec<Field>,
}

impl Fractions {
    /// Work fields for `bodies` (none for the single solid, which reads the state's).
    pub(super) fn new(bodies: &[ElasticBody], grid: &Grid) -> Self {
        Fractions {
            fields: bodies
                .iter()
                .filter(|b| b.index.is_some())
                .map(|_| Field::zeros(grid))
                .collect(),
        }
    }

    /// Refresh the bodies' fractions from `state`: each `φ_k` written into its field and its
    /// ghosts filled as the state's solid fraction's (`bc`'s scalar sides).
    pub(super) fn refresh(
        &mut self,
        bodies: &[ElasticBody],
        grid: &Grid,
        bc: &BoundarySet,
        state: &State,
    ) -> Result<(), String> {
        if self.fields.is_empty() {
            return Ok(());
        }
        let all = state
            .resources
            .get::<BodyFractions>()
            .ok_or("the bodies' fractions are not in the state")?;
        for (f, b) in self.fields.iter_mut().zip(bodies) {
            let k = b.index.expect("a body of several");
            let bf = all.bodies.get(k).filter(|f| f.is_set()).ok_or_else(|| {
                format!(
                    "body \"{}\" has no fraction in the state (the VOF stage publishes \
                         them): its deformation cannot be weighted",
                    b.name
                )
            })?;
            bf.fill(f);
            bc.fill_scalar(grid, f, false);
        }
        Ok(())
    }

    /// Body `k`'s fraction: its field, or the state's `phi` for the single solid.
    pub(super) fn of<'a>(&'a self, k: usize, phi: &'a Field) -> &'a Field {
        self.fields.get(k).unwrap_or(phi)
    }
}

/// Each elastic body's strain energy into its record in the state's [`BodyFractions`] (for
/// its `<body>.elastic_energy` probe); nothing for the single solid.
pub(super) fn record_energies(bodies: &[ElasticBody], state: &mut State) {
    let Some(many) = state.resources.take::<BodyDeformations>() else {
        return;
    };
    if let Some(all) = state.resources.get_mut::<BodyFractions>() {
        for (b, d) in bodies.iter().zip(&many.bodies) {
            if let Some(f) = b.index.and_then(|k| all.bodies.get_mut(k)) {
                f.elastic_energy = d.elastic_energy;
            }
        }
    }
    state.resources.put(many);
}
