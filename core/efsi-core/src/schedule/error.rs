//! [`ScheduleError`]: why a pipeline could not be assembled.

use super::Phase;
use crate::grid::Geometry;

/// The pipeline could not be assembled.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ScheduleError {
    /// A stage reads a field that nothing provides.
    #[error("stage `{stage}` reads `{field}`, which no scheduled stage provides")]
    MissingField {
        /// The stage.
        stage: String,
        /// The field.
        field: &'static str,
    },
    /// Two stages of one phase touch the same field without an ordering between them.
    #[error(
        "stages `{a}` and `{b}` of phase {phase:?} both touch `{field}` but neither is declared after the other"
    )]
    Ambiguous {
        /// First stage.
        a: String,
        /// Second stage.
        b: String,
        /// Their phase.
        phase: Phase,
        /// The shared field.
        field: &'static str,
    },
    /// An ordering constraint names a stage that is not in the same phase, or forms a cycle.
    #[error("stage `{stage}`: ordering constraint on `{other}` cannot be satisfied ({why})")]
    BadOrder {
        /// The stage.
        stage: String,
        /// The stage it names.
        other: String,
        /// Why.
        why: &'static str,
    },
    /// Two plugins share a name, or two steps of one pipeline (stages, sub-steps).
    #[error("two stage plugins (or sub-steps of scheduled stages) are named `{0}`")]
    DuplicateName(String),
    /// Two scheduled stages declare an output of one name.
    #[error("stages `{first}` and `{second}` both declare the output `{output}`")]
    DuplicateOutput {
        /// The output's name.
        output: &'static str,
        /// The stage that declared it first.
        first: &'static str,
        /// The other.
        second: &'static str,
    },
    /// The scene needs stages that do not run in its geometry ([`super::StagePlugin::supports`]).
    #[error(
        "the {geometry:?} scene ({}) needs stages that do not support {geometry:?} geometry: {}",
        cells_text(*geometry, cells),
        stages.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")
    )]
    Unsupported {
        /// The stages, in the plugins' order.
        stages: Vec<&'static str>,
        /// The scene's geometry.
        geometry: Geometry,
        /// The grid's cells along each axis.
        cells: [usize; 3],
    },
    /// A plugin refused the scene.
    #[error("stage `{stage}`: {message}")]
    Build {
        /// The stage.
        stage: String,
        /// Its message.
        message: String,
    },
}

/// `nx×ny cells`, or `nx×ny×nz cells` in three dimensions.
fn cells_text(geometry: Geometry, [nx, ny, nz]: &[usize; 3]) -> String {
    if geometry == Geometry::Cartesian3D {
        format!("{nx}×{ny}×{nz} cells")
    } else {
        format!("{nx}×{ny} cells")
    }
}
