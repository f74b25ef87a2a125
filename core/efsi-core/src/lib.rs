//! # efsi-core
//!
//! The framework of efsi, a full-Eulerian fluid–structure interaction solver: the MAC grid and
//! its axisymmetric metric, fields, boundary conditions, the RON scene model, the stage contract
//! and scheduler, linear solvers, probes and output writers. No physics stage lives here; the
//! stages are plugins (crate `efsi-stages`) that attach to the phases named by [`schedule`].

pub mod field;
pub mod grid;
pub mod output;

pub use field::{Field, Stagger};
pub use grid::{G, GHOST, Geometry, Grid};
