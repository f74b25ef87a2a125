//! The law batches (stress and tangent at centres and corners, weighted), the block multigrid's
//! effective stiffness, and the stress divergence on the faces.

use super::{CELLS_OF_CORNER, CORNERS_OF_CELL, Four, Kernels, corner_weights};
use efsi_core::operators::minus;
use efsi_core::{Field, Index, Line, Region, unit};
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
            (self.solid_k, &self.edge[0].wk)
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
        self.gather_batches(b);
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
        let [t11, t22, t33, t12] = tau;
        let (ct, w) = (&self.ct, &self.w);
        cw.region(&self.grid)
            .for_each((t11, t22, t33), |l, (t11, t22, t33)| {
                let w = w.at(&l, [0; 3]);
                for (n, t) in ct[l.n * l.len..][..l.len].iter().enumerate() {
                    t11[n] = w[n] * t[0];
                    t22[n] = w[n] * t[1];
                    t33[n] = w[n] * t[2];
                }
            });
        let (kt, ks) = (&self.kt, &self.edge[0].ks);
        kw.region(&self.grid).for_each(t12, |l, t12| {
            let ks = ks.at(&l, [0; 3]);
            for (n, t) in kt[l.n * l.len..][..l.len].iter().enumerate() {
                t12[n] = ks[n] * t[3];
            }
        });
        Ok(())
    }

    /// The batches' B̃ from `b`: at the solid's centres ([`Kernels::solid_c`]) the normal
    /// components and the average of the cell's corners' shear, at its corners
    /// ([`Kernels::gather_corners`]).
    fn gather_batches(&mut self, b: &[Field; 4]) {
        let cells = self.solid_c.region(&self.grid);
        for l in (0..cells.lines()).map(|n| cells.line(n)) {
            let [b11, b22, b33] = [0, 1, 2].map(|c| b[c].at(&l, [0; 3]));
            let b12 = Four::new(&b[3], &l, CORNERS_OF_CELL);
            for n in 0..l.len {
                self.cb[l.n * l.len + n] = [b11[n], b22[n], b33[n], b12.avg(n)];
            }
        }
        self.gather_corners(b);
    }

    /// The corner batch's B̃ from `b` at the solid's corners ([`Kernels::solid_k`]): the
    /// solid-weighted normal components and the shear, times the corner's weight `w_k`.
    pub(super) fn gather_corners(&mut self, b: &[Field; 4]) {
        let corners = self.solid_k.region(&self.grid);
        for l in (0..corners.lines()).map(|n| corners.line(n)) {
            let wt = corner_weights(&self.edge[0].kwt, &l);
            let [b11, b22, b33] = [0, 1, 2].map(|c| Four::new(&b[c], &l, CELLS_OF_CORNER));
            let (b12, w) = (b[3].at(&l, [0; 3]), self.edge[0].wk.at(&l, [0; 3]));
            for n in 0..l.len {
                self.kb[l.n * l.len + n] = [
                    w[n] * b11.weighted(&wt, n),
                    w[n] * b22.weighted(&wt, n),
                    w[n] * b33.weighted(&wt, n),
                    w[n] * b12[n],
                ];
            }
        }
    }

    /// `dtau = J·db` with the tangents of the last [`Kernels::evaluate`] (rows 11, 22, 33 at
    /// centres, 12 at corners; the other components averaged to the location).
    /// Only at the solid's centres and corners ([`Kernels::solid_c`], `solid_k`): `dtau` is zero
    /// elsewhere, and there it is left untouched.
    pub(super) fn apply_tangent(&self, db: &[Field; 4], dtau: &mut [Field; 4]) {
        let g = &self.grid;
        let (cw, kw) = (self.solid_c.region(g), self.solid_k.region(g));
        let [t11, t22, t33, t12] = dtau;
        cw.for_each((t11, t22, t33), |l, (t11, t22, t33)| {
            let rows = [t11, t22, t33];
            let [w, d11, d22, d33] = [&self.w, &db[0], &db[1], &db[2]].map(|f| f.at(&l, [0; 3]));
            let d12 = Four::new(&db[3], &l, CORNERS_OF_CELL);
            for (n, jm) in self.cj[l.n * l.len..][..l.len].iter().enumerate() {
                let x = [d11[n], d22[n], d33[n], d12.avg(n)];
                for c in 0..3 {
                    rows[c][n] = w[n]
                        * (jm[4 * c] * x[0]
                            + jm[4 * c + 1] * x[1]
                            + jm[4 * c + 2] * x[2]
                            + jm[4 * c + 3] * x[3]);
                }
            }
        });
        kw.for_each(t12, |l, t12| {
            let wt = corner_weights(&self.edge[0].kwt, &l);
            let [d11, d22, d33] = [0, 1, 2].map(|c| Four::new(&db[c], &l, CELLS_OF_CORNER));
            let [w, d12, ks] =
                [&self.edge[0].wk, &db[3], &self.edge[0].ks].map(|f| f.at(&l, [0; 3]));
            for (n, jm) in self.kj[l.n * l.len..][..l.len].iter().enumerate() {
                let x = [
                    w[n] * d11.weighted(&wt, n),
                    w[n] * d22.weighted(&wt, n),
                    w[n] * d33.weighted(&wt, n),
                    w[n] * d12[n],
                ];
                t12[n] = ks[n] * (jm[12] * x[0] + jm[13] * x[1] + jm[14] * x[2] + jm[15] * x[3]);
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
        let g = &self.grid;
        let (cw, kw) = (self.solid_c.region(g), self.solid_k.region(g));
        cw.for_each(eta, |l, eta| {
            let w = self.w.at(&l, [0; 3]);
            let q0 = l.n * l.len;
            for (n, eta) in eta.iter_mut().enumerate() {
                let (jm, b) = (&self.cj[q0 + n], &self.cb[q0 + n]);
                let g = w[n] * 0.5 * (jm[0] * b[0] + jm[5] * b[1]);
                *eta += a * g.max(0.0);
            }
        });
        kw.for_each(eta_k, |l, eta| {
            let [ks, sf, relax, fy] = [
                &self.edge[0].ks,
                &self.edge[0].sf,
                relax,
                &self.edge[0].share,
            ]
            .map(|f| f.at(&l, [0; 3]));
            let q0 = l.n * l.len;
            for (n, eta) in eta.iter_mut().enumerate() {
                let (jm, b) = (&self.kj[q0 + n], &self.kb[q0 + n]);
                let f = ks[n] * sf[n] * relax[n];
                let g = f * jm[15] * (fy[n] * b[1] + (1.0 - fy[n]) * b[0]);
                *eta += a * g.max(0.0);
            }
        });
    }

    /// Volume-weighted `(∇·τ)_x` on the u-faces of `l`: `f(n, value)` for each point `n`.
    #[inline(always)]
    fn force_u(&self, tau: &[Field; 4], l: &Line, mut f: impl FnMut(usize, f64)) {
        let g = &self.grid;
        let m = &g.metric;
        let (t11w, t11e) = (tau[0].at(l, minus(0)), tau[0].at(l, [0; 3]));
        let (t33w, t33e) = (tau[2].at(l, minus(0)), tau[2].at(l, [0; 3]));
        let (t12s, t12n) = (tau[3].at(l, [0; 3]), tau[3].at(l, unit(1)));
        let (rx, rcw, rce, hoop) = (
            m.rx_on(l, 0),
            m.rc_on(l, -1),
            m.rc_on(l, 0),
            m.hoop_x_on(l, 0),
        );
        for n in 0..l.len {
            let r = rx[n];
            let t33f = 0.5 * (t33w[n] + t33e[n]);
            f(
                n,
                g.dy * (rce[n] * t11e[n] - rcw[n] * t11w[n]) + g.dx * r * (t12n[n] - t12s[n])
                    - g.dx * g.dy * r * hoop[n] * t33f,
            );
        }
    }

    /// Volume-weighted `(∇·τ)_y` on the v-faces of `l`: `f(n, value)` for each point `n`.
    #[inline(always)]
    fn force_v(&self, tau: &[Field; 4], l: &Line, mut f: impl FnMut(usize, f64)) {
        let g = &self.grid;
        let m = &g.metric;
        let (t22s, t22n) = (tau[1].at(l, minus(1)), tau[1].at(l, [0; 3]));
        let (t12w, t12e) = (tau[3].at(l, [0; 3]), tau[3].at(l, unit(0)));
        let (rw, re, rc) = (m.rx_on(l, 0), m.rx_on(l, 1), m.rc_on(l, 0));
        for n in 0..l.len {
            f(
                n,
                g.dy * (re[n] * t12e[n] - rw[n] * t12w[n]) + g.dx * rc[n] * (t22n[n] - t22s[n]),
            );
        }
    }

    /// Volume-weighted `∇·τ` on the unknown faces, into `out` (compact).
    pub(super) fn force(&self, tau: &[Field; 4], out: &mut [f64]) {
        let (ur, vr) = (self.faces.region(0), self.faces.region(1));
        let (ou, ov) = out.split_at_mut(ur.size());
        for (r, o, u) in [(ur, ou, true), (vr, ov, false)] {
            for l in (0..r.lines()).map(|n| r.line(n)) {
                let row = &mut o[l.n * l.len..][..l.len];
                let put = |n, f| row[n] = f;
                if u {
                    self.force_u(tau, &l, put);
                } else {
                    self.force_v(tau, &l, put);
                }
            }
        }
    }

    /// `y −= a·vol·∇·τ` for a `tau` that vanishes outside the solid's centres and corners
    /// ([`Kernels::solid_c`], `solid_k`): only the unknown faces next to them see a force —
    /// on a u-face (i, j) τ₁₁, τ₃₃ at centres i−1, i and τ₁₂ at corners (i, j), (i, j+1); on
    /// a v-face τ₂₂ at centres j−1, j and τ₁₂ at corners (i, j), (i+1, j).
    pub(super) fn force_sub(&self, tau: &[Field; 4], a: f64, y: &mut [f64]) {
        let cw = self.solid_c;
        if cw.i0 > cw.i1 {
            return;
        }
        let (ur, vr) = (self.faces.region(0), self.faces.region(1));
        let (yu, yv) = y.split_at_mut(ur.size());
        // The faces of the solid's centres, and the u-faces (v-faces) of the rows (columns)
        // beside them.
        let near = |r: Region, a: usize| {
            let (lo, hi) = (r.lo(), r.hi());
            let b = 1 - a;
            let mut w = [(cw.i0, cw.i1), (cw.j0, cw.j1)];
            w[a].1 += 1;
            w[b] = (w[b].0 - 1, w[b].1 + 1);
            r.range(a, w[a].0.max(lo[a]), (w[a].1 + 1).min(hi[a]))
                .range(b, w[b].0.max(lo[b]), (w[b].1 + 1).min(hi[b]))
        };
        for (r, y, u) in [(ur, yu, true), (vr, yv, false)] {
            let part = near(r, if u { 0 } else { 1 });
            for l in (0..part.lines()).map(|n| part.line(n)) {
                let row = &mut y[compact(&r, l.start)..][..l.len];
                let sub = |n, f| row[n] -= a * f;
                if u {
                    self.force_u(tau, &l, sub);
                } else {
                    self.force_v(tau, &l, sub);
                }
            }
        }
    }
}

/// The position of index `at` among the indices of region `r`, in its line order (the entry
/// of `at` in a compact vector over `r`).
fn compact(r: &Region, at: Index) -> usize {
    let (lo, n) = (r.lo(), [r.len(0), r.len(1)]);
    let d = |a: usize| (at[a] - lo[a]) as usize;
    (d(2) * n[1] + d(1)) * n[0] + d(0)
}
