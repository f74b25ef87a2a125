//! One FMU instance as both C APIs see it, the handles the importer holds, and the guarded way
//! into an instance from an `extern "C"` function.
//!
//! **Handles.** An `fmi2Component` / `fmi3Instance` and an FMU state are not pointers to our
//! data but numbers from a counter that never repeats (spaced 16 apart from
//! [`HANDLE_BASE`]). Instances live in a process-wide registry and each instance keeps its own
//! states, so a handle that is not one of ours — a foreign pointer, a freed instance, a state
//! freed twice, a state of another instance — is found missing and refused with `Error`; it is
//! never dereferenced or freed. Where the standard passes a *pointer to* a state handle
//! (`fmi2GetFMUstate`, `fmi2FreeFMUstate`, …) the pointer is the importer's memory: it is
//! probed before it is read or written, and a state handle passed in its place (the state
//! passed by value where its address was meant) is recognised and named.
//!
//! **Calls.** [`with_instance`] looks the instance up, checks the call against the life cycle
//! ([`crate::machine`]), runs it with panics caught, logs a refusal with the function's name,
//! and after an `Error` leaves the instance in the `Error` mode (FMI: "the simulation must not
//! be continued" until an FMU state is set or the instance is reset). One instance serves one
//! call at a time: a concurrent or re-entrant call on the same instance is refused.

use crate::log::{Logger, Status, guard};
use crate::machine::{Version, allowed};
use crate::model::{Fault, Model};
use crate::state::FmuState;
use std::collections::BTreeMap;
use std::ffi::{CString, c_int, c_void};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, TryLockError};

/// Where handles start: an address no allocation of this process is expected to have, so a
/// handle is recognisable in the logs and where a pointer was expected.
pub const HANDLE_BASE: usize = 0x0E75_0000_0000;

static NEXT: AtomicUsize = AtomicUsize::new(0);

/// A handle never handed out before.
fn fresh_handle() -> usize {
    HANDLE_BASE + 16 * NEXT.fetch_add(1, Ordering::Relaxed)
}

/// Whether `p` could be one of our handles (in our range, on our spacing).
pub fn looks_like_handle(p: usize) -> bool {
    p >= HANDLE_BASE && (p - HANDLE_BASE).is_multiple_of(16) && p < HANDLE_BASE + 16 * (1 << 36)
}

type Shared = Arc<Mutex<Instance>>;

static INSTANCES: Mutex<BTreeMap<usize, Shared>> = Mutex::new(BTreeMap::new());

fn registry() -> std::sync::MutexGuard<'static, BTreeMap<usize, Shared>> {
    INSTANCES.lock().unwrap_or_else(|p| p.into_inner())
}

/// An instance behind an `fmi2Component` / `fmi3Instance` handle.
pub struct Instance {
    /// The model.
    pub model: Model,
    /// Where messages go.
    pub log: Logger,
    /// The standard it was instantiated through.
    pub version: Version,
    /// Strings returned by the last get-string call (valid until the next one).
    pub strings: Vec<CString>,
    /// The FMU states made by this instance, by handle.
    states: BTreeMap<usize, FmuState>,
}

// SAFETY: the only non-`Send` parts are the importer's logger environment pointers, which the
// importer hands over with the instance; FMI lets an importer use an instance from any thread,
// one call at a time (which the registry's per-instance mutex enforces).
unsafe impl Send for Instance {}

impl Instance {
    /// A new instance of `model`, not yet registered.
    pub fn new(model: Model, log: Logger, version: Version) -> Self {
        Instance {
            model,
            log,
            version,
            strings: Vec::new(),
            states: BTreeMap::new(),
        }
    }

    /// Register the instance; its handle for the importer.
    pub fn register(self) -> *mut c_void {
        let h = fresh_handle();
        registry().insert(h, Arc::new(Mutex::new(self)));
        h as *mut c_void
    }

    /// Send the model's pending notes (category `logInfo`, only with debug logging on).
    fn flush_notes(&mut self) {
        for n in std::mem::take(&mut self.model.notes) {
            self.log.log(Status::Ok, "logInfo", &n);
        }
    }

    /// Keep `state` under a new handle.
    pub fn add_state(&mut self, state: FmuState) -> usize {
        let h = fresh_handle();
        self.states.insert(h, state);
        h
    }

    /// The state with handle `h`, if this instance made it and has not freed it.
    pub fn state(&self, h: *mut c_void) -> Result<&FmuState, String> {
        self.states.get(&(h as usize)).ok_or_else(|| not_ours(h))
    }

    /// As [`state`](Self::state), mutable.
    pub fn state_mut(&mut self, h: *mut c_void) -> Result<&mut FmuState, String> {
        self.states
            .get_mut(&(h as usize))
            .ok_or_else(|| not_ours(h))
    }

    /// Overwrite the state with handle `h` with the current state (reusing its storage).
    pub fn refresh_state(&mut self, h: *mut c_void) -> Result<(), Fault> {
        let s = self
            .states
            .get_mut(&(h as usize))
            .ok_or_else(|| not_ours(h))?;
        self.model.get_state_into(s)
    }

    /// Free the state with handle `h`.
    pub fn remove_state(&mut self, h: *mut c_void) -> Result<(), String> {
        self.states
            .remove(&(h as usize))
            .map(|_| ())
            .ok_or_else(|| not_ours(h))
    }

    /// Whether `h` is a state of this instance.
    pub fn has_state(&self, h: *mut c_void) -> bool {
        self.states.contains_key(&(h as usize))
    }
}

fn not_ours(h: *mut c_void) -> String {
    format!(
        "{h:p} is not an FMU state of this instance (never made by it, made by another instance, or already freed)"
    )
}

/// Free the instance behind `c` (nothing for null, an unknown or an already freed handle).
pub fn free(c: *mut c_void) {
    let removed = registry().remove(&(c as usize));
    drop(removed);
}

/// Run `f` on the instance behind `c` for the FMI function `func` (full name, e.g.
/// `fmi2DoStep`): an unknown handle is an `Error`; a call the life cycle does not allow in the
/// current mode is an `Error` naming the mode; a `Fault` is logged (prefixed with `func`) and
/// returned as its status; a panic is caught and logged. After any `Error` the instance is in
/// the `Error` mode. Nothing unwinds.
pub fn with_instance(
    c: *mut c_void,
    func: &str,
    f: impl FnOnce(&mut Instance) -> Result<Status, Fault>,
) -> c_int {
    let status = guard(
        || {
            let Some(shared) = registry().get(&(c as usize)).cloned() else {
                return Status::Error;
            };
            let mut lock = match shared.try_lock() {
                Ok(l) => l,
                Err(TryLockError::Poisoned(p)) => p.into_inner(),
                Err(TryLockError::WouldBlock) => return Status::Error,
            };
            let inst = &mut *lock;
            let mode = inst.model.mode();
            if !allowed(inst.version, func, mode) {
                inst.model.enter_error();
                inst.log.error(&format!(
                    "{func}: not allowed in the {} state (illegal call sequence); the instance is now in the Error state: set an FMU state or reset it",
                    mode.name(inst.version)
                ));
                return Status::Error;
            }
            let result = guard(
                || f(inst),
                |panic| {
                    Err(Fault::error(format!(
                        "internal error (a panic: {panic}); the instance is now in the Error state: set an FMU state or reset it"
                    )))
                },
            );
            inst.flush_notes();
            match result {
                Ok(s) => s,
                Err(fault) => {
                    if fault.status == Status::Error {
                        inst.model.enter_error();
                    }
                    let category = match fault.status {
                        Status::Discard => "logStatusDiscard",
                        _ => "logStatusError",
                    };
                    inst.log.log(
                        fault.status,
                        category,
                        &format!("{func}: {}", fault.message),
                    );
                    fault.status
                }
            }
        },
        |_| Status::Error,
    );
    status as c_int
}

/// Whether `n` bytes at `p` can be read (and, with `write`, written) by this process: probed
/// with `process_vm_readv` / `process_vm_writev` on our own process, which report a bad
/// address as `EFAULT` instead of faulting. Where the kernel refuses the probe itself, the
/// memory is assumed accessible.
fn accessible(p: *const c_void, n: usize, write: bool) -> bool {
    if p.is_null() {
        return false;
    }
    let mut buf = vec![0u8; n];
    let local = libc::iovec {
        iov_base: buf.as_mut_ptr() as *mut c_void,
        iov_len: n,
    };
    let remote = libc::iovec {
        iov_base: p as *mut c_void,
        iov_len: n,
    };
    // SAFETY: the kernel validates `remote`; `local` is our buffer of `n` bytes.
    let got = unsafe { libc::process_vm_readv(libc::getpid(), &local, 1, &remote, 1, 0) };
    if got < 0 {
        return std::io::Error::last_os_error().raw_os_error() != Some(libc::EFAULT);
    }
    if got as usize != n {
        return false;
    }
    if !write {
        return true;
    }
    // Write the same bytes back: a no-op where the memory is writable.
    // SAFETY: as above; the bytes written are the ones just read.
    let put = unsafe { libc::process_vm_writev(libc::getpid(), &local, 1, &remote, 1, 0) };
    put as usize == n
        || (put < 0 && std::io::Error::last_os_error().raw_os_error() != Some(libc::EFAULT))
}

/// The importer's variable holding a state handle (`fmi2FMUstate*`, `fmi3FMUState*`), checked:
/// readable and writable, and not itself one of our handles (a state passed by value where its
/// address was meant).
// The pointer is the importer's: it is probed before it is dereferenced, so the function is
// safe to call with any value.
#[allow(clippy::not_unsafe_ptr_arg_deref)]
pub fn state_slot<'a>(slot: *mut *mut c_void) -> Result<&'a mut *mut c_void, String> {
    if slot.is_null() {
        return Err("a null pointer where the address of an FMU state variable is expected".into());
    }
    if looks_like_handle(slot as usize) {
        return Err(format!(
            "{slot:p} is an FMU state handle, passed where the address of a variable holding one is expected"
        ));
    }
    if !accessible(
        slot as *const c_void,
        std::mem::size_of::<*mut c_void>(),
        true,
    ) {
        return Err(format!(
            "{slot:p} is not the address of a writable FMU state variable"
        ));
    }
    // SAFETY: probed readable and writable for one pointer.
    Ok(unsafe { &mut *slot })
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
