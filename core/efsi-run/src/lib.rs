//! # efsi-run
//!
//! Running an efsi [`Simulation`](efsi_core::Simulation): the run loop with its outputs
//! ([`run`]: VTK and `.pvd`, probes, profiles, `run.json`, landing on output times), the
//! writers ([`output`]: VTK XML, atomic files), the probes' definitions ([`probes`]) and the
//! checkpoint file with resume ([`checkpoint`]), the lock that keeps an output folder to one
//! process ([`lock`]), the energy guard that stops a run gaining energy nothing supplied
//! ([`guard`]), reading scene files and overrides ([`overrides`]: `--set`, `--refine`, FMU
//! and Python parameters), and the set-up of a simulation for a run ([`simulation`]: the memory
//! check, the `output` section's). The CLI, the FMU and other drivers use them.

pub mod binary;
pub mod checkpoint;
pub mod guard;
pub mod lock;
pub mod output;
pub mod overrides;
pub mod probes;
pub mod run;
pub mod setup;

pub use checkpoint::{Checkpoint, CheckpointFile};
pub use output::spec::{OutputSpec, ProbeSpec, ProfileSpec, SceneOutput};
pub use overrides::SceneOverrides;
pub use setup::simulation;
