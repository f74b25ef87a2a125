//! [`Options`]: the scene's plugin-owned sections in their owners' types, read once.
//!
//! The core keeps a plugin's section as RON text ([`super::Section`]) and does not name its
//! type. When a scene is checked ([`super::options::check_sections`]) each section is read into
//! the type its owner declares, validated, and kept here, one value per type; the stages are
//! built from this map ([`crate::StagePlugin::build`]), so no reader parses a section again and
//! none can fall back to a default when a section does not read: the check has already failed,
//! naming the setting.

use std::any::{Any, TypeId};
use std::collections::HashMap;

/// The typed sections of a checked scene, one value per type: each stage's `numerics` options
/// ([`super::StageOptions`]) and what a plugin's [`crate::StagePlugin::check_scene`] read
/// (the stages' solid). Made by [`super::options::check_sections`]; read-only after it.
#[derive(Default)]
pub struct Options {
    map: HashMap<TypeId, Box<dyn Any + Send + Sync>>,
}

impl Options {
    /// The value of type `T`, if the check put one in.
    pub fn get<T: Any + Send + Sync>(&self) -> Option<&T> {
        self.map
            .get(&TypeId::of::<T>())
            .and_then(|b| b.downcast_ref())
    }

    /// Keep `value` as the value of type `T` (replacing any before it): what a plugin's
    /// [`crate::StagePlugin::check_scene`] read of the sections it owns.
    pub fn insert<T: Any + Send + Sync>(&mut self, value: T) {
        self.map.insert(TypeId::of::<T>(), Box::new(value));
    }

    /// The options of section `O::SECTION`, as checked (the scene's settings, the defaults for
    /// what it leaves out, the preset applied). An error names the section if the scene was
    /// not checked with a plugin that declares it.
    pub fn section<O: super::StageOptions>(&self) -> Result<&O, String> {
        self.get::<O>().ok_or_else(|| {
            format!(
                "numerics.{}: not checked (no plugin given to the check declares it)",
                O::SECTION
            )
        })
    }

    /// Another stage's options, borrowed by a stage that needs one of its settings: section
    /// `O::SECTION` as checked, or, where no plugin given to the check declares it (a pipeline
    /// built without that stage, whose section a scene could then not set), its defaults with
    /// the scene's `preset` applied.
    pub fn section_or_default<O: super::StageOptions>(&self, preset: super::Preset) -> O {
        self.get::<O>().cloned().unwrap_or_else(|| {
            let mut o = O::default();
            if preset == super::Preset::Strict {
                o.strict();
            }
            o
        })
    }
}

impl std::fmt::Debug for Options {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Options")
            .field("values", &self.map.len())
            .finish()
    }
}
