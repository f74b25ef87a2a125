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
pub use stencil5::{IncompleteCholesky, Stencil5};
