//! Which kind of elastic step a step is (`numerics.elastic.coupling`): the split step, the
//! coupled one, or `Auto`'s choice between them, and the flag that tells the stages after the
//! elastic one which it was.

use super::{ElasticCoupling, ElasticOptions, ElasticPreconditioner, law_needed};
use efsi_core::scene::{Options, Preset};

/// Whether a checked scene (`options`) may take the coupled elastic step
/// (`numerics.elastic.coupling` `Coupled` or `Auto` with a solid that has an implicit law): a
/// coupled step leaves a pressure for the projection stage to complete, and Δt may reach
/// `coupled_wave_courant` elastic-wave Courant numbers.
pub(crate) fn may_couple(options: &Options) -> bool {
    coupling(options) != ElasticCoupling::Split
}

/// `numerics.elastic.coupling` as checked (its default where no plugin given to the check
/// declares the section), or `Split` where the scene has no solid with an implicit law.
pub(crate) fn coupling(options: &Options) -> ElasticCoupling {
    let o: ElasticOptions = options.section_or_default(Preset::Default);
    if law_needed(options) && o.implicit {
        o.coupling
    } else {
        ElasticCoupling::Split
    }
}

/// Whether the step under way is a coupled one, set by the elastic stage at the start of each
/// step and read by the stages after it in the same step (the deformation update's θ, the
/// projection's increment). Shared through the pipeline's [`efsi_core::Resources`]; nothing of
/// it outlives the step, so snapshots and checkpoints do not carry it.
#[derive(Clone, Default)]
pub(crate) struct CoupledStep(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl CoupledStep {
    /// The pipeline's flag (made by the first stage that asks).
    pub(crate) fn shared(shared: &mut efsi_core::Resources) -> CoupledStep {
        shared
            .get_or_try_insert_with(|| Ok::<_, ()>(CoupledStep::default()))
            .cloned()
            .unwrap_or_default()
    }

    pub(crate) fn get(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }

    pub(super) fn set(&self, coupled: bool) {
        self.0.store(coupled, std::sync::atomic::Ordering::Relaxed)
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
