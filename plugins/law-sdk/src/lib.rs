//! # efsi-law-sdk — write an efsi constitutive law in safe Rust
//!
//! A law gives the elastic stress `τ(B̃)` of the modified left Cauchy–Green tensor `B̃` and its
//! tangent `J = ∂τ/∂B̃` (seed Eqs. 7, 14, 16). To make one:
//!
//! 1. implement [`HyperelasticLaw`] for a struct holding the law's constants: a name, the
//!    declared parameters ([`ParamDecl`]: name, unit, description, default, allowed range),
//!    a constructor from the parameter values, and per-cell `stress` and `tangent`;
//! 2. call [`export_law!`] with the type, in a crate built as a `cdylib`.
//!
//! The SDK supplies the rest: the C-ABI entry point (`efsi_law_descriptor`, see
//! [`efsi_law_abi`]), the loop over a batch of cells, parameter count and range checks, a check
//! that every output is finite (naming the first bad cell), and `catch_unwind` around every entry
//! point so a panic in the law comes back to efsi as an error with its message instead of
//! aborting the host. The loader in `efsi-core` then checks the tangent against finite differences
//! of the stress before it accepts the law.
//!
//! ```
//! use efsi_law_sdk::{HyperelasticLaw, ParamDecl, Sym, Tangent, export_law, tensor};
//!
//! /// τ = G B̃.
//! pub struct NeoHookean { g: f64 }
//!
//! impl HyperelasticLaw for NeoHookean {
//!     const NAME: &'static str = "my_neo_hookean";
//!     const DESCRIPTION: &'static str = "neo-Hookean, τ = G B̃";
//!     fn parameters() -> &'static [ParamDecl] {
//!         const P: &[ParamDecl] =
//!             &[ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0)];
//!         P
//!     }
//!     fn new(values: &[f64]) -> Result<Self, String> {
//!         Ok(NeoHookean { g: values[0] })
//!     }
//!     fn stress(&self, b: &Sym) -> Sym {
//!         b.map(|x| self.g * x)
//!     }
//!     fn tangent(&self, _b: &Sym) -> Tangent {
//!         tensor::scaled_identity(self.g)
//!     }
//! }
//!
//! export_law!(NeoHookean);
//! ```
//!
//! # Tensor layout
//!
//! [`Sym`] `= [t11, t22, t33, t12]` (in-plane tensors, 3 out of plane) and [`Tangent`] is
//! row-major `J[4a + b] = ∂τ_a/∂B̃_b` in that 4-component representation, the shear component
//! counted **once** (`Δτ = J·ΔB̃` for symmetric increments). The [`tensor`] module has the trace,
//! the square `B̃·B̃` and their derivatives in this representation. [`testing`] has random
//! deformed states and a finite-difference tangent for a law's unit tests.

use std::ffi::{CString, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

pub use efsi_law_abi as abi;
pub use efsi_law_abi::{ABI_VERSION, Sym, Tangent};

use efsi_law_abi::{
    ErrBuf, LawDescriptor, PARAM_MAX_EXCLUSIVE, PARAM_MIN_EXCLUSIVE, ParamDesc, STATUS_ERROR,
    STATUS_INVALID_ARGUMENT, STATUS_NON_FINITE, STATUS_OK, STATUS_PANIC,
};

/// A declared parameter: name, unit, one-line description, default and allowed range.
///
/// Build it with [`ParamDecl::new`] (unbounded range) and narrow the range with
/// [`greater_than`](ParamDecl::greater_than), [`at_least`](ParamDecl::at_least),
/// [`less_than`](ParamDecl::less_than), [`at_most`](ParamDecl::at_most); all are `const`, so a
/// parameter table can be a `const` slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamDecl {
    /// Name used in scenes (`parameters: {"G": 1e5}`).
    pub name: &'static str,
    /// Unit, e.g. `Pa`; empty for a dimensionless parameter.
    pub unit: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// The value used when the scene gives none.
    pub default: f64,
    /// Lower bound (`-∞` when unbounded).
    pub min: f64,
    /// Upper bound (`+∞` when unbounded).
    pub max: f64,
    /// Whether `min` itself is excluded.
    pub min_exclusive: bool,
    /// Whether `max` itself is excluded.
    pub max_exclusive: bool,
}

impl ParamDecl {
    /// A parameter with an unbounded range `(-∞, ∞)`.
    pub const fn new(
        name: &'static str,
        unit: &'static str,
        description: &'static str,
        default: f64,
    ) -> Self {
        ParamDecl {
            name,
            unit,
            description,
            default,
            min: f64::NEG_INFINITY,
            max: f64::INFINITY,
            min_exclusive: false,
            max_exclusive: false,
        }
    }

    /// Requires `value > min`.
    pub const fn greater_than(mut self, min: f64) -> Self {
        self.min = min;
        self.min_exclusive = true;
        self
    }

    /// Requires `value ≥ min`.
    pub const fn at_least(mut self, min: f64) -> Self {
        self.min = min;
        self.min_exclusive = false;
        self
    }

    /// Requires `value < max`.
    pub const fn less_than(mut self, max: f64) -> Self {
        self.max = max;
        self.max_exclusive = true;
        self
    }

    /// Requires `value ≤ max`.
    pub const fn at_most(mut self, max: f64) -> Self {
        self.max = max;
        self.max_exclusive = false;
        self
    }

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
}

/// A hyperelastic law written in safe Rust; [`export_law!`] turns it into a loadable plugin.
///
/// Implementations must be thread-safe (`Send + Sync`): efsi may evaluate one instance from
/// several threads at once. `stress` and `tangent` see one cell's `B̃`; the SDK loops over the
/// batch, checks that the outputs are finite and catches panics.
pub trait HyperelasticLaw: Sized + Send + Sync + 'static {
    /// The law's name as shown by `efsi laws` and in error messages (letters, digits, `_`).
    const NAME: &'static str;
    /// One line describing the law, e.g. its formula and reference.
    const DESCRIPTION: &'static str;

    /// The declared parameters, in the order [`new`](HyperelasticLaw::new) receives them.
    fn parameters() -> &'static [ParamDecl];

    /// Builds the law from one value per declared parameter (in declaration order). Each value
    /// is finite and within its declared range when this is called; check combinations here and
    /// return a message naming the parameters when they do not fit together.
    fn new(values: &[f64]) -> Result<Self, String>;

    /// `τ(B̃)`.
    fn stress(&self, b: &Sym) -> Sym;

    /// `∂τ/∂B̃ (B̃)`, row-major, shear counted once (see the crate docs).
    fn tangent(&self, b: &Sym) -> Tangent;

    /// Both at once; override when they share work. Defaults to `stress` then `tangent`.
    fn stress_and_tangent(&self, b: &Sym) -> (Sym, Tangent) {
        (self.stress(b), self.tangent(b))
    }
}

/// Checks `values` against `L`'s parameter table (count, finiteness, ranges) and builds the law.
pub fn create_law<L: HyperelasticLaw>(values: &[f64]) -> Result<L, String> {
    let decls = L::parameters();
    if values.len() != decls.len() {
        return Err(format!(
            "expected {} parameter values ({}), got {}",
            decls.len(),
            decls.iter().map(|p| p.name).collect::<Vec<_>>().join(", "),
            values.len()
        ));
    }
    for (p, &v) in decls.iter().zip(values) {
        if !p.contains(v) {
            return Err(format!(
                "parameter `{}` = {v} {} is outside its allowed range {} {}",
                p.name,
                p.unit,
                p.range_text(),
                p.unit
            ));
        }
    }
    L::new(values)
}

/// The default parameter values of `L`, in declaration order.
pub fn defaults<L: HyperelasticLaw>() -> Vec<f64> {
    L::parameters().iter().map(|p| p.default).collect()
}

/// Evaluates `law` over a batch (what the exported `evaluate` does, minus `catch_unwind`).
///
/// Slices must have equal lengths. Returns an ABI status and message on failure: a non-finite
/// output is [`STATUS_NON_FINITE`] naming the first bad cell.
pub fn evaluate_batch<L: HyperelasticLaw>(
    law: &L,
    b: &[Sym],
    tau: &mut [Sym],
    tangent: Option<&mut [Tangent]>,
) -> Result<(), (i32, String)> {
    if tau.len() != b.len() || tangent.as_ref().is_some_and(|j| j.len() != b.len()) {
        return Err((
            STATUS_INVALID_ARGUMENT,
            "batch slices of different lengths".to_string(),
        ));
    }
    let non_finite = |k: usize, what: &str, b: &Sym| {
        (
            STATUS_NON_FINITE,
            format!("non-finite {what} at cell {k} (B̃ = {b:?})"),
        )
    };
    match tangent {
        None => {
            for (k, (t, b)) in tau.iter_mut().zip(b).enumerate() {
                *t = law.stress(b);
                if !t.iter().all(|x| x.is_finite()) {
                    return Err(non_finite(k, "stress", b));
                }
            }
        }
        Some(j) => {
            for (k, ((t, j), b)) in tau.iter_mut().zip(j.iter_mut()).zip(b).enumerate() {
                (*t, *j) = law.stress_and_tangent(b);
                if !t.iter().all(|x| x.is_finite()) {
                    return Err(non_finite(k, "stress", b));
                }
                if !j.iter().all(|x| x.is_finite()) {
                    return Err(non_finite(k, "tangent", b));
                }
            }
        }
    }
    Ok(())
}

/// Tensor helpers in the 4-component representation `[t11, t22, t33, t12]`.
pub mod tensor {
    use super::{Sym, Tangent};

    /// The identity tensor.
    pub const IDENTITY: Sym = [1.0, 1.0, 1.0, 0.0];

    /// `∂tr(B)/∂B` in the 4-component representation: `[1, 1, 1, 0]` (shear counted once).
    pub const D_TRACE: Sym = [1.0, 1.0, 1.0, 0.0];

    /// `tr(B) = b11 + b22 + b33`.
    pub fn trace(b: &Sym) -> f64 {
        b[0] + b[1] + b[2]
    }

    /// `B·B`: `[b11² + b12², b22² + b12², b33², b12 (b11 + b22)]`.
    pub fn square(b: &Sym) -> Sym {
        let [b11, b22, b33, b12] = *b;
        [
            b11 * b11 + b12 * b12,
            b22 * b22 + b12 * b12,
            b33 * b33,
            b12 * (b11 + b22),
        ]
    }

    /// `∂(B·B)_a/∂B_b`, row-major, shear counted once.
    pub fn square_tangent(b: &Sym) -> Tangent {
        let [b11, b22, b33, b12] = *b;
        #[rustfmt::skip]
        let j = [
            2.0 * b11, 0.0,       0.0,       2.0 * b12,
            0.0,       2.0 * b22, 0.0,       2.0 * b12,
            0.0,       0.0,       2.0 * b33, 0.0,
            b12,       b12,       0.0,       b11 + b22,
        ];
        j
    }

    /// `s I` in tangent form (`J[4a + b] = s δ_ab`).
    pub fn scaled_identity(s: f64) -> Tangent {
        let mut j = [0.0; 16];
        for a in 0..4 {
            j[5 * a] = s;
        }
        j
    }

    /// The outer product `u ⊗ v` in tangent form (`J[4a + b] = u_a v_b`).
    pub fn outer(u: &Sym, v: &Sym) -> Tangent {
        let mut j = [0.0; 16];
        for a in 0..4 {
            for c in 0..4 {
                j[4 * a + c] = u[a] * v[c];
            }
        }
        j
    }
}

/// Helpers for a law's unit tests: random deformed states and a finite-difference tangent.
pub mod testing {
    use super::{HyperelasticLaw, Sym, Tangent};

    /// A small xorshift64* generator (seeded, reproducible; not for cryptography).
    #[derive(Clone, Debug)]
    pub struct XorShift(u64);

    impl XorShift {
        /// A generator from a seed (0 is replaced by a fixed non-zero seed).
        pub fn new(seed: u64) -> Self {
            XorShift(if seed == 0 {
                0x9E37_79B9_7F4A_7C15
            } else {
                seed
            })
        }

        /// The next value uniform in `[0, 1)`.
        pub fn uniform(&mut self) -> f64 {
            let mut x = self.0;
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            self.0 = x;
            (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }

        /// The next value uniform in `[-1, 1)`.
        pub fn symmetric(&mut self) -> f64 {
            2.0 * self.uniform() - 1.0
        }
    }

    /// `n` deformed states `B̃ = φ^{1/2} F Fᵀ`: `F` = identity plus in-plane entries uniform in
    /// `±amplitude` and `F33 = 1 ± amplitude`, `φ` cycling through `1, 0.6, 0.25, 0.05`.
    pub fn deformed_states(n: usize, amplitude: f64, seed: u64) -> Vec<Sym> {
        let mut rng = XorShift::new(seed);
        let phis = [1.0, 0.6, 0.25, 0.05_f64];
        (0..n)
            .map(|k| {
                let f11 = 1.0 + amplitude * rng.symmetric();
                let f12 = amplitude * rng.symmetric();
                let f21 = amplitude * rng.symmetric();
                let f22 = 1.0 + amplitude * rng.symmetric();
                let f33 = 1.0 + amplitude * rng.symmetric();
                let s = phis[k % phis.len()].sqrt();
                [
                    s * (f11 * f11 + f12 * f12),
                    s * (f21 * f21 + f22 * f22),
                    s * f33 * f33,
                    s * (f11 * f21 + f12 * f22),
                ]
            })
            .collect()
    }

    /// Central finite differences of `law.stress` at `b`, step `1e-6 · max(1, max|b|)`.
    pub fn fd_tangent<L: HyperelasticLaw>(law: &L, b: &Sym) -> Tangent {
        let h = 1e-6 * b.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        let mut j = [0.0; 16];
        for c in 0..4 {
            let (mut bp, mut bm) = (*b, *b);
            bp[c] += h;
            bm[c] -= h;
            let (tp, tm) = (law.stress(&bp), law.stress(&bm));
            for a in 0..4 {
                j[4 * a + c] = (tp[a] - tm[a]) / (2.0 * h);
            }
        }
        j
    }

    /// `max|J − J_fd| / max(max|J|, max|J_fd|)` at `b` (0 when both vanish).
    pub fn tangent_error<L: HyperelasticLaw>(law: &L, b: &Sym) -> f64 {
        let (j, fd) = (law.tangent(b), fd_tangent(law, b));
        let err = j
            .iter()
            .zip(&fd)
            .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
        let scale = j.iter().chain(&fd).fold(0.0_f64, |m, x| m.max(x.abs()));
        if scale == 0.0 { err } else { err / scale }
    }
}

/// Writes `text` into a caller's error buffer when it is not null.
///
/// # Safety
/// `err` is null or points to a writable [`ErrBuf`].
unsafe fn report(err: *mut ErrBuf, text: &str) {
    if !err.is_null() {
        // SAFETY: non-null and writable by the caller's contract.
        unsafe { (*err).set(text) }
    }
}

/// The message of a caught panic payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-text payload".to_string()
    }
}

/// Support for [`export_law!`]; not a stable API.
#[doc(hidden)]
pub mod __private {
    use super::*;
    use std::sync::OnceLock;

    /// The descriptor of one law and the storage its pointers point into.
    struct Built {
        descriptor: LawDescriptor,
        _strings: Vec<CString>,
        _params: Vec<ParamDesc>,
    }

    /// A lazily built descriptor, held in a `static` by the generated entry point.
    pub struct DescriptorCell(OnceLock<Built>);

    impl DescriptorCell {
        /// An empty cell.
        #[allow(clippy::new_without_default)]
        pub const fn new() -> Self {
            DescriptorCell(OnceLock::new())
        }
    }

    fn c_string(s: &str) -> CString {
        CString::new(s.replace('\0', " ")).expect("NULs were replaced")
    }

    fn build<L: HyperelasticLaw>() -> Built {
        let mut strings = Vec::new();
        let mut keep = |s: &str| {
            let c = c_string(s);
            let p = c.as_ptr();
            strings.push(c);
            p
        };
        let name = keep(L::NAME);
        let description = keep(L::DESCRIPTION);
        let params: Vec<ParamDesc> = L::parameters()
            .iter()
            .map(|p| ParamDesc {
                name: keep(p.name),
                unit: keep(p.unit),
                description: keep(p.description),
                default: p.default,
                min: p.min,
                max: p.max,
                flags: if p.min_exclusive {
                    PARAM_MIN_EXCLUSIVE
                } else {
                    0
                } | if p.max_exclusive {
                    PARAM_MAX_EXCLUSIVE
                } else {
                    0
                },
            })
            .collect();
        let descriptor = LawDescriptor {
            abi_version: efsi_law_abi::ABI_VERSION,
            descriptor_size: efsi_law_abi::DESCRIPTOR_SIZE,
            name,
            description,
            param_count: params.len(),
            params: params.as_ptr(),
            param_desc_size: std::mem::size_of::<ParamDesc>(),
            create: Some(create::<L>),
            destroy: Some(destroy::<L>),
            evaluate: Some(evaluate::<L>),
        };
        Built {
            descriptor,
            _strings: strings,
            _params: params,
        }
    }

    /// The descriptor of `L`, built on first use; null if building it panicked.
    pub fn descriptor<L: HyperelasticLaw>(cell: &'static DescriptorCell) -> *const LawDescriptor {
        catch_unwind(|| &cell.0.get_or_init(build::<L>).descriptor as *const LawDescriptor)
            .unwrap_or(std::ptr::null())
    }

    /// The ABI `create` of `L`.
    ///
    /// # Safety
    /// `params` points to `n` readable values (or `n == 0`); `err` is null or writable.
    pub unsafe extern "C" fn create<L: HyperelasticLaw>(
        params: *const f64,
        n: usize,
        err: *mut ErrBuf,
    ) -> *mut c_void {
        let outcome = catch_unwind(|| {
            let values: &[f64] = if n == 0 {
                &[]
            } else if params.is_null() {
                return Err("null parameter array".to_string());
            } else {
                // SAFETY: `n` readable values by the caller's contract.
                unsafe { std::slice::from_raw_parts(params, n) }
            };
            create_law::<L>(values).map(|law| Box::into_raw(Box::new(law)).cast::<c_void>())
        });
        match outcome {
            Ok(Ok(handle)) => handle,
            Ok(Err(message)) => {
                // SAFETY: `err` is null or writable by the caller's contract.
                unsafe { report(err, &message) };
                std::ptr::null_mut()
            }
            Err(payload) => {
                let message = format!("panicked: {}", panic_message(&*payload));
                // SAFETY: as above.
                unsafe { report(err, &message) };
                std::ptr::null_mut()
            }
        }
    }

    /// The ABI `destroy` of `L`.
    ///
    /// # Safety
    /// `handle` came from [`create`] of the same `L` and is not used again.
    pub unsafe extern "C" fn destroy<L: HyperelasticLaw>(handle: *mut c_void) {
        if handle.is_null() {
            return;
        }
        // A panic in `L::drop` is swallowed: there is nowhere to report it.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: `handle` is a `Box<L>` from `create`, by the caller's contract.
            drop(unsafe { Box::from_raw(handle.cast::<L>()) });
        }));
    }

    /// The ABI `evaluate` of `L`.
    ///
    /// # Safety
    /// `handle` came from [`create`] of the same `L`; `b` has `4 n` readable values, `tau`
    /// `4 n` writable ones, `tangent` is null or has `16 n` writable ones, none overlapping;
    /// `err` is null or writable.
    pub unsafe extern "C" fn evaluate<L: HyperelasticLaw>(
        handle: *const c_void,
        n_cells: usize,
        b: *const f64,
        tau: *mut f64,
        tangent: *mut f64,
        err: *mut ErrBuf,
    ) -> i32 {
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            if n_cells == 0 {
                return Ok(());
            }
            if handle.is_null() || b.is_null() || tau.is_null() {
                return Err((
                    STATUS_INVALID_ARGUMENT,
                    "null handle, B̃ or τ pointer".to_string(),
                ));
            }
            // SAFETY: the pointers satisfy the caller's contract above; `Sym`/`Tangent` are
            // arrays of f64 with f64's alignment, laid out cell-major.
            let (law, b, tau, tangent) = unsafe {
                (
                    &*handle.cast::<L>(),
                    std::slice::from_raw_parts(b.cast::<Sym>(), n_cells),
                    std::slice::from_raw_parts_mut(tau.cast::<Sym>(), n_cells),
                    (!tangent.is_null()).then(|| {
                        std::slice::from_raw_parts_mut(tangent.cast::<Tangent>(), n_cells)
                    }),
                )
            };
            evaluate_batch(law, b, tau, tangent)
        }));
        let (status, message) = match outcome {
            Ok(Ok(())) => return STATUS_OK,
            Ok(Err(e)) => e,
            Err(payload) => (STATUS_PANIC, panic_message(&*payload)),
        };
        // SAFETY: `err` is null or writable by the caller's contract.
        unsafe { report(err, &message) };
        if status == STATUS_OK {
            STATUS_ERROR
        } else {
            status
        }
    }
}

/// Exports a [`HyperelasticLaw`] as an efsi law library: generates the C entry point
/// `efsi_law_descriptor` (see [`efsi_law_abi`]). Use it once per `cdylib` crate:
///
/// ```ignore
/// efsi_law_sdk::export_law!(MyLaw);
/// ```
#[macro_export]
macro_rules! export_law {
    ($law:ty) => {
        /// Entry point of this efsi law library: its descriptor (generated by
        /// `efsi_law_sdk::export_law!`).
        #[unsafe(no_mangle)]
        pub extern "C" fn efsi_law_descriptor() -> *const $crate::abi::LawDescriptor {
            static CELL: $crate::__private::DescriptorCell =
                $crate::__private::DescriptorCell::new();
            $crate::__private::descriptor::<$law>(&CELL)
        }

        const _: $crate::abi::EntryFn = efsi_law_descriptor;
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Quadratic {
        k: f64,
    }

    impl HyperelasticLaw for Quadratic {
        const NAME: &'static str = "quadratic";
        const DESCRIPTION: &'static str = "τ = k B·B (a test law)";
        fn parameters() -> &'static [ParamDecl] {
            const P: &[ParamDecl] = &[ParamDecl::new("k", "Pa", "modulus", 2.0).greater_than(0.0)];
            P
        }
        fn new(values: &[f64]) -> Result<Self, String> {
            if values[0] > 100.0 {
                panic!("k too large for this test");
            }
            Ok(Quadratic { k: values[0] })
        }
        fn stress(&self, b: &Sym) -> Sym {
            if b[0] > 50.0 {
                panic!("b11 = {} is too large", b[0]);
            }
            tensor::square(b).map(|x| self.k * x)
        }
        fn tangent(&self, b: &Sym) -> Tangent {
            tensor::square_tangent(b).map(|x| self.k * x)
        }
    }

    export_law!(Quadratic);

    #[test]
    fn square_tangent_matches_finite_differences() {
        let law = Quadratic { k: 3.0 };
        for b in testing::deformed_states(50, 0.4, 7) {
            assert!(testing::tangent_error(&law, &b) < 1e-8);
        }
    }

    #[test]
    fn range_text_and_contains() {
        let p = ParamDecl::new("G", "Pa", "", 1.0).greater_than(0.0);
        assert_eq!(p.range_text(), "(0, ∞)");
        assert!(p.contains(1.0) && !p.contains(0.0) && !p.contains(f64::NAN));
        let q = ParamDecl::new("x", "", "", 0.5)
            .at_least(0.0)
            .less_than(1.0);
        assert_eq!(q.range_text(), "[0, 1)");
        assert!(q.contains(0.0) && !q.contains(1.0));
    }

    #[test]
    fn entry_points_round_trip_and_catch_panics() {
        let d = unsafe { &*efsi_law_descriptor() };
        assert_eq!(d.abi_version, ABI_VERSION);
        assert_eq!(d.descriptor_size, efsi_law_abi::DESCRIPTOR_SIZE);
        assert_eq!(d.param_count, 1);
        let (create, destroy, evaluate) =
            (d.create.unwrap(), d.destroy.unwrap(), d.evaluate.unwrap());
        let mut err = ErrBuf::new();

        // Out of range, wrong count, panic in `new`.
        let h = unsafe { create([-1.0].as_ptr(), 1, &mut err) };
        assert!(h.is_null());
        assert!(err.text().contains("`k` = -1"), "{}", err.text());
        let h = unsafe { create([1.0, 2.0].as_ptr(), 2, &mut err) };
        assert!(h.is_null() && err.text().contains("expected 1"));
        let h = unsafe { create([1000.0].as_ptr(), 1, &mut err) };
        assert!(
            h.is_null() && err.text().contains("k too large"),
            "{}",
            err.text()
        );

        let h = unsafe { create([2.0].as_ptr(), 1, &mut err) };
        assert!(!h.is_null());
        let b = [[1.0, 2.0, 3.0, 0.5], [60.0, 1.0, 1.0, 0.0]];
        let mut tau = [[0.0; 4]; 2];
        let mut j = [[0.0; 16]; 2];
        let s = unsafe {
            evaluate(
                h,
                1,
                b.as_ptr().cast(),
                tau.as_mut_ptr().cast(),
                j.as_mut_ptr().cast(),
                &mut err,
            )
        };
        assert_eq!(s, STATUS_OK);
        assert_eq!(tau[0], tensor::square(&b[0]).map(|x| 2.0 * x));
        let s = unsafe {
            evaluate(
                h,
                2,
                b.as_ptr().cast(),
                tau.as_mut_ptr().cast(),
                std::ptr::null_mut(),
                &mut err,
            )
        };
        assert_eq!(s, STATUS_PANIC);
        assert!(
            err.text().contains("b11 = 60 is too large"),
            "{}",
            err.text()
        );

        let nan = [[f64::NAN, 1.0, 1.0, 0.0]];
        let s = unsafe {
            evaluate(
                h,
                1,
                nan.as_ptr().cast(),
                tau.as_mut_ptr().cast(),
                std::ptr::null_mut(),
                &mut err,
            )
        };
        assert_eq!(s, STATUS_NON_FINITE);
        assert!(err.text().contains("cell 0"), "{}", err.text());
        unsafe { destroy(h) };
    }
}
