//! # Test-only law that returns NaN
//!
//! `τ = G B̃`, but the stress is NaN in every cell whose `b11` exceeds the parameter `limit`
//! (default 1.7, above every state of the load-time tangent check, so the law loads). A run
//! whose solid stretches past `limit` must stop with exit code 3 and a message naming the law,
//! and save its last good state. Built as `libefsi_test_law_nan.so`; loaded by path only.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, Sym, Tangent, export_law, tensor};

/// `τ = G B̃`, NaN when `b11 > limit`.
pub struct NanPastLimit {
    g: f64,
    limit: f64,
}

impl HyperelasticLaw for NanPastLimit {
    const NAME: &'static str = "test_nan";
    const DESCRIPTION: &'static str = "test only: τ = G B̃, NaN when b11 > limit";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] = &[
            ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0),
            ParamDecl::new("limit", "", "b11 above which the stress is NaN", 1.7).greater_than(0.0),
        ];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(NanPastLimit {
            g: values[0],
            limit: values[1],
        })
    }

    fn stress(&self, b: &Sym) -> Sym {
        if b[0] > self.limit {
            return [f64::NAN; 4];
        }
        b.map(|x| self.g * x)
    }

    fn tangent(&self, _b: &Sym) -> Tangent {
        tensor::scaled_identity(self.g)
    }
}

export_law!(NanPastLimit);
