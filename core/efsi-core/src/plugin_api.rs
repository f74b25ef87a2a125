//! What the framework knows of its plugins beyond the stage contract ([`crate::schedule`]).
//!
//! The layers: nothing in the framework (`core/`) depends on a plugin crate (`plugins/`). The
//! stages attach through [`StagePlugin`](crate::StagePlugin); what else the run loop, its
//! outputs and its checkpoints need from a plugin they reach through the traits here, whose
//! implementations a plugin puts in the checked scene's [`Options`] when it reads the section
//! it owns. The front ends (the `efsi` command, the FMU, the Python module) are the only places
//! that compose the framework with the shipped plugins.
//!
//! - [`LawLoader`]: the constitutive-law loader, as a checkpoint needs it — the identity of the
//!   law library a scene names (its declared name, ABI version and parameter table), never a
//!   law's evaluation, which is the elastic stage's. The plugin that checks the `solid`
//!   section keeps it in [`Options`] as [`Laws`].

use crate::scene::Options;
use std::path::{Path, PathBuf};

/// What a law library declares, as a checkpoint records it.
#[derive(Clone, Debug, PartialEq)]
pub struct LawDescription {
    /// The name the library declares.
    pub name: String,
    /// The ABI version it was built for.
    pub abi_version: u32,
    /// The library file the scene's name resolved to.
    pub library: PathBuf,
    /// Its parameter table, one line per parameter: name, unit, default, range.
    pub parameters: Vec<String>,
}

/// The loader of constitutive-law libraries, as the framework sees it.
pub trait LawLoader: Send + Sync {
    /// The library that `name` (a shipped law's name or a library path) names for a scene in
    /// folder `dir`, resolved as the elastic stage resolves it, and what it declares; on error
    /// the loader's message (a missing file, a wrong ABI version, a missing symbol, …).
    fn describe(&self, name: &str, dir: &Path) -> Result<LawDescription, String>;
}

/// The law loader of a checked scene, kept in its [`Options`] by the plugin that checks the
/// `solid` section.
#[derive(Clone, Copy)]
pub struct Laws(pub &'static dyn LawLoader);

impl Laws {
    /// The law loader of the checked scene whose sections are `options`, if a plugin put one
    /// there.
    pub fn of(options: &Options) -> Option<&'static dyn LawLoader> {
        options.get::<Laws>().map(|l| l.0)
    }
}

impl std::fmt::Debug for Laws {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Laws(..)")
    }
}
