//! Overrides: changes to a document's settings by path, applied in order to its text, each
//! checked by the caller's loader before the next — what efsi's scene overrides are
//! (`efsi run --set PATH=VALUE --refine F`; the scene's side is `efsi_core::overrides`).

use crate::{Aliases, Document, Path, Value};
use serde::{Deserialize, Serialize};
use std::fmt;

/// One change to a scene: a setting by its path, or the grid refined.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Override {
    /// Set the setting at `path` to `value`.
    Set {
        /// `grid.nx`, `solid.law.parameters.G`, `output.probes[2].at`, …
        path: String,
        /// The new value.
        value: Value,
    },
    /// Multiply every grid dimension by this factor (> 0), keeping the domain; the caller
    /// applies it, after the `Set`s. It changes the setting `grid`.
    Refine(f64),
}

impl Override {
    /// Set the setting at `path` to `value`.
    pub fn set(path: impl Into<String>, value: impl Into<Value>) -> Override {
        Override::Set {
            path: path.into(),
            value: value.into(),
        }
    }

    /// Parse the command line's `PATH=VALUE`, `VALUE` being RON text.
    pub fn parse(arg: &str) -> Result<Override, String> {
        let Some((path, value)) = arg.split_once('=') else {
            return Err(format!(
                "`{arg}`: expected PATH=VALUE, e.g. grid.nx=128 or solid.law.parameters.G=1e6"
            ));
        };
        let (path, value) = (path.trim(), value.trim());
        Path::parse(path, &[]).map_err(|m| format!("`{arg}`: {m}"))?;
        if value.is_empty() {
            return Err(format!("`{arg}`: the value is empty"));
        }
        Ok(Override::set(path, Value::Ron(value.to_string())))
    }

    /// The override for a message: as [`Display`](fmt::Display) shows it, with a long value
    /// cut short (a value of thousands of characters must not become the message; records
    /// keep the whole text).
    pub fn brief(&self) -> String {
        crate::elide(&self.to_string()).into_owned()
    }

    /// The setting it changes, `aliases` resolved (`grid` for a refinement).
    pub fn path(&self, aliases: Aliases) -> Path {
        match self {
            Override::Set { path, .. } => Path::parse(path, aliases).unwrap_or_default(),
            Override::Refine(_) => Path::key("grid"),
        }
    }
}

impl fmt::Display for Override {
    /// `set PATH=VALUE` or `refine F`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Override::Set { path, value } => write!(f, "set {path}={value}"),
            Override::Refine(x) => write!(f, "refine {}", crate::number(*x)),
        }
    }
}

/// The last of `overrides` whose setting is `field` or lies inside it or around it: the one
/// to blame for an error in `field`.
pub fn blame<'a>(overrides: &'a [Override], field: &str, aliases: Aliases) -> Option<&'a Override> {
    let named = Path::parse(field, aliases).unwrap_or_default();
    overrides
        .iter()
        .rev()
        .find(|o| o.path(aliases).overlaps(&named))
}

/// Apply the `Set`s of `overrides` to `text`, whose reading is `first`, one by one; each
/// result is read with `read` before the next, so that an error is the override's that caused
/// it. `hints` gives a reading's text with its defaults filled in: the shape of what `text`
/// leaves out ([`Document::set`]). On error the override and what is wrong.
pub fn apply_sets<'o, T>(
    text: &str,
    first: T,
    overrides: &'o [Override],
    aliases: Aliases,
    hints: impl Fn(&T) -> String,
    mut read: impl FnMut(&str) -> Result<T, String>,
) -> Result<T, (&'o Override, String)> {
    let mut text = text.to_string();
    let mut value = first;
    for o in overrides {
        let Override::Set { path, value: v } = o else {
            continue;
        };
        let setting = Path::parse(path, aliases).map_err(|m| (o, m))?;
        let hints = Document::parse(hints(&value), aliases).ok();
        // A path the value's shape cannot hold (through a value, past a list's end).
        if let Some(h) = &hints {
            h.check_reachable(&setting).map_err(|m| (o, m))?;
        }
        let doc = Document::parse(text, aliases)
            .map_err(|(_, m)| (o, format!("cannot read the scene: {m}")))?;
        text = doc.set(hints.as_ref(), &setting, v).map_err(|m| (o, m))?;
        value = read(&text).map_err(|m| (o, m))?;
    }
    Ok(value)
}
