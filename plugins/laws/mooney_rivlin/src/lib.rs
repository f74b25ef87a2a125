//! # Mooney–Rivlin law (seed Eqs. 7, 14)
//!
//! ```text
//! τ = 2 C1 B̃ + 2 C2 [tr(B̃) B̃ − B̃·B̃] + 4 C3 [tr(B̃) − 3] B̃
//! ```
//!
//! the stress of the strain energy `W = C1 (I1 − 3) + C2 (I2 − 3) + C3 (I1 − 3)²` written on
//! `B̃` (seed Eq. 7 evaluated at the transported `B̃`, Eq. 14). Its initial shear modulus is
//! `2 (C1 + C2)`, which must be positive. Neo-Hookean is `C1 = G/2, C2 = C3 = 0` (Eq. 9);
//! Saint Venant–Kirchhoff is `C1 = μ, C2 = −μ/2, C3 = (λ + 2μ)/8` (Eq. 10).
//!
//! Tangent in either representation (6 or 4 components, shear counted once), with
//! `t = tr(B̃)`, `∂t/∂B̃ = [1, 1, 1, 0, 0, 0]` (or `[1, 1, 1, 0]`) and `Q = ∂(B̃·B̃)/∂B̃` (see
//! `efsi_law_sdk::tensor::square_tangent`):
//!
//! ```text
//! J = 2 C1 I + 2 C2 [B̃ ⊗ ∂t/∂B̃ + t I − Q] + 4 C3 [B̃ ⊗ ∂t/∂B̃ + (t − 3) I]
//! ```
//!
//! Parameters (Pa): `C1` default 5e4, `C2` default 0, `C3` default 0 (≥ 0); the defaults are
//! neo-Hookean with G = 1e5 Pa.
//!
//! Built as `libefsi_law_mooney_rivlin.so`; a scene names it `mooney_rivlin`.

use efsi_law_sdk::{HyperelasticLaw, ParamDecl, SymTensor, export_law, tensor};

/// Mooney–Rivlin solid (seed Eq. 7).
#[derive(Clone, Debug, PartialEq)]
pub struct MooneyRivlin {
    /// C1 (Pa).
    pub c1: f64,
    /// C2 (Pa).
    pub c2: f64,
    /// C3 (Pa).
    pub c3: f64,
}

impl HyperelasticLaw for MooneyRivlin {
    const NAME: &'static str = "mooney_rivlin";
    const DESCRIPTION: &'static str = "Mooney–Rivlin, τ(B) = 2C1 B + 2C2 [tr(B) B − B·B] + 4C3 [tr(B) − 3] B of the solid's own B (seed Eq. 7)";

    fn parameters() -> &'static [ParamDecl] {
        const P: &[ParamDecl] = &[
            ParamDecl::new("C1", "Pa", "coefficient of (I1 − 3)", 5.0e4),
            ParamDecl::new("C2", "Pa", "coefficient of (I2 − 3)", 0.0),
            ParamDecl::new("C3", "Pa", "coefficient of (I1 − 3)²", 0.0).at_least(0.0),
        ];
        P
    }

    fn new(values: &[f64]) -> Result<Self, String> {
        let (c1, c2, c3) = (values[0], values[1], values[2]);
        if c1 + c2 <= 0.0 {
            return Err(format!(
                "the initial shear modulus 2 (C1 + C2) = {} Pa must be positive (C1 = {c1} Pa, C2 = {c2} Pa)",
                2.0 * (c1 + c2)
            ));
        }
        Ok(MooneyRivlin { c1, c2, c3 })
    }

    fn stress<T: SymTensor>(&self, b: &T) -> T {
        let t = tensor::trace(b);
        let q = tensor::square(b);
        let s = 2.0 * self.c1 + 2.0 * self.c2 * t + 4.0 * self.c3 * (t - 3.0);
        T::from_fn(|a| s * b[a] - 2.0 * self.c2 * q[a])
    }

    fn tangent<T: SymTensor>(&self, b: &T) -> T::Tangent {
        let t = tensor::trace(b);
        let q = tensor::square_tangent(b);
        let bt = tensor::outer(b, &T::D_TRACE);
        let diag = 2.0 * self.c1 + 2.0 * self.c2 * t + 4.0 * self.c3 * (t - 3.0);
        let k = 2.0 * self.c2 + 4.0 * self.c3;
        let mut j = tensor::scaled_identity::<T>(diag);
        for i in 0..T::TANGENT_LEN {
            j[i] += k * bt[i] - 2.0 * self.c2 * q[i];
        }
        j
    }
}

export_law!(MooneyRivlin);

#[cfg(test)]
mod tests {
    use super::*;
    use efsi_law_sdk::testing::{
        XorShift, assert_in_plane_exact, assert_objective, deformed_states, deformed_states_full,
        tangent_error,
    };

    #[test]
    fn tangent_matches_finite_differences() {
        for (c1, c2, c3) in [(5e4, 0.0, 0.0), (3e5, -1e5, 2e5), (1e5, 4e4, 1e3)] {
            let law = MooneyRivlin { c1, c2, c3 };
            let worst = deformed_states(200, 0.3, 2)
                .iter()
                .map(|b| tangent_error(&law, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "C = {c1}, {c2}, {c3}: worst {worst:e}");
        }
    }

    #[test]
    fn neo_hookean_special_case() {
        let law = MooneyRivlin {
            c1: 1.5,
            c2: 0.0,
            c3: 0.0,
        };
        let b = [1.2, 0.9, 1.1, 0.3];
        assert_eq!(law.stress(&b), b.map(|x| 3.0 * x));
    }

    #[test]
    fn stress_matches_full_3x3_formula() {
        // Eq. 7 with 3×3 matrices, independent of the component shortcuts.
        let law = MooneyRivlin {
            c1: 1.0,
            c2: 0.7,
            c3: 0.3,
        };
        for b in deformed_states_full(20, 0.4, 3) {
            let m = efsi_law_sdk::testing::to_matrix(&b);
            let tr = m[0][0] + m[1][1] + m[2][2];
            let mut sq = [[0.0; 3]; 3];
            for i in 0..3 {
                for k in 0..3 {
                    sq[i][k] = (0..3).map(|l| m[i][l] * m[l][k]).sum();
                }
            }
            let tau = |i: usize, k: usize| {
                2.0 * law.c1 * m[i][k]
                    + 2.0 * law.c2 * (tr * m[i][k] - sq[i][k])
                    + 4.0 * law.c3 * (tr - 3.0) * m[i][k]
            };
            let want = [
                tau(0, 0),
                tau(1, 1),
                tau(2, 2),
                tau(0, 1),
                tau(1, 2),
                tau(0, 2),
            ];
            let got = law.stress(&b);
            for a in 0..6 {
                assert!((got[a] - want[a]).abs() < 1e-12 * (1.0 + want[a].abs()));
            }
        }
    }

    #[test]
    fn refuses_non_positive_shear_modulus() {
        let e = efsi_law_sdk::create_law::<MooneyRivlin>(&[1.0, -2.0, 0.0]).unwrap_err();
        assert!(e.contains("2 (C1 + C2)"), "{e}");
    }

    #[test]
    fn full_tangent_matches_finite_differences() {
        for law in [(5e4, 0.0, 0.0), (3e5, -1e5, 2e5), (1e5, 4e4, 1e3)]
            .map(|(c1, c2, c3)| MooneyRivlin { c1, c2, c3 })
        {
            let worst = deformed_states_full(200, 0.3, 51)
                .iter()
                .map(|b| tangent_error(&law, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "{law:?}: worst {worst:e}");
        }
    }

    #[test]
    fn rotating_b_rotates_tau() {
        let mut rng = XorShift::new(52);
        for law in [(5e4, 0.0, 0.0), (3e5, -1e5, 2e5), (1e5, 4e4, 1e3)]
            .map(|(c1, c2, c3)| MooneyRivlin { c1, c2, c3 })
        {
            assert_objective(&law, &mut rng, 53);
        }
    }

    /// A v2 law on an in-plane B̃ (13 = 23 = 0) gives the in-plane evaluation's numbers, which
    /// are version 1's, bit for bit.
    #[test]
    fn in_plane_b_gives_the_in_plane_result_exactly() {
        for law in [(5e4, 0.0, 0.0), (3e5, -1e5, 2e5), (1e5, 4e4, 1e3)]
            .map(|(c1, c2, c3)| MooneyRivlin { c1, c2, c3 })
        {
            assert_in_plane_exact(&law, 54);
        }
    }
}
