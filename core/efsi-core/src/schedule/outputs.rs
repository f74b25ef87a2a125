//! What a stage contributes to a run's outputs ([`crate::StagePlugin::outputs`]): VTK arrays,
//! fields to sample at points and probe quantities of the fields it owns, each computed from
//! the state. The run's writers (crate `efsi-run`) list the shared fields' outputs first, then
//! the scheduled stages'; `efsi-run` checks the scene's
//! `output.vtk.fields`, `output.probes` and `output.profiles` against exactly these. A stage
//! that adds a field adds its outputs here, and no core or writer file changes.

use crate::field::Field;
use crate::grid::{Geometry, Grid};
use crate::state::State;

/// One output of a stage, by name.
#[derive(Clone, Copy, Debug)]
pub struct OutputDecl {
    /// Its name: the VTK array's (`output.vtk.fields`) or the probe's column
    /// (`output.probes: [Quantity("name")]`).
    pub name: &'static str,
    /// What it holds (documented in `run.json`).
    pub meaning: &'static str,
    /// Its unit for a scene in SI units.
    pub unit: &'static str,
    /// Its kind and how it is computed.
    pub kind: OutputKind,
}

/// How an output is computed.
#[derive(Clone, Copy, Debug)]
pub enum OutputKind {
    /// A VTK cell array.
    Array {
        /// Its components in the file's order (VTK's: vectors X, Y, Z; symmetric tensors XX,
        /// YY, ZZ, XY, YZ, XZ), each named by the physical component it holds.
        components: fn(Geometry) -> Vec<&'static str>,
        /// Its values at the cell centres, cell-major (`components` per cell, rows of x in
        /// order of y), or `None` when the state does not hold it.
        values: fn(&Grid, &State) -> Option<Vec<f64>>,
    },
    /// A scalar field at the cell centres (ghosts filled): a VTK array of one component, and
    /// a field `Point` probes and line profiles sample by name (bilinear interpolation).
    Field(fn(&State) -> Option<&Field>),
    /// A number per probe sample: one column of `probes.csv`.
    Quantity(fn(&Grid, &State) -> f64),
}

impl OutputDecl {
    /// Whether it is a VTK array.
    pub fn is_array(&self) -> bool {
        matches!(self.kind, OutputKind::Array { .. } | OutputKind::Field(_))
    }
}
