//! What a stage plugin declares of its place in a step: the [`Phase`] it attaches to and the
//! fields ([`FieldId`]) it reads and writes, which the scheduler checks and orders.

/// The phases of one time step, in execution order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Explicit convective term → V* (seed Eq. 11).
    Advection,
    /// Body forces (gravity) → V* (seed Eq. 11).
    BodyForce,
    /// The last step's pressure gradient → V* (incremental pressure correction; the
    /// projection then finds the pressure's increment).
    PressurePredictor,
    /// Semi-implicit viscous term → V^{n+1/3} (seed Eq. 12); B̃ predictor (Eq. 13).
    Viscous,
    /// Semi-implicit elastic term → V^{n+2/3} (seed Eqs. 15–20).
    Elastic,
    /// Pressure projection → V^{n+1} (seed Eqs. 21–23), B̃^{n+1} (Eq. 25).
    Projection,
    /// Interface transport (VOF PLIC) and material properties (seed Eqs. 4–6).
    Interface,
}

impl Phase {
    /// All phases in order.
    pub const ALL: [Phase; 7] = [
        Phase::Advection,
        Phase::BodyForce,
        Phase::PressurePredictor,
        Phase::Viscous,
        Phase::Elastic,
        Phase::Projection,
        Phase::Interface,
    ];
}

/// A field a stage may read or write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FieldId {
    /// Velocity component on x-faces.
    VelocityX,
    /// Velocity component on y-faces.
    VelocityY,
    /// Velocity component on z-faces (three-dimensional grids only).
    VelocityZ,
    /// Pressure.
    Pressure,
    /// Density.
    Density,
    /// Viscosity.
    Viscosity,
    /// Solid volume fraction (allocated only when declared).
    SolidFraction,
    /// A field a stage owns, by name (e.g. the elastic stages' `B`): it lives in the stage's
    /// [`StateResource`](crate::state::StateResource), which the stage adds to the state
    /// ([`Stage::init_state`](super::Stage::init_state)); declaring it lets the scheduler order and check its users.
    Stage(&'static str),
}

impl FieldId {
    /// Fields every state has, whatever the pipeline.
    pub const BASE: [FieldId; 5] = [
        FieldId::VelocityX,
        FieldId::VelocityY,
        FieldId::Pressure,
        FieldId::Density,
        FieldId::Viscosity,
    ];

    /// The name used in messages and outputs.
    pub fn name(self) -> &'static str {
        match self {
            FieldId::VelocityX => "u",
            FieldId::VelocityY => "v",
            FieldId::VelocityZ => "w",
            FieldId::Pressure => "pressure",
            FieldId::Density => "density",
            FieldId::Viscosity => "viscosity",
            FieldId::SolidFraction => "solid_fraction",
            FieldId::Stage(name) => name,
        }
    }
}

/// The velocity components, for declarations (`w` exists on three-dimensional grids only).
pub const VELOCITY: [FieldId; 3] = [FieldId::VelocityX, FieldId::VelocityY, FieldId::VelocityZ];
