//! The strain energy of the deformation, `∫ w W(B) dV`.

use super::Kernels;
use super::stress::rest_stress;
use efsi_core::{Field, Region, Stagger};
use efsi_laws_host::ConstitutiveLaw;

/// One solid cell of [`Kernels::strain_energy`]: its weight, its principal axes and the
/// isochoric logarithms of its principal stretches ([`Principal`]), and its volume.
pub(super) type EnergyCell = (f64, Principal, f64);

/// The principal axes of a cell's B and the isochoric logarithms `m_k` of its principal
/// stretches: in two dimensions the in-plane axes' angle (cos, sin) and `m₁, m₂` in the plane,
/// `m₃` out of it; in three the orthonormal axes `q` (columns) and `m₁, m₂, m₃`.
#[derive(Clone, Copy, Debug)]
pub(super) enum Principal {
    Plane([f64; 5]),
    Space([[f64; 3]; 3], [f64; 3]),
}

impl Principal {
    /// The principal stretches of `b` (`[11, 22, 33, 12]` or the six components), or `None`
    /// where one is not positive.
    fn of(b: &[f64]) -> Option<Self> {
        if b.len() == 4 {
            principal_log(b[0], b[1], b[3], b[2]).map(Principal::Plane)
        } else {
            principal_log_3d(b).map(|(q, m)| Principal::Space(q, m))
        }
    }

    /// `exp(s M)` (B along the isochoric path at `s`) into `out`, in the law's components.
    fn path(&self, s: f64, out: &mut [f64]) {
        match *self {
            Principal::Plane([cs, sn, m1, m2, m3]) => {
                let (e1, e2, e3) = ((s * m1).exp(), (s * m2).exp(), (s * m3).exp());
                out.copy_from_slice(&[
                    e1 * cs * cs + e2 * sn * sn,
                    e1 * sn * sn + e2 * cs * cs,
                    e3,
                    (e1 - e2) * cs * sn,
                ]);
            }
            Principal::Space(q, m) => out.copy_from_slice(&rotate(q, m.map(|m| (s * m).exp()))),
        }
    }

    /// `tr((τ − τ_rest) M)` with `M` in the grid's axes (each shear counted twice).
    fn work(&self, t: &[f64], r: &[f64]) -> f64 {
        match *self {
            Principal::Plane([cs, sn, m1, m2, m3]) => {
                let (mm11, mm22, mm12) = (
                    m1 * cs * cs + m2 * sn * sn,
                    m1 * sn * sn + m2 * cs * cs,
                    (m1 - m2) * cs * sn,
                );
                (t[0] - r[0]) * mm11 + (t[1] - r[1]) * mm22 + (t[2] - r[2]) * m3 + 2.0 * t[3] * mm12
            }
            Principal::Space(q, m) => {
                let mm = rotate(q, m);
                let mut s = 0.0;
                for c in 0..6 {
                    let shear = if c < 3 { 1.0 } else { 2.0 };
                    s += shear * (t[c] - r[c]) * mm[c];
                }
                s
            }
        }
    }
}

/// `Q diag(d) Qᵀ` in the components `[11, 22, 33, 12, 23, 13]`.
fn rotate(q: [[f64; 3]; 3], d: [f64; 3]) -> [f64; 6] {
    let e = |i: usize, j: usize| (0..3).map(|k| q[i][k] * d[k] * q[j][k]).sum::<f64>();
    [e(0, 0), e(1, 1), e(2, 2), e(0, 1), e(1, 2), e(0, 2)]
}

impl Kernels {
    /// The strain energy `∫ W dV` of `b` (per radian when axisymmetric, per unit depth when
    /// planar; a Cartesian3D cell's volume is `dx dy dz`). A law gives only its
    /// stress, but for an isotropic hyperelastic law `dW = ½ tr(τ B⁻¹ dB)`; along the isochoric
    /// path `B(s) = exp(s M)`, `M = log B`, this is `W(B) = ½ ∫₀¹ tr(τ(B(s)) M) ds`, taken with
    /// four-point Gauss–Legendre quadrature — the stress-free reference subtracted, as in the
    /// momentum equation, so the isotropic part does no work — for the isochoric part of B
    /// (`M` less its trace over 3): the drift of `det B` from 1 is not strain. Exact for
    /// neo-Hookean, whose integrand is then `G (tr B̄ − 3)/2` with `B̄ = B / det(B)^{1/3}`.
    /// A cell's B takes its shears as the mean of its edges of each pair (as the law batches do);
    /// its principal axes come in closed form in two dimensions, by Jacobi rotations in three.
    pub(super) fn strain_energy(
        &mut self,
        law: &dyn ConstitutiveLaw,
        b: &[Field],
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
        let (g, m, pairs) = (&self.grid, self.m, self.edge.len());
        let r = rest_stress(law, m)?;
        let mut cells = std::mem::take(&mut self.energy_cells);
        cells.clear();
        let interior = Region::of(g, Stagger::Cell);
        for l in (0..interior.lines()).map(|n| interior.line(n)) {
            let (w, b11) = (self.w.at(&l, [0; 3]), b[0].at(&l, [0; 3]));
            let (b22, b33) = (b[1].at(&l, [0; 3]), b[2].at(&l, [0; 3]));
            let sh = self.centre_shears(b, &l);
            for n in (0..l.len).filter(|&n| w[n] != 0.0) {
                let mut x = [b11[n], b22[n], b33[n], 0.0, 0.0, 0.0];
                for (x, s) in x[3..3 + pairs].iter_mut().zip(&sh) {
                    *x = s.avg(n);
                }
                if let Some(p) = Principal::of(&x[..m]) {
                    cells.push((w[n], p, g.cell_volume(l.index(n)[0]) * g.dz));
                }
            }
        }
        let mut energy = 0.0;
        for (q, wq) in S.iter().zip(WQ) {
            for (n, (_, p, _)) in cells.iter().enumerate() {
                p.path(*q, &mut self.cb[n * m..(n + 1) * m]);
            }
            let n = cells.len();
            super::stress::eval(law, m, &self.cb[..n * m], &mut self.ct[..n * m], None)
                .map_err(|e| e.to_string())?;
            // By reference: a cell's principal axes are not copied per quadrature point.
            for (n, (w, p, vol)) in cells.iter().enumerate() {
                let tr = p.work(&self.ct[n * m..(n + 1) * m], &r);
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

/// The orthonormal principal axes (columns of `q`) of the symmetric `b` (six components) and
/// the isochoric parts of the logarithms of its eigenvalues, by cyclic Jacobi rotations (to
/// round-off: at most 50 sweeps, each annihilating the three off-diagonal entries in turn), or
/// `None` where an eigenvalue is not positive (see [`principal_log`]).
fn principal_log_3d(b: &[f64]) -> Option<([[f64; 3]; 3], [f64; 3])> {
    let mut a = [[b[0], b[3], b[5]], [b[3], b[1], b[4]], [b[5], b[4], b[2]]];
    let mut q = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
    for _ in 0..50 {
        let off = a[0][1].abs() + a[1][2].abs() + a[0][2].abs();
        // Stops on round-off, and on NaN.
        if off.partial_cmp(&(1e-15 * scale)) != Some(std::cmp::Ordering::Greater) {
            break;
        }
        for (p, r) in [(0, 1), (1, 2), (0, 2)] {
            if a[p][r] == 0.0 {
                continue;
            }
            // The rotation in the p–r plane that zeroes a[p][r] (Golub & Van Loan, Alg. 8.4.1).
            let tau = (a[r][r] - a[p][p]) / (2.0 * a[p][r]);
            let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
            let c = 1.0 / (1.0 + t * t).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akr) = (a[k][p], a[k][r]);
                a[k][p] = c * akp - s * akr;
                a[k][r] = s * akp + c * akr;
            }
            for k in 0..3 {
                let (apk, ark) = (a[p][k], a[r][k]);
                a[p][k] = c * apk - s * ark;
                a[r][k] = s * apk + c * ark;
            }
            for row in &mut q {
                let (qp, qr) = (row[p], row[r]);
                row[p] = c * qp - s * qr;
                row[r] = s * qp + c * qr;
            }
        }
    }
    let l = [a[0][0], a[1][1], a[2][2]];
    if !l.iter().all(|&l| l > 0.0) {
        return None;
    }
    let m = l.map(f64::ln);
    let mean = (m[0] + m[1] + m[2]) / 3.0;
    Some((q, m.map(|m| m - mean)))
}
