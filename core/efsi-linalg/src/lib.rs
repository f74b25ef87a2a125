//! Linear solvers: preconditioned conjugate gradient and the preconditioners it uses
//! (incomplete Cholesky, geometric multigrid), BiCGSTAB, flexible GMRES, and deterministic
//! parallel loops.

pub mod bicgstab;
pub mod fgmres;
pub mod multigrid;
pub mod par;
pub mod pcg;
pub mod stencil5;

pub use bicgstab::BiCgStab;
pub use fgmres::{Accept, Fgmres, FlexiblePreconditioner};
pub use multigrid::Multigrid;
pub use pcg::{LinearOperator, Norm, Pcg, Preconditioner, SolveStats};
pub use stencil5::{IncompleteCholesky, Stencil5, Stencil5View};

/// Small systems shared by the solvers' unit tests.
#[cfg(test)]
pub(crate) mod test_systems {
    use super::LinearOperator;

    /// A non-symmetric advection–diffusion matrix of size `n`.
    pub(crate) struct AdvDiff(pub(crate) usize);

    impl LinearOperator for AdvDiff {
        fn apply(&mut self, x: &[f64], y: &mut [f64]) {
            let n = self.0;
            for k in 0..n {
                let l = if k > 0 { x[k - 1] } else { 0.0 };
                let r = if k + 1 < n { x[k + 1] } else { 0.0 };
                y[k] = 3.0 * x[k] - 1.6 * l - 0.4 * r;
            }
        }
    }
}
