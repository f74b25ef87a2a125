//! # Neo-Hookean law (seed Eq. 9)
//!
//! `τ = G B̃`, the Mooney–Rivlin form of seed Eq. 7 with `C1 = G/2`, `C2 = C3 = 0`;
//! tangent `∂τ/∂B̃ = G I` (the identity of the 6- or 4-component representation, shear counted
//! once).
//!
//! Parameter: `G`, shear modulus in Pa, default 1e5 Pa, range `(0, ∞)`.
//!
//! Built as `libefsi_law_neo_hookean.so`; a scene names it `neo_hookean`:
//! `law: (name: "neo_hookean", parameters: {"G": 0.18e6})`.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// Neo-Hookean solid, `τ = G B̃`.
#[derive(Clone, Debug, PartialEq)]
pub struct NeoHookean {
    /// Shear modulus G (Pa).
    pub g: f64,
}

impl HyperelasticLaw for NeoHookean {
    const NAME: &'static str = "neo_hookean";
    const DESCRIPTION: &'static str = "neo-Hookean, τ(B) = G B of the solid's own B (seed Eq. 9)";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] =
            &[ParamDecl::new("G", "Pa", "shear modulus", 1.0e5).greater_than(0.0)];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(NeoHookean { g: values[0] })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        b.map(|x| self.g * x)
    }

    fn tangent<T: SymTensor>(&self, _b: &T) -> T::Tangent {
        tensor::scaled_identity::<T>(self.g)
    }
}

export_law!(NeoHookean);

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_law_sdk::testing::{
        XorShift, assert_in_plane_exact, assert_objective, deformed_states, deformed_states_full,
        tangent_error,
    };

    #[test]
    fn tangent_matches_finite_differences() {
        let law = NeoHookean { g: 2.5e5 };
        let worst = deformed_states(200, 0.3, 1)
            .iter()
            .map(|b| tangent_error(&law, b))
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "worst relative tangent error {worst:e}");
    }

    #[test]
    fn defaults_build_and_stress_is_g_b() {
        let law: NeoHookean =
            efsi_law_sdk::create_law(&efsi_law_sdk::defaults::<NeoHookean>()).unwrap();
        assert_eq!(law.g, 1.0e5);
        assert_eq!(law.stress(&[1.0, 2.0, 3.0, 0.5]), [1e5, 2e5, 3e5, 0.5e5]);
        assert_eq!(
            law.stress(&[1.0, 2.0, 3.0, 0.5, -0.25, 0.125]),
            [1e5, 2e5, 3e5, 0.5e5, -0.25e5, 0.125e5]
        );
        assert!(efsi_law_sdk::create_law::<NeoHookean>(&[0.0]).is_err());
    }

    #[test]
    fn full_tangent_matches_finite_differences() {
        for law in [NeoHookean { g: 2.5e5 }, NeoHookean { g: 3.0 }] {
            let worst = deformed_states_full(200, 0.3, 31)
                .iter()
                .map(|b| tangent_error(&law, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "{law:?}: worst {worst:e}");
        }
    }

    #[test]
    fn rotating_b_rotates_tau() {
        let mut rng = XorShift::new(32);
        for law in [NeoHookean { g: 2.5e5 }, NeoHookean { g: 3.0 }] {
            assert_objective(&law, &mut rng, 33);
        }
    }

    /// A v2 law on an in-plane B̃ (13 = 23 = 0) gives the in-plane evaluation's numbers, which
    /// are version 1's, bit for bit.
    #[test]
    fn in_plane_b_gives_the_in_plane_result_exactly() {
        for law in [NeoHookean { g: 2.5e5 }, NeoHookean { g: 3.0 }] {
            assert_in_plane_exact(&law, 34);
        }
    }
}
