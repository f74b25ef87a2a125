//! Opaque scene sections: a part of the scene whose type another crate owns (the `output`
//! section, crate `efsi-run`; each stage's section under `numerics`, [`super::options`]).
//!
//! The core keeps such a section as the RON text the file wrote, with where it starts in the
//! file, and does not name its type. The crate that owns it reads it with [`Section::get`]
//! (a reader's error names the line and column in the scene file), checks it, and may replace
//! it with its settings in force ([`Section::of`]) so that records hold the defaults too.
//! Overrides reach inside it by path like any other setting, since they edit the text.

use ron::value::RawValue;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A section of the scene as RON text, read by the crate that owns its type.
#[derive(Clone, Debug)]
pub struct Section {
    raw: Box<RawValue>,
    /// Line and column of the section's text in the scene file, for messages.
    at: Option<(usize, usize)>,
}

impl Default for Section {
    /// An empty section, `()`: a struct whose settings all take their defaults.
    fn default() -> Self {
        Section::from_raw(RawValue::from_boxed_ron("()".into()).expect("`()` is RON"))
    }
}

impl Section {
    fn from_raw(raw: Box<RawValue>) -> Section {
        Section { raw, at: None }
    }

    /// The section holding `value`, as one line of RON: `(tolerance: 1e-6, max_iterations: 10)`.
    pub fn of<T: Serialize>(value: &T) -> Result<Section, String> {
        let config = ron::ser::PrettyConfig::new().new_line(" ").indentor("");
        let mut text = ron::ser::to_string_pretty(value, config).map_err(|e| e.to_string())?;
        if !text.contains(['"', '\'']) {
            text = text.replace("( ", "(").replace(", )", ")");
        }
        let raw = RawValue::from_boxed_ron(text.into_boxed_str()).map_err(|e| e.to_string())?;
        Ok(Section::from_raw(raw))
    }

    /// Read the section as a `T` (RON's `implicit_some` enabled, as for the scene file). On
    /// error the reader's message, with the setting's path inside the section where there is
    /// one (`coupling: …`) and the line and column in the scene file where known.
    pub fn get<T: DeserializeOwned>(&self) -> Result<T, String> {
        self.read("").map_err(|(path, m)| {
            if path.is_empty() {
                m
            } else {
                format!("{path}: {m}")
            }
        })
    }

    /// Read the section as a `T`, the section being the setting `at` of the scene (`solid`,
    /// `numerics.elastic`). On error the path of the setting that does not read (`at` and the
    /// path inside the section, `numerics.elastic.coupling`) and the reader's message, with the
    /// line and column in the scene file where known.
    pub fn read<T: DeserializeOwned>(&self, at: &str) -> Result<T, (String, String)> {
        let opts = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let text = self.raw.get_ron();
        let mut de = ron::Deserializer::from_str_with_options(text, &opts)
            .map_err(|e| (at.to_string(), self.message(e)))?;
        let value = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let inside = e
                .path()
                .iter()
                .next()
                .is_some()
                .then(|| e.path().to_string());
            let path = match inside {
                Some(inside) if at.is_empty() => inside,
                Some(inside) => format!("{at}.{inside}"),
                None => at.to_string(),
            };
            (path, self.message(de.span_error(e.into_inner())))
        })?;
        de.end()
            .map_err(|e| (at.to_string(), self.message(de.span_error(e))))?;
        Ok(value)
    }

    /// A reader's error as a message, with the line and column in the scene file where known.
    fn message(&self, e: ron::error::SpannedError) -> String {
        let at = match self.at {
            Some((line, col)) => {
                let (l, c) = (e.span.start.line, e.span.start.col);
                let c = if l == 1 { col + c - 1 } else { c };
                format!(" (line {}, column {c})", line + l - 1)
            }
            None => String::new(),
        };
        format!("{}{at}", e.code)
    }

    /// The section's RON text.
    pub fn text(&self) -> &str {
        self.raw.get_ron()
    }

    /// Record where the section's text starts in `text`, the scene file it was read from; not
    /// found there as written (an override rewrote it), it gets no position.
    pub fn locate_in(&mut self, text: &str) {
        self.at = text.find(self.raw.get_ron()).map(|offset| {
            let before = &text[..offset];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            (line, col)
        });
    }
}

impl Serialize for Section {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.raw.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Section {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Box::<RawValue>::deserialize(d).map(Section::from_raw)
    }
}
