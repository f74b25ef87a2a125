//! # efsi-law-abi — the C-compatible ABI of efsi's constitutive-law plugins
//!
//! A constitutive law is a dynamic library (`.so`, `.dylib`, `.dll`) that exports **one symbol**,
//! [`ENTRY_SYMBOL`] (`efsi_law_descriptor`), a function of type [`EntryFn`] returning a pointer to a
//! static [`LawDescriptor`]. The descriptor says which ABI version the library was built for, its
//! own size (a layout guard), the law's name and description, its parameter table
//! ([`ParamDesc`]: name, unit, description, default, allowed range) and three functions:
//!
//! * [`CreateFn`] — build a law instance from parameter values (one per declared parameter, in
//!   table order); returns an opaque handle, or null with a message in the [`ErrBuf`];
//! * [`DestroyFn`] — free a handle;
//! * [`EvaluateFn`] — for a **batch** of cells, the stress `τ(B̃)` and optionally the tangent
//!   `J = ∂τ/∂B̃`; returns a status ([`STATUS_OK`], …) and on failure a message in the [`ErrBuf`].
//!
//! Rust authors do not use this crate directly: they implement the safe trait of `efsi-law-sdk`
//! and call its `export_law!` macro. The ABI is documented here for everyone else (a law written
//! in C, C++, Fortran…) and for the loader in `efsi-laws-host`.
//!
//! # Tensor layout
//!
//! Deformations are in-plane: symmetric tensors have components 11, 22, 33, 12 (13 = 23 = 0),
//! stored as four `f64` in the order `[t11, t22, t33, t12]` ([`Sym`]). Direction 3 is out of plane
//! (z in plane strain, the hoop direction θ in axisymmetric runs). The tangent ([`Tangent`]) is
//! sixteen `f64`, row-major, `J[4a + b] = ∂τ_a/∂B̃_b` in the same 4-component representation with
//! the shear component counted **once**: `Δτ = J·ΔB̃` holds for symmetric increments
//! `ΔB̃ = [Δb11, Δb22, Δb33, Δb12]` (so e.g. `∂tr(B̃)/∂b12 = 0` and `∂(B̃·B̃)_11/∂b12 = 2 b12`).
//! Batches are **cell-major**: cell `k`'s `B̃` is `b[4k .. 4k+4]`, its stress `tau[4k .. 4k+4]`,
//! its tangent `tangent[16k .. 16k+16]`.
//!
//! # Rules a plugin must follow
//!
//! * No unwinding across the boundary: every function catches its own panics / exceptions and
//!   returns [`STATUS_PANIC`] (or null from `create`) with the message. An uncaught Rust panic
//!   aborts the host process.
//! * `evaluate` may be called **concurrently** from several threads on the same handle: it must
//!   not mutate shared state. `create` and `destroy` may be called from any thread.
//! * Outputs must be finite: a plugin reports a non-finite result as [`STATUS_NON_FINITE`]
//!   naming the first bad cell (the host checks again).
//! * Strings in the descriptor are NUL-terminated UTF-8 and, like the descriptor itself, live as
//!   long as the library is loaded.
//!
//! # Version policy
//!
//! [`ABI_VERSION`] is an integer, currently **1**. It is raised on **any** change to the layout
//! or meaning of the items of this crate (a field added, removed, reordered or retyped; a
//! function signature; a status code; the tensor layout; the error-buffer size). A host loads a
//! library only if the library's `abi_version` equals the host's [`ABI_VERSION`] exactly and
//! `descriptor_size` equals `size_of::<LawDescriptor>()`; otherwise it refuses the library and
//! asks for a rebuild against the matching `efsi-law-sdk`. The entry symbol's name and the first
//! two fields of the descriptor (`abi_version: u32`, `descriptor_size: u32`) are **frozen across
//! all versions**, so that any host can read a library's version before trusting the rest.
//! Changes that touch nothing in this crate (a new SDK helper, a new shipped law) do not
//! change the ABI version.
//!
//! This crate has no dependencies and only `#[repr(C)]` types, constants and small safe helpers.

use std::ffi::{c_char, c_void};

/// The ABI version this crate describes (see the version policy in the crate docs).
pub const ABI_VERSION: u32 = 1;

/// The version of the `efsi-law-abi` / `efsi-law-sdk` crates (one workspace version), for messages
/// such as "rebuild the law against efsi-law-sdk 0.1.0".
pub const CRATE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Name of the one symbol a law library exports, with its NUL terminator (for `dlsym`).
/// Its type is [`EntryFn`]. The name does not change between ABI versions.
pub const ENTRY_SYMBOL: &[u8] = b"efsi_law_descriptor\0";

/// Name of the entry symbol without the NUL terminator, for messages.
pub const ENTRY_SYMBOL_NAME: &str = "efsi_law_descriptor";

/// Capacity in bytes of an [`ErrBuf`] message, NUL terminator included.
pub const ERR_BUF_CAPACITY: usize = 1024;

/// Success.
pub const STATUS_OK: i32 = 0;
/// The law refused the input or failed; the message says why.
pub const STATUS_ERROR: i32 = 1;
/// The law panicked (or threw); the message carries the panic message.
pub const STATUS_PANIC: i32 = 2;
/// The law produced a non-finite stress or tangent; the message names the first bad cell.
pub const STATUS_NON_FINITE: i32 = 3;
/// The host passed an invalid argument (a null pointer where data was required).
pub const STATUS_INVALID_ARGUMENT: i32 = 4;

/// [`ParamDesc::flags`] bit: the lower bound [`ParamDesc::min`] is excluded (`value > min`).
pub const PARAM_MIN_EXCLUSIVE: u32 = 1;
/// [`ParamDesc::flags`] bit: the upper bound [`ParamDesc::max`] is excluded (`value < max`).
pub const PARAM_MAX_EXCLUSIVE: u32 = 2;

/// Stored components of an in-plane symmetric tensor: `[t11, t22, t33, t12]` (identical to
/// `efsi_laws_host::Sym`).
pub type Sym = [f64; 4];

/// Tangent `∂τ_a/∂B̃_b`, row-major over the [`Sym`] components, shear counted once (identical
/// to `efsi_laws_host::Tangent`).
pub type Tangent = [f64; 16];

/// The type of the entry symbol [`ENTRY_SYMBOL`]: returns a pointer to the library's descriptor,
/// valid as long as the library stays loaded, or null if the library could not build it.
pub type EntryFn = unsafe extern "C" fn() -> *const LawDescriptor;

/// Builds a law instance.
///
/// * `params` — `n` values, one per entry of the descriptor's parameter table, in table order
///   (the host fills in defaults and checks ranges first); may be null when `n == 0`.
/// * `err` — where to write a message on failure (may be null).
///
/// Returns an opaque non-null handle, or null on failure (message in `err`).
pub type CreateFn =
    unsafe extern "C" fn(params: *const f64, n: usize, err: *mut ErrBuf) -> *mut c_void;

/// Frees a handle returned by [`CreateFn`]. Called once per handle, never with null.
pub type DestroyFn = unsafe extern "C" fn(handle: *mut c_void);

/// Evaluates the law on a batch of `n_cells` cells (cell-major, see the crate docs).
///
/// * `b` — `4 n_cells` values of `B̃`;
/// * `tau` — `4 n_cells` values to write `τ(B̃)` into;
/// * `tangent` — `16 n_cells` values to write `∂τ/∂B̃` into, or null when the tangent is not
///   wanted (then the law computes the stress only);
/// * `err` — where to write a message when the status is not [`STATUS_OK`] (may be null).
///
/// Returns a status code: [`STATUS_OK`], [`STATUS_ERROR`], [`STATUS_PANIC`],
/// [`STATUS_NON_FINITE`] or [`STATUS_INVALID_ARGUMENT`]. May be called concurrently on one
/// handle.
pub type EvaluateFn = unsafe extern "C" fn(
    handle: *const c_void,
    n_cells: usize,
    b: *const f64,
    tau: *mut f64,
    tangent: *mut f64,
    err: *mut ErrBuf,
) -> i32;

/// A fixed-size, caller-provided buffer for an error message: NUL-terminated UTF-8 in
/// `message` (a plugin truncates longer messages; the host reads up to the first NUL).
#[repr(C)]
#[derive(Clone)]
pub struct ErrBuf {
    /// The message bytes, NUL-terminated.
    pub message: [u8; ERR_BUF_CAPACITY],
}

impl ErrBuf {
    /// An empty buffer.
    pub const fn new() -> Self {
        ErrBuf {
            message: [0; ERR_BUF_CAPACITY],
        }
    }

    /// Stores `text`, truncated on a character boundary to fit with its NUL terminator.
    pub fn set(&mut self, text: &str) {
        let mut n = text.len().min(ERR_BUF_CAPACITY - 1);
        while !text.is_char_boundary(n) {
            n -= 1;
        }
        self.message[..n].copy_from_slice(&text.as_bytes()[..n]);
        self.message[n] = 0;
    }

    /// The stored message (up to the first NUL; invalid UTF-8 replaced).
    pub fn text(&self) -> String {
        let end = self
            .message
            .iter()
            .position(|&c| c == 0)
            .unwrap_or(ERR_BUF_CAPACITY);
        String::from_utf8_lossy(&self.message[..end]).into_owned()
    }
}

impl Default for ErrBuf {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for ErrBuf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("ErrBuf").field(&self.text()).finish()
    }
}

/// One declared parameter of a law.
///
/// The allowed range is `[min, max]`, with either end excluded when the matching
/// [`PARAM_MIN_EXCLUSIVE`] / [`PARAM_MAX_EXCLUSIVE`] bit of `flags` is set; `±∞` means
/// unbounded. `default` lies in the range.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ParamDesc {
    /// Name used in scenes, e.g. `G` (NUL-terminated UTF-8, non-null).
    pub name: *const c_char,
    /// Unit, e.g. `Pa`, or an empty string for a dimensionless parameter (non-null).
    pub unit: *const c_char,
    /// One-line description (non-null).
    pub description: *const c_char,
    /// The value used when the scene does not give one.
    pub default: f64,
    /// Lower bound of the allowed range (may be `-∞`).
    pub min: f64,
    /// Upper bound of the allowed range (may be `+∞`).
    pub max: f64,
    /// Bit set of [`PARAM_MIN_EXCLUSIVE`] and [`PARAM_MAX_EXCLUSIVE`].
    pub flags: u32,
}

// SAFETY: the pointers point to immutable NUL-terminated strings that live as long as the
// library; nothing is ever written through them.
unsafe impl Send for ParamDesc {}
// SAFETY: as above.
unsafe impl Sync for ParamDesc {}

/// What a law library describes about itself, returned by the entry symbol.
///
/// Layout (64-bit targets): `abi_version` at 0, `descriptor_size` at 4, then eight
/// pointer-sized fields — 72 bytes in all. The first two fields are frozen across ABI versions.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LawDescriptor {
    /// The ABI version the library was built for: [`ABI_VERSION`] of its `efsi-law-abi`.
    pub abi_version: u32,
    /// `size_of::<LawDescriptor>()` as the library sees it (a layout guard).
    pub descriptor_size: u32,
    /// The law's name, e.g. `neo_hookean` (NUL-terminated UTF-8, non-null).
    pub name: *const c_char,
    /// One-line description of the law, e.g. its formula (NUL-terminated UTF-8, non-null).
    pub description: *const c_char,
    /// Number of entries of `params`.
    pub param_count: usize,
    /// The parameter table (`param_count` entries; may be null when `param_count == 0`).
    pub params: *const ParamDesc,
    /// `size_of::<ParamDesc>()` as the library sees it (a layout guard).
    pub param_desc_size: usize,
    /// Builds an instance (required).
    pub create: Option<CreateFn>,
    /// Frees an instance (required).
    pub destroy: Option<DestroyFn>,
    /// Evaluates a batch (required).
    pub evaluate: Option<EvaluateFn>,
}

// SAFETY: the descriptor is immutable and its pointers point to immutable data living as long as
// the library; the functions are thread-safe by the ABI's rules.
unsafe impl Send for LawDescriptor {}
// SAFETY: as above.
unsafe impl Sync for LawDescriptor {}

/// `size_of::<LawDescriptor>()` as a `u32`, the value of [`LawDescriptor::descriptor_size`].
pub const DESCRIPTOR_SIZE: u32 = std::mem::size_of::<LawDescriptor>() as u32;

/// Whether `value` is finite and inside the range `min..max` with the given exclusions — the
/// one rule the SDK (when a law is created) and the loader (when a scene names parameters) share.
/// A Rust-level helper: not part of the binary interface, so it does not change [`ABI_VERSION`].
pub fn range_contains(
    value: f64,
    min: f64,
    max: f64,
    min_exclusive: bool,
    max_exclusive: bool,
) -> bool {
    let above = if min_exclusive {
        value > min
    } else {
        value >= min
    };
    let below = if max_exclusive {
        value < max
    } else {
        value <= max
    };
    value.is_finite() && above && below
}

/// The range in interval notation, e.g. `(0, ∞)` or `[0, 1]` (an infinite end is open).
pub fn range_text(min: f64, max: f64, min_exclusive: bool, max_exclusive: bool) -> String {
    let num = |x: f64| {
        if x == f64::INFINITY {
            "∞".to_string()
        } else if x == f64::NEG_INFINITY {
            "-∞".to_string()
        } else if x == 0.0 || (1e-4..1e16).contains(&x.abs()) {
            format!("{x}")
        } else {
            // `1e308`, not 309 digits.
            format!("{x:e}")
        }
    };
    let open = min_exclusive || min == f64::NEG_INFINITY;
    let close = max_exclusive || max == f64::INFINITY;
    format!(
        "{}{}, {}{}",
        if open { "(" } else { "[" },
        num(min),
        num(max),
        if close { ")" } else { "]" }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_stable_on_64_bit() {
        if cfg!(target_pointer_width = "64") {
            assert_eq!(std::mem::size_of::<LawDescriptor>(), 72);
            assert_eq!(std::mem::size_of::<ParamDesc>(), 56);
            assert_eq!(std::mem::offset_of!(LawDescriptor, descriptor_size), 4);
            assert_eq!(std::mem::offset_of!(LawDescriptor, name), 8);
            assert_eq!(std::mem::offset_of!(LawDescriptor, evaluate), 64);
        }
        assert_eq!(std::mem::size_of::<ErrBuf>(), ERR_BUF_CAPACITY);
    }

    #[test]
    fn err_buf_truncates_on_char_boundary() {
        let mut e = ErrBuf::new();
        e.set("short");
        assert_eq!(e.text(), "short");
        let long = "é".repeat(ERR_BUF_CAPACITY);
        e.set(&long);
        let t = e.text();
        assert!(t.len() < ERR_BUF_CAPACITY);
        assert!(t.chars().all(|c| c == 'é'));
    }
}
