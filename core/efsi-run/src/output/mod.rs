//! Output writers: VTK XML for ParaView, CSV probes and profiles.

pub mod atomic;
pub mod fields;
pub mod read;
pub mod vtk;
