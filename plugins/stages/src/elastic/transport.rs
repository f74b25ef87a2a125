//! The transport kernels of B: the velocity gradient (centres and corners), the stretching
//! `H(V; B) = L B + B Lᵀ` with the interface corners' solid gradient, the relaxation of the
//! corners' shear, and the conservative advection `∇·(V B)`.

use super::{Kernels, PAR_POINTS, Window, at, avg4, rows1, rows2, rows3};
use crate::advection::face_value;
use efsi_core::Field;
use efsi_laws_host::ConstitutiveLaw;
use efsi_linalg::par;

/// The solid fraction from which a cell counts as the solid's bulk for the shear gradient's
/// four-point stencil (all eight cells it spans at least this).
const BULK_PHI: f64 = 1.0 - 1e-9;

/// The weights of the bulk shear gradient `D₄ f = [a (f₀ − f₋₁) + b (f₁ − f₋₂)] / h` at a
/// corner between `f₋₁` and `f₀`: `a = 5/4`, `b = −1/12` (see [`Kernels::gradient_in`]).
const BULK_NEAR: f64 = 1.25;
/// See [`BULK_NEAR`].
const BULK_FAR: f64 = -1.0 / 12.0;

impl Kernels {
    /// Velocity gradients of `(u, v)` (ghosts filled), wherever [`Kernels::stretch`] reads
    /// them (near the material, [`Kernels::near_c`]).
    pub(super) fn gradient(&mut self, u: &Field, v: &Field) {
        let (c, k) = self.gradient_windows(self.near_c);
        self.gradient_in(u, v, c, k);
    }

    /// Velocity gradients of `(u, v)` (ghosts filled): `L₁₁, L₂₂, L₃₃` at the centres `cw`,
    /// `L₁₂, L₂₁` at the corners `kw`.
    ///
    /// **Bulk shear gradient.** A shear wave in the solid is the pair `ρ u_t = D τ₁₂`,
    /// `τ₁₂,t = G L u` of the stress divergence `D` (two-point, on the faces) and the corner
    /// gradient `L`. With the two-point gradient both are `∂ + (h²/24) ∂³`: the wave's phase
    /// lags by `(kh)²/24` (symbol `2 sin(kh/2)/h` each), second order but with a large
    /// constant for a steep wave that nothing damps — an inviscid solid started by a fluid
    /// that diffuses an impulsive start into it (Sugiyama's Couette layer: a front a few cells
    /// wide at 64 cells, bouncing through the layer for seconds, the error first order up to
    /// 256 cells). Where the eight cells around the four u (v) faces of the derivative hold
    /// only solid, the derivative across the corner takes
    /// `D₄ f = [5/4 (f₀ − f₋₁) − 1/12 (f₁ − f₋₂)] / h = ∂f − (h²/24) ∂³f + O(h⁴)`, symbol
    /// `(2/h) sin(kh/2) (1 + ⅓ sin²(kh/2))`: the product `D D₄ = ∂² + O(h⁴)` for the wave, and
    /// positive for every k (`D₄ = (I − (h²/12) δ²) D₂`, an SPD factor on the two-point
    /// gradient: the same dispersion as a mass matrix blended halfway between lumped and
    /// consistent, without touching the mass). Near the interface and where cells hold less
    /// solid the gradient stays the two-point one (the series closure there).
    pub(super) fn gradient_in(&mut self, u: &Field, v: &Field, cw: Window, kw: Window) {
        let g = &self.grid;
        let m = &g.metric;
        let s = u.stride();
        let (ud, vd) = (u.data(), v.data());
        let [l11, l22, l33] = &mut self.lc;
        rows3(
            [l11, l22, l33],
            cw.rows(),
            cw.points() >= PAR_POINTS,
            |j, [r11, r22, r33]| {
                for i in cw.i0..=cw.i1 {
                    let k = u.idx(i, j);
                    r11[at(i)] = (ud[k + 1] - ud[k]) / g.dx;
                    r22[at(i)] = (vd[k + s] - vd[k]) / g.dy;
                    r33[at(i)] = 0.5 * (ud[k] + ud[k + 1]) * m.hoop_c(i);
                }
            },
        );
        // The solid's shear gradients at the corners: the shear rate times `s` (1 away from
        // interfaces), the extra going to the derivative across the interface — `L₁₂` by the
        // share `n_y²`, `L₂₁` by `n_x²` (see "Interface corners").
        // In the solid's bulk the shear derivative across the corner takes the four-point
        // stencil `D₄` (see "Bulk shear gradient" in the docs of `Kernels::gradient_in`).
        let (sf, ny2, wd) = (self.sf.data(), self.ny2.data(), self.w.data());
        let bulk = |k: usize, o: usize, across: usize| {
            [k - 2 * o, k - o, k, k + o]
                .iter()
                .all(|&c| wd[c] * wd[c] >= BULK_PHI && wd[c - across] * wd[c - across] >= BULK_PHI)
        };
        let d4 = |d: &[f64], k: usize, o: usize| {
            BULK_NEAR * (d[k] - d[k - o]) + BULK_FAR * (d[k + o] - d[k - 2 * o])
        };
        let (g0, nx, ny) = (-efsi_core::G, g.nx as isize, g.ny as isize);
        let par = kw.points() >= PAR_POINTS;
        let [g12, g21] = &mut self.lk;
        rows2([g12, g21], kw.rows(), par, |j, [r12, r21]| {
            for i in kw.i0..=kw.i1 {
                let k = u.idx(i, j);
                // The stencil's rows (columns) within the ghosts.
                let rows_in = j - 2 >= g0 && j + 1 < ny - g0 && i > g0;
                let cols_in = i - 2 >= g0 && i + 1 < nx - g0 && j > g0;
                let l12 = if rows_in && bulk(k, s, 1) {
                    d4(ud, k, s) / g.dy
                } else {
                    (ud[k] - ud[k - s]) / g.dy
                };
                let l21 = if cols_in && bulk(k, 1, s) {
                    d4(vd, k, 1) / g.dx
                } else {
                    (vd[k] - vd[k - 1]) / g.dx
                };
                let e = (sf[k] - 1.0) * (l12 + l21);
                r12[at(i)] = l12 + ny2[k] * e;
                r21[at(i)] = l21 + (1.0 - ny2[k]) * e;
            }
        });
    }

    /// `out = base + a·H(V; b)` for the gradients of the last [`Kernels::gradient`] call
    /// (`base` may be `None` for zero), near the material ([`Kernels::near_c`], `near_k`;
    /// `out` is left untouched elsewhere). At interface corners the shear rate is the solid's
    /// share (factor `s`), and with `relax` the corner result is divided by this step's
    /// relaxation.
    pub(super) fn stretch(
        &self,
        b: &[Field; 4],
        a: f64,
        base: Option<(&[Field; 4], &[Field; 4])>,
        relax: Option<&Field>,
        out: &mut [Field; 4],
    ) {
        let (cw, kw) = (self.near_c, self.near_k);
        self.stretch_in(b, a, base, relax, out, cw, kw);
    }

    /// [`Kernels::stretch`] at the centres `cw` and the corners `kw` only (the gradients of the
    /// last [`Kernels::gradient_in`] there).
    pub(super) fn stretch_in(
        &self,
        b: &[Field; 4],
        a: f64,
        base: Option<(&[Field; 4], &[Field; 4])>,
        relax: Option<&Field>,
        out: &mut [Field; 4],
        cw: Window,
        kw: Window,
    ) {
        let s = b[0].stride();
        let [l11, l22, l33] = [self.lc[0].data(), self.lc[1].data(), self.lc[2].data()];
        let [g12, g21] = [self.lk[0].data(), self.lk[1].data()];
        let [b11, b22, b33, b12] = [b[0].data(), b[1].data(), b[2].data(), b[3].data()];
        let [o11, o22, o33, o12] = out;
        // `base + a·h`, or `a·h` alone without a base (as `0 + a·h`: the same bits).
        let (cpar, kpar) = (cw.points() >= PAR_POINTS, kw.points() >= PAR_POINTS);
        rows3([o11, o22, o33], cw.rows(), cpar, |j, rows| {
            for i in cw.i0..=cw.i1 {
                let k = b[0].idx(i, j);
                // The solid's gradients at the corners (as for `h12` below).
                let (mut l12b12, mut l21b12) = (0.0, 0.0);
                for c in [k, k + 1, k + s, k + s + 1] {
                    l12b12 += 0.25 * g12[c] * b12[c];
                    l21b12 += 0.25 * g21[c] * b12[c];
                }
                let h = [
                    2.0 * (l11[k] * b11[k] + l12b12),
                    2.0 * (l21b12 + l22[k] * b22[k]),
                    2.0 * l33[k] * b33[k],
                ];
                match base {
                    Some((x, y)) => {
                        for c in 0..3 {
                            rows[c][at(i)] = x[c].data()[k] + y[c].data()[k] + a * h[c];
                        }
                    }
                    None => {
                        for c in 0..3 {
                            rows[c][at(i)] = 0.0 + a * h[c];
                        }
                    }
                }
            }
        });
        rows1(o12, kw.rows(), kpar, |j, row| {
            for i in kw.i0..=kw.i1 {
                let k = b[3].idx(i, j);
                let (a0, a1, a2, a3) = (k - s - 1, k - s, k - 1, k);
                // The solid's velocity gradient; the solid's own normal components
                // (solid-weighted).
                let h12 = avg4(l11, a0, a1, a2, a3) * b12[k]
                    + g12[k] * self.kavg(b22, k, s)
                    + self.kavg(b11, k, s) * g21[k]
                    + b12[k] * avg4(l22, a0, a1, a2, a3);
                let base = base.map_or(0.0, |(x, y)| x[3].data()[k] + y[3].data()[k]);
                let q = relax.map_or(1.0, |r| r.data()[k]);
                row[at(i)] = q * (base + a * h12);
            }
        });
    }

    /// `out = ∇·(V b)` (conservative, van Leer face values), at the interior centres and
    /// corners near the material ([`Kernels::near_c`], `near_k`; `out` is left untouched
    /// elsewhere); rows in parallel (each writes only its own entries: the same bits on any
    /// number of threads).
    pub(super) fn advect(&self, u: &Field, v: &Field, b: &[Field; 4], out: &mut [Field; 4]) {
        let g = &self.grid;
        let m = &g.metric;
        let (nx, ny) = self.nxy();
        let s = u.stride();
        let (ud, vd) = (u.data(), v.data());
        let at = |d: &[f64], k: usize, o: usize| (d[k - 2 * o], d[k - o], d[k], d[k + o]);
        let fx = |a: f64, d: &[f64], k: usize, o: usize| {
            let (p, q, r, t) = at(d, k, o);
            a * face_value(a, p, q, r, t)
        };
        let gu = efsi_core::G as usize;
        let (cw, kw) = (self.near_c, self.near_k);
        let (ci0, ci1) = (cw.i0.max(0), cw.i1.min(nx - 1));
        for c in 0..3 {
            let bd = b[c].data();
            par::rows(out[c].data_mut(), s).for_each(|jp, row| {
                let j = jp as isize - efsi_core::G;
                if j < 0 || j >= ny || j < cw.j0 || j > cw.j1 {
                    return;
                }
                for i in ci0..=ci1 {
                    let k = jp * s + gu + i as usize;
                    // x-faces i, i+1 (between cells i−1|i and i|i+1); y-faces j, j+1.
                    let fw = fx(ud[k], bd, k, 1);
                    let fe = fx(ud[k + 1], bd, k + 1, 1);
                    let fs = fx(vd[k], bd, k, s);
                    let fn_ = fx(vd[k + s], bd, k + s, s);
                    row[gu + i as usize] =
                        (m.rx(i + 1) * fe - m.rx(i) * fw) / (m.rc(i) * g.dx) + (fn_ - fs) / g.dy;
                }
            });
        }
        let bd = b[3].data();
        par::rows(out[3].data_mut(), s).for_each(|jp, row| {
            let j = jp as isize - efsi_core::G;
            if j < 0 || j > ny || j < kw.j0 || j > kw.j1 {
                return;
            }
            for i in kw.i0..=kw.i1 {
                let (k, o) = (jp * s + gu + i as usize, gu + i as usize);
                let r = m.rx(i);
                if r == 0.0 {
                    row[o] = 0.0;
                    continue;
                }
                // The corner's control volume has x-faces at the cell centres i−1, i and y-faces
                // at the row centres j−1, j; advecting velocities are 4-point averages.
                let ue = 0.25 * (ud[k] + ud[k + 1] + ud[k - s] + ud[k + 1 - s]);
                let uw = 0.25 * (ud[k - 1] + ud[k] + ud[k - 1 - s] + ud[k - s]);
                let vn = 0.25 * (vd[k] + vd[k - 1] + vd[k + s] + vd[k + s - 1]);
                let vs = 0.25 * (vd[k - s] + vd[k - s - 1] + vd[k] + vd[k - 1]);
                let fe = fx(ue, bd, k + 1, 1);
                let fw = fx(uw, bd, k, 1);
                let fn_ = fx(vn, bd, k + s, s);
                let fs = fx(vs, bd, k, s);
                row[o] = (m.rc(i) * fe - m.rc(i - 1) * fw) / (r * g.dx) + (fn_ - fs) / g.dy;
            }
        });
    }

    /// The interface relaxation of the corner shear for this step (see "Interface corners"):
    /// evaluates the law at the corners of `start` (Bⁿ), folds the linearised relaxation's
    /// explicit part into `explicit[3]` and sets the divisor `relax` (1 away from interfaces).
    pub(super) fn relaxation(
        &mut self,
        law: &dyn ConstitutiveLaw,
        start: &[Field; 4],
        dt: f64,
        explicit: &mut [Field; 4],
        relax: &mut Field,
    ) -> Result<(), String> {
        relax.fill(1.0);
        // Only the solid's corners relax (`r > 0` needs a solid cell beside the corner).
        let kw = self.solid_k;
        let s = start[0].stride();
        let [b11, b22, b33, b12] = [
            start[0].data(),
            start[1].data(),
            start[2].data(),
            start[3].data(),
        ];
        let mut any = false;
        for j in kw.j0..=kw.j1 {
            for i in kw.i0..=kw.i1 {
                let k = start[0].idx(i, j);
                let q = self.ki(i, j);
                let w = self.wk.data()[k];
                any |= self.rc.data()[k] > 0.0;
                self.kb[q] = [
                    w * self.kavg(b11, k, s),
                    w * self.kavg(b22, k, s),
                    w * self.kavg(b33, k, s),
                    w * b12[k],
                ];
            }
        }
        if !any {
            return Ok(());
        }
        // At the corners touching solid only (the law may be undefined at B = 0).
        self.batch(law, true, true, [0.0; 4])?;
        for j in kw.j0..=kw.j1 {
            for i in kw.i0..=kw.i1 {
                let k = start[0].idx(i, j);
                let rc = self.rc.data()[k];
                if rc == 0.0 {
                    continue;
                }
                let q = self.ki(i, j);
                // The shear-rate change times the B it stretches (as in `stretch_in`).
                let fy = self.ny2.data()[k];
                let bbar = fy * self.kb[q][1] + (1.0 - fy) * self.kb[q][0];
                let jt = self.kj[q][15].max(0.0);
                let lambda = dt * rc * bbar;
                // The relaxation at θ_r = ½ + ½ z/(1 + z), `z = λ J` its stiffness over the
                // step: trapezoidal where it is slow (θ_r − ½ = O(Δt), second order), backward
                // Euler where it is stiff (a solid in air; monotone for every z).
                let z = lambda * jt;
                let th = 0.5 + 0.5 * z / (1.0 + z);
                relax.data_mut()[k] = 1.0 / (1.0 + th * z);
                explicit[3].data_mut()[k] -= lambda * (self.kt[q][3] - th * jt * b12[k]);
                // The same relaxation of the solid's shear rate stretches the normal components
                // of the four cells around (explicit, at Bⁿ): `Ḃ₁₁ = 2 L₁₂ B₁₂`, `Ḃ₂₂ = 2 L₂₁ B₁₂`
                // averaged over a centre's corners, with the share n_y² to L₁₂.
                let fy = self.ny2.data()[k];
                // The relaxation as the corner's implicit step applies it (× q): bounded where
                // it is stiff (a solid in air), where the explicit rate would blow up.
                let d = 0.5 * dt * rc * self.kt[q][3] * b12[k] * relax.data()[k];
                for c in [k, k - 1, k - s, k - s - 1] {
                    explicit[0].data_mut()[c] -= fy * d;
                    explicit[1].data_mut()[c] -= (1.0 - fy) * d;
                }
            }
        }
        Ok(())
    }
}
