//! # efsi-stages
//!
//! The sub-steps of one efsi time step (seed Fig. 1), each a plugin that attaches to a phase of
//! the core scheduler ([`efsi_core::schedule`]). [`builtin`] lists them; the scheduler keeps
//! those a scene needs.

pub mod advection;
mod block_multigrid;
pub mod body_force;
pub mod contact;
pub mod elastic;
mod faces;
pub mod projection;
mod scratch;
pub mod solid;
mod verdict;
pub mod viscous;
mod viscous_operator;
pub mod vof;

use efsi_core::StagePlugin;

/// Whether `scene` has a second material (a `solid` or `solids` section: solids or other
/// fluids), whose interfaces the VOF stage tracks. The defaults that depend on the scene follow
/// it: the advection's predictor and the projection's tolerance.
pub(crate) fn second_material(scene: &efsi_core::Scene) -> bool {
    use efsi_core::scene::bodies::SceneBodies;
    scene.has_bodies()
}

/// Whether a checked scene (`options`) has an elastic solid (a solid with a constitutive law):
/// its momentum step after the viscous one is then the implicit-momentum stage's
/// ([`elastic::Momentum`]: the elastic solve, the projection and the deformation update as its
/// sub-steps), else the [`projection`] stage's.
pub(crate) fn elastic_solid(options: &efsi_core::scene::Options) -> bool {
    elastic::any_elastic(options)
}

/// Whether a checked scene (`options`) runs the incremental pressure correction (its predictor
/// stage and increments in the projection): `numerics.projection.incremental`, by default on
/// unless the scene has an elastic solid; never where the implicit-momentum stage may take the
/// coupled step ([`elastic::may_couple`]), which finds its own pressure. (The section's default
/// where no plugin given to the check declares it.)
pub(crate) fn incremental_pressure(options: &efsi_core::scene::Options) -> bool {
    let o: projection::ProjectionOptions =
        options.section_or_default(efsi_core::scene::Preset::Default);
    o.incremental.unwrap_or(!elastic_solid(options)) && !elastic::may_couple(options)
}

/// Every stage plugin shipped with efsi.
pub fn builtin() -> Vec<&'static dyn StagePlugin> {
    vec![
        &advection::Advection,
        &body_force::BodyForce,
        &contact::Contact,
        &projection::PressurePredictor,
        &viscous::Viscous,
        &elastic::Momentum,
        &projection::Projection,
        &vof::Vof,
    ]
}
