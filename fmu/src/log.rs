//! Messages to the importer's logger, and the panic guard every entry point runs in.

use std::ffi::{CString, c_char, c_int, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// An FMI status (the same codes in FMI 2.0 and FMI 3.0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(i32)]
pub enum Status {
    /// All well.
    Ok = 0,
    /// Something to know.
    Warning = 1,
    /// The call was refused; the instance is unchanged.
    Discard = 2,
    /// The call failed.
    Error = 3,
    /// The instance is unusable.
    Fatal = 4,
}

/// FMI 2.0's logger: `(componentEnvironment, instanceName, status, category, message, ...)`,
/// variadic: the message is a printf format.
pub type Fmi2Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);

/// FMI 3.0's logger: `(instanceEnvironment, status, category, message)`.
pub type Fmi3Logger = unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char);

/// The log categories the model descriptions declare, with what each carries.
pub const CATEGORIES: [(&str, &str); 3] = [
    (
        "logStatusError",
        "Errors: refused calls and parameters, illegal call sequences, failed steps that leave the instance in the Error state",
    ),
    (
        "logStatusDiscard",
        "Communication steps refused with the instance kept at their start (fmi3Discard / fmi2Discard)",
    ),
    (
        "logInfo",
        "The grid and stages at initialisation, solver steps per communication step",
    ),
];

/// Where an instance's messages go.
pub struct Logger {
    /// The instance name (FMI 2.0 passes it with every message).
    pub instance_name: CString,
    /// The FMI 2.0 callback and its environment.
    pub fmi2: Option<(Fmi2Logger, *mut c_void)>,
    /// The FMI 3.0 callback and its environment.
    pub fmi3: Option<(Fmi3Logger, *mut c_void)>,
    /// Which of [`CATEGORIES`] are on (errors go out whatever this says).
    pub enabled: [bool; 3],
}

/// A C string of `s`, with interior NULs replaced.
pub fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}

impl Logger {
    /// A logger with debug logging `on` or off: errors and discarded steps are reported
    /// either way, informational messages only when it is on.
    pub fn new(instance_name: &str, on: bool) -> Self {
        Logger {
            instance_name: c_string(instance_name),
            fmi2: None,
            fmi3: None,
            enabled: [true, true, on],
        }
    }

    /// `fmi2SetDebugLogging` / `fmi3SetDebugLogging`: turn the named categories (all of them
    /// when none is named) on or off. An unknown category is refused, naming the known ones.
    pub fn set_categories(&mut self, on: bool, names: &[String]) -> Result<(), String> {
        let mut picked = Vec::new();
        for n in names {
            let k = CATEGORIES.iter().position(|(c, _)| c == n).ok_or_else(|| {
                format!(
                    "unknown log category `{n}`; this FMU has: {}",
                    CATEGORIES.map(|(c, _)| c).join(", ")
                )
            })?;
            picked.push(k);
        }
        if names.is_empty() {
            picked = (0..CATEGORIES.len()).collect();
        }
        for k in picked {
            self.enabled[k] = on;
        }
        Ok(())
    }

    /// Send `message` in `category`: errors always, other messages when their category is on.
    pub fn log(&self, status: Status, category: &str, message: &str) {
        let on = CATEGORIES
            .iter()
            .position(|(c, _)| *c == category)
            .is_some_and(|k| self.enabled[k]);
        if status != Status::Error && status != Status::Fatal && !on {
            return;
        }
        let category = c_string(category);
        if let Some((f, env)) = self.fmi2 {
            // The message is a printf format for the importer: escape its `%`.
            let text = c_string(&message.replace('%', "%%"));
            // SAFETY: the importer gave this callback for this purpose; all strings are
            // NUL-terminated and outlive the call.
            unsafe {
                f(
                    env,
                    self.instance_name.as_ptr(),
                    status as c_int,
                    category.as_ptr(),
                    text.as_ptr(),
                )
            };
        }
        if let Some((f, env)) = self.fmi3 {
            let text = c_string(message);
            // SAFETY: as above.
            unsafe { f(env, status as c_int, category.as_ptr(), text.as_ptr()) };
        }
    }

    /// Log an error (category `logStatusError`).
    pub fn error(&self, message: &str) {
        self.log(Status::Error, "logStatusError", message);
    }
}

/// The text of a panic payload.
pub fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into())
}

/// Run `f`, turning a panic into `on_panic(message)`: nothing unwinds across the C boundary.
pub fn guard<T>(f: impl FnOnce() -> T, on_panic: impl FnOnce(String) -> T) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => v,
        Err(p) => on_panic(panic_text(p.as_ref())),
    }
}
