//! # Gent law — the efsi law template
//!
//! Copy this crate to write your own constitutive law: change every place marked `EDIT:`
//! (here and in `Cargo.toml`), build with `cargo build --release`, and name the library in a
//! scene. `README.md` beside this file walks through it.
//!
//! The example law is Gent's (Gent 1996), a neo-Hookean solid whose chains lock at a finite
//! stretch: with `I1 = tr(B̃)`,
//!
//! ```text
//! W = −(G Jm / 2) ln(1 − (I1 − 3)/Jm),    τ = 2 ∂W/∂I1 B̃ = f B̃,    f = G Jm / (Jm − I1 + 3)
//! ```
//!
//! and, in efsi's component representations — the full `[11, 22, 33, 12, 23, 13]` of 3-D
//! scenes and the in-plane `[11, 22, 33, 12]` of planar and axisymmetric ones, shear counted
//! once, `∂I1/∂B̃ = [1, 1, 1, 0, 0, 0]` (or `[1, 1, 1, 0]`) — the tangent is
//!
//! ```text
//! J = f I + (f² / (G Jm)) B̃ ⊗ ∂I1/∂B̃
//! ```
//!
//! `stress` and `tangent` are written once, generic over the representation `T`; the SDK exports
//! both.
//!
//! As `Jm → ∞` it tends to neo-Hookean `τ = G B̃`. Past the locking limit (`I1 − 3 ≥ Jm`) the
//! law is undefined and returns NaN, which the SDK reports as a non-finite stress at that cell.

// EDIT: keep `HyperelasticLaw`, `ParamDecl`, `SymTensor`, `export_law`; `tensor` has the
// trace, `B̃·B̃`, their derivatives, `s I` and outer products in either representation.
use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

// EDIT: the struct holding your law's constants (rename it, and in `export_law!` at the end).
/// A Gent solid.
#[derive(Clone, Debug, PartialEq)]
pub struct Gent {
    /// Shear modulus G (Pa).
    pub g: f64,
    /// Locking parameter Jm: the largest `I1 − 3` (dimensionless).
    pub jm: f64,
}

// EDIT: the default of each parameter (used when a scene leaves it out).
/// Default shear modulus G (Pa).
pub const DEFAULT_G: f64 = 1.0e5;
/// Default locking parameter Jm.
pub const DEFAULT_JM: f64 = 50.0;

impl HyperelasticLaw for Gent {
    // EDIT: the law's name (shown by `efsi laws` and in error messages).
    const NAME: &'static str = "gent";
    // EDIT: one line saying what the law is.
    const DESCRIPTION: &'static str =
        "Gent, τ(B) = G Jm / (Jm − tr(B) + 3) B of the solid's own B (the law template)";

    // EDIT: the parameters: name (as written in scenes), unit, description, default, range.
    // `new` receives the values in this order, each already checked against its range.
    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] = &[
            ParamDecl::new("G", "Pa", "shear modulus", DEFAULT_G).greater_than(0.0),
            ParamDecl::new("Jm", "", "locking limit of tr(B̃) − 3", DEFAULT_JM).greater_than(0.0),
        ];
        P
    }

    // EDIT: build your law from the values; return `Err` with a message naming the parameters
    // when a combination of them is not allowed.
    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(Gent {
            g: values[0],
            jm: values[1],
        })
    }

    // EDIT: the stress τ(B̃) of one cell, `T` being the full (6 components) or the in-plane (4)
    // representation: index components with `b[a]`, build with `T::from_fn`, `b.map`.
    fn stress<T: SymTensor>(&self, b: &T) -> T {
        let f = self.factor(b);
        b.map(|x| f * x)
    }

    // EDIT: the tangent ∂τ_a/∂B̃_b of one cell, row-major `J[N a + b]` (`N = T::N`), shear
    // counted once. efsi checks it against finite differences of `stress` when it loads the law
    // (in-plane and full) and refuses the law if they disagree.
    fn tangent<T: SymTensor>(&self, b: &T) -> T::Tangent {
        let f = self.factor(b);
        let mut j = tensor::scaled_identity::<T>(f);
        let db = tensor::outer(b, &T::D_TRACE);
        let df = f * f / (self.g * self.jm);
        for i in 0..T::TANGENT_LEN {
            j[i] += df * db[i];
        }
        j
    }
}

impl Gent {
    /// `f = G Jm / (Jm − I1 + 3)`, NaN past the locking limit.
    fn factor<T: SymTensor>(&self, b: &T) -> f64 {
        let room = self.jm - (tensor::trace(b) - 3.0);
        if room > 0.0 {
            self.g * self.jm / room
        } else {
            f64::NAN
        }
    }
}

// EDIT: the type of your law.
export_law!(Gent);

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_law_sdk::testing::{
        XorShift, assert_in_plane_exact, assert_objective, deformed_states, deformed_states_full,
        tangent_error,
    };

    // EDIT: test your law: here the tangent against finite differences of the stress at random
    // deformed states (in-plane and full), objectivity, the in-plane embedding and the
    // neo-Hookean limit.
    #[test]
    fn tangent_matches_finite_differences() {
        let law = Gent { g: 2e5, jm: 5.0 };
        let worst = deformed_states(200, 0.3, 11)
            .iter()
            .map(|b| tangent_error(&law, b))
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "worst relative tangent error {worst:e}");
        let worst = deformed_states_full(200, 0.3, 12)
            .iter()
            .map(|b| tangent_error(&law, b))
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "worst relative 3-D tangent error {worst:e}");
    }

    #[test]
    fn rotating_b_rotates_tau() {
        assert_objective(&Gent { g: 2e5, jm: 5.0 }, &mut XorShift::new(13), 14);
    }

    /// A v2 law on an in-plane B̃ (13 = 23 = 0) gives the in-plane evaluation's numbers, which
    /// are version 1's, bit for bit.
    #[test]
    fn in_plane_b_gives_the_in_plane_result_exactly() {
        assert_in_plane_exact(&Gent { g: 2e5, jm: 5.0 }, 15);
    }

    #[test]
    fn tends_to_neo_hookean_for_large_jm() {
        let law = Gent { g: 1.0, jm: 1e12 };
        let b = [1.3, 0.8, 1.1, 0.2];
        let tau = law.stress(&b);
        for a in 0..4 {
            assert!((tau[a] - b[a]).abs() < 1e-9);
        }
    }

    #[test]
    fn locking_limit_gives_nan() {
        let law = Gent { g: 1.0, jm: 1.0 };
        assert!(law.stress(&[3.0, 1.0, 1.0, 0.0])[0].is_nan());
        assert!(law.stress(&[3.0, 1.0, 1.0, 0.0, 0.0, 0.0])[0].is_nan());
    }
}
