//! The strain energy of the deformation, `∫ w W(B) dV`.

use super::{Kernels, avg4};
use efsi_core::Field;
use efsi_laws_host::ConstitutiveLaw;

impl Kernels {
    /// The strain energy `∫ W dV` of `b` (per radian when axisymmetric). A law gives only its
    /// stress, but for an isotropic hyperelastic law `dW = ½ tr(τ B⁻¹ dB)`; along the isochoric
    /// path `B(s) = exp(s M)`, `M = log B`, this is `W(B) = ½ ∫₀¹ tr(τ(B(s)) M) ds`, taken with
    /// four-point Gauss–Legendre quadrature — the stress-free reference subtracted, as in the
    /// momentum equation, so the isotropic part does no work — for the isochoric part of B
    /// (`M` less its trace over 3): the drift of `det B` from 1 is not strain. Exact for
    /// neo-Hookean, whose integrand is then `G (tr B̄ − 3)/2` with `B̄ = B / det(B)^{1/3}`.
    pub(super) fn strain_energy(
        &mut self,
        law: &dyn ConstitutiveLaw,
        b: &[Field; 4],
    ) -> Result<f64, String> {
        const S: [f64; 4] = [
            0.069_431_844_202_973_71,
            0.330_009_478_207_571_9,
            0.669_990_521_792_428_1,
            0.930_568_155_797_026_3,
        ];
        const WQ: [f64; 4] = [
            0.173_927_422_568_726_9,
            0.326_072_577_431_273_1,
            0.326_072_577_431_273_1,
            0.173_927_422_568_726_9,
        ];
        let (nx, ny) = self.nxy();
        let g = &self.grid;
        let s = b[0].stride();
        let [b11, b22, b33, b12] = [b[0].data(), b[1].data(), b[2].data(), b[3].data()];
        // Per centre: the in-plane eigen-decomposition (cos, sin, λ₁, λ₂) and λ₃ = B₃₃.
        let mut energy = 0.0;
        let r = super::stress::rest_stress(law)?;
        let mut cells = std::mem::take(&mut self.energy_cells);
        cells.clear();
        for j in 0..ny {
            for i in 0..nx {
                let k = b[0].idx(i, j);
                let w = self.w.data()[k];
                if w == 0.0 {
                    continue;
                }
                let (a, d, c) = (b11[k], b22[k], avg4(b12, k, k + 1, k + s, k + s + 1));
                let theta = 0.5 * (2.0 * c).atan2(a - d);
                let (cs, sn) = (theta.cos(), theta.sin());
                let l1 = a * cs * cs + 2.0 * c * cs * sn + d * sn * sn;
                let l2 = a * sn * sn - 2.0 * c * cs * sn + d * cs * cs;
                let l3 = b33[k];
                if !(l1 > 0.0 && l2 > 0.0 && l3 > 0.0) {
                    // No strain energy is defined (a sliver of an interface cell whose B the
                    // mixed-cell velocity gradient has spoiled): it contributes nothing.
                    continue;
                }
                // The isochoric part: an incompressible law's energy does not see det B, whose
                // drift from 1 under the discrete transport would otherwise count as strain
                // (G·Δ(det B)/2 per volume — the leading term for stiff solids).
                let (m1, m2, m3) = (l1.ln(), l2.ln(), l3.ln());
                let mean = (m1 + m2 + m3) / 3.0;
                cells.push((
                    k,
                    w,
                    cs,
                    sn,
                    m1 - mean,
                    m2 - mean,
                    m3 - mean,
                    g.cell_volume(i),
                ));
            }
        }
        for (q, wq) in S.iter().zip(WQ) {
            for (n, &(_, _, cs, sn, m1, m2, m3, _)) in cells.iter().enumerate() {
                let (e1, e2, e3) = ((q * m1).exp(), (q * m2).exp(), (q * m3).exp());
                self.cb[n] = [
                    e1 * cs * cs + e2 * sn * sn,
                    e1 * sn * sn + e2 * cs * cs,
                    e3,
                    (e1 - e2) * cs * sn,
                ];
            }
            let n = cells.len();
            law.evaluate(&self.cb[..n], &mut self.ct[..n], None)
                .map_err(|e| e.to_string())?;
            for (n, &(_, w, cs, sn, m1, m2, m3, vol)) in cells.iter().enumerate() {
                let t = self.ct[n];
                // M in the grid's axes.
                let (mm11, mm22, mm12) = (
                    m1 * cs * cs + m2 * sn * sn,
                    m1 * sn * sn + m2 * cs * cs,
                    (m1 - m2) * cs * sn,
                );
                let tr = (t[0] - r[0]) * mm11
                    + (t[1] - r[1]) * mm22
                    + (t[2] - r[2]) * m3
                    + 2.0 * t[3] * mm12;
                energy += 0.5 * wq * w * tr * vol;
            }
        }
        self.energy_cells = cells;
        Ok(energy)
    }
}
