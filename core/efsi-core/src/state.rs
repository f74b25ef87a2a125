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
    /// Pressure at cell centres (Pa).
    pub p: Field,
    /// Density at cell centres (kg/m³).
    pub rho: Field,
    /// Dynamic viscosity at cell centres (Pa·s).
    pub mu: Field,
    /// Solid volume fraction φ_s at cell centres, when a stage declares it.
    pub phi: Option<Field>,
    /// The deformation tensor B̃, when a stage declares it.
    pub deformation: Option<Deformation>,
    /// Acceleration of the grid's frame with respect to an inertial one (m/s², default zero):
    /// the body-force stage applies `gravity − frame_acceleration` (d'Alembert), so a frame
    /// accelerating upwards, like a shaking table, makes everything in it heavier. Set between
    /// steps with [`crate::Simulation::set_frame_acceleration`] (the FMU's base-acceleration
    /// input); kept here so snapshots and checkpoints carry it.
    pub frame_acceleration: (f64, f64),
}

/// The left Cauchy–Green tensor B of the solid, from which the elastic stages form the seed's
/// modified tensor `B̃ = φ_s^{1/2} B` (Eq. 8) with the current solid fraction. Since φ_s is
/// materially conserved, B and B̃ obey the same transport law; storing B (the identity in pure
/// fluid, where it is reset every step) keeps B̃ and the VOF interface consistent — rigid motion
/// leaves `B̃ = φ_s^{1/2} I` to round-off — whereas advecting B̃ and φ_s with two different
/// schemes would not.
///
/// Staggered like the stresses it produces: `b[0] = B₁₁`, `b[1] = B₂₂`, `b[2] = B₃₃` (zz in
/// plane strain, θθ axisymmetric) at cell centres, the shear `b[3] = B₁₂` at cell corners — so
/// the shear force is a compact stencil with no undamped checkerboard mode.
///
/// Seed Eqs. 13, 17 and 24 differ only in the velocity of their implicit part: each is
/// `B = Bⁿ + explicit + (Δt/2) H(V; Bⁿ)` with `H(V; B) = L(V)·B + B·L(V)ᵀ` and
/// `explicit = −Δt (AB2 of ∇·(V B)) + (Δt/2) H(Vⁿ; Bⁿ)`. The rates at the end of a step are
/// kept here (`advection`, `advection_prev`, `stretching`) because the next step's elastic
/// stage runs after the velocity has left Vⁿ.
#[derive(Clone, Debug)]
pub struct Deformation {
    /// B (components 11, 22, 33 at centres; 12 at corners).
    pub b: [Field; 4],
    /// Bⁿ, at the start of the step.
    pub start: [Field; 4],
    /// `∇·(Vⁿ Bⁿ)`.
    pub advection: [Field; 4],
    /// `∇·(Vⁿ⁻¹ Bⁿ⁻¹)`.
    pub advection_prev: [Field; 4],
    /// `H(Vⁿ; Bⁿ)`.
    pub stretching: [Field; 4],
    /// This step's explicit part.
    pub explicit: [Field; 4],
    /// This step's implicit-relaxation divisor of the corner shear `B₁₂` at interface corners
    /// (1 elsewhere): set by the elastic stage, used again by the end-of-step update. Scratch
    /// of one step: it is recomputed before use, so it carries no history.
    pub relax: Field,
    /// The elastic stress `τ(B̃) − τ(φ^{1/2} I)` at the end of the step (the law's stress less
    /// its stress-free isotropic part, which is pressure), staggered like `b`.
    pub stress: [Field; 4],
    /// The elastic (strain) energy in the solid at the end of the step, `∫ W dV` (per radian in
    /// axisymmetric geometry), from the law's stress by integration along the isochoric path
    /// `exp(s log B)` (see the elastic stage).
    pub elastic_energy: f64,
}

impl Deformation {
    /// Zero tensors shaped for `grid`.
    pub fn zeros(grid: &Grid) -> Self {
        let z = || std::array::from_fn(|_| Field::zeros(grid));
        Deformation {
            b: z(),
            start: z(),
            advection: z(),
            advection_prev: z(),
            stretching: z(),
            explicit: z(),
            relax: Field::zeros(grid),
            stress: z(),
            elastic_energy: 0.0,
        }
    }

    /// Names of the four components, in storage order.
    pub const COMPONENTS: [&'static str; 4] = ["11", "22", "33", "12"];

    /// The six tensors by name: `b`, `start`, `advection`, `advection_prev`, `stretching`,
    /// `explicit`.
    pub fn parts(&self) -> [(&'static str, &[Field; 4]); 7] {
        [
            ("b", &self.b),
            ("start", &self.start),
            ("advection", &self.advection),
            ("advection_prev", &self.advection_prev),
            ("stretching", &self.stretching),
            ("explicit", &self.explicit),
            ("stress", &self.stress),
        ]
    }

    /// [`parts`](Self::parts), mutable.
    pub fn parts_mut(&mut self) -> [(&'static str, &mut [Field; 4]); 7] {
        [
            ("b", &mut self.b),
            ("start", &mut self.start),
            ("advection", &mut self.advection),
            ("advection_prev", &mut self.advection_prev),
            ("stretching", &mut self.stretching),
            ("explicit", &mut self.explicit),
            ("stress", &mut self.stress),
        ]
    }

    /// The first non-finite component of `b` in the interior: `(component name, (i, j))`.
    pub fn first_non_finite(&self, nx: usize, ny: usize) -> Option<(&'static str, (usize, usize))> {
        const NAMES: [&str; 4] = ["11", "22", "33", "12"];
        for (c, f) in self.b.iter().enumerate() {
            let st = if c == 3 {
                crate::Stagger::Corner
            } else {
                crate::Stagger::Cell
            };
            if let Some(at) = f.first_non_finite(st, nx, ny) {
                return Some((NAMES[c], at));
            }
        }
        None
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
            p: Field::zeros(grid),
            rho: Field::filled(grid, density),
            mu: Field::filled(grid, viscosity),
            phi: fields
                .contains(&FieldId::SolidFraction)
                .then(|| Field::zeros(grid)),
            deformation: fields
                .contains(&FieldId::Deformation)
                .then(|| Deformation::zeros(grid)),
            frame_acceleration: (0.0, 0.0),
        }
    }

    /// Every stored array with a stable name, in a fixed order: `u`, `v`, `p`, `rho`, `mu`, then
    /// `phi` and the seven deformation tensors (`B.b.11` … `B.stress.12`) when allocated. What a
    /// checkpoint saves: with `t`, `step` and `dt_prev` this is the whole state, ghosts included.
    pub fn arrays(&self) -> Vec<(String, &Field)> {
        self.array_names().into_iter().zip(self.fields()).collect()
    }

    /// The names of [`arrays`](Self::arrays), in its order.
    fn array_names(&self) -> Vec<String> {
        let mut out: Vec<String> = ["u", "v", "p", "rho", "mu"].map(String::from).into();
        if self.phi.is_some() {
            out.push("phi".into());
        }
        if let Some(d) = &self.deformation {
            for (part, _) in d.parts() {
                for c in Deformation::COMPONENTS {
                    out.push(format!("B.{part}.{c}"));
                }
            }
        }
        out
    }

    /// The scalars that carry from step to step besides `t`, `step` and `dt_prev`, with stable
    /// names: the frame acceleration (`frame_acceleration_x`, `_y`), then the elastic energy
    /// when a solid has a law. A checkpoint saves them with the arrays.
    pub fn scalars(&self) -> Vec<(&'static str, f64)> {
        let mut out = vec![
            ("frame_acceleration_x", self.frame_acceleration.0),
            ("frame_acceleration_y", self.frame_acceleration.1),
        ];
        if let Some(d) = &self.deformation {
            out.push(("elastic_energy", d.elastic_energy));
        }
        out
    }

    /// [`scalars`](Self::scalars), mutable, same names and order.
    pub fn scalars_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
        let mut out = vec![
            ("frame_acceleration_x", &mut self.frame_acceleration.0),
            ("frame_acceleration_y", &mut self.frame_acceleration.1),
        ];
        if let Some(d) = &mut self.deformation {
            out.push(("elastic_energy", &mut d.elastic_energy));
        }
        out
    }

    /// The value a scalar of [`scalars`](Self::scalars) takes when a checkpoint does not record
    /// it: zero frame acceleration (checkpoints written before it existed had none); `None`
    /// for a scalar that must be recorded.
    pub fn scalar_default(name: &str) -> Option<f64> {
        name.starts_with("frame_acceleration_").then_some(0.0)
    }

    /// [`arrays`](Self::arrays), mutable, same names and order.
    pub fn arrays_mut(&mut self) -> Vec<(String, &mut Field)> {
        self.array_names()
            .into_iter()
            .zip(self.fields_mut())
            .collect()
    }

    /// Copy `other` into `self` without allocating. Both must hold the same arrays of the same
    /// shapes (two states of one simulation do); returns whether they did (nothing is copied
    /// otherwise).
    pub fn copy_from(&mut self, other: &State) -> bool {
        let fits = self.phi.is_some() == other.phi.is_some()
            && self.deformation.is_some() == other.deformation.is_some()
            && self
                .fields()
                .zip(other.fields())
                .all(|(f, g)| f.data().len() == g.data().len());
        if !fits {
            return false;
        }
        for (f, g) in self.fields_mut().zip(other.fields()) {
            f.copy_from(g);
        }
        self.t = other.t;
        self.step = other.step;
        self.dt_prev = other.dt_prev;
        self.frame_acceleration = other.frame_acceleration;
        if let (Some(d), Some(e)) = (&mut self.deformation, &other.deformation) {
            d.elastic_energy = e.elastic_energy;
        }
        true
    }

    /// The arrays of [`arrays`](Self::arrays), without their names (no allocation): the one
    /// place that fixes their order.
    fn fields(&self) -> impl Iterator<Item = &Field> {
        [&self.u, &self.v, &self.p, &self.rho, &self.mu]
            .into_iter()
            .chain(self.phi.iter())
            .chain(
                self.deformation
                    .iter()
                    .flat_map(|d| d.parts().into_iter().flat_map(|(_, t)| t.iter())),
            )
    }

    /// [`fields`](Self::fields), mutable.
    fn fields_mut(&mut self) -> impl Iterator<Item = &mut Field> {
        [
            &mut self.u,
            &mut self.v,
            &mut self.p,
            &mut self.rho,
            &mut self.mu,
        ]
        .into_iter()
        .chain(self.phi.iter_mut())
        .chain(
            self.deformation
                .iter_mut()
                .flat_map(|d| d.parts_mut().into_iter().flat_map(|(_, t)| t.iter_mut())),
        )
    }

    /// The field stored for `id`, if allocated.
    pub fn field(&self, id: FieldId) -> Option<&Field> {
        match id {
            FieldId::VelocityX => Some(&self.u),
            FieldId::VelocityY => Some(&self.v),
            FieldId::Pressure => Some(&self.p),
            FieldId::Density => Some(&self.rho),
            FieldId::Viscosity => Some(&self.mu),
            FieldId::SolidFraction => self.phi.as_ref(),
            FieldId::Deformation => self.deformation.as_ref().map(|d| &d.b[0]),
        }
    }
}
