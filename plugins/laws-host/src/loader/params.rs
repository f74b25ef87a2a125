//! A law's parameters: the declared table ([`ParamInfo`]), and the checks of a scene's values
//! against it (every one declared, finite and in its range; defaults for the others) before the
//! law's instance is created.

use super::LawInfo;
use super::law::LoadedLaw;
use super::open::open;
use crate::LawError;
use efsi_law_abi::ErrBuf;
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::ptr::NonNull;

/// One declared parameter of a law.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name used in scenes.
    pub name: String,
    /// Unit (empty when dimensionless).
    pub unit: String,
    /// One-line description.
    pub description: String,
    /// Value used when the scene gives none.
    pub default: f64,
    /// Lower bound (`-∞` when unbounded).
    pub min: f64,
    /// Upper bound (`+∞` when unbounded).
    pub max: f64,
    /// Whether `min` is excluded.
    pub min_exclusive: bool,
    /// Whether `max` is excluded.
    pub max_exclusive: bool,
}

impl ParamInfo {
    /// Whether `value` is finite and in the allowed range.
    pub fn contains(&self, value: f64) -> bool {
        efsi_law_abi::range_contains(
            value,
            self.min,
            self.max,
            self.min_exclusive,
            self.max_exclusive,
        )
    }

    /// The allowed range in interval notation, e.g. `(0, ∞)`.
    pub fn range_text(&self) -> String {
        efsi_law_abi::range_text(self.min, self.max, self.min_exclusive, self.max_exclusive)
    }

    /// `value` followed by the unit, if any.
    fn with_unit(&self, value: impl fmt::Display) -> String {
        if self.unit.is_empty() {
            value.to_string()
        } else {
            format!("{value} {}", self.unit)
        }
    }
}

/// Open the library at `path` (named `name` in errors) and create its law with `parameters`
/// (by name, checked against the declared ranges; defaults for the others), without the
/// tangent check.
pub(super) fn instantiate(
    path: &Path,
    name: &str,
    parameters: &BTreeMap<String, f64>,
) -> Result<LoadedLaw, LawError> {
    let opened = open(path, name)?;
    let info = opened.info;
    let fail = |message: String| LawError {
        law: info.name.clone(),
        message,
        cell: None,
    };

    let mut values: Vec<f64> = info.parameters.iter().map(|p| p.default).collect();
    for (name, &value) in parameters {
        let Some(k) = info.parameters.iter().position(|p| &p.name == name) else {
            let known = info
                .parameters
                .iter()
                .map(|p| {
                    if p.unit.is_empty() {
                        format!("`{}`", p.name)
                    } else {
                        format!("`{}` ({})", p.name, p.unit)
                    }
                })
                .collect::<Vec<_>>();
            return Err(fail(format!(
                "unknown parameter `{name}`; the law's parameters are: {}",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )));
        };
        let p = &info.parameters[k];
        if !p.contains(value) {
            return Err(fail(
                format!(
                    "parameter `{name}` = {} is out of range: allowed {} {}",
                    p.with_unit(super::number(value)),
                    p.range_text(),
                    p.unit
                )
                .trim_end()
                .to_string(),
            ));
        }
        values[k] = value;
    }

    let mut err = ErrBuf::new();
    // SAFETY: `values` holds `len` readable f64; `err` is writable.
    let handle = unsafe { (opened.create)(values.as_ptr(), values.len(), &mut err) };
    let Some(handle) = NonNull::new(handle) else {
        return Err(fail(format!(
            "could not be created with {}: {}",
            describe_values(&info, &values),
            err.text()
        )));
    };
    Ok(LoadedLaw {
        info,
        values,
        handle,
        evaluate_in_plane: opened.evaluate_in_plane,
        evaluate_full: opened.evaluate_full,
        destroy_fn: opened.destroy,
        check: None,
        check_full: None,
        _library: opened.library,
    })
}

/// `G = 1e5 Pa, …` for messages.
pub(super) fn describe_values(info: &LawInfo, values: &[f64]) -> String {
    if values.is_empty() {
        return "no parameters".to_string();
    }
    info.parameters
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{} = {}", p.name, p.with_unit(super::number(*v))))
        .collect::<Vec<_>>()
        .join(", ")
}
