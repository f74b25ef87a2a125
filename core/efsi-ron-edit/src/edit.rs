//! Locating a path in a tree and planning the text edit that sets it.

use crate::Aliases;
use crate::Value;
use crate::path::{Seg, canonical, show};
use crate::tree::{Atom, Kind, Node, Parser, a_name, parse_ron};

/// Where a path leads in a tree.
pub(crate) enum Found<'a> {
    /// The node at the whole path.
    Node(&'a Node),
    /// The path leaves the tree at `container` (a struct or map): `rest` is missing there.
    Missing { container: &'a Node, rest: usize },
}

/// The child of `node` at `seg`, looking through `Some(…)` and one-value variants.
/// `Ok(None)`: absent from a struct or map (insertable). `Err`: why the path cannot go on.
fn child<'a>(
    node: &'a Node,
    seg: &Seg,
    text: Option<&str>,
    aliases: Aliases,
) -> Result<Option<&'a Node>, String> {
    match (&node.kind, seg) {
        (Kind::Tuple(_, items), _)
            if items.len() == 1 && !matches!(items[0].kind, Kind::Atom(_)) =>
        {
            match child(&items[0], seg, text, aliases) {
                Ok(found) => Ok(found),
                Err(_) if *seg == Seg::Index(0) => Ok(Some(&items[0])),
                Err(e) => Err(e),
            }
        }
        (Kind::Struct(fields), Seg::Key(k)) => Ok(fields
            .iter()
            .find(|(name, _)| canonical(aliases, name) == k)
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

pub(crate) fn locate<'a>(
    root: &'a Node,
    segs: &[Seg],
    text: &str,
    aliases: Aliases,
) -> Result<Found<'a>, String> {
    let mut node = root;
    for (k, seg) in segs.iter().enumerate() {
        match child(node, seg, Some(text), aliases) {
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
fn hint<'a>(
    hints: Option<(&'a Node, &'a str)>,
    segs: &[Seg],
    aliases: Aliases,
) -> Option<&'a Node> {
    let (root, text) = hints?;
    match locate(root, segs, text, aliases) {
        Ok(Found::Node(n)) => Some(n),
        _ => None,
    }
}

/// A text edit: replace `start..end` with `text`.
pub(crate) struct Edit {
    pub(crate) start: usize,
    pub(crate) end: usize,
    pub(crate) text: String,
}

pub(crate) fn plan(
    root: (&Node, &str),
    hints: Option<(&Node, &str)>,
    segs: &[Seg],
    value: &Value,
    aliases: Aliases,
) -> Result<Edit, String> {
    let (tree, text) = root;
    if segs.is_empty() {
        return Err("the path is empty".into());
    }
    match locate(tree, segs, text, aliases)? {
        Found::Node(node) => {
            let hinted = hint(hints, segs, aliases).and_then(Node::atom);
            let target = match (node.atom(), hinted) {
                // A real number the file wrote as a whole one (`end: 1`) stays real.
                (Some(Atom::Int), Some(Atom::Float)) => Some(Atom::Float),
                // `None` in the file: the type of the default's value, if it has one.
                (atom, hinted) => atom.or(hinted),
            };
            let new = render(
                value,
                target.filter(|a| *a != Atom::Ident || !is_none(node, text)),
            )?;
            Ok(Edit {
                start: node.start,
                end: node.end,
                text: new,
            })
        }
        Found::Missing { container, rest } => {
            let is_map = matches!(container.kind, Kind::Map(_));
            let mut inner = render(value, hint(hints, segs, aliases).and_then(Node::atom))?;
            for k in (rest + 1..segs.len()).rev() {
                let Seg::Key(key) = &segs[k] else {
                    return Err(format!(
                        "{} is not in the scene: no element to index",
                        show(&segs[..k])
                    ));
                };
                let map = hint(hints, &segs[..k], aliases)
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

pub(crate) fn is_none(node: &Node, text: &str) -> bool {
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
pub(crate) fn render(value: &Value, target: Option<Atom>) -> Result<String, String> {
    let whole = |x: f64| -> Result<String, String> {
        if x.fract() == 0.0 && x.abs() < 9e15 {
            Ok(format!("{}", x as i64))
        } else {
            Err(format!("expected an integer, got {x:?}"))
        }
    };
    match (value, target) {
        (Value::Bool(b), Some(t)) if t != Atom::Bool => {
            Err(format!("expected {}, got {b}", a_name(t)))
        }
        (Value::Bool(b), _) => Ok(b.to_string()),
        (Value::Int(i), Some(Atom::Float)) => Ok(format!("{i}.0")),
        (Value::Int(i), Some(Atom::Str)) => Ok(ron_string(&i.to_string())),
        (Value::Int(i), _) => Ok(i.to_string()),
        (Value::Float(x), Some(Atom::Int)) => whole(*x),
        (Value::Float(x), Some(Atom::Str)) => Ok(ron_string(&format!("{x:?}"))),
        (Value::Float(x), _) => ron::to_string(x).map_err(|e| e.to_string()),
        (Value::Str(s), Some(Atom::Ident)) if is_identifier(s) => Ok(s.clone()),
        // A setting of unknown type (in a stage's section the file leaves out, whose defaults
        // the scene does not know): a capitalised identifier is an enum's variant.
        (Value::Str(s), None) if is_identifier(s) && s.starts_with(char::is_uppercase) => {
            Ok(s.clone())
        }
        (Value::Str(s), _) => Ok(ron_string(s)),
        (Value::Ron(t), target) => {
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
                Err((at, m)) => Err(format!(
                    "the value `{}` is not RON: {m} (at byte {at})",
                    crate::elide(t)
                )),
            }
        }
    }
}
