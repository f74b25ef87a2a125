//! # efsi-law-abi — the C-compatible ABI of efsi's constitutive-law plugins
//!
//! A constitutive law is a dynamic library (`.so`, `.dylib`, `.dll`) that exports **one symbol**,
//! [`ENTRY_SYMBOL`] (`efsi_law_descriptor`), a function of type [`EntryFn`] returning a pointer to a
//! static [`LawDescriptor`]. The descriptor says which ABI version the library was built for, its
//! own size (a layout guard), the law's name and description, its parameter table
//! ([`ParamDesc`]: name, unit, description, default, allowed range) and four functions:
//!
//! * [`CreateFn`] — build a law instance from parameter values (one per declared parameter, in
//!   table order); returns an opaque handle, or null with a message in the [`ErrBuf`];
//! * [`DestroyFn`] — free a handle;
//! * two [`EvaluateFn`]s — for a **batch** of cells, the stress `τ(B̃)` and optionally the tangent
//!   `J = ∂τ/∂B̃`, one on the full symmetric tensor ([`LawDescriptor::evaluate_full`]) and one
//!   on in-plane tensors ([`LawDescriptor::evaluate_in_plane`]); each returns a status
//!   ([`STATUS_OK`], …) and on failure a message in the [`ErrBuf`].
//!
//! Rust authors do not use this crate directly: they implement the safe trait of `efsi-law-sdk`
//! and call its `export_law!` macro, which writes the law once and exports both evaluations.
//! The ABI is documented here for everyone else (a law written in C, C++, Fortran…) and for the
//! loader in `efsi-laws-host`.
//!
//! # Tensor layouts
//!
//! **Full** (3-D scenes): a symmetric tensor is six `f64` in the order
//! `[t11, t22, t33, t12, t23, t13]` ([`Sym6`], VTK's order of a symmetric tensor). The tangent
//! ([`Tangent6`]) is 36 `f64`, row-major, `J[6a + b] = ∂τ_a/∂B̃_b`, the shear components counted
//! **once**: `Δτ = J·ΔB̃` holds for symmetric increments `ΔB̃ = [Δb11, Δb22, Δb33, Δb12, Δb23,
//! Δb13]`, an increment `Δb12` changing both entries 12 and 21 of the matrix (so e.g.
//! `∂tr(B̃)/∂b12 = 0` and `∂(B̃·B̃)_11/∂b12 = 2 b12`).
//!
//! **In-plane** (planar and axisymmetric scenes, 13 = 23 = 0): the first four components,
//! `[t11, t22, t33, t12]` ([`Sym`]), and the tangent's in-plane block ([`Tangent`], sixteen `f64`,
//! `J[4a + b]`), with the same convention. Direction 3 is out of plane (z in plane strain, the
//! hoop direction θ in axisymmetric runs). This is version 1's only layout.
//!
//! The two must describe one law: `evaluate_in_plane` on `[b11, b22, b33, b12]` gives the
//! components 11, 22, 33, 12 of `evaluate_full` on `[b11, b22, b33, b12, 0, 0]`, and its tangent
//! the matching 4×4 block (an isotropic law's 23 and 13 stresses vanish there; the loader
//! compares the two at load, to `1e-10` relative). The in-plane entry
//! exists so that 2-D runs keep the arithmetic of version 1 exactly; the SDK derives both from
//! one generic law. Batches are **cell-major**: with `m` components (6 or 4), cell `k`'s `B̃` is
//! `b[m k .. m k + m]`, its stress `tau[m k .. m k + m]`, its tangent `tangent[m² k .. m² k + m²]`.
//!
//! # Rules a plugin must follow
//!
//! * No unwinding across the boundary: every function catches its own panics / exceptions and
//!   returns [`STATUS_PANIC`] (or null from `create`) with the message. An uncaught Rust panic
//!   aborts the host process.
//! * `evaluate_*` may be called **concurrently** from several threads on the same handle: they
//!   must not mutate shared state. `create` and `destroy` may be called from any thread.
//! * Outputs must be finite: a plugin reports a non-finite result as [`STATUS_NON_FINITE`]
//!   naming the first bad cell (the host checks again).
//! * Strings in the descriptor are NUL-terminated UTF-8 and, like the descriptor itself, live as
//!   long as the library is loaded.
//!
//! # Version policy
//!
//! [`ABI_VERSION`] is an integer, currently **2**. It is raised on **any** change to the layout
//! or meaning of the items of this crate (a field added, removed, reordered or retyped; a
//! function signature; a status code; a tensor layout; the error-buffer size). The entry
//! symbol's name and the first two fields of the descriptor (`abi_version: u32`,
//! `descriptor_size: u32`) are **frozen across all versions**, so that any host can read a
//! library's version before trusting the rest. A host loads a library whose `abi_version` is
//! [`ABI_VERSION`] and whose `descriptor_size` is [`DESCRIPTOR_SIZE`]; it may also load an older
//! version it keeps a frozen definition of (module [`v1`], whose items never change), with that
//! version's size; it refuses anything else and asks for a rebuild against the matching
//! `efsi-law-sdk`. Changes that touch nothing in this crate (a new SDK helper, a new shipped law)
//! do not change the ABI version.
//!
//! Version 2 (this one) added the full tensor: the descriptor's last field `evaluate_full`
//! (version 1's `evaluate`, now `evaluate_in_plane`, keeps its offset and meaning). A version-1
//! library therefore carries in-plane tensors only: efsi loads and runs it in planar and
//! axisymmetric scenes as before and refuses it in a 3-D scene, naming the version.
//!
//! This crate has no dependencies and only `#[repr(C)]` types, constants and small safe helpers.

use std::ffi::{c_char, c_void};

/// The ABI version this crate describes (see the version policy in the crate docs).
pub const ABI_VERSION: u32 = 2;

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

/// Stored components of a symmetric tensor: `[t11, t22, t33, t12, t23, t13]` (identical to
/// `efsi_laws_host::Sym6`).
pub type Sym6 = [f64; 6];

/// Tangent `∂τ_a/∂B̃_b`, row-major over the [`Sym6`] components, shear counted once (identical
/// to `efsi_laws_host::Tangent6`).
pub type Tangent6 = [f64; 36];

/// Stored components of an in-plane symmetric tensor (13 = 23 = 0): `[t11, t22, t33, t12]`
/// (identical to `efsi_laws_host::Sym`).
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

/// Evaluates the law on a batch of `n_cells` cells (cell-major, see the crate docs), with `m`
/// components per tensor: `m = 6` for [`LawDescriptor::evaluate_full`], `m = 4` for
/// [`LawDescriptor::evaluate_in_plane`].
///
/// * `b` — `m n_cells` values of `B̃`;
/// * `tau` — `m n_cells` values to write `τ(B̃)` into;
/// * `tangent` — `m² n_cells` values to write `∂τ/∂B̃` into, or null when the tangent is not
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
/// Layout (64-bit targets): `abi_version` at 0, `descriptor_size` at 4, then nine
/// pointer-sized fields — 80 bytes in all. The first two fields are frozen across ABI versions;
/// the first ten are version 1's ([`v1::LawDescriptor`]), with `evaluate` renamed
/// `evaluate_in_plane`.
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
    /// Evaluates a batch of in-plane tensors, 4 components each (required).
    pub evaluate_in_plane: Option<EvaluateFn>,
    /// Evaluates a batch of full symmetric tensors, 6 components each (required).
    pub evaluate_full: Option<EvaluateFn>,
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

/// The frozen definition of ABI version 1, which a host needs to read a version-1 library.
///
/// Version 1 carried in-plane tensors only: one evaluate function on `[t11, t22, t33, t12]`
/// with a 4×4 tangent, the layout of today's `evaluate_in_plane`. The items it shares with
/// version 2 ([`ParamDesc`], [`ErrBuf`], [`CreateFn`], [`DestroyFn`], [`EvaluateFn`], the
/// status codes) are unchanged; if a later version changes one of them, its version-1 form is
/// copied here. Nothing in this module ever changes.
pub mod v1 {
    use super::{CreateFn, DestroyFn, EvaluateFn, ParamDesc};
    use std::ffi::c_char;

    /// Version 1's number.
    pub const ABI_VERSION: u32 = 1;

    /// The type of a version-1 library's entry symbol (the same name, [`super::ENTRY_SYMBOL`]).
    pub type EntryFn = unsafe extern "C" fn() -> *const LawDescriptor;

    /// A version-1 descriptor. Layout (64-bit targets): `abi_version` at 0, `descriptor_size`
    /// at 4, then eight pointer-sized fields — 72 bytes in all.
    #[repr(C)]
    #[derive(Clone, Copy, Debug)]
    pub struct LawDescriptor {
        /// `1`.
        pub abi_version: u32,
        /// `size_of::<LawDescriptor>()` as the library sees it (a layout guard).
        pub descriptor_size: u32,
        /// The law's name (NUL-terminated UTF-8, non-null).
        pub name: *const c_char,
        /// One-line description of the law (NUL-terminated UTF-8, non-null).
        pub description: *const c_char,
        /// Number of entries of `params`.
        pub param_count: usize,
        /// The parameter table (may be null when `param_count == 0`).
        pub params: *const ParamDesc,
        /// `size_of::<ParamDesc>()` as the library sees it (a layout guard).
        pub param_desc_size: usize,
        /// Builds an instance (required).
        pub create: Option<CreateFn>,
        /// Frees an instance (required).
        pub destroy: Option<DestroyFn>,
        /// Evaluates a batch of in-plane tensors, 4 components each (required).
        pub evaluate: Option<EvaluateFn>,
    }

    // SAFETY: as for the current descriptor: immutable, pointing to immutable data.
    unsafe impl Send for LawDescriptor {}
    // SAFETY: as above.
    unsafe impl Sync for LawDescriptor {}

    /// `size_of::<LawDescriptor>()` of version 1 as a `u32`.
    pub const DESCRIPTOR_SIZE: u32 = std::mem::size_of::<LawDescriptor>() as u32;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_stable_on_64_bit() {
        if cfg!(target_pointer_width = "64") {
            assert_eq!(std::mem::size_of::<LawDescriptor>(), 80);
            assert_eq!(std::mem::size_of::<ParamDesc>(), 56);
            assert_eq!(std::mem::offset_of!(LawDescriptor, descriptor_size), 4);
            assert_eq!(std::mem::offset_of!(LawDescriptor, name), 8);
            assert_eq!(std::mem::offset_of!(LawDescriptor, evaluate_in_plane), 64);
            assert_eq!(std::mem::offset_of!(LawDescriptor, evaluate_full), 72);
            // Version 1 is frozen, and a prefix of version 2.
            assert_eq!(std::mem::size_of::<v1::LawDescriptor>(), 72);
            assert_eq!(std::mem::offset_of!(v1::LawDescriptor, evaluate), 64);
            assert_eq!(v1::DESCRIPTOR_SIZE, 72);
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
