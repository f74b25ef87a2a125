//! The law batches (stress and tangent at centres and corners, weighted), the block multigrid's
//! effective stiffness, and the stress divergence on the faces.

use super::{Kernels, PAR_POINTS, at, avg4, rows1, rows3};
use efsi_core::Field;
use efsi_laws_host::ConstitutiveLaw;
use efsi_laws_host::{LawError, Sym, Tangent};

/// The law's stress in the undeformed state `B = I` (the same at every point).
pub(super) fn rest_stress(law: &dyn ConstitutiveLaw) -> Result<efsi_laws_host::Sym, String> {
    let mut r = [[0.0; 4]];
    law.evaluate(&[[1.0, 1.0, 1.0, 0.0]], &mut r, None)
        .map_err(|e| e.to_string())?;
    Ok(r[0])
}

/// `eval(b, tau, tangent)` on the points `q` of a batch with `live(q)` only, in one call: the
/// live points are moved to the front (a sequence of swaps), evaluated, and the swaps undone,
/// so that every array is back in the batch's order with the live points' results, the stress
/// `dead` and a zero tangent at the others, and `b` unchanged. An error's cell is the batch
/// index `q` of the live point it names.
fn live_only(
    live: impl Fn(usize) -> bool,
    dead: Sym,
    b: &mut [Sym],
    tau: &mut [Sym],
    mut tangent: Option<&mut [Tangent]>,
    eval: impl FnOnce(&[Sym], &mut [Sym], Option<&mut [Tangent]>) -> Result<(), LawError>,
) -> Result<(), LawError> {
    let n = b.len();
    let mut m = 0;
    for q in 0..n {
        if live(q) {
            b.swap(m, q);
            m += 1;
        }
    }
    let result = eval(
        &b[..m],
        &mut tau[..m],
        tangent.as_deref_mut().map(|j| &mut j[..m]),
    );
    tau[m..].fill(dead);
    if let Some(j) = tangent.as_deref_mut() {
        j[m..].fill([0.0; 16]);
    }
    for q in (0..n).rev() {
        if live(q) {
            m -= 1;
            b.swap(m, q);
            tau.swap(m, q);
            if let Some(j) = tangent.as_deref_mut() {
                j.swap(m, q);
            }
        }
    }
    result.map_err(|mut e| {
        e.cell = e.cell.and_then(|c| (0..n).filter(|&q| live(q)).nth(c));
        e
    })
}

impl Kernels {
    /// The law on the centre batch (`cb` into `ct`, and `cj` if `tangent`), or on the corner
    /// batch (`kb`, `kt`, `kj`) if `corners`, at the points with a weight only (`w > 0` at a
    /// centre, `w_k > 0` at a corner: those holding or touching solid), in one call; the
    /// others get the stress `dead` and a zero tangent ([`live_only`]). A law's error names
    /// the grid point.
    pub(super) fn batch(
        &mut self,
        law: &dyn ConstitutiveLaw,
        corners: bool,
        tangent: bool,
        dead: Sym,
    ) -> Result<(), String> {
        let (win, weights) = if corners {
            (self.solid_k, &self.wk)
        } else {
            (self.solid_c, &self.w)
        };
        let n = win.points();
        let width = (win.i1 - win.i0 + 1).max(1) as usize;
        let live = |q: usize| {
            weights[(win.i0 + (q % width) as isize, win.j0 + (q / width) as isize)] != 0.0
        };
        let (b, t, j) = if corners {
            (&mut self.kb[..n], &mut self.kt[..n], &mut self.kj[..n])
        } else {
            (&mut self.cb[..n], &mut self.ct[..n], &mut self.cj[..n])
        };
        let result = live_only(live, dead, b, t, tangent.then_some(j), |b, t, j| {
            law.evaluate(b, t, j)
        });
        result.map_err(|e| self.locate(e, corners))
    }

    /// τ (and J if `tangent`) of `b` into the batches and `tau`. The law sees the solid's
    /// centres and corners only ([`Kernels::solid_c`], `solid_k`, packed in that order: see
    /// [`Kernels::ci`]), and of those only the ones with a weight (`w > 0`, `w_k > 0`): it is
    /// never called on a point without solid. Elsewhere the weights `w`, `1/κ` vanish and so
    /// does `tau`.
    pub(super) fn evaluate(
        &mut self,
        law: &dyn ConstitutiveLaw,
        b: &[Field; 4],
        tau: &mut [Field; 4],
        tangent: bool,
    ) -> Result<(), String> {
        let (cw, kw) = (self.solid_c, self.solid_k);
        let nc = cw.points();
        let s = b[0].stride();
        let [b11, b22, b33, b12] = [b[0].data(), b[1].data(), b[2].data(), b[3].data()];
        for j in cw.j0..=cw.j1 {
            for i in cw.i0..=cw.i1 {
                let k = b[0].idx(i, j);
                let q = self.ci(i, j);
                self.cb[q] = [
                    b11[k],
                    b22[k],
                    b33[k],
                    avg4(b12, k, k + 1, k + s, k + s + 1),
                ];
            }
        }
        for j in kw.j0..=kw.j1 {
            for i in kw.i0..=kw.i1 {
                let k = b[0].idx(i, j);
                let q = self.ki(i, j);
                let w = self.wk.data()[k];
                self.kb[q] = [
                    w * self.kavg(b11, k, s),
                    w * self.kavg(b22, k, s),
                    w * self.kavg(b33, k, s),
                    w * b12[k],
                ];
            }
        }
        for f in tau.iter_mut() {
            f.fill(0.0);
        }
        if nc == 0 {
            return Ok(());
        }
        // The law is called only where the weight is not zero (centres with solid, corners
        // touching it): the window's other points hold no solid — the fluid's B = I at a
        // centre, nothing (B̃ = 0, outside many laws' domains) at a corner. Their stress is the
        // rest stress at a centre (nothing once it is subtracted) and zero at a corner, their
        // tangent zero; all of it is weighted by zero.
        let r = rest_stress(law)?;
        self.batch(law, false, tangent, r)?;
        self.batch(law, true, tangent, [0.0; 4])?;
        // Subtract the stress of the stress-free state B = I (B̃ = w I): isotropic, so only a
        // change of pressure — but it jumps across the interface, and fed through the implicit
        // solve it would not stay a pure gradient (see "Stress-free reference" in the docs).
        for t in &mut self.ct[..nc] {
            for c in 0..3 {
                t[c] -= r[c];
            }
        }
        for j in cw.j0..=cw.j1 {
            for i in cw.i0..=cw.i1 {
                let k = b[0].idx(i, j);
                let (t, w) = (self.ct[self.ci(i, j)], self.w.data()[k]);
                for c in 0..3 {
                    tau[c].data_mut()[k] = w * t[c];
                }
            }
        }
        for j in kw.j0..=kw.j1 {
            for i in kw.i0..=kw.i1 {
                let k = b[0].idx(i, j);
                tau[3].data_mut()[k] = self.ks.data()[k] * self.kt[self.ki(i, j)][3];
            }
        }
        Ok(())
    }

    /// `dtau = J·db` with the tangents of the last [`Kernels::evaluate`] (rows 11, 22, 33 at
    /// centres, 12 at corners; the other components averaged to the location).
    /// Only at the solid's centres and corners ([`Kernels::solid_c`], `solid_k`): `dtau` is zero
    /// elsewhere, and there it is left untouched.
    pub(super) fn apply_tangent(&self, db: &[Field; 4], dtau: &mut [Field; 4]) {
        let (cw, kw) = (self.solid_c, self.solid_k);
        let s = db[0].stride();
        let [d11, d22, d33, d12] = [db[0].data(), db[1].data(), db[2].data(), db[3].data()];
        let [t11, t22, t33, t12] = dtau;
        rows3(
            [t11, t22, t33],
            cw.rows(),
            cw.points() >= PAR_POINTS,
            |j, rows| {
                for i in cw.i0..=cw.i1 {
                    let k = db[0].idx(i, j);
                    let w = self.w.data()[k];
                    let x = [
                        d11[k],
                        d22[k],
                        d33[k],
                        avg4(d12, k, k + 1, k + s, k + s + 1),
                    ];
                    let jm = &self.cj[self.ci(i, j)];
                    for c in 0..3 {
                        rows[c][at(i)] = w
                            * (jm[4 * c] * x[0]
                                + jm[4 * c + 1] * x[1]
                                + jm[4 * c + 2] * x[2]
                                + jm[4 * c + 3] * x[3]);
                    }
                }
            },
        );
        rows1(t12, kw.rows(), kw.points() >= PAR_POINTS, |j, row| {
            for i in kw.i0..=kw.i1 {
                let k = db[0].idx(i, j);
                let w = self.wk.data()[k];
                let x = [
                    w * self.kavg(d11, k, s),
                    w * self.kavg(d22, k, s),
                    w * self.kavg(d33, k, s),
                    w * d12[k],
                ];
                let jm = &self.kj[self.ki(i, j)];
                row[at(i)] = self.ks.data()[k]
                    * (jm[12] * x[0] + jm[13] * x[1] + jm[14] * x[2] + jm[15] * x[3]);
            }
        });
    }

    /// `eta += a·G_eff`: the stiffness of the tangent of the last [`Kernels::evaluate`] as the
    /// viscosity it acts like in the implicit system (module docs: `J : H(δ) ≈ 2 G_eff D(δ)`).
    /// At a centre `G_eff = ½ (J₁₁₁₁ B̃₁₁ + J₂₂₂₂ B̃₂₂)` (the normal stresses), at a corner
    /// `G_eff = J₁₂₁₂ ½ (B̃₁₁ + B̃₂₂)` times the interface factors of the shear in series (stress
    /// `1/κ`, shear rate `s`) and this step's relaxation divisor `relax`; negative values count
    /// zero.
    pub(super) fn stiffness(&self, relax: &Field, a: f64, eta: &mut Field, eta_k: &mut Field) {
        let (nx, ny) = self.nxy();
        let c = self.solid_c;
        for j in c.j0..=c.j1 {
            for i in c.i0..=c.i1 {
                let (jm, b) = (&self.cj[self.ci(i, j)], &self.cb[self.ci(i, j)]);
                let g = self.w[(i, j)] * 0.5 * (jm[0] * b[0] + jm[5] * b[1]);
                eta[(i, j)] += a * g.max(0.0);
            }
        }
        let kw = c.corners(nx, ny);
        for j in kw.j0..=kw.j1 {
            for i in kw.i0..=kw.i1 {
                let q = self.ki(i, j);
                let (jm, b) = (&self.kj[q], &self.kb[q]);
                let k = eta_k.idx(i, j);
                let f = self.ks.data()[k] * self.sf.data()[k] * relax.data()[k];
                let fy = self.ny2.data()[k];
                let g = f * jm[15] * (fy * b[1] + (1.0 - fy) * b[0]);
                eta_k.data_mut()[k] += a * g.max(0.0);
            }
        }
    }

    /// Volume-weighted `(∇·τ)_x` on the u-face `(i, j)` at linear index `k`.
    #[inline(always)]
    pub(super) fn force_u(&self, tau: &[Field; 4], i: isize, k: usize) -> f64 {
        let g = &self.grid;
        let m = &g.metric;
        let s = tau[0].stride();
        let [t11, t33, t12] = [tau[0].data(), tau[2].data(), tau[3].data()];
        let r = m.rx(i);
        let t33f = 0.5 * (t33[k - 1] + t33[k]);
        g.dy * (m.rc(i) * t11[k] - m.rc(i - 1) * t11[k - 1]) + g.dx * r * (t12[k + s] - t12[k])
            - g.dx * g.dy * r * m.hoop_x(i) * t33f
    }

    /// Volume-weighted `(∇·τ)_y` on the v-face `(i, j)` at linear index `k`.
    #[inline(always)]
    pub(super) fn force_v(&self, tau: &[Field; 4], i: isize, k: usize) -> f64 {
        let g = &self.grid;
        let m = &g.metric;
        let s = tau[0].stride();
        let [t22, t12] = [tau[1].data(), tau[3].data()];
        g.dy * (m.rx(i + 1) * t12[k + 1] - m.rx(i) * t12[k])
            + g.dx * m.rc(i) * (t22[k] - t22[k - s])
    }

    /// Volume-weighted `∇·τ` on the unknown faces, into `out` (compact).
    pub(super) fn force(&self, tau: &[Field; 4], out: &mut [f64]) {
        let (nx, ny) = self.nxy();
        let mut c = 0;
        for j in 0..ny {
            for i in self.faces.ux.lo..self.faces.ux.hi {
                out[c] = self.force_u(tau, i, tau[0].idx(i, j));
                c += 1;
            }
        }
        for j in self.faces.vy.lo..self.faces.vy.hi {
            for i in 0..nx {
                out[c] = self.force_v(tau, i, tau[0].idx(i, j));
                c += 1;
            }
        }
    }

    /// `y −= a·vol·∇·τ` for a `tau` that vanishes outside the solid's centres and corners
    /// ([`Kernels::solid_c`], `solid_k`): only the unknown faces next to them see a force.
    pub(super) fn force_sub(&self, tau: &[Field; 4], a: f64, y: &mut [f64]) {
        let cw = self.solid_c;
        if cw.i0 > cw.i1 {
            return;
        }
        let (nx, ny) = self.nxy();
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let nur = (ux.hi - ux.lo) as usize;
        let nu = self.faces.nu();
        // u-face (i, j): τ₁₁, τ₃₃ at centres i−1, i; τ₁₂ at corners (i, j), (i, j+1).
        for j in (cw.j0 - 1).max(0)..=(cw.j1 + 1).min(ny - 1) {
            for i in cw.i0.max(ux.lo)..=(cw.i1 + 1).min(ux.hi - 1) {
                let c = j as usize * nur + (i - ux.lo) as usize;
                y[c] -= a * self.force_u(tau, i, tau[0].idx(i, j));
            }
        }
        // v-face (i, j): τ₂₂ at centres j−1, j; τ₁₂ at corners (i, j), (i+1, j).
        for j in cw.j0.max(vy.lo)..=(cw.j1 + 1).min(vy.hi - 1) {
            for i in (cw.i0 - 1).max(0)..=(cw.i1 + 1).min(nx - 1) {
                let c = nu + (j - vy.lo) as usize * nx as usize + i as usize;
                y[c] -= a * self.force_v(tau, i, tau[0].idx(i, j));
            }
        }
    }
}
