//! The simulation state: time, and the fields the scheduled stages declared.

use crate::field::Field;
use crate::grid::Grid;
use crate::schedule::FieldId;
use std::collections::BTreeSet;

/// Time, step counter and the fields of a run.
///
/// Velocity, pressure, density and viscosity always exist. Fields that only some physics need
/// (the solid fraction, B̃, …) are allocated only when a scheduled stage declares them, so a
/// single-fluid scene carries no solid storage.
#[derive(Clone, Debug)]
pub struct State {
    /// Simulated time (s).
    pub t: f64,
    /// Number of completed steps.
    pub step: u64,
    /// The previous step's Δt (0 before the first step).
    pub dt_prev: f64,
    /// Velocity component on x-faces (u, or u_r).
    pub u: Field,
    /// Velocity component on y-faces (v, or u_z).
    pub v: Field,
    /// Velocity component on z-faces (w), on a three-dimensional grid only.
    pub w: Option<Field>,
    /// Pressure at cell centres (Pa).
    pub p: Field,
    /// Density at cell centres (kg/m³).
    pub rho: Field,
    /// Dynamic viscosity at cell centres (Pa·s).
    pub mu: Field,
    /// Solid volume fraction φ_s at cell centres, when a stage declares it.
    pub phi: Option<Field>,
    /// Acceleration of the grid's frame with respect to an inertial one (m/s², default zero):
    /// the body-force stage applies `gravity − frame_acceleration` (d'Alembert), so a frame
    /// accelerating upwards, like a shaking table, makes everything in it heavier. Set between
    /// steps with `efsi_stages::body_force::FrameAcceleration` (the FMU's base-acceleration
    /// input); kept here so snapshots and checkpoints carry it.
    pub frame_acceleration: (f64, f64),
    /// The stages' own data ([`StateResource`]).
    pub resources: StateResources,
}

/// Data a stage keeps in the [`State`] beside the shared fields (in the spirit of Bevy's
/// `Resource`): one value per type, added by the stage that owns it
/// ([`crate::Stage::init_state`]) and read by the stages and outputs that know its type
/// ([`StateResources::get`]). Its arrays and scalars, named, travel with the state into snapshots
/// and checkpoints, so a stage's history (the elastic stages' B̃, say) needs no core field.
pub trait StateResource: std::any::Any + Send + Sync + std::fmt::Debug {
    /// Its arrays with stable names, in a fixed order (what a checkpoint saves).
    fn arrays(&self) -> Vec<(String, &Field)>;
    /// [`arrays`](Self::arrays), mutable, same names and order.
    fn arrays_mut(&mut self) -> Vec<(String, &mut Field)>;
    /// Scalars that carry from step to step, with stable names (default: none).
    fn scalars(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// [`scalars`](Self::scalars), mutable, same names and order.
    fn scalars_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
        Vec::new()
    }
    /// Take the shapes a checkpoint recorded before its arrays are read back into
    /// [`arrays_mut`](Self::arrays_mut): `recorded(name)` gives the values recorded under
    /// `name` (`None` if there are none). A resource whose arrays change shape during a run
    /// (a body's window that follows it) takes its recorded shapes here; default: nothing,
    /// the shapes are the grid's.
    fn reshape(&mut self, _recorded: &dyn Fn(&str) -> Option<Vec<f64>>) -> Result<(), String> {
        Ok(())
    }
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn StateResource>;
    /// Copy `other` (a value of the same type) into `self`, without allocating where the shapes
    /// agree; returns whether it fitted (nothing is copied otherwise). A resource whose arrays
    /// change shape during a run takes `other`'s shapes.
    fn copy_from(&mut self, other: &dyn StateResource) -> bool;
    /// The first non-finite value in the interior, as (what, cell), checked after a stage that
    /// writes the resource's field (default: none).
    fn first_non_finite(&self, _nx: usize, _ny: usize) -> Option<(String, (usize, usize))> {
        None
    }
    /// The mechanical energy it stores (a solid's strain energy), which the energy guard
    /// counts as a supply (default: 0).
    fn stored_energy(&self) -> f64 {
        0.0
    }
}

/// A state's resources, one per type, in the order they were added. Borrowing one borrows
/// only this field of the [`State`], not the shared fields beside it.
#[derive(Debug, Default)]
pub struct StateResources(Vec<(std::any::TypeId, Option<Box<dyn StateResource>>)>);

impl Clone for StateResources {
    fn clone(&self) -> Self {
        StateResources(
            self.0
                .iter()
                .map(|(t, r)| (*t, r.as_ref().map(|r| r.clone_box())))
                .collect(),
        )
    }
}

impl StateResources {
    /// Add a resource, replacing one of its type.
    pub fn insert<T: StateResource>(&mut self, value: T) {
        self.put(Box::new(value));
    }

    /// The resource of type `T`, if a stage added one.
    pub fn get<T: StateResource>(&self) -> Option<&T> {
        let id = std::any::TypeId::of::<T>();
        let r = self.0.iter().find(|(t, _)| *t == id)?.1.as_deref()?;
        (r as &dyn std::any::Any).downcast_ref()
    }

    /// [`get`](Self::get), mutable.
    pub fn get_mut<T: StateResource>(&mut self) -> Option<&mut T> {
        let id = std::any::TypeId::of::<T>();
        let r = self
            .0
            .iter_mut()
            .find(|(t, _)| *t == id)?
            .1
            .as_deref_mut()?;
        (r as &mut dyn std::any::Any).downcast_mut()
    }

    /// Take the resource of type `T` out (to use it beside a `&mut State`; give it back with
    /// [`put`](Self::put)). Neither allocates.
    pub fn take<T: StateResource>(&mut self) -> Option<Box<T>> {
        let id = std::any::TypeId::of::<T>();
        let slot = &mut self.0.iter_mut().find(|(t, _)| *t == id)?.1;
        let r: Box<dyn std::any::Any> = slot.take()?;
        Some(r.downcast().expect("a slot holds its own type"))
    }

    /// Put a resource (back) in its place, keeping the resources' order.
    pub fn put<T: StateResource>(&mut self, value: Box<T>) {
        let id = std::any::TypeId::of::<T>();
        match self.0.iter_mut().find(|(t, _)| *t == id) {
            Some(slot) => slot.1 = Some(value),
            None => self.0.push((id, Some(value))),
        }
    }

    /// Copy `other` (the resources of a state of the same simulation) into these without
    /// allocating; returns whether they fitted (else some may have been copied).
    pub(crate) fn copy_from(&mut self, other: &StateResources) -> bool {
        self.0.len() == other.0.len()
            && self
                .0
                .iter_mut()
                .zip(&other.0)
                .all(|(a, b)| match (&mut a.1, &b.1) {
                    (Some(a), Some(b)) => a.copy_from(&**b),
                    (None, None) => true,
                    _ => false,
                })
    }

    /// Every resource, in the order they were added.
    pub fn iter(&self) -> impl Iterator<Item = &dyn StateResource> {
        self.0.iter().filter_map(|(_, r)| r.as_deref())
    }
    fn iter_mut(&mut self) -> impl Iterator<Item = &mut (dyn StateResource + 'static)> {
        self.0.iter_mut().filter_map(|(_, r)| r.as_deref_mut())
    }
}

/// The face velocities of a [`State`], one per axis ([`State::velocity`]): a slice of two or
/// three fields without an allocation.
#[derive(Clone, Copy, Debug)]
pub struct Velocity<'a>([&'a Field; 3], usize);

impl<'a> std::ops::Deref for Velocity<'a> {
    type Target = [&'a Field];
    fn deref(&self) -> &[&'a Field] {
        &self.0[..self.1]
    }
}

impl State {
    /// A state at rest, uniform density and viscosity, with the optional `fields` allocated.
    pub fn new(grid: &Grid, density: f64, viscosity: f64, fields: &BTreeSet<FieldId>) -> Self {
        State {
            t: 0.0,
            step: 0,
            dt_prev: 0.0,
            u: Field::zeros(grid),
            v: Field::zeros(grid),
            w: grid.is_3d().then(|| Field::zeros(grid)),
            p: Field::zeros(grid),
            rho: Field::filled(grid, density),
            mu: Field::filled(grid, viscosity),
            phi: fields
                .contains(&FieldId::SolidFraction)
                .then(|| Field::zeros(grid)),
            frame_acceleration: (0.0, 0.0),
            resources: StateResources::default(),
        }
    }

    /// The face velocities, one per axis: `[u, v]`, and `w` on a three-dimensional grid — the
    /// form [`crate::operators`] take (`&state.velocity()` is a `&[&Field]`).
    pub fn velocity(&self) -> Velocity<'_> {
        let w = self.w.as_ref();
        Velocity(
            [&self.u, &self.v, w.unwrap_or(&self.v)],
            2 + w.is_some() as usize,
        )
    }

    /// Every stored array with a stable name, in a fixed order: `u`, `v`, `p`, `rho`, `mu`, then
    /// `w` on a three-dimensional grid, then `phi` when allocated, then each resource's arrays ([`StateResource::arrays`]). What a
    /// checkpoint saves: with `t`, `step` and `dt_prev` this is the whole state, ghosts included.
    pub fn arrays(&self) -> Vec<(String, &Field)> {
        let mut out = self.field_arrays();
        for r in self.resources.iter() {
            out.extend(r.arrays());
        }
        out
    }

    /// The state's own arrays of [`arrays`](Self::arrays), the resources' aside: the shapes
    /// the grid fixes.
    pub fn field_arrays(&self) -> Vec<(String, &Field)> {
        let base = [&self.u, &self.v, &self.p, &self.rho, &self.mu];
        let mut out: Vec<(String, &Field)> = ["u", "v", "p", "rho", "mu"]
            .into_iter()
            .map(String::from)
            .zip(base)
            .collect();
        out.extend(self.w.iter().map(|f| ("w".to_string(), f)));
        out.extend(self.phi.iter().map(|f| ("phi".to_string(), f)));
        out
    }

    /// Each resource's [`StateResource::reshape`] to the shapes a checkpoint recorded.
    pub fn reshape_resources(
        &mut self,
        recorded: &dyn Fn(&str) -> Option<Vec<f64>>,
    ) -> Result<(), String> {
        self.resources
            .iter_mut()
            .try_for_each(|r| r.reshape(recorded))
    }

    /// [`arrays`](Self::arrays), mutable, same names and order.
    pub fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        let base = [
            &mut self.u,
            &mut self.v,
            &mut self.p,
            &mut self.rho,
            &mut self.mu,
        ];
        let mut out: Vec<(String, &mut Field)> = ["u", "v", "p", "rho", "mu"]
            .into_iter()
            .map(String::from)
            .zip(base)
            .collect();
        out.extend(self.w.iter_mut().map(|f| ("w".to_string(), f)));
        out.extend(self.phi.iter_mut().map(|f| ("phi".to_string(), f)));
        for r in self.resources.iter_mut() {
            out.extend(r.arrays_mut());
        }
        out
    }

    /// The scalars that carry from step to step besides `t`, `step` and `dt_prev`, with stable
    /// names: the frame acceleration (`frame_acceleration_x`, `_y`), then the resources' (the
    /// elastic energy when a solid has a law). A checkpoint saves them with the arrays.
    pub fn scalars(&self) -> Vec<(&'static str, f64)> {
        let mut out = vec![
            ("frame_acceleration_x", self.frame_acceleration.0),
            ("frame_acceleration_y", self.frame_acceleration.1),
        ];
        for r in self.resources.iter() {
            out.extend(r.scalars());
        }
        out
    }

    /// [`scalars`](Self::scalars), mutable, same names and order.
    pub fn scalars_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
        let mut out = vec![
            ("frame_acceleration_x", &mut self.frame_acceleration.0),
            ("frame_acceleration_y", &mut self.frame_acceleration.1),
        ];
        for r in self.resources.iter_mut() {
            out.extend(r.scalars_mut());
        }
        out
    }

    /// The value a scalar of [`scalars`](Self::scalars) takes when a checkpoint does not record
    /// it: zero frame acceleration (checkpoints written before it existed had none); `None`
    /// for a scalar that must be recorded.
    pub fn scalar_default(name: &str) -> Option<f64> {
        name.starts_with("frame_acceleration_").then_some(0.0)
    }

    /// Copy `other` into `self` without allocating. Both must hold the same arrays of the same
    /// shapes and the same resources (two states of one simulation do); returns whether they
    /// did (nothing is copied otherwise).
    pub fn copy_from(&mut self, other: &State) -> bool {
        let base = |s: &State| [&s.u, &s.v, &s.p, &s.rho, &s.mu].map(|f| f.data().len());
        let fits = base(self) == base(other)
            && self.w.as_ref().map(|f| f.data().len()) == other.w.as_ref().map(|f| f.data().len())
            && self.phi.as_ref().map(|f| f.data().len())
                == other.phi.as_ref().map(|f| f.data().len())
            && self.resources.0.len() == other.resources.0.len()
            && self
                .resources
                .0
                .iter()
                .zip(&other.resources.0)
                .all(|(a, b)| a.0 == b.0 && a.1.is_some() == b.1.is_some());
        if !fits {
            return false;
        }
        for (a, b) in self.resources.iter_mut().zip(other.resources.iter()) {
            if !a.copy_from(b) {
                return false;
            }
        }
        for (f, g) in [
            (&mut self.u, &other.u),
            (&mut self.v, &other.v),
            (&mut self.p, &other.p),
            (&mut self.rho, &other.rho),
            (&mut self.mu, &other.mu),
        ] {
            f.copy_from(g);
        }
        if let (Some(f), Some(g)) = (&mut self.w, &other.w) {
            f.copy_from(g);
        }
        if let (Some(f), Some(g)) = (&mut self.phi, &other.phi) {
            f.copy_from(g);
        }
        self.t = other.t;
        self.step = other.step;
        self.dt_prev = other.dt_prev;
        self.frame_acceleration = other.frame_acceleration;
        true
    }

    /// Store `f` as the field of `id` (allocating an optional one; a stage's own field,
    /// [`FieldId::Stage`], is in its resource: nothing happens).
    pub(crate) fn put_field(&mut self, id: FieldId, f: Field) {
        match id {
            FieldId::VelocityX => self.u = f,
            FieldId::VelocityY => self.v = f,
            FieldId::VelocityZ => self.w = Some(f),
            FieldId::Pressure => self.p = f,
            FieldId::Density => self.rho = f,
            FieldId::Viscosity => self.mu = f,
            FieldId::SolidFraction => self.phi = Some(f),
            FieldId::Stage(_) => {}
        }
    }

    /// [`field`](Self::field), mutable.
    pub(crate) fn field_mut(&mut self, id: FieldId) -> Option<&mut Field> {
        match id {
            FieldId::VelocityX => Some(&mut self.u),
            FieldId::VelocityY => Some(&mut self.v),
            FieldId::VelocityZ => self.w.as_mut(),
            FieldId::Pressure => Some(&mut self.p),
            FieldId::Density => Some(&mut self.rho),
            FieldId::Viscosity => Some(&mut self.mu),
            FieldId::SolidFraction => self.phi.as_mut(),
            FieldId::Stage(_) => None,
        }
    }

    /// The field stored for `id`, if allocated (a stage's own field, [`FieldId::Stage`], is
    /// in its resource).
    pub fn field(&self, id: FieldId) -> Option<&Field> {
        match id {
            FieldId::VelocityX => Some(&self.u),
            FieldId::VelocityY => Some(&self.v),
            FieldId::VelocityZ => self.w.as_ref(),
            FieldId::Pressure => Some(&self.p),
            FieldId::Density => Some(&self.rho),
            FieldId::Viscosity => Some(&self.mu),
            FieldId::SolidFraction => self.phi.as_ref(),
            FieldId::Stage(_) => None,
        }
    }
}
