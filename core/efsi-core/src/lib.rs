//! # efsi-core
//!
//! The framework of efsi, a full-Eulerian fluid–structure interaction solver: the MAC grid and
//! its axisymmetric metric, fields, boundary conditions, the RON scene model, the stage contract
//! and scheduler, and the simulation that steps them. No physics stage lives here; the stages
//! are plugins (crate `efsi-stages`) that attach to the phases named by [`schedule`], and the
//! rest of what the framework needs from a plugin it reaches through [`plugin_api`]; no crate of
//! the framework depends on a plugin crate. The linear solvers and the parallel loops are in
//! `efsi-linalg`, the run loop, outputs, probes and checkpoints in `efsi-run`; the law plugins'
//! host (`efsi-laws-host`) is a plugin crate.

pub mod advance;
pub mod bc;
pub mod body_fractions;
pub mod error;
pub mod field;
pub mod grid;
pub mod loops;
pub mod operators;
pub mod overrides;
pub mod plugin_api;
pub mod scene;
pub mod schedule;
pub mod simulation;
pub mod snapshot;
pub mod state;
pub mod validate;

pub use advance::{Advance, AdvanceError, Advanced, Flow, Rollback, StepInfo, StepStart, due};
pub use bc::BoundarySet;
pub use error::EfsiError;
pub use field::{Field, Stagger};
pub use grid::{G, GHOST, Geometry, Grid};
pub use loops::{Index, Line, Region, Storage, unit};
pub use overrides::{Override, OverrideValue};
pub use scene::{Scene, SceneError};
pub use schedule::{
    FieldId, OutputDecl, OutputKind, Phase, Pipeline, Resources, Stage, StageError, StagePlugin,
    StageStats, StepContext, SubStep,
};
pub use simulation::{Simulation, StepCheck};
pub use snapshot::Snapshot;
pub use state::{State, StateResource, StateResources, Velocity};
