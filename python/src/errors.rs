//! How an efsi error or a panic reaches Python: the class of `efsi.errors` each kind of
//! failure is raised as, with its arguments.

use efsi_core::EfsiError;
use pyo3::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// How a failure is raised in Python: the class of `efsi.errors` and its arguments.
pub(crate) enum Failure {
    /// `efsi.errors.SceneError(message)`: bad scene, setting, checkpoint or target.
    Scene(String),
    /// `efsi.errors.UnstableError(message, stage, field, cell)`: a run that failed numerically.
    Unstable {
        message: String,
        stage: Option<String>,
        field: Option<String>,
        cell: Option<(i64, i64)>,
    },
    /// `efsi.errors.EfsiError(message)`: anything else (I/O, an internal error).
    Other(String),
}

impl Failure {
    pub(crate) fn raise(self, py: Python<'_>) -> PyErr {
        let errors = match py.import("efsi.errors") {
            Ok(m) => m,
            Err(e) => return e,
        };
        let made = match self {
            Failure::Scene(m) => errors.getattr("SceneError").and_then(|c| c.call1((m,))),
            Failure::Unstable {
                message,
                stage,
                field,
                cell,
            } => errors
                .getattr("UnstableError")
                .and_then(|c| c.call1((message, stage, field, cell))),
            Failure::Other(m) => errors.getattr("EfsiError").and_then(|c| c.call1((m,))),
        };
        match made {
            Ok(exc) => PyErr::from_value(exc),
            Err(e) => e,
        }
    }
}

/// The field and cell named by a stage's non-finite-value message: ``produced a non-finite `u`
/// at cell (3, 4)``, ``produced a non-finite B11 at (3, 4)``, a law's ``non-finite stress (…)
/// in cell (i, j) = (3, 4)``.
fn non_finite(message: &str) -> (Option<String>, Option<(i64, i64)>) {
    let Some((_, rest)) = message.split_once("non-finite ") else {
        return (None, None);
    };
    let field = match rest.strip_prefix('`') {
        Some(r) => r.split('`').next().unwrap_or(""),
        None => rest.split_whitespace().next().unwrap_or(""),
    };
    let pair = |text: &str| -> Option<(i64, i64)> {
        let (inside, _) = text.split_once(')')?;
        let (i, j) = inside.split_once(',')?;
        Some((i.trim().parse().ok()?, j.trim().parse().ok()?))
    };
    let cell = ["(i, j) = (", " at cell (", " at ("]
        .iter()
        .find_map(|key| rest.split_once(key).and_then(|(_, after)| pair(after)));
    ((!field.is_empty()).then(|| field.to_string()), cell)
}

fn classify(e: &EfsiError) -> Failure {
    let message = e.to_string();
    match e {
        EfsiError::Saved { error, .. } => match classify(error) {
            Failure::Unstable {
                stage, field, cell, ..
            } => Failure::Unstable {
                message,
                stage,
                field,
                cell,
            },
            Failure::Scene(_) => Failure::Scene(message),
            Failure::Other(_) => Failure::Other(message),
        },
        EfsiError::Stage(s) => {
            let (field, cell) = non_finite(&s.message);
            Failure::Unstable {
                message,
                stage: Some(s.stage.clone()),
                field,
                cell,
            }
        }
        EfsiError::Unstable { .. } | EfsiError::EnergyGrowth { .. } => Failure::Unstable {
            message,
            stage: None,
            field: None,
            cell: None,
        },
        _ => match e.exit_code() {
            2 => Failure::Scene(message),
            _ => Failure::Other(message),
        },
    }
}

pub(crate) fn efsi_err(py: Python<'_>, e: impl Into<EfsiError>) -> PyErr {
    classify(&e.into()).raise(py)
}

/// [`efsi_err`] with `note` as a last line of the message (what state the simulation is in).
pub(crate) fn efsi_err_noted(py: Python<'_>, e: EfsiError, note: &str) -> PyErr {
    let mut failure = classify(&e);
    match &mut failure {
        Failure::Scene(m) | Failure::Other(m) | Failure::Unstable { message: m, .. } => {
            m.push('\n');
            m.push_str(note);
        }
    }
    failure.raise(py)
}

pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into());
    format!("internal error: efsi panicked: {what}")
}

/// Run `f`, turning a panic into `efsi.errors.EfsiError`.
pub(crate) fn guarded<T>(py: Python<'_>, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => Err(Failure::Other(panic_message(p.as_ref())).raise(py)),
    }
}
