//! # efsi-fmu
//!
//! efsi's sphere-impact model (seed §5.1) as a Functional Mock-up Unit: one library
//! (`sphere_impact.so`) that exports both the FMI 2.0 Co-Simulation API ([`fmi2`]) and the FMI
//! 3.0 Co-Simulation API ([`fmi3`]) over one model ([`model`]), which builds an efsi scene from
//! its parameters ([`params`]) and steps it with efsi's own solver ([`stepping`]). `cargo xtask
//! fmu` packages it as `target/fmu/sphere_impact.fmu` (FMI 2.0) and
//! `target/fmu/sphere_impact_fmi3.fmu` (FMI 3.0), with the shipped law libraries beside it in
//! `binaries/<platform>/` and the `modelDescription.xml` of [`description`].
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
pub mod params;
pub mod state;
pub mod stepping;

pub use model::Model;
pub use params::Params;
