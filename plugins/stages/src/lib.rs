//! # efsi-stages
//!
//! The sub-steps of one efsi time step (seed Fig. 1), each a plugin that attaches to a phase of
//! the core scheduler.

pub mod vof;
