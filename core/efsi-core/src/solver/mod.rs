//! Linear solvers: preconditioned conjugate gradient and the preconditioners it uses.

pub mod bicgstab;
pub mod pcg;
pub mod stencil5;

pub use bicgstab::BiCgStab;
pub use pcg::{LinearOperator, Pcg, Preconditioner, SolveStats};
pub use stencil5::{IncompleteCholesky, Stencil5};
