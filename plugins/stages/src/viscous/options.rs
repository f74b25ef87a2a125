//! The viscous stage's options (`numerics.viscous`).

use efsi_core::Scene;
use efsi_core::scene::options::{StageOptions, check_iterations, check_tolerance};
use serde::{Deserialize, Serialize};

/// Parameters of the implicit viscous step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscousOptions {
    /// Implicitness θ ∈ [0.5, 1]: 1 is backward Euler (the seed's Eq. 12, default), 0.5 is
    /// Crank–Nicolson.
    #[serde(default = "one")]
    pub theta: f64,
    /// Relative residual at which the conjugate gradient stops: `‖r‖ ≤ tolerance·‖b‖` with
    /// `b = Δt K(V*)`, so the viscous velocity increment of the step is solved to about this
    /// relative accuracy (default 1e-3, Basilisk's default magnitude). In a transient flow the
    /// error does not accumulate: each step's increment is accurate to this fraction of itself,
    /// well below the discretisation error of the shipped cases (the paper's quick cases pass
    /// their accuracy checks at this default, `tests/tests/paper_quick.rs`). Near a steady state
    /// (`time.steady`) the stage tightens its own stop (see the stage's module docs), so a
    /// steady state does not depend on this tolerance. A strict setting is 1e-9 (the `Strict`
    /// preset).
    #[serde(default = "default_visc_tol")]
    pub tolerance: f64,
    /// Iteration cap (default 10000).
    #[serde(default = "default_max_iter")]
    pub max_iterations: usize,
    /// The preconditioner of the conjugate gradient (default `Jacobi`).
    #[serde(default)]
    pub preconditioner: ViscousPreconditioner,
}

impl Default for ViscousOptions {
    fn default() -> Self {
        ViscousOptions {
            theta: 1.0,
            tolerance: default_visc_tol(),
            max_iterations: default_max_iter(),
            preconditioner: ViscousPreconditioner::default(),
        }
    }
}

/// Preconditioner of the viscous step's conjugate gradient.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ViscousPreconditioner {
    /// Each step, `Multigrid` where the diffusion number makes Jacobi slow (the largest
    /// diagonal-to-mass ratio of the system above 40), else `Jacobi`.
    Auto,
    /// The diagonal (the default): cheapest per iteration; iterations grow like
    /// `√(1 + 8 μΔt/(ρh²))`. It keeps a flow that is uniform along a periodic direction
    /// exactly uniform, which the red–black smoother of `Multigrid` does only to the solver
    /// tolerance (the oscillating Couette flow then leaks solid fraction ~1e-7 into the fluid).
    #[default]
    Jacobi,
    /// Multigrid V-cycles on the diagonal blocks, one per velocity component (the coupling
    /// between components through the shear stress left to CG):
    /// ≈ 16 iterations whatever the grid and the diffusion number, at about four times
    /// Jacobi's cost per iteration.
    Multigrid,
}

fn one() -> f64 {
    1.0
}
fn default_visc_tol() -> f64 {
    1e-3
}

/// The strict preset's tolerance, and that of a solve from zero near a steady state whose
/// criterion is at round-off (see the stage's module docs).
pub(crate) const STRICT_TOLERANCE: f64 = 1e-9;

impl StageOptions for ViscousOptions {
    const SECTION: &'static str = "viscous";

    fn validate(&self, _scene: &Scene) -> Result<(), (&'static str, String)> {
        if !(0.5..=1.0).contains(&self.theta) {
            return Err((
                "theta",
                format!(
                    "must be in [0.5, 1], got {}",
                    efsi_core::scene::num(self.theta)
                ),
            ));
        }
        check_tolerance("tolerance", self.tolerance)?;
        check_iterations("max_iterations", self.max_iterations)
    }

    fn strict(&mut self) {
        self.tolerance = self.tolerance.min(STRICT_TOLERANCE);
    }
}

fn default_max_iter() -> usize {
    10000
}
