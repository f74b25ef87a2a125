//! # Test-only law library of ABI version 1
//!
//! A Mooney–Rivlin law (seed Eq. 7, `τ = 2C1 B̃ + 2C2 [tr(B̃) B̃ − B̃·B̃] + 4C3 [tr(B̃) − 3] B̃`)
//! built the way every law was before ABI version 2: against the version-1 interface — one
//! `evaluate` on in-plane tensors `[b11, b22, b33, b12]` with a 4×4 tangent, a 72-byte
//! descriptor — with the arithmetic of version 1's SDK and shipped `mooney_rivlin` law. The
//! interface is a **frozen copy** inside this crate (no dependency on `efsi-law-abi`), so the
//! library stays a version-1 library whatever the current ABI becomes.
//!
//! The loader's tests check that it loads and runs in planar and axisymmetric scenes exactly as
//! before (its numbers equal the version-2 `mooney_rivlin` law's in-plane ones, bit for bit),
//! that a 3-D scene refuses it naming the version, and that its in-plane numbers equal the
//! version-2 law's full evaluation of the same `B̃` embedded in six components.
//!
//! Built as `libefsi_test_law_v1.so`; loaded by path only.

use std::ffi::{CStr, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// The frozen version-1 interface (`efsi-law-abi` 0.1.0 with `ABI_VERSION = 1`).
pub mod abi_v1 {
    use std::ffi::{c_char, c_void};

    /// ABI version 1.
    pub const ABI_VERSION: u32 = 1;
    /// Capacity of an error buffer, NUL included.
    pub const ERR_BUF_CAPACITY: usize = 1024;
    /// Success.
    pub const STATUS_OK: i32 = 0;
    /// The law panicked.
    pub const STATUS_PANIC: i32 = 2;
    /// A non-finite output.
    pub const STATUS_NON_FINITE: i32 = 3;
    /// A null pointer where data was required.
    pub const STATUS_INVALID_ARGUMENT: i32 = 4;

    /// An error message buffer.
    #[repr(C)]
    pub struct ErrBuf {
        /// NUL-terminated UTF-8.
        pub message: [u8; ERR_BUF_CAPACITY],
    }

    /// One declared parameter.
    #[repr(C)]
    pub struct ParamDesc {
        /// Name.
        pub name: *const c_char,
        /// Unit.
        pub unit: *const c_char,
        /// Description.
        pub description: *const c_char,
        /// Default.
        pub default: f64,
        /// Lower bound.
        pub min: f64,
        /// Upper bound.
        pub max: f64,
        /// Exclusion bits.
        pub flags: u32,
    }

    /// `create`.
    pub type CreateFn =
        unsafe extern "C" fn(params: *const f64, n: usize, err: *mut ErrBuf) -> *mut c_void;
    /// `destroy`.
    pub type DestroyFn = unsafe extern "C" fn(handle: *mut c_void);
    /// `evaluate`: `4 n` values of B̃ and τ, `16 n` of the tangent (or null).
    pub type EvaluateFn = unsafe extern "C" fn(
        handle: *const c_void,
        n_cells: usize,
        b: *const f64,
        tau: *mut f64,
        tangent: *mut f64,
        err: *mut ErrBuf,
    ) -> i32;

    /// The version-1 descriptor (72 bytes on 64-bit targets).
    #[repr(C)]
    pub struct LawDescriptor {
        /// `1`.
        pub abi_version: u32,
        /// `size_of::<LawDescriptor>()`.
        pub descriptor_size: u32,
        /// Name.
        pub name: *const c_char,
        /// Description.
        pub description: *const c_char,
        /// Entries of `params`.
        pub param_count: usize,
        /// Parameter table.
        pub params: *const ParamDesc,
        /// `size_of::<ParamDesc>()`.
        pub param_desc_size: usize,
        /// Builds an instance.
        pub create: Option<CreateFn>,
        /// Frees an instance.
        pub destroy: Option<DestroyFn>,
        /// Evaluates a batch of in-plane tensors.
        pub evaluate: Option<EvaluateFn>,
    }

    // SAFETY: immutable data living as long as the library.
    unsafe impl Send for LawDescriptor {}
    // SAFETY: as above.
    unsafe impl Sync for LawDescriptor {}
    // SAFETY: as above.
    unsafe impl Send for ParamDesc {}
    // SAFETY: as above.
    unsafe impl Sync for ParamDesc {}
}

use abi_v1::{
    ABI_VERSION, ERR_BUF_CAPACITY, ErrBuf, LawDescriptor, ParamDesc, STATUS_INVALID_ARGUMENT,
    STATUS_NON_FINITE, STATUS_OK, STATUS_PANIC,
};

/// In-plane `[t11, t22, t33, t12]`.
type Sym = [f64; 4];
/// Its 4×4 tangent, row-major, shear counted once.
type Tangent = [f64; 16];

/// The law's constants.
#[derive(Clone, Debug, PartialEq)]
pub struct MooneyRivlinV1 {
    /// C1 (Pa).
    pub c1: f64,
    /// C2 (Pa).
    pub c2: f64,
    /// C3 (Pa).
    pub c3: f64,
}

fn trace(b: &Sym) -> f64 {
    b[0] + b[1] + b[2]
}

fn square(b: &Sym) -> Sym {
    let [b11, b22, b33, b12] = *b;
    [
        b11 * b11 + b12 * b12,
        b22 * b22 + b12 * b12,
        b33 * b33,
        b12 * (b11 + b22),
    ]
}

fn square_tangent(b: &Sym) -> Tangent {
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

fn scaled_identity(s: f64) -> Tangent {
    let mut j = [0.0; 16];
    for a in 0..4 {
        j[5 * a] = s;
    }
    j
}

fn outer(u: &Sym, v: &Sym) -> Tangent {
    let mut j = [0.0; 16];
    for a in 0..4 {
        for c in 0..4 {
            j[4 * a + c] = u[a] * v[c];
        }
    }
    j
}

const D_TRACE: Sym = [1.0, 1.0, 1.0, 0.0];

impl MooneyRivlinV1 {
    /// `τ(B̃)`, version 1's arithmetic.
    pub fn stress(&self, b: &Sym) -> Sym {
        let t = trace(b);
        let q = square(b);
        let s = 2.0 * self.c1 + 2.0 * self.c2 * t + 4.0 * self.c3 * (t - 3.0);
        std::array::from_fn(|a| s * b[a] - 2.0 * self.c2 * q[a])
    }

    /// `∂τ/∂B̃`, version 1's arithmetic.
    pub fn tangent(&self, b: &Sym) -> Tangent {
        let t = trace(b);
        let q = square_tangent(b);
        let bt = outer(b, &D_TRACE);
        let diag = 2.0 * self.c1 + 2.0 * self.c2 * t + 4.0 * self.c3 * (t - 3.0);
        let k = 2.0 * self.c2 + 4.0 * self.c3;
        let mut j = scaled_identity(diag);
        for i in 0..16 {
            j[i] += k * bt[i] - 2.0 * self.c2 * q[i];
        }
        j
    }
}

/// Writes `text` into `err` when it is not null.
///
/// # Safety
/// `err` is null or writable.
unsafe fn report(err: *mut ErrBuf, text: &str) {
    if err.is_null() {
        return;
    }
    let mut n = text.len().min(ERR_BUF_CAPACITY - 1);
    while !text.is_char_boundary(n) {
        n -= 1;
    }
    // SAFETY: non-null and writable by the caller's contract.
    let e = unsafe { &mut *err };
    e.message[..n].copy_from_slice(&text.as_bytes()[..n]);
    e.message[n] = 0;
}

unsafe extern "C" fn create(params: *const f64, n: usize, err: *mut ErrBuf) -> *mut c_void {
    let built = catch_unwind(|| {
        if n != 3 || params.is_null() {
            return Err(format!("expected 3 parameter values (C1, C2, C3), got {n}"));
        }
        // SAFETY: `n` readable values by the ABI's contract.
        let v = unsafe { std::slice::from_raw_parts(params, n) };
        if v[0] + v[1] <= 0.0 {
            return Err(format!(
                "the initial shear modulus 2 (C1 + C2) = {} Pa must be positive",
                2.0 * (v[0] + v[1])
            ));
        }
        let law = MooneyRivlinV1 {
            c1: v[0],
            c2: v[1],
            c3: v[2],
        };
        Ok(Box::into_raw(Box::new(law)).cast::<c_void>())
    });
    match built {
        Ok(Ok(h)) => h,
        Ok(Err(m)) => {
            // SAFETY: `err` is null or writable.
            unsafe { report(err, &m) };
            std::ptr::null_mut()
        }
        Err(_) => {
            // SAFETY: as above.
            unsafe { report(err, "panicked in create") };
            std::ptr::null_mut()
        }
    }
}

unsafe extern "C" fn destroy(handle: *mut c_void) {
    if !handle.is_null() {
        // SAFETY: a `Box<MooneyRivlinV1>` from `create`.
        drop(unsafe { Box::from_raw(handle.cast::<MooneyRivlinV1>()) });
    }
}

unsafe extern "C" fn evaluate(
    handle: *const c_void,
    n: usize,
    b: *const f64,
    tau: *mut f64,
    tangent: *mut f64,
    err: *mut ErrBuf,
) -> i32 {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if n == 0 {
            return Ok(());
        }
        if handle.is_null() || b.is_null() || tau.is_null() {
            return Err((STATUS_INVALID_ARGUMENT, "null pointer".to_string()));
        }
        // SAFETY: the ABI's contract: `4 n` values of B̃ and τ, `16 n` of the tangent.
        let (law, b, tau) = unsafe {
            (
                &*handle.cast::<MooneyRivlinV1>(),
                std::slice::from_raw_parts(b.cast::<Sym>(), n),
                std::slice::from_raw_parts_mut(tau.cast::<Sym>(), n),
            )
        };
        let mut j = (!tangent.is_null())
            // SAFETY: as above.
            .then(|| unsafe { std::slice::from_raw_parts_mut(tangent.cast::<Tangent>(), n) });
        for k in 0..n {
            tau[k] = law.stress(&b[k]);
            if !tau[k].iter().all(|x| x.is_finite()) {
                return Err((
                    STATUS_NON_FINITE,
                    format!("non-finite stress at cell {k} (B̃ = {:?})", b[k]),
                ));
            }
            if let Some(j) = j.as_deref_mut() {
                j[k] = law.tangent(&b[k]);
            }
        }
        Ok(())
    }));
    let (status, message) = match outcome {
        Ok(Ok(())) => return STATUS_OK,
        Ok(Err(e)) => e,
        Err(_) => (STATUS_PANIC, "panicked in evaluate".to_string()),
    };
    // SAFETY: `err` is null or writable.
    unsafe { report(err, &message) };
    status
}

const NAME: &CStr = c"test_v1_mooney_rivlin";
const DESCRIPTION: &CStr =
    c"test only: Mooney-Rivlin built against law ABI version 1 (in-plane tensors only)";

/// `(name, unit, description, default, lower bound)` of the three parameters (upper bound
/// `+∞`, bounds included).
const PARAMS: [(&CStr, &CStr, &CStr, f64, f64); 3] = [
    (
        c"C1",
        c"Pa",
        c"coefficient of (I1 - 3)",
        5.0e4,
        f64::NEG_INFINITY,
    ),
    (
        c"C2",
        c"Pa",
        c"coefficient of (I2 - 3)",
        0.0,
        f64::NEG_INFINITY,
    ),
    (c"C3", c"Pa", c"coefficient of (I1 - 3)^2", 0.0, 0.0),
];

/// The parameter table.
struct Table([ParamDesc; 3]);

static TABLE: std::sync::OnceLock<Table> = std::sync::OnceLock::new();
static DESCRIPTOR: std::sync::OnceLock<LawDescriptor> = std::sync::OnceLock::new();

fn c(s: &CStr) -> *const c_char {
    s.as_ptr()
}

/// The entry point of a version-1 library.
#[unsafe(no_mangle)]
pub extern "C" fn efsi_law_descriptor() -> *const LawDescriptor {
    catch_unwind(|| {
        let table = TABLE.get_or_init(|| {
            Table(
                PARAMS.map(|(name, unit, description, default, min)| ParamDesc {
                    name: c(name),
                    unit: c(unit),
                    description: c(description),
                    default,
                    min,
                    max: f64::INFINITY,
                    flags: 0,
                }),
            )
        });
        DESCRIPTOR.get_or_init(|| LawDescriptor {
            abi_version: ABI_VERSION,
            descriptor_size: std::mem::size_of::<LawDescriptor>() as u32,
            name: c(NAME),
            description: c(DESCRIPTION),
            param_count: table.0.len(),
            params: table.0.as_ptr(),
            param_desc_size: std::mem::size_of::<ParamDesc>(),
            create: Some(create),
            destroy: Some(destroy),
            evaluate: Some(evaluate),
        }) as *const LawDescriptor
    })
    .unwrap_or(std::ptr::null())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frozen_layout_is_version_1s() {
        if cfg!(target_pointer_width = "64") {
            assert_eq!(std::mem::size_of::<LawDescriptor>(), 72);
            assert_eq!(std::mem::size_of::<ParamDesc>(), 56);
            assert_eq!(std::mem::offset_of!(LawDescriptor, evaluate), 64);
        }
        // SAFETY: the descriptor is static.
        let d = unsafe { &*efsi_law_descriptor() };
        assert_eq!(d.abi_version, 1);
        assert_eq!(d.param_count, 3);
    }

    #[test]
    fn stress_is_mooney_rivlin() {
        let law = MooneyRivlinV1 {
            c1: 1.0,
            c2: 0.5,
            c3: 0.25,
        };
        let b = [1.2, 0.9, 1.1, 0.3];
        let (t, sq) = (trace(&b), square(&b));
        let want: Sym = std::array::from_fn(|a| 2.0 * b[a] + (t * b[a] - sq[a]) + (t - 3.0) * b[a]);
        let got = law.stress(&b);
        for a in 0..4 {
            assert!((got[a] - want[a]).abs() < 1e-14, "{got:?} vs {want:?}");
        }
    }
}
