//! # Test-only law that returns NaN
//!
//! `τ = G B̃`, but the stress is NaN in every cell whose `b11` exceeds the parameter `limit`
//! (default 1.7, above every state of the load-time tangent check, so the law loads), or is
//! below the parameter `floor` (default 0: never) — a law undefined at `B = 0`, as an Ogden law
//! with logarithms is, which efsi must never call where there is no solid. A run
//! whose solid stretches past `limit` must stop with exit code 3 and a message naming the law,
//! and save its last good state. Built as `libefsi_test_law_nan.so`; loaded by path only.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// `τ = G B̃`, NaN when `b11 > limit` or `b11 < floor`.
pub struct NanPastLimit {
    g: f64,
    limit: f64,
    floor: f64,
}

impl HyperelasticLaw for NanPastLimit {
    const NAME: &'static str = "test_nan";
    const DESCRIPTION: &'static str = "test only: τ = G B̃, NaN when b11 > limit or b11 < floor";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] = &[
            ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0),
            ParamDecl::new("limit", "", "b11 above which the stress is NaN", 1.7).greater_than(0.0),
            ParamDecl::new("floor", "", "b11 below which the stress is NaN", 0.0).at_least(0.0),
        ];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(NanPastLimit {
            g: values[0],
            limit: values[1],
            floor: values[2],
        })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        if b[0] > self.limit || b[0] < self.floor {
            return T::from_fn(|_| f64::NAN);
        }
        b.map(|x| self.g * x)
    }

    fn tangent<T: SymTensor>(&self, _b: &T) -> T::Tangent {
        tensor::scaled_identity::<T>(self.g)
    }
}

export_law!(NanPastLimit);
