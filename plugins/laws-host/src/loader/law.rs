//! [`LoadedLaw`], the safe wrapper of a law instance in a plugin library: it owns the library and
//! the instance, evaluates batches through the plugin (in-plane, or full for a version-2
//! library) and turns a failed status, a panic in the plugin or a non-finite output into a
//! [`LawError`].

use super::LawInfo;
use super::tangent::TangentCheck;
use crate::{ConstitutiveLaw, LawError, Sym, Sym6, Tangent, Tangent6};
use efsi_law_abi::{
    CRATE_VERSION, DestroyFn, ErrBuf, EvaluateFn, STATUS_ERROR, STATUS_INVALID_ARGUMENT,
    STATUS_NON_FINITE, STATUS_OK, STATUS_PANIC,
};
use libloading::Library;
use std::ffi::c_void;
use std::fmt;
use std::ptr::NonNull;

/// A law loaded from a plugin library: a [`ConstitutiveLaw`] holding the library and one
/// instance of the law (destroyed on drop, before the library is closed).
pub struct LoadedLaw {
    pub(super) info: LawInfo,
    pub(super) values: Vec<f64>,
    pub(super) handle: NonNull<c_void>,
    pub(super) evaluate_in_plane: EvaluateFn,
    /// `None` for a version-1 library (in-plane tensors only).
    pub(super) evaluate_full: Option<EvaluateFn>,
    pub(super) destroy_fn: DestroyFn,
    pub(super) check: Option<TangentCheck>,
    pub(super) check_full: Option<TangentCheck>,
    // Declared last: dropped after `Drop::drop` destroyed the handle.
    pub(super) _library: Library,
}

// SAFETY: the ABI requires `evaluate` to be callable concurrently on one handle and
// `create`/`destroy` from any thread (the SDK enforces `Send + Sync` on the law type).
unsafe impl Send for LoadedLaw {}
// SAFETY: as above.
unsafe impl Sync for LoadedLaw {}

impl fmt::Debug for LoadedLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LoadedLaw")
            .field("info", &self.info)
            .field("values", &self.values)
            .finish_non_exhaustive()
    }
}

impl LoadedLaw {
    /// What the library says about the law.
    pub fn info(&self) -> &LawInfo {
        &self.info
    }

    /// The parameter values in use (scene values, or defaults), by name, in declaration order.
    pub fn parameter_values(&self) -> Vec<(String, f64)> {
        self.info
            .parameters
            .iter()
            .map(|p| p.name.clone())
            .zip(self.values.iter().copied())
            .collect()
    }

    /// The load-time tangent check's result on in-plane tensors.
    pub fn tangent_check(&self) -> &TangentCheck {
        self.check
            .as_ref()
            .expect("a loaded law has passed its tangent check")
    }

    /// The load-time tangent check's result on full 3-D tensors; `None` for a version-1
    /// library, which has no full evaluation.
    pub fn tangent_check_full(&self) -> Option<&TangentCheck> {
        self.check_full.as_ref()
    }

    /// Whether the law evaluates full 3-D tensors (a version-2 library; a version-1 library
    /// carries in-plane tensors only).
    pub fn evaluates_full(&self) -> bool {
        self.evaluate_full.is_some()
    }

    /// The refusal of a version-1 library in a 3-D scene, naming the version.
    pub(super) fn in_plane_only(&self) -> LawError {
        self.error(format!(
            "{} was built for ABI v{}, which carries in-plane tensors only (components 11, 22, 33, 12): it runs in planar and axisymmetric scenes but cannot be evaluated on a 3-D tensor; rebuild it against efsi-law-sdk {CRATE_VERSION} (ABI v{}) to use it in a 3-D scene",
            self.info.path.display(),
            self.info.abi_version,
            efsi_law_abi::ABI_VERSION
        ))
    }

    pub(super) fn error(&self, message: String) -> LawError {
        LawError {
            law: self.info.name.clone(),
            message,
            cell: None,
        }
    }
}

impl Drop for LoadedLaw {
    fn drop(&mut self) {
        // SAFETY: the handle came from this library's `create` and is not used again.
        unsafe { (self.destroy_fn)(self.handle.as_ptr()) }
    }
}

impl ConstitutiveLaw for LoadedLaw {
    fn name(&self) -> &str {
        &self.info.name
    }

    fn evaluate(
        &self,
        b: &[Sym],
        tau: &mut [Sym],
        tangent: Option<&mut [Tangent]>,
    ) -> Result<(), LawError> {
        self.call(self.evaluate_in_plane, b, tau, tangent)
    }

    fn evaluate_full(
        &self,
        b: &[Sym6],
        tau: &mut [Sym6],
        tangent: Option<&mut [Tangent6]>,
    ) -> Result<(), LawError> {
        let Some(f) = self.evaluate_full else {
            return Err(self.in_plane_only());
        };
        self.call(f, b, tau, tangent)
    }
}

impl LoadedLaw {
    /// One plugin call on a batch of `N`-component tensors through `f` (`N = 4` in-plane,
    /// `N = 6` full; `NN = N²`), its status and outputs checked.
    fn call<const N: usize, const NN: usize>(
        &self,
        f: EvaluateFn,
        b: &[[f64; N]],
        tau: &mut [[f64; N]],
        mut tangent: Option<&mut [[f64; NN]]>,
    ) -> Result<(), LawError> {
        let n = b.len();
        if tau.len() != n || tangent.as_ref().is_some_and(|j| j.len() != n) {
            return Err(self.error(format!(
                "evaluate called with {n} B̃, {} τ and {} tangent slots",
                tau.len(),
                tangent.as_ref().map_or(0, |j| j.len())
            )));
        }
        if n == 0 {
            return Ok(());
        }
        let mut err = ErrBuf::new();
        let tangent_ptr = tangent
            .as_deref_mut()
            .map_or(std::ptr::null_mut(), |j| j.as_mut_ptr().cast::<f64>());
        // SAFETY: `b`, `tau` and `tangent` hold `n` cells of N, N and N² contiguous f64
        // (cell-major, as the ABI lays them out for the function `f`, the matching one of the
        // descriptor's two) and do not overlap (distinct borrows); the handle is alive.
        let status = unsafe {
            f(
                self.handle.as_ptr(),
                n,
                b.as_ptr().cast::<f64>(),
                tau.as_mut_ptr().cast::<f64>(),
                tangent_ptr,
                &mut err,
            )
        };
        if status != STATUS_OK {
            let text = err.text();
            if status == STATUS_NON_FINITE {
                // The SDK says "non-finite stress at cell k (…)": keep k as the batch index.
                if let Some(at) = text.find(" at cell ") {
                    let rest = &text[at + 9..];
                    let digits = rest
                        .find(|c: char| !c.is_ascii_digit())
                        .unwrap_or(rest.len());
                    if let Ok(k) = rest[..digits].parse() {
                        let message = format!("{}{}", &text[..at], &rest[digits..]);
                        return Err(LawError {
                            cell: Some(k),
                            ..self.error(message)
                        });
                    }
                }
            }
            return Err(self.error(match status {
                STATUS_ERROR => format!("evaluate failed: {text}"),
                STATUS_PANIC => format!("panicked in evaluate: {text}"),
                STATUS_NON_FINITE => text,
                STATUS_INVALID_ARGUMENT => format!("evaluate refused its arguments: {text}"),
                s => format!("evaluate returned unknown status {s}: {text}"),
            }));
        }
        // The plugin promises finite outputs; check anyway (a C plugin may not).
        let bad_tau = tau.iter().position(|t| !t.iter().all(|x| x.is_finite()));
        let bad_j = tangent
            .as_deref()
            .and_then(|j| j.iter().position(|j| !j.iter().all(|x| x.is_finite())));
        match (bad_tau, bad_j) {
            (None, None) => Ok(()),
            (Some(k), j) if j.is_none_or(|j| k <= j) => Err(LawError {
                cell: Some(k),
                ..self.error(format!("non-finite stress (B̃ = {:?})", b[k]))
            }),
            (_, Some(k)) => Err(LawError {
                cell: Some(k),
                ..self.error(format!("non-finite tangent (B̃ = {:?})", b[k]))
            }),
            (Some(_), None) => unreachable!("covered by the guard above"),
        }
    }
}
