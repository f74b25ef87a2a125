//! The strain energy of the deformation, `∫ w W(B) dV`.

use super::{CORNERS_OF_CELL, Four, Kernels};
use efsi_core::{Field, Region, Stagger};
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
        let g = &self.grid;
        let r = super::stress::rest_stress(law)?;
        let mut cells = std::mem::take(&mut self.energy_cells);
        cells.clear();
        let interior = Region::of(g, Stagger::Cell);
        for l in (0..interior.lines()).map(|n| interior.line(n)) {
            let [w, b11, b22, b33] = [&self.w, &b[0], &b[1], &b[2]].map(|f| f.at(&l, [0; 3]));
            let b12 = Four::new(&b[3], &l, CORNERS_OF_CELL);
            for n in (0..l.len).filter(|&n| w[n] != 0.0) {
                if let Some(p) = principal_log(b11[n], b22[n], b12.avg(n), b33[n]) {
                    cells.push((w[n], p, g.cell_volume(l.index(n)[0])));
                }
            }
        }
        let mut energy = 0.0;
        for (q, wq) in S.iter().zip(WQ) {
            for (n, &(_, [cs, sn, m1, m2, m3], _)) in cells.iter().enumerate() {
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
            for (n, &(w, [cs, sn, m1, m2, m3], vol)) in cells.iter().enumerate() {
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

/// The principal axes of B's in-plane part `[[a, c], [c, d]]` (cos, sin of the first axis'
/// angle) and the isochoric parts of the logarithms of the principal stretches (`λ₁, λ₂` in the
/// plane, `λ₃ = B₃₃`), or `None` where a stretch is not positive: no strain energy is defined
/// there (a sliver of an interface cell whose B the mixed-cell velocity gradient has spoiled),
/// and the cell contributes nothing.
fn principal_log(a: f64, d: f64, c: f64, l3: f64) -> Option<[f64; 5]> {
    let theta = 0.5 * (2.0 * c).atan2(a - d);
    let (cs, sn) = (theta.cos(), theta.sin());
    let l1 = a * cs * cs + 2.0 * c * cs * sn + d * sn * sn;
    let l2 = a * sn * sn - 2.0 * c * cs * sn + d * cs * cs;
    if !(l1 > 0.0 && l2 > 0.0 && l3 > 0.0) {
        return None;
    }
    // The isochoric part: an incompressible law's energy does not see det B, whose drift from
    // 1 under the discrete transport would otherwise count as strain (G·Δ(det B)/2 per volume —
    // the leading term for stiff solids).
    let (m1, m2, m3) = (l1.ln(), l2.ln(), l3.ln());
    let mean = (m1 + m2 + m3) / 3.0;
    Some([cs, sn, m1 - mean, m2 - mean, m3 - mean])
}
