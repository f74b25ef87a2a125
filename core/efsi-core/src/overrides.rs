//! The scene's side of overrides (`efsi run --set PATH=VALUE --refine F`): the field-name
//! aliases a path may use, and attributing a setting's error to the override that set it. The mechanism is [`efsi_ron_edit::overrides`]; applying overrides to
//! a scene (`Scene::load_with`, `Scene::set`, …) is `efsi_run::SceneOverrides`.

use crate::scene::SceneError;
use efsi_ron_edit::overrides::blame;
use std::path::Path;

/// One change to a scene: a setting by its path, or the grid refined.
pub use efsi_ron_edit::overrides::Override;

/// The value an override sets: what a Python caller or an FMU parameter holds, or RON text
/// ([`efsi_ron_edit::Value`]).
pub use efsi_ron_edit::Value as OverrideValue;

/// Field-name aliases the scene accepts, as `(alias, canonical)`: a path may use either.
pub const FIELD_ALIASES: efsi_ron_edit::Aliases = &[
    ("r", "x"),
    ("z", "y"),
    ("nr", "nx"),
    ("nz", "ny"),
    ("r_min", "x_min"),
    ("r_max", "x_max"),
    ("z_min", "y_min"),
    ("z_max", "y_max"),
];

/// The aliases of a scene of `geometry`: [`FIELD_ALIASES`] in two dimensions, none in
/// `Cartesian3D`, where `z`, `nz`, `z_min` and `z_max` name the third axis (and the `r`
/// spellings are refused, [`crate::scene`]'s "Three dimensions").
pub fn field_aliases(geometry: crate::grid::Geometry) -> efsi_ron_edit::Aliases {
    if geometry == crate::grid::Geometry::Cartesian3D {
        &[]
    } else {
        FIELD_ALIASES
    }
}

/// A validation error of the scene read from `path`, attributed to the last of the scene's
/// `overrides` whose path it names (or that lies inside the field it names): an
/// [`SceneError::Override`] naming it, else [`SceneError::Invalid`].
pub fn attribute(
    path: &Path,
    overrides: &[Override],
    field: String,
    message: String,
) -> SceneError {
    match blame(overrides, &field, FIELD_ALIASES) {
        Some(o) => SceneError::Override {
            path: path.to_path_buf(),
            setting: o.brief(),
            message: format!("{field}: {message}"),
        },
        None => SceneError::Invalid {
            path: path.to_path_buf(),
            field,
            message,
        },
    }
}
