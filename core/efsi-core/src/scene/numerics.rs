//! The `numerics` section: a preset, and one section per stage that declares options.
//!
//! The core does not know a stage's settings. A stage plugin that has some declares them as a
//! type implementing [`StageOptions`] — its section's name under `numerics`, its fields with
//! their defaults, its range checks and its strict preset — and returns
//! [`OptionsDecl::of`] from [`crate::StagePlugin::options`]. The scene keeps each section as
//! the RON text the file wrote ([`Numerics::section`]), which overrides edit. When a scene is
//! checked ([`check_sections`], which [`crate::Simulation::new`] runs against the declarations
//! of the plugins it is given) each declared section is read once into its type, validated
//! once and kept typed in the [`Options`] the check returns; the stages are built from those
//! (`&Options`), never from the text. An unknown section, a malformed or out of range setting
//! is refused there, naming the setting (`numerics.elastic.coupling`), and the scene it keeps
//! holds every declared section with its defaults filled in and the preset applied, so
//! `run.json` records the settings in force. Adding an option or a section touches only the
//! stage that owns it.
//!
//! ```text
//! numerics: (
//!     preset: Strict,
//!     projection: (tolerance: 1e-8, solver: Multigrid),
//!     viscous: (preconditioner: Jacobi),
//! )
//! ```

use super::{Options, Scene, Section};
use crate::schedule::StagePlugin;
use crate::validate::Failure;
use serde::de::{DeserializeOwned, MapAccess, Visitor};
use serde::ser::SerializeStruct;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;
use std::fmt;

/// The numerics of a scene: the tolerance preset and the stages' option sections.
#[derive(Clone, Debug, Default)]
pub struct Numerics {
    /// A set of solver tolerances (default `Default`); `Strict` tightens each stage's
    /// tolerances to at most their strict values ([`StageOptions::strict`]) — one setting for
    /// the strict run a check or a reference needs.
    pub preset: Preset,
    sections: BTreeMap<String, Entry>,
}

/// Solver-tolerance presets (`numerics.preset`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preset {
    /// The tolerances as set, or their defaults, chosen by the error/time trade of the
    /// paper's cases (`docs/benchmarks.md`).
    #[default]
    Default,
    /// Each tolerance at most its strict value (the stage's [`StageOptions::strict`]; a
    /// tighter one set in the scene stays).
    Strict,
}

/// One stage's section as the scene wrote it, and its settings in force as JSON (set by
/// [`check_sections`]), for records.
type Entry = (Section, Option<serde_json::Value>);

/// The options a stage reads from its `numerics` section.
pub trait StageOptions:
    Serialize + DeserializeOwned + Default + Clone + Send + Sync + 'static
{
    /// The section's name under `numerics` (`projection`, `viscous`, …).
    const SECTION: &'static str;
    /// Check ranges and consistency; on failure the field's name within the section and what
    /// was expected. `scene` is the whole scene, for checks that depend on it.
    fn validate(&self, scene: &Scene) -> Result<(), (&'static str, String)>;
    /// Tighten the tolerances to the strict preset's (idempotent).
    fn strict(&mut self) {}
    /// Fill in the settings left unset whose default depends on the scene, so that the
    /// settings in force as JSON (`run.json`, [`Numerics::sections_json`]) name a value.
    /// `options` holds every section of the scene read into its type (and what the plugins'
    /// [`StagePlugin::check_scene`] read), for defaults that depend on another stage's
    /// settings. The section's text keeps them unset: a checked scene changed afterwards (a
    /// solid added) resolves them anew. Default: nothing.
    fn resolve(&mut self, _scene: &Scene, _options: &Options) {}
}

/// What a stage plugin declares of its options: the section's name and how to check it.
#[derive(Clone, Copy)]
pub struct OptionsDecl {
    /// The section's name under `numerics`.
    pub section: &'static str,
    /// Read the section into its type (the preset applied), keep it in the options, and
    /// return its text with the defaults filled in.
    read: fn(&Scene, &mut Options) -> Result<Section, Failure>,
    /// Check the section read, its scene-dependent defaults resolved; its settings in force as
    /// JSON.
    settle: fn(&Scene, &Options) -> Result<serde_json::Value, Failure>,
}

impl fmt::Debug for OptionsDecl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("OptionsDecl")
            .field("section", &self.section)
            .finish()
    }
}

impl OptionsDecl {
    /// The declaration of the options type `O`.
    pub fn of<O: StageOptions>() -> OptionsDecl {
        OptionsDecl {
            section: O::SECTION,
            read: |scene, options| {
                let o: O = scene.numerics.read()?;
                // The text as the scene set it (defaults filled in, the preset applied).
                let raw = Section::of(&o).map_err(|m| (format!("numerics.{}", O::SECTION), m))?;
                options.insert(o);
                Ok(raw)
            },
            settle: |scene, options| {
                let mut resolved = options
                    .section::<O>()
                    .map_err(|m| (O::SECTION.into(), m))?
                    .clone();
                resolved.resolve(scene, options);
                resolved
                    .validate(scene)
                    .map_err(|(field, m)| (format!("numerics.{}.{field}", O::SECTION), m))?;
                // The JSON with the scene's own defaults resolved.
                serde_json::to_value(&resolved)
                    .map_err(|e| (format!("numerics.{}", O::SECTION), e.to_string()))
            },
        }
    }
}

/// Check the scene's sections that `plugins` own, first those outside `numerics`
/// ([`StagePlugin::check_scene`]), then the `numerics` sections against the options `plugins`
/// declare: each section must be declared by one of them (whether or not the scene needs that
/// stage), parse as its type and pass its checks. On success every declared section is
/// replaced by its settings in force (defaults filled in, the preset applied), and the typed
/// values — each section read once, and what the plugins' [`StagePlugin::check_scene`] read —
/// are returned for the stages' builds. On failure the setting's path and why.
pub fn check_sections(scene: &mut Scene, plugins: &[&dyn StagePlugin]) -> Result<Options, Failure> {
    let mut options = Options::default();
    for p in plugins {
        p.check_scene(scene, &mut options)?;
    }
    let mut decls: BTreeMap<&'static str, OptionsDecl> = BTreeMap::new();
    for d in plugins.iter().filter_map(|p| p.options()) {
        decls.entry(d.section).or_insert(d);
    }
    if let Some(name) = scene
        .numerics
        .sections
        .keys()
        .find(|n| !decls.contains_key(n.as_str()))
    {
        let known: Vec<&str> = decls.keys().copied().collect();
        return Err((
            format!("numerics.{name}"),
            format!(
                "no stage has a section `{name}`; the sections are preset, {}",
                known.join(", ")
            ),
        ));
    }
    // Every section read once into its type, then each checked with all of them at hand.
    let mut texts = Vec::with_capacity(decls.len());
    for d in decls.values() {
        texts.push((d.section, (d.read)(scene, &mut options)?));
    }
    let mut effective = Vec::with_capacity(decls.len());
    for ((name, raw), d) in texts.into_iter().zip(decls.values()) {
        effective.push((name, raw, (d.settle)(scene, &options)?));
    }
    for (name, raw, json) in effective {
        scene
            .numerics
            .sections
            .insert(name.to_string(), (raw, Some(json)));
    }
    Ok(options)
}

impl Scene {
    /// [`check_sections`] with the plugins `plugins`, for the scene read from `path`: the
    /// typed sections for the stages' builds; an error an override caused names the override
    /// ([`crate::overrides::attribute`]).
    pub fn check_options(
        &mut self,
        path: &std::path::Path,
        plugins: &[&dyn StagePlugin],
    ) -> Result<Options, super::SceneError> {
        check_sections(self, plugins).map_err(|(field, message)| {
            crate::overrides::attribute(path, &self.overrides, field, message)
        })
    }
}

impl Numerics {
    /// Read section `O::SECTION` from its text: the scene's settings, the defaults for what it
    /// leaves out, the preset applied. On error the setting's path and the reader's message
    /// (with the line and column in the scene file where known). Only the check
    /// ([`check_sections`]) and an edit ([`Numerics::update`]) read the text; stages take the
    /// checked value from [`Options`].
    fn read<O: StageOptions>(&self) -> Result<O, (String, String)> {
        let mut o = match self.sections.get(O::SECTION) {
            None => O::default(),
            Some((s, _)) => s.read(&format!("numerics.{}", O::SECTION))?,
        };
        if self.preset == Preset::Strict {
            o.strict();
        }
        Ok(o)
    }

    /// Replace section `O::SECTION` by `options` (what a scene built in code sets).
    pub fn set<O: StageOptions>(&mut self, options: &O) {
        let raw = Section::of(options).expect("stage options serialise to RON");
        self.sections.insert(O::SECTION.to_string(), (raw, None));
    }

    /// Change section `O::SECTION` in place, an edit of the scene before it is checked: read
    /// its text (without the preset), apply `change`, write it back.
    pub fn update<O: StageOptions>(
        &mut self,
        change: impl FnOnce(&mut O),
    ) -> Result<(), (String, String)> {
        let preset = std::mem::take(&mut self.preset);
        let got = self.read::<O>();
        self.preset = preset;
        let mut o = got?;
        change(&mut o);
        self.set(&o);
        Ok(())
    }

    /// The RON text of a section as the scene holds it, if it has one.
    pub fn section(&self, name: &str) -> Option<&str> {
        self.sections.get(name).map(|(s, _)| s.text())
    }

    /// Each section's name and RON text, in name order.
    pub fn sections(&self) -> impl Iterator<Item = (&str, &str)> {
        self.sections
            .iter()
            .map(|(name, (s, _))| (name.as_str(), s.text()))
    }

    /// Each checked section's settings in force as JSON ([`check_sections`]; sections not
    /// checked since they were set are left out), in name order.
    pub fn sections_json(&self) -> impl Iterator<Item = (&str, &serde_json::Value)> {
        self.sections
            .iter()
            .filter_map(|(name, (_, json))| Some((name.as_str(), json.as_ref()?)))
    }

    /// Setting `numerics.SECTION.FIELD` as the settings in force record it ([`check_sections`]:
    /// a default that depends on the scene resolved); `None` if the section was not checked
    /// since it was set, or has no such field.
    pub fn in_force(&self, section: &str, field: &str) -> Option<&serde_json::Value> {
        self.sections.get(section)?.1.as_ref()?.get(field)
    }

    /// Record where each section's text starts in `text`, the scene file it was read from; a
    /// section not found there as written (an override rewrote it) gets no position.
    pub(crate) fn locate_in(&mut self, text: &str) {
        for (s, _) in self.sections.values_mut() {
            s.locate_in(text);
        }
    }
}

/// A section's name as the `'static` field name a serializer needs: each distinct name is
/// leaked once (a scene has a handful).
fn intern(name: &str) -> &'static str {
    use std::sync::Mutex;
    static NAMES: Mutex<Vec<&'static str>> = Mutex::new(Vec::new());
    let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(n) = names.iter().find(|n| **n == name) {
        return n;
    }
    let n: &'static str = Box::leak(name.to_string().into_boxed_str());
    names.push(n);
    n
}

impl Serialize for Numerics {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("Numerics", 1 + self.sections.len())?;
        st.serialize_field("preset", &self.preset)?;
        for (name, (section, _)) in &self.sections {
            st.serialize_field(intern(name), section)?;
        }
        st.end()
    }
}

impl<'de> Deserialize<'de> for Numerics {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Numerics;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("the numerics: `(preset: …, <stage>: (…), …)`")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Numerics, A::Error> {
                let mut n = Numerics::default();
                while let Some(key) = m.next_key::<String>()? {
                    if key == "preset" {
                        n.preset = m.next_value()?;
                    } else {
                        let section: Section = m.next_value()?;
                        if n.sections.contains_key(&key) {
                            return Err(serde::de::Error::custom(format!(
                                "duplicate section `{key}`"
                            )));
                        }
                        n.sections.insert(key, (section, None));
                    }
                }
                Ok(n)
            }
        }
        d.deserialize_struct("Numerics", &[], V)
    }
}
