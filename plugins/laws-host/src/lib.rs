//! # efsi-laws-host
//!
//! Hosting constitutive laws: the elastic stress `τ(B̃)` and its tangent `J = ∂τ/∂B̃`.
//!
//! A law sees the modified left Cauchy–Green tensor `B̃ = φ_s^{1/2} B` of a cell (seed Eq. 8)
//! and returns the elastic (extra) stress the momentum equation divides (seed Eqs. 7, 9, 10, 14)
//! and its derivative (Eq. 16). Laws are evaluated **in batches** of cells, never one call per
//! cell, because a shipped or user law is a dynamically loaded plugin.
//!
//! # Tensor layouts
//!
//! **In-plane** (planar and axisymmetric scenes): the tensors have components 11, 22, 33 and 12
//! only (13 = 23 = 0). Direction 1 is x (or r), 2 is y (or z), 3 is out of plane — z in planar
//! (plane strain) and the hoop direction θ in axisymmetric geometry. A symmetric tensor is stored
//! as [`Sym`] `= [t11, t22, t33, t12]`, and the tangent as [`Tangent`], row-major
//! `J[4a + b] = ∂τ_a/∂B̃_b` in that same 4-component representation (the shear component counted
//! once: `Δτ = J·ΔB̃` holds exactly for symmetric increments).
//!
//! **Full** (3-D scenes): [`Sym6`] `= [t11, t22, t33, t12, t23, t13]` and [`Tangent6`],
//! row-major `J[6a + b]`, the shears counted once. [`ConstitutiveLaw::evaluate`] takes the first,
//! [`ConstitutiveLaw::evaluate_full`] the second.
//!
//! # Plugins
//!
//! [`load_law`] loads the law a scene names from a plugin library (C ABI of `efsi-law-abi`,
//! written with `efsi-law-sdk`; the shipped laws are in `plugins/laws/`, a template to copy in
//! `plugins/law-template/`), checks its parameters and its tangent ([`check_tangent`], and
//! [`check_tangent_full`] for a version-2 library) and returns a [`LoadedLaw`]; [`load_law_3d`]
//! does the same for a 3-D scene and refuses a version-1 library, which carries in-plane
//! tensors only; [`list_laws`] and [`describe`] serve `efsi laws`. See [`loader`].

use std::fmt;

pub mod loader;

pub use loader::{
    EmbeddingCheck, FD_TANGENT_TOLERANCE, LawInfo, LibraryCheck, Listed, LoadedLaw, ParamInfo,
    TangentCheck, check_embedding, check_library, check_tangent, check_tangent_full, describe,
    list_laws, load_law, load_law_3d,
};

/// Stored components of an in-plane symmetric tensor: `[t11, t22, t33, t12]`.
pub type Sym = [f64; 4];
/// Tangent `∂τ_a/∂B̃_b`, row-major over the [`Sym`] components.
pub type Tangent = [f64; 16];
/// Stored components of a full symmetric tensor: `[t11, t22, t33, t12, t23, t13]`.
pub type Sym6 = [f64; 6];
/// Tangent `∂τ_a/∂B̃_b`, row-major over the [`Sym6`] components.
pub type Tangent6 = [f64; 36];

/// A law failed, or was refused: names the law and says why.
#[derive(Debug, Clone, PartialEq)]
pub struct LawError {
    /// The law (its name, or the library path when the name is not known yet).
    pub law: String,
    /// What is wrong (the parameter, symbol or check that failed).
    pub message: String,
    /// When an evaluation produced a non-finite value: the index in the batch of the first
    /// such cell (the caller knows where that cell is on the grid).
    pub cell: Option<usize>,
}

impl fmt::Display for LawError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "law `{}`: {}", self.law, self.message)?;
        if let Some(k) = self.cell {
            write!(f, " at entry {k} of the batch")?;
        }
        Ok(())
    }
}

impl std::error::Error for LawError {}

/// A hyperelastic law ready to evaluate (built in, or loaded from a plugin library).
pub trait ConstitutiveLaw: Send + Sync {
    /// The law's name.
    fn name(&self) -> &str;

    /// For each cell `k` of an in-plane batch: `tau[k] = τ(b[k])`, and when `tangent` is given
    /// `tangent[k] = ∂τ/∂B̃ (b[k])`. Slices have equal lengths.
    fn evaluate(
        &self,
        b: &[Sym],
        tau: &mut [Sym],
        tangent: Option<&mut [Tangent]>,
    ) -> Result<(), LawError>;

    /// The same on full symmetric tensors (3-D scenes). A law that carries in-plane tensors only
    /// (a version-1 library) returns an error saying so.
    fn evaluate_full(
        &self,
        b: &[Sym6],
        tau: &mut [Sym6],
        tangent: Option<&mut [Tangent6]>,
    ) -> Result<(), LawError>;
}

/// Neo-Hookean `τ = G B̃` (seed Eq. 9) in plain Rust: a reference for tests of the elastic
/// stage and of the plugin loader; scenes use the plugin build of the same law.
#[derive(Clone, Debug)]
pub struct NeoHookeanReference {
    /// Shear modulus G (Pa).
    pub g: f64,
}

impl ConstitutiveLaw for NeoHookeanReference {
    fn name(&self) -> &str {
        "neo_hookean_reference"
    }

    fn evaluate(
        &self,
        b: &[Sym],
        tau: &mut [Sym],
        tangent: Option<&mut [Tangent]>,
    ) -> Result<(), LawError> {
        for (t, b) in tau.iter_mut().zip(b) {
            *t = b.map(|x| self.g * x);
        }
        if let Some(j) = tangent {
            for j in j.iter_mut() {
                *j = [0.0; 16];
                for a in 0..4 {
                    j[5 * a] = self.g;
                }
            }
        }
        Ok(())
    }

    fn evaluate_full(
        &self,
        b: &[Sym6],
        tau: &mut [Sym6],
        tangent: Option<&mut [Tangent6]>,
    ) -> Result<(), LawError> {
        for (t, b) in tau.iter_mut().zip(b) {
            *t = b.map(|x| self.g * x);
        }
        if let Some(j) = tangent {
            for j in j.iter_mut() {
                *j = [0.0; 36];
                for a in 0..6 {
                    j[7 * a] = self.g;
                }
            }
        }
        Ok(())
    }
}
