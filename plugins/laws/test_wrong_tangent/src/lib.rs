//! # Test-only law with a wrong tangent
//!
//! Stress `τ = G B̃` but tangent `1.5 G I` (deliberately wrong by 50 %): the loader's
//! finite-difference check must refuse it. Built as `libefsi_test_law_wrong_tangent.so`; not a
//! shipped law (its library name lacks the `efsi_law_` prefix, so it is loaded by path only).

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// `τ = G B̃` with the wrong tangent `1.5 G I`.
pub struct WrongTangent {
    g: f64,
}

impl HyperelasticLaw for WrongTangent {
    const NAME: &'static str = "test_wrong_tangent";
    const DESCRIPTION: &'static str = "test only: τ = G B̃ with the wrong tangent 1.5 G I";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] =
            &[ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0)];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(WrongTangent { g: values[0] })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        b.map(|x| self.g * x)
    }

    fn tangent<T: SymTensor>(&self, _b: &T) -> T::Tangent {
        tensor::scaled_identity::<T>(1.5 * self.g)
    }
}

export_law!(WrongTangent);
