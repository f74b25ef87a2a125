//! # efsi-core
//!
//! The framework of efsi, a full-Eulerian fluid–structure interaction solver: the MAC grid and
//! its axisymmetric metric, fields, boundary conditions, the RON scene model, the stage contract
//! and scheduler, linear solvers, probes and output writers. No physics stage lives here; the
//! stages are plugins (crate `efsi-stages`) that attach to the phases named by [`schedule`].

pub mod bc;
pub mod checkpoint;
pub mod error;
pub mod field;
pub mod grid;
pub mod interface;
pub mod law;
pub mod ops;
pub mod output;
pub mod overrides;
pub mod probes;
pub mod run;
pub mod scene;
pub mod schedule;
pub mod simulation;
pub mod solver;
pub mod state;

pub use bc::BoundarySet;
pub use checkpoint::{Checkpoint, CheckpointFile, Snapshot};
pub use error::EfsiError;
pub use field::{Field, Stagger};
pub use grid::{G, GHOST, Geometry, Grid};
pub use overrides::{Override, OverrideValue};
pub use scene::{Scene, SceneError};
pub use schedule::{
    FieldId, Phase, Pipeline, Stage, StageError, StagePlugin, StageStats, StepContext,
};
pub use simulation::Simulation;
pub use state::{Deformation, State};
