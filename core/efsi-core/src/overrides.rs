//! Scene overrides: change any setting of a scene by its path, without editing the file.
//!
//! ```text
//! efsi run cases/sphere_impact.ron --set grid.nx=128 --set solid.law.parameters.G=1e6 --refine 2
//! ```
//!
//! ```no_run
//! # use efsi_core::{Scene, overrides::Override};
//! let scene = Scene::load_with(
//!     "cases/sphere_impact.ron",
//!     &[Override::set("solid.law.parameters.G", 1e6), Override::set("solid.shape.radius", 0.02)],
//! )?;
//! # Ok::<(), efsi_core::SceneError>(())
//! ```
//!
//! # Paths
//!
//! A path names a setting as the scene file nests it: struct fields by name (`grid.nx`,
//! `time.steady`), fields inside an enum's variant (`solid.shape.radius` of a `Disk`,
//! `boundaries.y_max.speed` of a `MovingWall`), list and tuple elements by index
//! (`output.probes[2].at`, `solid.shape.center[1]`, `gravity.1`), map entries by key
//! (`solid.law.parameters.G`). An `Option` that holds a value (`Some(…)`) and a variant that
//! wraps one value (`Union([…])`) are looked through. The scene's aliases (`nr`, `nz`, `r`,
//! `z`, `r_min`, …; [`FIELD_ALIASES`]) name the same fields as their canonical names.
//!
//! A setting absent from the file, whose default applies, is inserted (with the containers it
//! needs: `numerics.projection.solver` in a scene without `numerics` inserts
//! `numerics: (projection: (solver: …))`, a law parameter not in the file inserts it into the
//! `parameters` map). Whether a missing container is a struct `( )` or a map `{ }`, and the type
//! of a missing value, are read from the scene with its defaults filled in. A stage's
//! `numerics` section that the file leaves out has no defaults in the scene (the stage owns
//! them, [`crate::scene::options`]): its containers are structs and a string that is a
//! capitalised identifier is written as an enum's variant (`IncompleteCholesky`).
//!
//! # Values
//!
//! An [`OverrideValue`] is a number, a string, a boolean — what a Python caller or an FMU
//! parameter holds — or RON text (the command line's `--set PATH=VALUE`, where `VALUE` may be
//! any RON value: `Disk(center: (0, 0.05), radius: 0.02)`). The setting's current type decides
//! how it is written: a string for a string setting (`--set solid.law.name=mooney_rivlin` needs
//! no quotes), a bare identifier for an enum's unit variant (`"IncompleteCholesky"`), an integer
//! for an integer setting (a whole float such as `128.0` is accepted; `1.5` is refused).
//!
//! # Why on the RON text, not on the Rust types
//!
//! An override edits the scene's RON text — the file as written, or [`Scene::to_ron`] for a
//! scene in memory — and the result goes through the same loader as any scene file: the same
//! syntax checks, unknown-field errors and range validation, and nothing else to keep in step
//! with the scene's types. A section of the scene that a stage plugin declares and
//! deserialises itself is reached the same way as a core one, because the path is looked up in
//! the text, not in a Rust struct. The price is that the loader's errors point into rewritten
//! text, so they are attributed back: the file is parsed alone first (its own errors keep its
//! line and column), then again after each override (each must leave a scene the loader can
//! parse, so a syntax or type error is the override's just applied), and the ranges are
//! validated once after the last (a range error belongs to the last override whose path it
//! names). A message names the override (`set grid.nx=0: grid.nx: must be at least 1 cell,
//! got 0`), never a line and column of text the user did not write.
//!
//! # Refinement
//!
//! [`Override::Refine`] (`--refine F`) multiplies every grid dimension by `F` (rounded to the
//! nearest whole number of cells, at least 1) and keeps the domain: the speed/accuracy knob. It
//! is applied after the `set`s of the same call, so `--set grid.nx=100 --refine 2` gives 200.
//!
//! # Recording
//!
//! A scene keeps the overrides applied to it ([`Scene::overrides`]). `run.json` records them
//! with the effective scene; a checkpoint records them with the scene file's path, and a
//! resumed run applies them again to the file, so it runs the same effective scene (and still
//! refuses a file changed since).

use crate::scene::{Scene, SceneError};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

/// Field-name aliases the scene accepts, as `(alias, canonical)`: a path may use either.
pub const FIELD_ALIASES: &[(&str, &str)] = &[
    ("r", "x"),
    ("z", "y"),
    ("nr", "nx"),
    ("nz", "ny"),
    ("r_min", "x_min"),
    ("r_max", "x_max"),
    ("z_min", "y_min"),
    ("z_max", "y_max"),
];

/// The canonical name of a field name that may be an alias.
fn canonical(name: &str) -> &str {
    FIELD_ALIASES
        .iter()
        .find(|(a, _)| *a == name)
        .map_or(name, |(_, c)| c)
}

/// The value an override sets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum OverrideValue {
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

impl From<f64> for OverrideValue {
    fn from(v: f64) -> Self {
        OverrideValue::Float(v)
    }
}
impl From<i64> for OverrideValue {
    fn from(v: i64) -> Self {
        OverrideValue::Int(v)
    }
}
impl From<i32> for OverrideValue {
    fn from(v: i32) -> Self {
        OverrideValue::Int(v.into())
    }
}
impl From<usize> for OverrideValue {
    fn from(v: usize) -> Self {
        OverrideValue::Int(i64::try_from(v).unwrap_or(i64::MAX))
    }
}
impl From<bool> for OverrideValue {
    fn from(v: bool) -> Self {
        OverrideValue::Bool(v)
    }
}
impl From<&str> for OverrideValue {
    fn from(v: &str) -> Self {
        OverrideValue::Str(v.to_string())
    }
}
impl From<String> for OverrideValue {
    fn from(v: String) -> Self {
        OverrideValue::Str(v)
    }
}

impl fmt::Display for OverrideValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OverrideValue::Bool(b) => write!(f, "{b}"),
            OverrideValue::Int(i) => write!(f, "{i}"),
            OverrideValue::Float(x) => write!(f, "{x:?}"),
            OverrideValue::Str(s) => write!(f, "{s:?}"),
            OverrideValue::Ron(t) => f.write_str(t),
        }
    }
}

/// One change to a scene: a setting by its path, or the grid refined.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Override {
    /// Set the setting at `path` (see the module docs) to `value`.
    Set {
        /// `grid.nx`, `solid.law.parameters.G`, `output.probes[2].at`, …
        path: String,
        /// The new value.
        value: OverrideValue,
    },
    /// Multiply every grid dimension by this factor (> 0), keeping the domain.
    Refine(f64),
}

impl Override {
    /// Set the setting at `path` to `value`.
    pub fn set(path: impl Into<String>, value: impl Into<OverrideValue>) -> Override {
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
        parse_path(path).map_err(|m| format!("`{arg}`: {m}"))?;
        if value.is_empty() {
            return Err(format!("`{arg}`: the value is empty"));
        }
        Ok(Override::set(path, OverrideValue::Ron(value.to_string())))
    }

    /// The path it changes, as segments with aliases resolved (`grid` for a refinement).
    fn segments(&self) -> Vec<Seg> {
        match self {
            Override::Set { path, .. } => parse_path(path).unwrap_or_default(),
            Override::Refine(_) => vec![Seg::Key("grid".into())],
        }
    }
}

impl fmt::Display for Override {
    /// `set PATH=VALUE` or `refine F`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Override::Set { path, value } => write!(f, "set {path}={value}"),
            Override::Refine(x) => write!(f, "refine {x}"),
        }
    }
}

impl Scene {
    /// Read a scene file, apply `overrides` in order and validate the result (see the module
    /// docs). Errors in the file name its line and column; errors an override causes name the
    /// override ([`SceneError::Override`]).
    pub fn load_with(path: impl AsRef<Path>, overrides: &[Override]) -> Result<Scene, SceneError> {
        let path = path.as_ref();
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
        let mut scene = Scene::from_str_with(&text, path, overrides)?;
        scene.source_dir = path.parent().map(Path::to_path_buf);
        Ok(scene)
    }

    /// Parse scene text, apply `overrides` in order and validate; `path` is used in messages.
    pub fn from_str_with(
        text: &str,
        path: &Path,
        overrides: &[Override],
    ) -> Result<Scene, SceneError> {
        let parsed = Scene::parse(text, path)?;
        let mut scene = if overrides.iter().any(|o| matches!(o, Override::Set { .. })) {
            apply_sets(text, parsed, path, overrides)?
        } else {
            parsed
        };
        for o in overrides {
            if let Override::Refine(f) = o {
                scene
                    .refine_grid(*f)
                    .map_err(|message| SceneError::Override {
                        path: path.to_path_buf(),
                        setting: o.to_string(),
                        message,
                    })?;
            }
        }
        scene.overrides = overrides.to_vec();
        scene
            .validate()
            .map_err(|(field, message)| attribute(path, overrides, field, message))?;
        Ok(scene)
    }

    /// Set the setting at `path` to `value` in this scene (see the module docs), validate the
    /// result and record the override. On error the scene is unchanged.
    pub fn set(&mut self, path: &str, value: impl Into<OverrideValue>) -> Result<(), SceneError> {
        self.apply(&[Override::set(path, value)])
    }

    /// Multiply every grid dimension by `factor` (rounded, at least one cell), keeping the
    /// domain; validate and record it. On error the scene is unchanged.
    pub fn refine(&mut self, factor: f64) -> Result<(), SceneError> {
        self.apply(&[Override::Refine(factor)])
    }

    /// Apply `overrides` to this scene in order, validate the result and record them after the
    /// ones already applied. On error the scene is unchanged.
    pub fn apply(&mut self, overrides: &[Override]) -> Result<(), SceneError> {
        let label = PathBuf::from(format!("scene `{}`", self.name));
        let mut next = Scene::from_str_with(&self.to_ron(), &label, overrides)?;
        next.source_dir = self.source_dir.clone();
        let mut all = std::mem::take(&mut self.overrides);
        all.extend_from_slice(overrides);
        next.overrides = all;
        *self = next;
        Ok(())
    }

    /// The value of the setting at `path` (with the scene's defaults filled in): a number, a
    /// string (an enum's unit variant by its name), a boolean, or RON text for anything else
    /// (a struct, tuple, list or `None`). What an FMU shows as a parameter's start value.
    pub fn get(&self, path: &str) -> Result<OverrideValue, SceneError> {
        let fail = |message: String| SceneError::Override {
            path: PathBuf::from(format!("scene `{}`", self.name)),
            setting: format!("get {path}"),
            message,
        };
        let segs = parse_path(path).map_err(fail)?;
        let text = self.to_ron();
        let root =
            parse_ron(&text).map_err(|(_, m)| fail(format!("cannot read the scene: {m}")))?;
        let node = match locate(&root, &segs, &text).map_err(fail)? {
            Found::Node(n) => n,
            Found::Missing { .. } => {
                return Err(fail(format!("the scene has no setting {}", show(&segs))));
            }
        };
        let raw = &text[node.start..node.end];
        let inner = match &node.kind {
            Kind::Tuple(Some(n), items) if n == "Some" && items.len() == 1 => &items[0],
            _ => node,
        };
        let atom_text = &text[inner.start..inner.end];
        Ok(match inner.atom() {
            Some(Atom::Int) => atom_text
                .parse()
                .map(OverrideValue::Int)
                .unwrap_or_else(|_| OverrideValue::Ron(atom_text.into())),
            Some(Atom::Float) => atom_text
                .parse()
                .map(OverrideValue::Float)
                .unwrap_or_else(|_| OverrideValue::Ron(atom_text.into())),
            Some(Atom::Bool) => OverrideValue::Bool(atom_text == "true"),
            Some(Atom::Str) => ron::from_str::<String>(atom_text)
                .map(OverrideValue::Str)
                .unwrap_or_else(|_| OverrideValue::Ron(atom_text.into())),
            Some(Atom::Ident) if atom_text != "None" => OverrideValue::Str(atom_text.into()),
            _ => OverrideValue::Ron(raw.into()),
        })
    }

    fn refine_grid(&mut self, f: f64) -> Result<(), String> {
        if !(f.is_finite() && f > 0.0) {
            return Err(format!("the factor must be a finite number > 0, got {f}"));
        }
        let scale = |n: usize| ((n as f64) * f).round().clamp(1.0, 1e15) as usize;
        self.grid.nx = scale(self.grid.nx);
        self.grid.ny = scale(self.grid.ny);
        Ok(())
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
    let named = parse_path(&field).unwrap_or_default();
    let overlaps = |o: &&Override| {
        let s = o.segments();
        let n = s.len().min(named.len());
        n > 0 && s[..n] == named[..n]
    };
    match overrides.iter().rev().find(overlaps) {
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

/// Apply the `Set` overrides to `text` (whose parse is `parsed`) one by one, each checked by
/// the loader's parse before the next: an error is the override's that caused it.
fn apply_sets(
    text: &str,
    parsed: Scene,
    path: &Path,
    overrides: &[Override],
) -> Result<Scene, SceneError> {
    let mut text = text.to_string();
    let mut scene = parsed;
    for o in overrides {
        let Override::Set { path: p, value } = o else {
            continue;
        };
        let fail = |message: String| SceneError::Override {
            path: path.to_path_buf(),
            setting: o.to_string(),
            message,
        };
        let segs = parse_path(p).map_err(fail)?;
        // The scene with its defaults filled in: the shape of what the file leaves out.
        let full = scene.to_ron();
        let hints = parse_ron(&full).ok().map(|n| (n, full));
        // A path the scene's shape cannot hold (through a value, past a list's end).
        if let Some((root, t)) = &hints
            && let Err(e) = locate(root, &segs, t)
            && !e.contains("None")
        {
            return Err(fail(e));
        }
        let root =
            parse_ron(&text).map_err(|(_, m)| fail(format!("cannot read the scene: {m}")))?;
        let edit = plan(&(root, text.clone()), hints.as_ref(), &segs, value).map_err(fail)?;
        text.replace_range(edit.start..edit.end, &edit.text);
        scene = Scene::parse(&text, path).map_err(|e| match e {
            SceneError::Syntax { message, .. } => fail(message),
            other => other,
        })?;
    }
    Ok(scene)
}

// ---- paths --------------------------------------------------------------------------------

/// One step of a path: a field or map key, or an element index.
#[derive(Clone, Debug, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

impl fmt::Display for Seg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Seg::Key(k) => f.write_str(k),
            Seg::Index(i) => write!(f, "[{i}]"),
        }
    }
}

fn show(segs: &[Seg]) -> String {
    let mut s = String::new();
    for seg in segs {
        if matches!(seg, Seg::Key(_)) && !s.is_empty() {
            s.push('.');
        }
        s.push_str(&seg.to_string());
    }
    if s.is_empty() { "the scene".into() } else { s }
}

/// `a.b[2].c.1` → keys (aliases resolved) and indices.
fn parse_path(path: &str) -> Result<Vec<Seg>, String> {
    let bad = |why: &str| {
        Err(format!(
            "bad path `{path}`: {why} (expected e.g. grid.nx, output.probes[2].at, solid.law.parameters.G)"
        ))
    };
    let mut segs = Vec::new();
    for part in path.split('.') {
        let (head, mut rest) = match part.find('[') {
            Some(k) => part.split_at(k),
            None => (part, ""),
        };
        if head.is_empty() && (segs.is_empty() || rest.is_empty()) {
            return bad("an empty name");
        }
        if !head.is_empty() {
            if head
                .chars()
                .any(|c| c.is_whitespace() || "]=\"'(){}:,".contains(c))
            {
                return bad(&format!("`{head}` is not a name"));
            }
            segs.push(match head.parse::<usize>() {
                Ok(i) => Seg::Index(i),
                Err(_) => Seg::Key(canonical(head).to_string()),
            });
        }
        while !rest.is_empty() {
            let Some(close) = rest.find(']') else {
                return bad("an unclosed `[`");
            };
            match rest[1..close].trim().parse::<usize>() {
                Ok(i) => segs.push(Seg::Index(i)),
                Err(_) => return bad(&format!("`{}` is not an index", &rest[..=close])),
            }
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return bad(&format!("unexpected `{rest}` after an index"));
            }
        }
    }
    Ok(segs)
}

// ---- a RON syntax tree with byte spans ------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq)]
enum Atom {
    Int,
    Float,
    Str,
    Char,
    Bool,
    Ident,
}

#[derive(Debug)]
enum Kind {
    Atom(Atom),
    /// `Name(a: 1, b: 2)` or `(a: 1)`; `()` is an empty struct.
    Struct(Vec<(String, Node)>),
    /// `Name(1, 2)`, `Some(x)`, `(1.0, 2.0)`.
    Tuple(Option<String>, Vec<Node>),
    Seq(Vec<Node>),
    Map(Vec<(Node, Node)>),
}

#[derive(Debug)]
struct Node {
    start: usize,
    end: usize,
    kind: Kind,
    /// For containers: the byte offset of the closing bracket, and whether the last entry is
    /// followed by a comma.
    close: usize,
    trailing_comma: bool,
}

impl Node {
    fn describe(&self, text: Option<&str>) -> String {
        match &self.kind {
            Kind::Atom(Atom::Ident) => match text {
                Some(t) => format!("`{}`", &t[self.start..self.end]),
                None => "a name".into(),
            },
            Kind::Atom(a) => a_name(*a),
            Kind::Struct(_) => "a struct".into(),
            Kind::Tuple(..) => "a tuple".into(),
            Kind::Seq(_) => "a list".into(),
            Kind::Map(_) => "a map".into(),
        }
    }

    fn is_empty(&self) -> bool {
        match &self.kind {
            Kind::Struct(f) => f.is_empty(),
            Kind::Tuple(_, i) | Kind::Seq(i) => i.is_empty(),
            Kind::Map(e) => e.is_empty(),
            Kind::Atom(_) => true,
        }
    }

    /// The atom a value holds, looking through `Some(…)`.
    fn atom(&self) -> Option<Atom> {
        match &self.kind {
            Kind::Atom(a) => Some(*a),
            Kind::Tuple(Some(n), items) if n == "Some" && items.len() == 1 => items[0].atom(),
            _ => None,
        }
    }
}

/// `a number`, `an integer`.
fn a_name(a: Atom) -> String {
    let n = atom_name(a);
    let article = if n.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {n}")
}

fn atom_name(a: Atom) -> &'static str {
    match a {
        Atom::Int => "integer",
        Atom::Float => "number",
        Atom::Str => "string",
        Atom::Char => "character",
        Atom::Bool => "boolean",
        Atom::Ident => "name",
    }
}

/// Parse one RON value filling `text` (a leading `#![enable(…)]` and comments allowed).
/// On error, the byte offset and what was expected.
fn parse_ron(text: &str) -> Result<Node, (usize, String)> {
    let mut p = Parser {
        s: text.as_bytes(),
        at: 0,
    };
    p.skip();
    while p.s[p.at..].starts_with(b"#![") {
        match p.s[p.at..].iter().position(|&c| c == b']') {
            Some(k) => p.at += k + 1,
            None => return Err((p.at, "an unclosed `#![`".into())),
        }
        p.skip();
    }
    let node = p.value()?;
    p.skip();
    if p.at != p.s.len() {
        return Err((p.at, "unexpected text after the value".into()));
    }
    Ok(node)
}

struct Parser<'a> {
    s: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.at).copied()
    }

    /// Skip whitespace and comments (`//…`, nested `/* … */`).
    fn skip(&mut self) {
        loop {
            while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
                self.at += 1;
            }
            if self.s[self.at..].starts_with(b"//") {
                while self.peek().is_some_and(|c| c != b'\n') {
                    self.at += 1;
                }
            } else if self.s[self.at..].starts_with(b"/*") {
                let mut depth = 0usize;
                while self.at < self.s.len() {
                    if self.s[self.at..].starts_with(b"/*") {
                        depth += 1;
                        self.at += 2;
                    } else if self.s[self.at..].starts_with(b"*/") {
                        depth -= 1;
                        self.at += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        self.at += 1;
                    }
                }
            } else {
                return;
            }
        }
    }

    fn err<T>(&self, what: &str) -> Result<T, (usize, String)> {
        let found = match self.peek() {
            None => "the end".to_string(),
            Some(_) => {
                let rest = String::from_utf8_lossy(&self.s[self.at..]);
                format!("`{}`", rest.chars().take(12).collect::<String>())
            }
        };
        Err((self.at, format!("expected {what}, found {found}")))
    }

    fn is_ident_start(c: u8) -> bool {
        c.is_ascii_alphabetic() || c == b'_' || c >= 0x80
    }

    fn is_ident(c: u8) -> bool {
        c.is_ascii_alphanumeric() || c == b'_' || c >= 0x80
    }

    fn ident(&mut self) -> String {
        let start = self.at;
        if self.s[self.at..].starts_with(b"r#") {
            self.at += 2;
        }
        while self.peek().is_some_and(Self::is_ident) {
            self.at += 1;
        }
        String::from_utf8_lossy(&self.s[start..self.at])
            .trim_start_matches("r#")
            .to_string()
    }

    fn value(&mut self) -> Result<Node, (usize, String)> {
        self.skip();
        let start = self.at;
        let atom = |p: &Self, a| Node {
            start,
            end: p.at,
            kind: Kind::Atom(a),
            close: p.at,
            trailing_comma: false,
        };
        match self.peek() {
            None => self.err("a value"),
            Some(b'(') => self.paren(start, None),
            Some(b'[') => {
                let (items, close, trailing) = self.list(b']')?;
                Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Seq(items),
                    close,
                    trailing_comma: trailing,
                })
            }
            Some(b'{') => self.map(start),
            Some(b'"') => {
                self.string()?;
                Ok(atom(self, Atom::Str))
            }
            Some(b'\'') => {
                self.at += 1;
                while let Some(c) = self.peek() {
                    self.at += 1;
                    match c {
                        b'\\' => self.at += 1,
                        b'\'' => return Ok(atom(self, Atom::Char)),
                        _ => {}
                    }
                }
                self.err("a closing `'`")
            }
            Some(b'r' | b'b') if self.raw_or_byte_string()? => Ok(atom(self, Atom::Str)),
            Some(c) if c.is_ascii_digit() || c == b'+' || c == b'-' || c == b'.' => {
                self.at += 1;
                let mut float = c == b'.';
                let hex = self.s[start..].starts_with(b"0x") || self.s[start..].starts_with(b"0b");
                while let Some(c) = self.peek() {
                    let exponent_sign = (c == b'+' || c == b'-')
                        && !hex
                        && matches!(self.s[self.at - 1], b'e' | b'E');
                    if Self::is_ident(c) || c == b'.' || exponent_sign {
                        float |= !hex && (c == b'.' || c == b'e' || c == b'E');
                        self.at += 1;
                    } else {
                        break;
                    }
                }
                let word = &self.s[start..self.at];
                float |= word.ends_with(b"inf") || word.ends_with(b"NaN");
                Ok(atom(self, if float { Atom::Float } else { Atom::Int }))
            }
            Some(c) if Self::is_ident_start(c) => {
                let name = self.ident();
                let ident_end = self.at;
                self.skip();
                if self.peek() == Some(b'(') {
                    return self.paren(start, Some(name));
                }
                self.at = ident_end;
                let a = match name.as_str() {
                    "true" | "false" => Atom::Bool,
                    "inf" | "NaN" => Atom::Float,
                    _ => Atom::Ident,
                };
                Ok(atom(self, a))
            }
            Some(_) => self.err("a value"),
        }
    }

    /// A raw string `r"…"`, `r#"…"#` or a byte string `b"…"`; false if it is an identifier.
    fn raw_or_byte_string(&mut self) -> Result<bool, (usize, String)> {
        let rest = &self.s[self.at..];
        if rest.starts_with(b"b\"") {
            self.at += 1;
            self.string()?;
            return Ok(true);
        }
        let hashes = rest[1..].iter().take_while(|&&c| c == b'#').count();
        if !(rest.first() == Some(&b'r') && rest.get(1 + hashes) == Some(&b'"')) {
            return Ok(false);
        }
        self.at += 2 + hashes;
        let mut end = b"\"".to_vec();
        end.extend(std::iter::repeat_n(b'#', hashes));
        match self.s[self.at..].windows(end.len()).position(|w| w == end) {
            Some(k) => {
                self.at += k + end.len();
                Ok(true)
            }
            None => self.err("the end of a raw string"),
        }
    }

    fn string(&mut self) -> Result<(), (usize, String)> {
        self.at += 1;
        while let Some(c) = self.peek() {
            self.at += 1;
            match c {
                b'\\' => self.at += 1,
                b'"' => return Ok(()),
                _ => {}
            }
        }
        self.err("a closing `\"`")
    }

    /// Items separated by commas up to `close`; returns them, the closing offset and whether
    /// a comma follows the last.
    fn list(&mut self, close: u8) -> Result<(Vec<Node>, usize, bool), (usize, String)> {
        self.at += 1;
        let mut items = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(close) {
                let at = self.at;
                self.at += 1;
                return Ok((items, at, trailing));
            }
            items.push(self.value()?);
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(close) {
                return self.err(&format!("`,` or `{}`", close as char));
            }
        }
    }

    fn map(&mut self, start: usize) -> Result<Node, (usize, String)> {
        self.at += 1;
        let mut entries = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(b'}') {
                let close = self.at;
                self.at += 1;
                return Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Map(entries),
                    close,
                    trailing_comma: trailing,
                });
            }
            let key = self.value()?;
            self.skip();
            if self.peek() != Some(b':') {
                return self.err("`:` after a map key");
            }
            self.at += 1;
            let value = self.value()?;
            entries.push((key, value));
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(b'}') {
                return self.err("`,` or `}`");
            }
        }
    }

    /// After an optional name, at `(`: a struct if the first entry is `name:`, else a tuple.
    fn paren(&mut self, start: usize, name: Option<String>) -> Result<Node, (usize, String)> {
        let open = self.at;
        self.at += 1;
        self.skip();
        let is_struct = if self.peek() == Some(b')') {
            true
        } else if self.peek().is_some_and(Self::is_ident_start) {
            let back = self.at;
            self.ident();
            self.skip();
            let colon = self.peek() == Some(b':') && self.s.get(self.at + 1) != Some(&b':');
            self.at = back;
            colon
        } else {
            false
        };
        if !is_struct {
            self.at = open;
            let (items, close, trailing) = self.list(b')')?;
            return Ok(Node {
                start,
                end: self.at,
                kind: Kind::Tuple(name, items),
                close,
                trailing_comma: trailing,
            });
        }
        let mut fields = Vec::new();
        let mut trailing = false;
        loop {
            self.skip();
            if self.peek() == Some(b')') {
                let close = self.at;
                self.at += 1;
                return Ok(Node {
                    start,
                    end: self.at,
                    kind: Kind::Struct(fields),
                    close,
                    trailing_comma: trailing,
                });
            }
            if !self.peek().is_some_and(Self::is_ident_start) {
                return self.err("a field name");
            }
            let key = self.ident();
            self.skip();
            if self.peek() != Some(b':') {
                return self.err(&format!("`:` after the field name `{key}`"));
            }
            self.at += 1;
            let value = self.value()?;
            fields.push((key, value));
            self.skip();
            trailing = self.peek() == Some(b',');
            if trailing {
                self.at += 1;
            } else if self.peek() != Some(b')') {
                return self.err("`,` or `)`");
            }
        }
    }
}

// ---- locating a path and planning the edit ------------------------------------------------

/// Where a path leads in a tree.
enum Found<'a> {
    /// The node at the whole path.
    Node(&'a Node),
    /// The path leaves the tree at `container` (a struct or map): `rest` is missing there.
    Missing { container: &'a Node, rest: usize },
}

/// The child of `node` at `seg`, looking through `Some(…)` and one-value variants.
/// `Ok(None)`: absent from a struct or map (insertable). `Err`: why the path cannot go on.
fn child<'a>(node: &'a Node, seg: &Seg, text: Option<&str>) -> Result<Option<&'a Node>, String> {
    match (&node.kind, seg) {
        (Kind::Tuple(_, items), _)
            if items.len() == 1 && !matches!(items[0].kind, Kind::Atom(_)) =>
        {
            match child(&items[0], seg, text) {
                Ok(found) => Ok(found),
                Err(_) if *seg == Seg::Index(0) => Ok(Some(&items[0])),
                Err(e) => Err(e),
            }
        }
        (Kind::Struct(fields), Seg::Key(k)) => Ok(fields
            .iter()
            .find(|(name, _)| canonical(name) == k)
            .map(|(_, v)| v)),
        (Kind::Map(entries), Seg::Key(k)) => Ok(entries.iter().find_map(|(key, v)| {
            let name = text.map_or("", |t| t[key.start..key.end].trim_matches('"'));
            (name == k).then_some(v)
        })),
        (Kind::Tuple(_, items) | Kind::Seq(items), Seg::Index(i)) => match items.get(*i) {
            Some(v) => Ok(Some(v)),
            None => Err(format!("has {} elements, no [{i}]", items.len())),
        },
        (Kind::Struct(fields), Seg::Index(_)) => Err(format!(
            "is a struct: expected a field name{}",
            if fields.is_empty() {
                String::new()
            } else {
                format!(
                    " ({})",
                    fields
                        .iter()
                        .map(|(k, _)| k.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        )),
        (Kind::Map(_), Seg::Index(_)) => Err("is a map: expected a key".into()),
        (Kind::Tuple(..) | Kind::Seq(_), Seg::Key(k)) => Err(format!(
            "is {}: expected an index [k], not `{k}`",
            node.describe(text)
        )),
        (Kind::Atom(Atom::Ident), _)
            if text.is_some_and(|t| &t[node.start..node.end] == "None") =>
        {
            Err("is None (not set) in this scene: set it whole first".into())
        }
        (Kind::Atom(_), _) => Err(format!("is {}, which has no {seg}", node.describe(text))),
    }
}

fn locate<'a>(root: &'a Node, segs: &[Seg], text: &str) -> Result<Found<'a>, String> {
    let mut node = root;
    for (k, seg) in segs.iter().enumerate() {
        match child(node, seg, Some(text)) {
            Ok(Some(next)) => node = next,
            Ok(None) => {
                return Ok(Found::Missing {
                    container: container(node),
                    rest: k,
                });
            }
            Err(e) => return Err(format!("{} {e}", show(&segs[..k]))),
        }
    }
    Ok(Found::Node(node))
}

/// The struct or map a key lookup ended in (looking through one-value wrappers).
fn container(node: &Node) -> &Node {
    match &node.kind {
        Kind::Tuple(_, items) if items.len() == 1 => container(&items[0]),
        _ => node,
    }
}

/// The node at `segs` in the scene with its defaults (for the shape of what is missing).
fn hint<'a>(hints: Option<&'a (Node, String)>, segs: &[Seg]) -> Option<&'a Node> {
    let (root, text) = hints?;
    match locate(root, segs, text) {
        Ok(Found::Node(n)) => Some(n),
        _ => None,
    }
}

/// A text edit: replace `start..end` with `text`.
struct Edit {
    start: usize,
    end: usize,
    text: String,
}

fn plan(
    root: &(Node, String),
    hints: Option<&(Node, String)>,
    segs: &[Seg],
    value: &OverrideValue,
) -> Result<Edit, String> {
    let (tree, text) = root;
    if segs.is_empty() {
        return Err("the path is empty".into());
    }
    match locate(tree, segs, text)? {
        Found::Node(node) => {
            let new = render(
                value,
                node.atom()
                    .or_else(|| {
                        // `None` in the file: the type of the default's value, if it has one.
                        hint(hints, segs).and_then(Node::atom)
                    })
                    .filter(|a| *a != Atom::Ident || !is_none(node, text)),
            )?;
            Ok(Edit {
                start: node.start,
                end: node.end,
                text: new,
            })
        }
        Found::Missing { container, rest } => {
            let is_map = matches!(container.kind, Kind::Map(_));
            let mut inner = render(value, hint(hints, segs).and_then(Node::atom))?;
            for k in (rest + 1..segs.len()).rev() {
                let Seg::Key(key) = &segs[k] else {
                    return Err(format!(
                        "{} is not in the scene: no element to index",
                        show(&segs[..k])
                    ));
                };
                let map = hint(hints, &segs[..k])
                    .is_some_and(|n| matches!(container_kind(n), Kind::Map(_)));
                inner = if map {
                    format!("{{{}: {inner}}}", ron_string(key))
                } else {
                    format!("({key}: {inner})")
                };
            }
            let Seg::Key(key) = &segs[rest] else {
                return Err(format!(
                    "{} has no element {}",
                    show(&segs[..rest]),
                    segs[rest]
                ));
            };
            let key = if is_map { ron_string(key) } else { key.clone() };
            let sep = if container.is_empty() || container.trailing_comma {
                ""
            } else {
                ", "
            };
            Ok(Edit {
                start: container.close,
                end: container.close,
                text: format!("{sep}{key}: {inner}"),
            })
        }
    }
}

fn container_kind(node: &Node) -> &Kind {
    &container(node).kind
}

fn is_none(node: &Node, text: &str) -> bool {
    matches!(node.kind, Kind::Atom(Atom::Ident)) && &text[node.start..node.end] == "None"
}

fn ron_string(s: &str) -> String {
    ron::to_string(s).unwrap_or_else(|_| format!("{s:?}"))
}

fn is_identifier(s: &str) -> bool {
    s.bytes().next().is_some_and(Parser::is_ident_start)
        && s.bytes().all(Parser::is_ident)
        && !matches!(s, "true" | "false" | "inf" | "NaN")
}

/// `value` as RON text for a setting whose current value is of kind `target` (if known).
fn render(value: &OverrideValue, target: Option<Atom>) -> Result<String, String> {
    let whole = |x: f64| -> Result<String, String> {
        if x.fract() == 0.0 && x.abs() < 9e15 {
            Ok(format!("{}", x as i64))
        } else {
            Err(format!("expected an integer, got {x:?}"))
        }
    };
    match (value, target) {
        (OverrideValue::Bool(b), Some(t)) if t != Atom::Bool => {
            Err(format!("expected {}, got {b}", a_name(t)))
        }
        (OverrideValue::Bool(b), _) => Ok(b.to_string()),
        (OverrideValue::Int(i), Some(Atom::Float)) => Ok(format!("{i}.0")),
        (OverrideValue::Int(i), Some(Atom::Str)) => Ok(ron_string(&i.to_string())),
        (OverrideValue::Int(i), _) => Ok(i.to_string()),
        (OverrideValue::Float(x), Some(Atom::Int)) => whole(*x),
        (OverrideValue::Float(x), Some(Atom::Str)) => Ok(ron_string(&format!("{x:?}"))),
        (OverrideValue::Float(x), _) => ron::to_string(x).map_err(|e| e.to_string()),
        (OverrideValue::Str(s), Some(Atom::Ident)) if is_identifier(s) => Ok(s.clone()),
        // A setting of unknown type (in a stage's section the file leaves out, whose defaults
        // the scene does not know): a capitalised identifier is an enum's variant.
        (OverrideValue::Str(s), None) if is_identifier(s) && s.starts_with(char::is_uppercase) => {
            Ok(s.clone())
        }
        (OverrideValue::Str(s), _) => Ok(ron_string(s)),
        (OverrideValue::Ron(t), target) => {
            let t = t.trim();
            match parse_ron(t) {
                Ok(node) => match (node.atom(), target) {
                    (Some(a), Some(Atom::Str)) if a != Atom::Str => Ok(ron_string(t)),
                    (Some(Atom::Float), Some(Atom::Int)) => match t.parse::<f64>() {
                        Ok(x) => whole(x),
                        Err(_) => Err(format!("expected an integer, got {t}")),
                    },
                    _ => Ok(t.to_string()),
                },
                Err(_) if target == Some(Atom::Str) => Ok(ron_string(t)),
                Err((at, m)) => Err(format!("the value `{t}` is not RON: {m} (at byte {at})")),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_with_indices_and_aliases() {
        assert_eq!(
            parse_path("output.probes[2].at").unwrap(),
            vec![
                Seg::Key("output".into()),
                Seg::Key("probes".into()),
                Seg::Index(2),
                Seg::Key("at".into())
            ]
        );
        assert_eq!(
            parse_path("grid.nr").unwrap(),
            vec![Seg::Key("grid".into()), Seg::Key("nx".into())]
        );
        assert_eq!(parse_path("gravity.1").unwrap()[1], Seg::Index(1));
        for bad in ["", "a..b", "a[x]", "a[1", "a[1]b", ".a"] {
            assert!(parse_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn settings_are_read_by_path_with_their_defaults() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../cases/sphere_impact.ron");
        let scene = Scene::load(&path).unwrap();
        let get = |p: &str| scene.get(p).unwrap();
        assert_eq!(get("grid.nr"), OverrideValue::Int(82));
        assert_eq!(get("solid.shape.radius"), OverrideValue::Float(0.0192));
        assert_eq!(get("solid.shape.center[1]"), OverrideValue::Float(0.0573));
        assert_eq!(get("solid.velocity[1]"), OverrideValue::Float(-1.22));
        assert_eq!(get("gravity.1"), OverrideValue::Float(-9.81));
        assert_eq!(
            get("solid.law.name"),
            OverrideValue::Str("neo_hookean".into())
        );
        assert_eq!(get("solid.law.parameters.G"), OverrideValue::Float(0.18e6));
        // A default the file leaves out, an enum's unit variant, a struct.
        assert_eq!(get("time.cfl"), OverrideValue::Float(0.4));
        assert_eq!(get("geometry"), OverrideValue::Str("Axisymmetric".into()));
        assert!(matches!(get("grid"), OverrideValue::Ron(_)));
        let e = scene.get("solid.law.parameters.K").unwrap_err().to_string();
        assert!(e.contains("no setting solid.law.parameters.K"), "{e}");
        assert!(scene.get("grid..nx").is_err());
    }

    #[test]
    fn the_tree_keeps_spans_through_comments_and_strings() {
        let text = "#![enable(implicit_some)]\n// c\nS(a: (1, 2.5e-3), /* (x: */ b: \"q)\", c: {\"G\": 1e6,}, d: Some([A, B(x: 1)]), e: r#\"a\"#)";
        let (root, _) = (parse_ron(text).unwrap(), ());
        let Kind::Struct(f) = &root.kind else {
            panic!("{root:?}")
        };
        let names: Vec<_> = f.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(names, ["a", "b", "c", "d", "e"]);
        assert_eq!(&text[f[1].1.start..f[1].1.end], "\"q)\"");
        assert!(f[2].1.trailing_comma);
        let Kind::Tuple(_, items) = &f[0].1.kind else {
            panic!()
        };
        assert_eq!(items[1].atom(), Some(Atom::Float));
        assert_eq!(items[0].atom(), Some(Atom::Int));
    }

    const SPHERE: &str = r#"// a comment (with a paren
Scene(
    name: "sphere",
    geometry: Axisymmetric,
    domain: (r: (0.0, 0.045), z: (0.0, 0.09)),
    grid: (nr: 23, nz: 47), /* cells */
    time: (end: 0.01, cfl: 0.4),
    fluid: (density: 1.2, viscosity: 1.8e-5),
    gravity: (0.0, -9.81),
    solid: (
        shape: Disk(center: (0.0, 0.0573), radius: 0.0192),
        density: 1106.0,
        law: (name: "neo_hookean"),
    ),
    boundaries: (r_min: Axis, r_max: NoSlip, z_min: NoSlip, z_max: NoSlip),
    output: (probes: [SolidCentroid, KineticEnergy, Point(name: "p0", field: "p", at: (0.01, 0.01))]),
)"#;

    fn with(overrides: &[Override]) -> Result<Scene, SceneError> {
        Scene::from_str_with(SPHERE, Path::new("sphere.ron"), overrides)
    }

    fn ron(p: &str, v: &str) -> Override {
        Override::set(p, OverrideValue::Ron(v.into()))
    }

    #[test]
    fn sets_reach_every_kind_of_setting() {
        let s = with(&[
            ron("grid.nx", "64"),
            Override::set("grid.nz", 96),
            Override::set("solid.shape.radius", 0.02),
            Override::set("solid.shape.center[1]", 0.06),
            ron("output.probes[2].at", "(0.02, 0.03)"),
            Override::set("gravity.1", -1.0),
            ron("solid.law.name", "mooney_rivlin"),
        ])
        .unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (64, 96));
        let crate::interface::Shape::Disk { center, radius } = s.solid.as_ref().unwrap().shape
        else {
            panic!("{:?}", s.solid)
        };
        assert_eq!((center, radius), ((0.0, 0.06), 0.02));
        let crate::scene::ProbeSpec::Point { at, .. } = &s.output.probes[2] else {
            panic!()
        };
        assert_eq!(*at, (0.02, 0.03));
        assert_eq!(s.gravity, (0.0, -1.0));
        assert_eq!(
            s.solid.as_ref().unwrap().law.as_ref().unwrap().name,
            "mooney_rivlin"
        );
        assert_eq!(s.overrides.len(), 7);
        // A later override reaches inside what an earlier one set.
        let s = with(&[
            ron("initial_velocity", "Uniform((1.0, 0.0))"),
            Override::set("initial_velocity[1]", 2.0),
            ron(
                "solid.shape",
                "Rectangle(min: (0.0, 0.01), max: (0.01, 0.03))",
            ),
            Override::set("solid.shape.max[1]", 0.04),
        ])
        .unwrap();
        assert!(matches!(
            s.initial_velocity,
            crate::scene::InitialVelocity::Uniform((1.0, 2.0))
        ));
        assert!(matches!(
            s.solid.unwrap().shape,
            crate::interface::Shape::Rectangle {
                max: (0.01, 0.04),
                ..
            }
        ));
    }

    #[test]
    fn absent_settings_are_inserted_with_their_containers() {
        let s = with(&[
            // A map key (the law's parameters are not in the file).
            ron("solid.law.parameters.G", "1e6"),
            Override::set("solid.law.parameters.K", 2),
            // A whole section absent, down to an enum value given as a string.
            Override::set("numerics.projection.solver", "IncompleteCholesky"),
            ron("numerics.projection.tolerance", "1e-9"),
            // An absent optional value, and an absent real given as an integer.
            ron("time.steady", "1e-6"),
            Override::set("solid.viscosity", 2),
        ])
        .unwrap();
        let law = s.solid.as_ref().unwrap().law.as_ref().unwrap();
        assert_eq!(law.parameters["G"], 1e6);
        assert_eq!(law.parameters["K"], 2.0);
        // A stage's section holds what the overrides wrote; the absent enum value given as a
        // string is written as its variant.
        assert_eq!(
            s.numerics.section("projection"),
            Some("(solver: IncompleteCholesky, tolerance: 1e-9)")
        );
        assert_eq!(s.time.steady, Some(1e-6));
        assert_eq!(s.solid.as_ref().unwrap().viscosity, Some(2.0));
    }

    #[test]
    fn refine_scales_the_grid_after_the_sets() {
        let s = with(&[Override::Refine(1.5)]).unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (35, 71)); // 34.5 → 35, 70.5 → 71
        assert_eq!(s.domain.x, (0.0, 0.045));
        let s = with(&[Override::Refine(2.0), ron("grid.nr", "10")]).unwrap();
        assert_eq!((s.grid.nx, s.grid.ny), (20, 94));
    }

    fn refused(overrides: &[Override], needles: &[&str]) {
        let e = with(overrides).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, SceneError::Override { .. }), "{msg}");
        assert!(msg.starts_with("sphere.ron: "), "{msg}");
        for n in needles {
            assert!(msg.contains(n), "expected `{n}` in: {msg}");
        }
        // Never a line:column of the rewritten text.
        assert!(
            !msg.starts_with("sphere.ron:") || msg.starts_with("sphere.ron: "),
            "{msg}"
        );
    }

    #[test]
    fn unknown_paths_are_refused_naming_the_override() {
        refused(&[ron("grid.nxx", "3")], &["set grid.nxx=3", "nxx", "nx"]);
        refused(
            &[ron("physics.convection", "false")],
            &["set physics.convection", "convection"],
        );
        refused(
            &[ron("output.probes[9].at", "(0, 0)")],
            &["output.probes has 3 elements, no [9]"],
        );
        refused(&[ron("grid.nx.n", "3")], &["grid.nx is an integer"]);
        refused(&[ron("grid[0]", "3")], &["grid is a struct"]);
        refused(
            &[ron("initial_velocity.x", "3")],
            &["set initial_velocity.x=3"],
        );
        refused(&[ron("a..b", "3")], &["bad path"]);
    }

    #[test]
    fn wrong_types_are_refused_naming_the_override() {
        refused(
            &[ron("fluid.viscosity", "true")],
            &["set fluid.viscosity=true", "float"],
        );
        refused(
            &[Override::set("fluid.viscosity", true)],
            &["expected a number"],
        );
        refused(
            &[ron("grid.nx", "1.5")],
            &["set grid.nx=1.5", "expected an integer"],
        );
        refused(
            &[Override::set("grid.nx", 1.5)],
            &["expected an integer, got 1.5"],
        );
        refused(&[ron("grid.nx", "many")], &["set grid.nx=many"]);
        refused(
            &[ron("solid.shape", "Disk(radius: 1.0)")],
            &["set solid.shape=", "center"],
        );
        refused(
            &[ron("boundaries.z_max", "Sticky")],
            &["set boundaries.z_max=Sticky", "Sticky"],
        );
        refused(&[ron("time.end", "(1")], &["not RON"]);
        // The second of two overrides is the one named.
        refused(
            &[ron("grid.nx", "30"), ron("fluid.density", "\"heavy\"")],
            &["set fluid.density=\"heavy\""],
        );
    }

    #[test]
    fn out_of_range_values_go_through_validation() {
        refused(
            &[ron("grid.nx", "0")],
            &["set grid.nx=0: grid.nx: must be at least 1 cell"],
        );
        refused(
            &[Override::set("solid.shape.radius", -1.0)],
            &["set solid.shape.radius=-1.0: solid.shape:"],
        );
        refused(
            &[Override::set("time.cfl", 2.0)],
            &["time.cfl: must be in (0, 1]"],
        );
        refused(&[Override::Refine(0.0)], &["refine 0: the factor must be"]);
        refused(
            &[Override::Refine(1e4)],
            &["refine 10000: grid: more than 1e8 cells"],
        );
        // A file error is still the file's, with its line and column.
        let bad = SPHERE.replace("cfl: 0.4", "cfl: 0.4 0.5");
        let e = Scene::from_str_with(&bad, Path::new("sphere.ron"), &[ron("grid.nx", "3")])
            .unwrap_err();
        assert!(e.to_string().starts_with("sphere.ron:7:"), "{e}");
    }

    #[test]
    fn a_scene_in_memory_takes_sets_and_keeps_them() {
        let mut s = with(&[]).unwrap();
        s.set("solid.law.parameters.G", 3e5).unwrap();
        s.refine(2.0).unwrap();
        assert_eq!(
            s.solid.as_ref().unwrap().law.as_ref().unwrap().parameters["G"],
            3e5
        );
        assert_eq!((s.grid.nx, s.grid.ny), (46, 94));
        assert_eq!(s.overrides.len(), 2);
        let e = s.set("grid.nx", 0).unwrap_err();
        assert!(
            e.to_string().contains("scene `sphere`: set grid.nx=0"),
            "{e}"
        );
        assert_eq!(s.grid.nx, 46);
        assert_eq!(s.overrides.len(), 2);
        // Setting a None: the whole value first, then inside it.
        s.set("time.dt_max", 1e-3).unwrap();
        assert_eq!(s.time.dt_max, Some(1e-3));
    }

    #[test]
    fn every_alias_names_its_field() {
        for (alias, field) in FIELD_ALIASES {
            let scene = if ["r", "z"].contains(alias) {
                format!("domain.{alias}")
            } else if alias.starts_with('n') {
                format!("grid.{alias}")
            } else {
                format!("boundaries.{alias}")
            };
            let value = match *alias {
                "r" => "(0.0, 0.05)",
                "z" => "(0.0, 0.1)",
                "nr" | "nz" => "30",
                "r_min" => "Axis",
                _ => "FreeSlip",
            };
            let s = with(&[ron(&scene, value)]).unwrap_or_else(|e| panic!("{alias}: {e}"));
            let got = serde_json::to_value(&s).unwrap();
            let section = scene.split('.').next().unwrap();
            let expect: serde_json::Value = if is_identifier(value) {
                serde_json::json!(value)
            } else {
                ron::from_str::<ron::Value>(value)
                    .ok()
                    .and_then(|v| serde_json::to_value(v).ok())
                    .unwrap()
            };
            assert_eq!(got[section][field], expect, "{alias} → {field}");
        }
    }
}
