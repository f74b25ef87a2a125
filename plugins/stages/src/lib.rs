//! # efsi-stages
//!
//! The sub-steps of one efsi time step (seed Fig. 1), each a plugin that attaches to a phase of
//! the core scheduler ([`efsi_core::schedule`]). [`builtin`] lists them; the scheduler keeps
//! those a scene needs.

pub mod advection;
mod block_multigrid;
pub mod body_force;
pub mod elastic;
mod faces;
pub mod ops;
pub mod projection;
mod scratch;
pub mod solid;
mod verdict;
pub mod viscous;
mod viscous_operator;
pub mod vof;

use efsi_core::StagePlugin;

/// Whether `scene` has a second material (a `solid` section: a solid or a second fluid), whose
/// interface the VOF stage tracks. The defaults that depend on the scene follow it: the
/// advection's predictor and the projection's tolerance.
pub(crate) fn second_material(scene: &efsi_core::Scene) -> bool {
    scene.solid.is_some()
}

/// Every stage plugin shipped with efsi.
pub fn builtin() -> Vec<&'static dyn StagePlugin> {
    vec![
        &advection::Advection,
        &body_force::BodyForce,
        &projection::PressurePredictor,
        &viscous::Viscous,
        &elastic::Elastic,
        &projection::Projection,
        &elastic::DeformationUpdate,
        &vof::Vof,
    ]
}
