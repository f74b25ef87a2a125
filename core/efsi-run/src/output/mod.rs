//! What a run writes ([`spec`]: the scene's `output` section), when ([`schedule`]) and the
//! formats: VTK XML for ParaView (the box, and plane slices of a three-dimensional one: [`slice`](mod@slice)),
//! CSV probes and profiles. The run's writers, each paired with
//! its schedule, are in [`crate::run`]'s outputs.

pub mod atomic;
pub mod fields;
pub mod read;
pub mod schedule;
pub mod slice;
pub mod spec;
pub mod vtk;
