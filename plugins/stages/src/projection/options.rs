//! The projection's options (`numerics.projection`), read by the projection and its predictor.

use efsi_core::Scene;
use efsi_core::scene::options::{Options, StageOptions, check_iterations, check_tolerance};
use serde::{Deserialize, Serialize};

/// Parameters of the pressure projection.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProjectionOptions {
    /// Convergence criterion: after projection `max |∇·u|·Δt ≤ tolerance` — the largest
    /// fraction of its volume a cell may gain or lose in a step (dimensionless), reached after
    /// at least one iteration. Basilisk's default is 1e-3 in the same form; the `Strict`
    /// preset's is 1e-10. Default (unset; [`Self::tolerance_in`]):
    ///
    /// - [`INTERFACE_TOLERANCE`] (1e-6) in a scene with a second material (its `solid`
    ///   section: a solid or a second fluid), where what a step leaves moves the interface and
    ///   adds up in the tracked volume (the volume-drift targets of `tests/tests/two_material.rs`
    ///   and the drop benchmark).
    /// - [`ONE_FLUID_TOLERANCE`] (1e-4) in a scene of one fluid, where nothing carries the
    ///   divergence from step to step (each projection acts on the whole velocity, so what one
    ///   step leaves does not accumulate): the looser tolerance takes fewer iterations.
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Iteration cap of the preconditioned conjugate gradient (default 10000).
    #[serde(default = "default_max_iter")]
    pub max_iterations: usize,
    /// The preconditioner of the conjugate gradient (default `Multigrid`).
    #[serde(default)]
    pub solver: PressureSolver,
    /// Incremental pressure correction: the last step's pressure gradient joins the predicted
    /// velocity before the viscous step, and the projection solves for the pressure's
    /// increment, so a viscous fluid at rest under gravity stays at rest
    /// (`efsi_stages::projection`). `false` is the seed's scheme (Eqs. 11–23), the whole
    /// pressure found by the projection. Default (unset): incremental, except in a scene with
    /// an elastic solid, where the seed's scheme is kept (the predictor feeds energy into a
    /// stiff solid). Never with an elastic strategy that may take the coupled step
    /// (`numerics.elastic.coupling` `Coupled` or `Auto`), which finds its own pressure.
    #[serde(default)]
    pub incremental: Option<bool>,
}

impl Default for ProjectionOptions {
    fn default() -> Self {
        ProjectionOptions {
            tolerance: None,
            max_iterations: default_max_iter(),
            solver: PressureSolver::default(),
            incremental: None,
        }
    }
}

/// How the pressure equation is solved: conjugate gradient with one of two preconditioners.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PressureSolver {
    /// Geometric multigrid W-cycle (`efsi_linalg::Multigrid`): iterations independent
    /// of the grid size and of density ratios up to 1e4 (the default).
    #[default]
    Multigrid,
    /// Incomplete Cholesky IC(0), as the seed: the reference; iterations grow like the number
    /// of cells along a side.
    IncompleteCholesky,
}

/// The projection's default tolerance in a scene with a second material (see
/// [`ProjectionOptions::tolerance`]).
pub const INTERFACE_TOLERANCE: f64 = 1e-6;

/// The projection's default tolerance in a scene of one fluid (see
/// [`ProjectionOptions::tolerance`]).
pub const ONE_FLUID_TOLERANCE: f64 = 1e-4;

impl ProjectionOptions {
    /// The tolerance in force in `scene`: the one set, else [`ONE_FLUID_TOLERANCE`] in a scene
    /// of one fluid (no `solid` section) and [`INTERFACE_TOLERANCE`] in one with a second
    /// material.
    pub fn tolerance_in(&self, scene: &Scene) -> f64 {
        self.tolerance.unwrap_or(if crate::second_material(scene) {
            INTERFACE_TOLERANCE
        } else {
            ONE_FLUID_TOLERANCE
        })
    }
}
fn default_max_iter() -> usize {
    10000
}

impl StageOptions for ProjectionOptions {
    const SECTION: &'static str = "projection";

    fn validate(&self, _scene: &Scene) -> Result<(), (&'static str, String)> {
        if let Some(t) = self.tolerance {
            check_tolerance("tolerance", t)?;
        }
        check_iterations("max_iterations", self.max_iterations)
    }

    fn strict(&mut self) {
        self.tolerance = Some(self.tolerance.map_or(1e-10, |t| t.min(1e-10)));
    }

    fn resolve(&mut self, scene: &Scene, options: &Options) {
        self.tolerance = Some(self.tolerance_in(scene));
        self.incremental
            .get_or_insert_with(|| crate::incremental_pressure(options));
    }
}
