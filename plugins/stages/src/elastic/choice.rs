//! Which kind of elastic step a step is (`numerics.elastic.coupling`): the split step, the
//! coupled one, or `Auto`'s choice between them.

use super::{ElasticCoupling, ElasticOptions, ElasticPreconditioner};
use efsi_core::scene::{Options, Preset};

/// Whether a checked scene (`options`) may take the coupled elastic step
/// (`numerics.elastic.coupling` `Coupled` or `Auto` with a solid that has an implicit law): a
/// coupled step leaves a pressure for the projection to complete, and Δt may reach
/// `coupled_wave_courant` elastic-wave Courant numbers.
pub(crate) fn may_couple(options: &Options) -> bool {
    coupling(options) != ElasticCoupling::Split
}

/// `numerics.elastic.coupling` as checked (its default where no plugin given to the check
/// declares the section), or `Split` where the scene has no solid with an implicit law.
pub(crate) fn coupling(options: &Options) -> ElasticCoupling {
    let o: ElasticOptions = options.section_or_default(Preset::Default);
    if crate::elastic_solid(options) && o.implicit {
        o.coupling
    } else {
        ElasticCoupling::Split
    }
}

/// What differs between a split and a coupled step: θ of B's stretching, the momentum step's
/// weight of the new stress and the velocity block's preconditioner.
#[derive(Clone, Copy, Debug)]
pub(super) struct StepScheme {
    pub(super) theta: f64,
    /// The weight of `τ(B^{n+1})` in the momentum step, `1 − alpha` that of `τ(Bⁿ)`: θ in a
    /// coupled step, 1 (the stress at the step's end) in a split one.
    pub(super) alpha: f64,
    pub(super) preconditioner: ElasticPreconditioner,
}

/// Whether a step of `dt` is a coupled one: always with `Coupled`, never with `Split`, and with
/// `Auto` once Δt exceeds the split step's wave limit `split_dt` (by more than the run loop's
/// rounding when it lands on an output time).
pub(super) fn coupled_step(mode: ElasticCoupling, dt: f64, split_dt: f64) -> bool {
    match mode {
        ElasticCoupling::Split => false,
        ElasticCoupling::Coupled => true,
        ElasticCoupling::Auto => dt > split_dt * (1.0 + 1e-6),
    }
}
