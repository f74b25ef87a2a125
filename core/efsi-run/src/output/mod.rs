//! What a run writes ([`spec`]: the scene's `output` section) and the writers: VTK XML for
//! ParaView, CSV probes and profiles.

pub mod atomic;
pub mod fields;
pub mod read;
pub mod spec;
pub mod vtk;
