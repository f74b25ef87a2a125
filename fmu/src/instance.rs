//! One FMU instance as both C APIs see it: the model, its logger and the strings handed out,
//! and the guarded way into it from an `extern "C"` function.

use crate::log::{Logger, Status, guard};
use crate::model::Model;
use std::ffi::{CString, c_int, c_void};

/// An instance behind an `fmi2Component` / `fmi3Instance` pointer.
pub struct Instance {
    /// The model.
    pub model: Model,
    /// Where messages go.
    pub log: Logger,
    /// Strings returned by the last get-string call (valid until the next one).
    pub strings: Vec<CString>,
}

impl Instance {
    /// A boxed instance as an opaque pointer for the importer.
    pub fn into_raw(self) -> *mut c_void {
        Box::into_raw(Box::new(self)) as *mut c_void
    }

    /// Send the model's pending notes (informational; only with debug logging on).
    fn flush_notes(&mut self) {
        for n in std::mem::take(&mut self.model.notes) {
            self.log.log(Status::Ok, "logInfo", &n);
        }
    }
}

/// Run `f` on the instance behind `c` for the FMI function `func`: a null pointer is an error,
/// an `Err` is logged (prefixed with `func`) and returned as `Error`, and a panic is caught,
/// logged and leaves the model failed (until reset or a state is set). Nothing unwinds.
///
/// # Safety
/// `c` must be null or a pointer returned by an instantiate function of this library and not
/// yet freed, not used concurrently by another thread (FMI's rule for one instance).
pub unsafe fn with_instance(
    c: *mut c_void,
    func: &str,
    f: impl FnOnce(&mut Instance) -> Result<Status, String>,
) -> c_int {
    if c.is_null() {
        return Status::Error as c_int;
    }
    let p = c as *mut Instance;
    let status = guard(
        || {
            // SAFETY: the caller guarantees `c` is a live instance used by one thread.
            let inst = unsafe { &mut *p };
            let r = f(inst);
            inst.flush_notes();
            match r {
                Ok(s) => s,
                Err(m) => {
                    inst.log.error(&format!("{func}: {m}"));
                    Status::Error
                }
            }
        },
        |panic| {
            // SAFETY: as above; the closure that panicked no longer uses the instance.
            let inst = unsafe { &mut *p };
            inst.model.fail();
            guard(
                || {
                    inst.log.error(&format!(
                        "{func}: internal error (a panic: {panic}); reset the instance or set an FMU state"
                    ))
                },
                |_| (),
            );
            Status::Error
        },
    );
    status as c_int
}

/// The `n` values at `p` as a slice (empty for `n == 0`, whatever `p`).
///
/// # Safety
/// For `n > 0`, `p` must point to `n` readable values.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Result<&'a [T], String> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err("a null array was passed with a non-zero length".into());
    }
    // SAFETY: the caller guarantees `n` readable values.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// The `n` values at `p` as a mutable slice (empty for `n == 0`).
///
/// # Safety
/// For `n > 0`, `p` must point to `n` writable values.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Result<&'a mut [T], String> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err("a null array was passed with a non-zero length".into());
    }
    // SAFETY: the caller guarantees `n` writable values.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// A C string argument as UTF-8 (`None` for null).
///
/// # Safety
/// `p` must be null or NUL-terminated.
pub unsafe fn text<'a>(p: *const std::ffi::c_char) -> Option<std::borrow::Cow<'a, str>> {
    if p.is_null() {
        return None;
    }
    // SAFETY: the caller guarantees NUL termination.
    Some(unsafe { std::ffi::CStr::from_ptr(p) }.to_string_lossy())
}
