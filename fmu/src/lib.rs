//! # efsi-fmu
//!
//! Any efsi scene as a Functional Mock-up Unit for co-simulation: one library (`efsi_fmu`,
//! packaged as `binaries/<platform>/<model identifier>.so`) that exports both the FMI 2.0
//! Co-Simulation API ([`fmi2`]) and the FMI 3.0 Co-Simulation API ([`fmi3`]) over one model
//! ([`model`]). What the FMU is — the scene and the interface chosen for it, parameters as scene
//! paths, inputs, probes as outputs — is its [`spec`], packaged in `resources/`; the model
//! applies the parameters to the scene as overrides and steps it with efsi's own solver
//! ([`stepping`]). `cargo xtask fmu SCENE …` packages a scene (`efsi-fmu-package` writes the
//! descriptions, [`description`]); without a scene it packages the sphere impact.
//!
//! Every `extern "C"` function catches panics (nothing unwinds into the importer), validates
//! the handles it is given ([`instance`]) and follows the FMI life cycle ([`machine`]).

pub mod description;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod log;
pub mod machine;
pub mod model;
pub mod shim;
pub mod spec;
pub mod state;
pub mod stepping;

pub use model::Model;
pub use spec::Spec;
