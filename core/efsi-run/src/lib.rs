//! # efsi-run
//!
//! Running an efsi [`Simulation`](efsi_core::Simulation): the run loop with its outputs
//! ([`run`]: VTK and `.pvd`, probes, profiles, `run.json`, landing on output times), the
//! writers ([`output`]: VTK XML, atomic files), the probes' definitions ([`probes`]) and the
//! checkpoint file with resume ([`checkpoint`]), the lock that keeps an output folder to one
//! process ([`lock`]), the energy guard that stops a run gaining energy nothing supplied
//! ([`guard`]), reading scene files and overrides ([`overrides`]: `--set`, `--refine`, FMU
//! and Python parameters), and the set-up of a simulation for a run ([`simulation`]: the memory
//! check, the `output` section's). The outputs are `(schedule, writer)` pairs
//! ([`run::Writer`], [`output::schedule`]).
//!
//! Part of the framework: it knows stages, laws and shapes only through efsi-core's plugin API
//! (the stage contract, the scene model, [`efsi_core::plugin_api`]) and depends on no plugin
//! crate. The front ends — the `efsi` command, the FMU, the Python module — compose it with the
//! shipped plugins, passing them to [`simulation`] and [`run::resume`].

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
