//! The scene's side of overrides (`efsi run --set PATH=VALUE --refine F`): the field-name
//! aliases a path may use, reading a scene file, and attributing a setting's error to the
//! override that set it. The mechanism is [`efsi_ron_edit::overrides`]; applying overrides to
//! a scene (`Scene::load_with`, `Scene::set`, …) is `efsi_run::SceneOverrides`.

use crate::scene::{Scene, SceneError};
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

impl Scene {
    /// The text of the scene file at `path`: at most [`crate::scene::MAX_SCENE_BYTES`] of
    /// UTF-8; anything else is refused as not a scene file.
    pub fn read_file(path: &Path) -> Result<String, SceneError> {
        let io = |source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        };
        // Read at most one byte past the cap: `/dev/zero` or a huge file is refused, not read.
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| {
                use std::io::Read;
                f.take(crate::scene::MAX_SCENE_BYTES + 1)
                    .read_to_end(&mut bytes)
            })
            .map_err(io)?;
        if bytes.len() as u64 > crate::scene::MAX_SCENE_BYTES {
            return Err(io(std::io::Error::other(format!(
                "larger than {} MiB: not a scene file",
                crate::scene::MAX_SCENE_BYTES >> 20
            ))));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            io(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "not UTF-8 text (invalid byte at offset {})",
                    e.utf8_error().valid_up_to()
                ),
            ))
        })?;
        Ok(text)
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
            setting: o.to_string(),
            message: format!("{field}: {message}"),
        },
        None => SceneError::Invalid {
            path: path.to_path_buf(),
            field,
            message,
        },
    }
}
