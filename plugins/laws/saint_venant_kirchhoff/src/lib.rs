//! # Saint Venant–Kirchhoff law (seed Eqs. 7, 10)
//!
//! The push-forward of `S = λ tr(E) I + 2μ E`, `E = (C − I)/2`, written on `B̃`:
//!
//! ```text
//! τ = (λ/2) [tr(B̃) − 3] B̃ + μ (B̃·B̃ − B̃)
//! ```
//!
//! which is exactly seed Eq. 7 with the coefficients of Eq. 10, `C1 = μ`, `C2 = −μ/2`,
//! `C3 = (λ + 2μ)/8` (expand: `2μB̃ − μ[tr B̃ B̃ − B̃·B̃] + ((λ + 2μ)/2)(tr B̃ − 3)B̃`). The unit
//! tests check that identity; the loader's tests check it across the two plugin libraries.
//!
//! Tangent in either representation (6 or 4 components, shear counted once), `t = tr(B̃)`,
//! `∂t/∂B̃ = [1, 1, 1, 0, 0, 0]` (or `[1, 1, 1, 0]`), `Q = ∂(B̃·B̃)/∂B̃`:
//!
//! ```text
//! J = (λ/2) [B̃ ⊗ ∂t/∂B̃ + (t − 3) I] + μ (Q − I)
//! ```
//!
//! Parameters: Lamé `lambda` (Pa, default 4e5, ≥ 0) and `mu` (Pa, default 1e5, > 0) — the
//! defaults are a Poisson ratio of 0.4.
//!
//! Built as `libefsi_law_saint_venant_kirchhoff.so`; a scene names it `saint_venant_kirchhoff`.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// Saint Venant–Kirchhoff solid (seed Eq. 10).
#[derive(Clone, Debug, PartialEq)]
pub struct SaintVenantKirchhoff {
    /// Lamé's first parameter λ (Pa).
    pub lambda: f64,
    /// Lamé's second parameter μ, the shear modulus (Pa).
    pub mu: f64,
}

impl HyperelasticLaw for SaintVenantKirchhoff {
    const NAME: &'static str = "saint_venant_kirchhoff";
    const DESCRIPTION: &'static str = "Saint Venant–Kirchhoff, τ(B) = (λ/2)[tr(B) − 3] B + μ (B·B − B) of the solid's own B (seed Eqs. 7, 10)";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] = &[
            ParamDecl::new("lambda", "Pa", "Lamé's first parameter λ", 4.0e5).at_least(0.0),
            ParamDecl::new(
                "mu",
                "Pa",
                "Lamé's second parameter μ (shear modulus)",
                1.0e5,
            )
            .greater_than(0.0),
        ];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        Ok(SaintVenantKirchhoff {
            lambda: values[0],
            mu: values[1],
        })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        let s = 0.5 * self.lambda * (tensor::trace(b) - 3.0) - self.mu;
        let q = tensor::square(b);
        T::from_fn(|a| s * b[a] + self.mu * q[a])
    }

    fn tangent<T: SymTensor>(&self, b: &T) -> T::Tangent {
        let t = tensor::trace(b);
        let q = tensor::square_tangent(b);
        let bt = tensor::outer(b, &T::D_TRACE);
        let mut j = tensor::scaled_identity::<T>(0.5 * self.lambda * (t - 3.0) - self.mu);
        for i in 0..T::TANGENT_LEN {
            j[i] += 0.5 * self.lambda * bt[i] + self.mu * q[i];
        }
        j
    }
}

export_law!(SaintVenantKirchhoff);

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_law_sdk::testing::{
        XorShift, assert_in_plane_exact, assert_objective, deformed_states, deformed_states_full,
        tangent_error,
    };

    /// Seed Eq. 7 as written, with the SDK's helpers.
    fn mooney_rivlin<T: SymTensor>(c1: f64, c2: f64, c3: f64, b: &T) -> T {
        let t = tensor::trace(b);
        let q = tensor::square(b);
        T::from_fn(|a| 2.0 * c1 * b[a] + 2.0 * c2 * (t * b[a] - q[a]) + 4.0 * c3 * (t - 3.0) * b[a])
    }

    #[test]
    fn tangent_matches_finite_differences() {
        for (lambda, mu) in [(4e5, 1e5), (0.0, 1.0), (2e9, 1e6)] {
            let law = SaintVenantKirchhoff { lambda, mu };
            let worst = deformed_states(200, 0.3, 4)
                .iter()
                .map(|b| tangent_error(&law, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "λ = {lambda}, μ = {mu}: worst {worst:e}");
        }
    }

    #[test]
    fn equals_mooney_rivlin_with_eq_10_coefficients() {
        let (lambda, mu) = (3.0e5, 1.2e5);
        let law = SaintVenantKirchhoff { lambda, mu };
        let (c1, c2, c3) = (mu, -mu / 2.0, (lambda + 2.0 * mu) / 8.0);
        for b in deformed_states_full(100, 0.4, 5) {
            let (got, want) = (law.stress(&b), mooney_rivlin(c1, c2, c3, &b));
            for a in 0..6 {
                assert!(
                    (got[a] - want[a]).abs() <= 1e-10 * (lambda + mu),
                    "{got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn stress_free_at_rest() {
        let law = SaintVenantKirchhoff {
            lambda: 4e5,
            mu: 1e5,
        };
        assert_eq!(law.stress(&efsi_law_sdk::Sym::IDENTITY), [0.0; 4]);
        assert_eq!(law.stress(&efsi_law_sdk::Sym6::IDENTITY), [0.0; 6]);
    }

    #[test]
    fn full_tangent_matches_finite_differences() {
        for law in [(4e5, 1e5), (0.0, 1.0), (2e9, 1e6)]
            .map(|(lambda, mu)| SaintVenantKirchhoff { lambda, mu })
        {
            let worst = deformed_states_full(200, 0.3, 41)
                .iter()
                .map(|b| tangent_error(&law, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "{law:?}: worst {worst:e}");
        }
    }

    #[test]
    fn rotating_b_rotates_tau() {
        let mut rng = XorShift::new(42);
        for law in [(4e5, 1e5), (0.0, 1.0), (2e9, 1e6)]
            .map(|(lambda, mu)| SaintVenantKirchhoff { lambda, mu })
        {
            assert_objective(&law, &mut rng, 43);
        }
    }

    /// A v2 law on an in-plane B̃ (13 = 23 = 0) gives the in-plane evaluation's numbers, which
    /// are version 1's, bit for bit.
    #[test]
    fn in_plane_b_gives_the_in_plane_result_exactly() {
        for law in [(4e5, 1e5), (0.0, 1.0), (2e9, 1e6)]
            .map(|(lambda, mu)| SaintVenantKirchhoff { lambda, mu })
        {
            assert_in_plane_exact(&law, 44);
        }
    }
}
