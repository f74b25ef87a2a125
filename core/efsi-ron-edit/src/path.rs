//! Paths: `a.b[2].c.1` as keys (aliases resolved) and indices.

use crate::Aliases;
use std::fmt;

/// The canonical name of a field name that may be an alias.
pub(crate) fn canonical(aliases: Aliases, name: &str) -> &str {
    aliases
        .iter()
        .find(|(a, _)| *a == name)
        .map_or(name, |(_, c)| c)
}

/// One step of a path: a field or map key, or an element index.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Seg {
    /// A field or map key.
    Key(String),
    /// An element index.
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

pub(crate) fn show(segs: &[Seg]) -> String {
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
pub(crate) fn parse_path(path: &str, aliases: Aliases) -> Result<Vec<Seg>, String> {
    let bad = |why: &str| {
        Err(format!(
            "bad path `{path}`: {why} (expected names and indices, e.g. grid.nx, output.probes[2].at)"
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
                Err(_) => Seg::Key(canonical(aliases, head).to_string()),
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
