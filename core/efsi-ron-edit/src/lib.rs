//! # efsi-ron-edit
//!
//! Set and read the values of RON text by path, editing the text in place: what efsi's scene
//! overrides (`efsi run --set grid.nx=128`, `Scene::set`, FMU and Python parameters) are built
//! on. The edited text goes back through the caller's own loader, so its syntax checks,
//! unknown-field errors and range validation apply to an override as to a file, and nothing
//! here knows the caller's types.
//!
//! - A [`Path`] names a value as the text nests it: struct fields by name, fields inside an
//!   enum's variant, list and tuple elements by index (`probes[2]`, `center[1]`, `gravity.1`),
//!   map entries by key; `Some(…)` and one-value variants are looked through; field-name
//!   aliases are resolved ([`Aliases`]).
//! - [`Document::set`] replaces the value at a path, or inserts it with the containers it
//!   needs when the text leaves it out; the shape of what is missing (struct or map, the
//!   value's type) comes from a second document of *hints* — the caller's value with its
//!   defaults filled in. A value is written by the type of the one it replaces ([`Value`]).
//! - [`Document::get`] reads the value at a path.
//!
//! The parser keeps each value's byte span; it accepts RON's syntax (comments, raw strings,
//! `#![enable(…)]`), not its semantics — that is the caller's loader's job.

mod edit;
pub mod overrides;
mod path;
mod tree;

use serde::{Deserialize, Serialize};
use std::fmt;

/// How deep values may nest in the text this crate reads: a document, or a value to set (the
/// scene reader's own limit, `efsi_core::scene::RECURSION_LIMIT`). Deeper text is refused
/// with an error rather than read by recursion without bound.
pub const MAX_DEPTH: usize = 128;

/// Field-name aliases as `(alias, canonical)`: a path or a struct field may use either.
pub type Aliases = &'static [(&'static str, &'static str)];

/// A value to set: what a Python caller or an FMU parameter holds, or RON text.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Value {
    /// `true` / `false`.
    Bool(bool),
    /// An integer (also accepted by a real-valued setting).
    Int(i64),
    /// A real number (accepted by an integer setting when it is whole).
    Float(f64),
    /// A string; written bare for an enum's unit variant (`"IncompleteCholesky"`).
    Str(String),
    /// Any RON value as text (`Disk(center: (0, 0.05), radius: 0.02)`, `1e6`, `[1.0, 2.0]`);
    /// for a string setting, text that is not a quoted string is taken as the string itself.
    Ron(String),
}

impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Float(v)
    }
}
impl From<i64> for Value {
    fn from(v: i64) -> Self {
        Value::Int(v)
    }
}
impl From<i32> for Value {
    fn from(v: i32) -> Self {
        Value::Int(v.into())
    }
}
impl From<usize> for Value {
    fn from(v: usize) -> Self {
        Value::Int(i64::try_from(v).unwrap_or(i64::MAX))
    }
}
impl From<bool> for Value {
    fn from(v: bool) -> Self {
        Value::Bool(v)
    }
}
impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::Str(v.to_string())
    }
}
impl From<String> for Value {
    fn from(v: String) -> Self {
        Value::Str(v)
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Bool(b) => write!(f, "{b}"),
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => write!(f, "{x:?}"),
            Value::Str(s) => write!(f, "{s:?}"),
            Value::Ron(t) => f.write_str(t),
        }
    }
}

/// A number for a message or a record: plain where that is short (`0.05`, `128`), else in
/// exponent form, shortest round trip (`1e308`, `5e-324`, not 309 digits).
pub fn number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `text` for a message: whole when short, else its first 60 characters, `…` and its length
/// (a value of megabytes, or nested thousands of levels, must not become the message).
pub(crate) fn elide(text: &str) -> std::borrow::Cow<'_, str> {
    const SHOWN: usize = 60;
    match text.char_indices().nth(SHOWN + 20) {
        None => text.into(),
        Some(_) => {
            let cut = text
                .char_indices()
                .nth(SHOWN)
                .map_or(text.len(), |(i, _)| i);
            format!("{}… ({} characters)", &text[..cut], text.chars().count()).into()
        }
    }
}

/// `elide` for other crates' messages: `text` whole when short, else cut with its length.
pub fn elide_text(text: &str) -> String {
    elide(text).into_owned()
}

/// A path to a value: keys (aliases resolved) and indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path(Vec<path::Seg>);

impl Path {
    /// Parse `a.b[2].c.1` with `aliases`; the error says what is malformed.
    pub fn parse(path: &str, aliases: Aliases) -> Result<Path, String> {
        path::parse_path(path, aliases).map(Path)
    }

    /// A one-key path.
    pub fn key(name: &str) -> Path {
        Path(vec![path::Seg::Key(name.to_string())])
    }

    /// Whether one path lies inside the other (or they are equal): they agree on their
    /// common length, which is not zero.
    pub fn overlaps(&self, other: &Path) -> bool {
        let n = self.0.len().min(other.0.len());
        n > 0 && self.0[..n] == other.0[..n]
    }

    /// Whether the path has no segment.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&path::show(&self.0))
    }
}

/// RON text and its syntax tree.
pub struct Document {
    root: tree::Node,
    text: String,
    aliases: Aliases,
}

impl Document {
    /// Parse `text` (one RON value, comments and `#![enable(…)]` allowed) with the field
    /// aliases `aliases`. On error the byte offset and what was expected.
    pub fn parse(text: impl Into<String>, aliases: Aliases) -> Result<Document, (usize, String)> {
        let text = text.into();
        let root = tree::parse_ron(&text)?;
        Ok(Document {
            root,
            text,
            aliases,
        })
    }

    /// The text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Whether `path` can lead somewhere in this document: an error if a value that holds no
    /// fields or elements lies on the way, or an index is past a list's end. A path through a
    /// `None` passes (the value it would hold is set whole).
    pub fn check_reachable(&self, path: &Path) -> Result<(), String> {
        match edit::locate(&self.root, &path.0, &self.text, self.aliases) {
            Err(e) if !e.contains("None") => Err(e),
            _ => Ok(()),
        }
    }

    /// The text with the value at `path` set to `value` (inserted with its containers if
    /// absent; `hints`, the same value with its defaults filled in, gives the shape of what
    /// is missing and the type of a value given as `None`).
    pub fn set(
        &self,
        hints: Option<&Document>,
        path: &Path,
        value: &Value,
    ) -> Result<String, String> {
        let e = edit::plan(
            (&self.root, &self.text),
            hints.map(|h| (&h.root, h.text.as_str())),
            &path.0,
            value,
            self.aliases,
        )?;
        let mut text = self.text.clone();
        text.replace_range(e.start..e.end, &e.text);
        Ok(text)
    }

    /// The value at `path`: a number, a string (an enum's unit variant by its name), a
    /// boolean, or RON text for anything else (a struct, tuple, list or `None`); `None` if the
    /// text leaves it out. The error says why the path cannot lead anywhere.
    pub fn get(&self, path: &Path) -> Result<Option<Value>, String> {
        let node = match edit::locate(&self.root, &path.0, &self.text, self.aliases)? {
            edit::Found::Node(n) => n,
            edit::Found::Missing { .. } => return Ok(None),
        };
        let text = &self.text;
        let raw = &text[node.start..node.end];
        let inner = match &node.kind {
            tree::Kind::Tuple(Some(n), items) if n == "Some" && items.len() == 1 => &items[0],
            _ => node,
        };
        let atom_text = &text[inner.start..inner.end];
        use tree::Atom;
        Ok(Some(match inner.atom() {
            Some(Atom::Int) => atom_text
                .parse()
                .map(Value::Int)
                .unwrap_or_else(|_| Value::Ron(atom_text.into())),
            Some(Atom::Float) => atom_text
                .parse()
                .map(Value::Float)
                .unwrap_or_else(|_| Value::Ron(atom_text.into())),
            Some(Atom::Bool) => Value::Bool(atom_text == "true"),
            Some(Atom::Str) => ron::from_str::<String>(atom_text)
                .map(Value::Str)
                .unwrap_or_else(|_| Value::Ron(atom_text.into())),
            Some(Atom::Ident) if atom_text != "None" => Value::Str(atom_text.into()),
            _ => Value::Ron(raw.into()),
        }))
    }
}

#[cfg(test)]
mod tests;
