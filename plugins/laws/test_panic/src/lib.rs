//! # Test-only law that panics
//!
//! `τ = G B̃`, but `evaluate` panics when a cell has `b11 > 10` and `create` panics when
//! `G > 1e12`: the loader must get an error back (the SDK's `catch_unwind`) and the host process
//! must survive. Built as `libefsi_test_law_panic.so`; loaded by path only.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// `τ = G B̃`, panicking on `b11 > 10`.
pub struct Panicking {
    g: f64,
}

impl HyperelasticLaw for Panicking {
    const NAME: &'static str = "test_panic";
    const DESCRIPTION: &'static str = "test only: τ = G B̃, panics when b11 > 10";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] =
            &[ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0)];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        assert!(
            values[0] <= 1e12,
            "G = {} is too stiff for this test law",
            values[0]
        );
        Ok(Panicking { g: values[0] })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        assert!(b[0] <= 10.0, "b11 = {} exceeds 10", b[0]);
        b.map(|x| self.g * x)
    }

    fn tangent<T: SymTensor>(&self, _b: &T) -> T::Tangent {
        tensor::scaled_identity::<T>(self.g)
    }
}

export_law!(Panicking);
