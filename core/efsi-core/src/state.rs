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
        }
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
        }
    }
}
