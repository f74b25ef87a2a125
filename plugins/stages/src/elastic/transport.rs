//! The transport kernels of B: the velocity gradient (centres and corners), the stretching
//! `H(V; B) = L B + B Lᵀ` with the interface corners' solid gradient, the relaxation of the
//! corners' shear, and the conservative advection `∇·(V B)`.

use super::{CELLS_OF_CORNER, CORNERS_OF_CELL, Four, Kernels, Window, corner_weights, on, plus};
use crate::advection::face_value;
use efsi_core::operators::minus;
use efsi_core::{Field, Index, Line, Region, Stagger, unit};
use efsi_laws_host::ConstitutiveLaw;

/// The solid fraction from which a cell counts as the solid's bulk for the shear gradient's
/// four-point stencil (all eight cells it spans at least this).
const BULK_PHI: f64 = 1.0 - 1e-9;

/// The weights of the bulk shear gradient `D₄ f = [a (f₀ − f₋₁) + b (f₁ − f₋₂)] / h` at a
/// corner between `f₋₁` and `f₀`: `a = 5/4`, `b = −1/12` (see [`Kernels::gradient_in`]).
const BULK_NEAR: f64 = 1.25;
/// See [`BULK_NEAR`].
const BULK_FAR: f64 = -1.0 / 12.0;

/// The cells a corner's relaxation stretches, in the order it updates them: the corner's
/// upper-right, upper-left, lower-right and lower-left cells.
const AROUND: [Index; 4] = [[0, 0, 0], [-1, 0, 0], [0, -1, 0], [-1, -1, 0]];

/// The bulk shear gradient's stencil along axis `a` on a run of corners: the velocity
/// component `f` at `I − 2e_a … I + e_a` and the solid weights `w` there and at the cells
/// beside them across the corner (`− e_b`). It covers the points `off..off + len` of the corner
/// line it serves.
struct Bulk<'a> {
    w: [&'a [f64]; 8],
    f: [&'a [f64]; 4],
    off: usize,
    len: usize,
}

impl<'a> Bulk<'a> {
    /// The stencil on `line`, a run of the corner line starting at column `start`.
    fn new(w: &'a Field, f: &'a Field, line: &Line, a: usize, b: usize, start: isize) -> Self {
        let s = |d: isize, e: isize| {
            let mut x = [0; 3];
            x[a] += d;
            x[b] -= e;
            x
        };
        Bulk {
            w: [
                (-2, 0),
                (-1, 0),
                (0, 0),
                (1, 0),
                (-2, 1),
                (-1, 1),
                (0, 1),
                (1, 1),
            ]
            .map(|(d, e)| w.at(line, s(d, e))),
            f: [-2, -1, 0, 1].map(|d| f.at(line, s(d, 0))),
            off: (line.start[0] - start) as usize,
            len: line.len,
        }
    }

    /// `h D₄ f` at point `n` of the corner line, if the stencil covers it and its eight cells
    /// are all the solid's bulk ([`BULK_PHI`]).
    #[inline(always)]
    fn d4(&self, n: usize) -> Option<f64> {
        let m = n.checked_sub(self.off).filter(|&m| m < self.len)?;
        let (w, f) = (&self.w, &self.f);
        let solid = |c: usize| w[c][m] * w[c][m] >= BULK_PHI;
        let bulk = (0..4).all(|c| solid(c) && solid(c + 4));
        bulk.then(|| BULK_NEAR * (f[2][m] - f[1][m]) + BULK_FAR * (f[3][m] - f[0][m]))
    }
}

/// A field's values along axis `a` at `I − 2e_a … I + 2e_a` on a line, for the van Leer fluxes
/// through the faces below and above each point.
struct Flux<'a>([&'a [f64]; 5]);

impl<'a> Flux<'a> {
    fn new(f: &'a Field, line: &Line, a: usize) -> Self {
        Flux([-2, -1, 0, 1, 2].map(|d| {
            let mut s = [0; 3];
            s[a] = d;
            f.at(line, s)
        }))
    }

    /// The flux `a·f` through the face between `I − e_a` and `I` at speed `a`.
    #[inline(always)]
    fn lower(&self, a: f64, n: usize) -> f64 {
        let f = &self.0;
        a * face_value(a, f[0][n], f[1][n], f[2][n], f[3][n])
    }

    /// The flux through the face between `I` and `I + e_a`.
    #[inline(always)]
    fn upper(&self, a: f64, n: usize) -> f64 {
        let f = &self.0;
        a * face_value(a, f[1][n], f[2][n], f[3][n], f[4][n])
    }
}

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
        let (dx, dy) = (g.dx, g.dy);
        let [l11, l22, l33] = &mut self.lc;
        cw.region(g)
            .for_each((l11, l22, l33), |l, (r11, r22, r33)| {
                let (uw, ue) = (u.at(&l, [0; 3]), u.at(&l, unit(0)));
                let (vs, vn) = (v.at(&l, [0; 3]), v.at(&l, unit(1)));
                let hoop = g.metric.hoop_c_on(&l, 0);
                for n in 0..l.len {
                    r11[n] = (ue[n] - uw[n]) / dx;
                    r22[n] = (vn[n] - vs[n]) / dy;
                    r33[n] = 0.5 * (uw[n] + ue[n]) * hoop[n];
                }
            });
        self.corner_gradient(u, v, kw);
    }

    /// The solid's shear gradients `L₁₂, L₂₁` at the corners `kw`: the shear rate times `s` (1
    /// away from interfaces), the extra going to the derivative across the interface — `L₁₂`
    /// by the share `n_y²`, `L₂₁` by `n_x²` (see "Interface corners"). In the solid's bulk the
    /// derivative across the corner takes the four-point stencil `D₄` (see "Bulk shear
    /// gradient" in the docs of [`Kernels::gradient_in`]) wherever that stencil and the cells
    /// beside it lie within the fields' storage.
    fn corner_gradient(&mut self, u: &Field, v: &Field, kw: Window) {
        let g = &self.grid;
        let (dx, dy) = (g.dx, g.dy);
        let (sf, ny2, w) = (&self.sf, &self.ny2, &self.w);
        let corners = kw.region(g);
        // The storage: `D₄` along axis a at I reads I − 2e_a … I + e_a and the cells across.
        let whole = Region::whole(g);
        let (lo, hi) = (whole.lo(), whole.hi());
        let (k0, k1) = (corners.lo()[0], corners.hi()[0]);
        let along_y = corners.range(0, k0.max(lo[0] + 1), k1);
        let along_x = corners.range(0, k0.max(lo[0] + 2), k1.min(hi[0] - 2));
        let [g12, g21] = &mut self.lk;
        corners.for_each((g12, g21), |l, (r12, r21)| {
            let j = l.start[1];
            let by = ((lo[1] + 2..hi[1] - 2).contains(&j))
                .then(|| Bulk::new(w, u, &along_y.line(l.n), 1, 0, l.start[0]));
            let bx = (j > lo[1]).then(|| Bulk::new(w, v, &along_x.line(l.n), 0, 1, l.start[0]));
            let (uc, us) = (u.at(&l, [0; 3]), u.at(&l, minus(1)));
            let (vc, vw) = (v.at(&l, [0; 3]), v.at(&l, minus(0)));
            let (sf, ny2) = (sf.at(&l, [0; 3]), ny2.at(&l, [0; 3]));
            for n in 0..l.len {
                let l12 = match by.as_ref().and_then(|b| b.d4(n)) {
                    Some(d) => d / dy,
                    None => (uc[n] - us[n]) / dy,
                };
                let l21 = match bx.as_ref().and_then(|b| b.d4(n)) {
                    Some(d) => d / dx,
                    None => (vc[n] - vw[n]) / dx,
                };
                let e = (sf[n] - 1.0) * (l12 + l21);
                r12[n] = l12 + ny2[n] * e;
                r21[n] = l21 + (1.0 - ny2[n]) * e;
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
        let g = &self.grid;
        let (lc, lk) = (&self.lc, &self.lk);
        let [o11, o22, o33, o12] = out;
        // `base + a·h`, or `a·h` alone without a base (as `0 + a·h`: the same bits).
        cw.region(g)
            .for_each((o11, o22, o33), |l, (r11, r22, r33)| {
                let rows = [r11, r22, r33];
                let at = |f| on(f, &l);
                let [l11, l22, l33] = [at(&lc[0]), at(&lc[1]), at(&lc[2])];
                let [b11, b22, b33] = [at(&b[0]), at(&b[1]), at(&b[2])];
                // The solid's gradients at the cell's corners (as for `h12` below).
                let [g12, g21, b12] =
                    [&lk[0], &lk[1], &b[3]].map(|f| Four::new(f, &l, CORNERS_OF_CELL));
                let base = base.map(|(x, y)| [0, 1, 2].map(|c| (at(&x[c]), at(&y[c]))));
                for n in 0..l.len {
                    let (mut l12b12, mut l21b12) = (0.0, 0.0);
                    for m in 0..4 {
                        l12b12 += 0.25 * g12.get(m, n) * b12.get(m, n);
                        l21b12 += 0.25 * g21.get(m, n) * b12.get(m, n);
                    }
                    let h = [
                        2.0 * (l11[n] * b11[n] + l12b12),
                        2.0 * (l21b12 + l22[n] * b22[n]),
                        2.0 * l33[n] * b33[n],
                    ];
                    for c in 0..3 {
                        rows[c][n] = match base {
                            Some(xy) => xy[c].0[n] + xy[c].1[n] + a * h[c],
                            None => 0.0 + a * h[c],
                        };
                    }
                }
            });
        kw.region(g).for_each(o12, |l, row| {
            let at = |f| on(f, &l);
            let (b12, g12, g21) = (at(&b[3]), at(&lk[0]), at(&lk[1]));
            // The solid's velocity gradient; the solid's own normal components
            // (solid-weighted).
            let [l11, l22, b11, b22] =
                [&lc[0], &lc[1], &b[0], &b[1]].map(|f| Four::new(f, &l, CELLS_OF_CORNER));
            let wt = corner_weights(&self.kwt, &l);
            let base = base.map(|(x, y)| (at(&x[3]), at(&y[3])));
            let relax = relax.map(at);
            for n in 0..l.len {
                let h12 = l11.avg(n) * b12[n]
                    + g12[n] * b22.weighted(&wt, n)
                    + b11.weighted(&wt, n) * g21[n]
                    + b12[n] * l22.avg(n);
                let base = base.map_or(0.0, |(x, y)| x[n] + y[n]);
                let q = relax.map_or(1.0, |r| r[n]);
                row[n] = q * (base + a * h12);
            }
        });
    }

    /// `out = ∇·(V b)` (conservative, van Leer face values), at the interior centres and
    /// corners near the material ([`Kernels::near_c`], `near_k`; `out` is left untouched
    /// elsewhere); lines in parallel (each writes only its own entries: the same bits on any
    /// number of threads).
    pub(super) fn advect(&self, u: &Field, v: &Field, b: &[Field; 4], out: &mut [Field; 4]) {
        let g = &self.grid;
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let interior = Region::of(g, Stagger::Cell);
        let (cw, kw) = (self.near_c.region(g), self.near_k.region(g));
        let centres = cw
            .range(0, cw.lo()[0].max(0), cw.hi()[0].min(interior.hi()[0]))
            .range(1, cw.lo()[1].max(0), cw.hi()[1].min(interior.hi()[1]));
        for c in 0..3 {
            centres.for_each(&mut out[c], |l, row| {
                let (bx, by) = (Flux::new(&b[c], &l, 0), Flux::new(&b[c], &l, 1));
                let (uw, ue) = (u.at(&l, [0; 3]), u.at(&l, unit(0)));
                let (vs, vn) = (v.at(&l, [0; 3]), v.at(&l, unit(1)));
                let (rw, re, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
                for n in 0..l.len {
                    // x-faces i, i+1 (between cells i−1|i and i|i+1); y-faces j, j+1.
                    let (fw, fe) = (bx.lower(uw[n], n), bx.upper(ue[n], n));
                    let (fs, fn_) = (by.lower(vs[n], n), by.upper(vn[n], n));
                    row[n] = (re[n] * fe - rw[n] * fw) / (rc[n] * dx) + (fn_ - fs) / dy;
                }
            });
        }
        // The corners' rows 0..=ny.
        let corners = kw.range(1, kw.lo()[1].max(0), kw.hi()[1].min(interior.hi()[1] + 1));
        corners.for_each(&mut out[3], |l, row| {
            let (bx, by) = (Flux::new(&b[3], &l, 0), Flux::new(&b[3], &l, 1));
            // The corner's control volume has x-faces at the cell centres i−1, i and y-faces at
            // the row centres j−1, j; advecting velocities are 4-point averages.
            let four = |f, s: [[isize; 2]; 4]| Four::new(f, &l, s.map(|[a, b]| [a, b, 0]));
            let ue = four(u, [[0, 0], [1, 0], [0, -1], [1, -1]]);
            let uw = four(u, [[-1, 0], [0, 0], [-1, -1], [0, -1]]);
            let vn = four(v, [[0, 0], [-1, 0], [0, 1], [-1, 1]]);
            let vs = four(v, [[0, -1], [-1, -1], [0, 0], [-1, 0]]);
            let (rx, rc, rcw) = (m.rx_on(&l, 0), m.rc_on(&l, 0), m.rc_on(&l, -1));
            for n in 0..l.len {
                let r = rx[n];
                if r == 0.0 {
                    row[n] = 0.0;
                    continue;
                }
                let fe = bx.upper(ue.avg(n), n);
                let fw = bx.lower(uw.avg(n), n);
                let fn_ = by.upper(vn.avg(n), n);
                let fs = by.lower(vs.avg(n), n);
                row[n] = (rc[n] * fe - rcw[n] * fw) / (r * dx) + (fn_ - fs) / dy;
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
        let corners = self.solid_k.region(&self.grid);
        self.gather_corners(start);
        let any = corners.fold(
            false,
            |l| on(&self.rc, &l).iter().any(|&r| r > 0.0),
            |a, p| a || p,
        );
        if !any {
            return Ok(());
        }
        // At the corners touching solid only (the law may be undefined at B = 0).
        self.batch(law, true, true, [0.0; 4])?;
        for l in (0..corners.lines()).map(|n| corners.line(n)) {
            for (n, at) in l.indices().enumerate() {
                let rc = self.rc[at];
                if rc == 0.0 {
                    continue;
                }
                let q = l.n * l.len + n;
                // The shear-rate change times the B it stretches (as in `stretch_in`).
                let fy = self.ny2[at];
                let bbar = fy * self.kb[q][1] + (1.0 - fy) * self.kb[q][0];
                let jt = self.kj[q][15].max(0.0);
                let lambda = dt * rc * bbar;
                // The relaxation at θ_r = ½ + ½ z/(1 + z), `z = λ J` its stiffness over the
                // step: trapezoidal where it is slow (θ_r − ½ = O(Δt), second order), backward
                // Euler where it is stiff (a solid in air; monotone for every z).
                let z = lambda * jt;
                let th = 0.5 + 0.5 * z / (1.0 + z);
                let b12 = start[3][at];
                relax[at] = 1.0 / (1.0 + th * z);
                explicit[3][at] -= lambda * (self.kt[q][3] - th * jt * b12);
                // The same relaxation of the solid's shear rate stretches the normal components
                // of the four cells around (explicit, at Bⁿ): `Ḃ₁₁ = 2 L₁₂ B₁₂`, `Ḃ₂₂ = 2 L₂₁ B₁₂`
                // averaged over a centre's corners, with the share n_y² to L₁₂. The relaxation
                // as the corner's implicit step applies it (× q): bounded where it is stiff (a
                // solid in air), where the explicit rate would blow up.
                let d = 0.5 * dt * rc * self.kt[q][3] * b12 * relax[at];
                for c in AROUND {
                    explicit[0][plus(at, c)] -= fy * d;
                    explicit[1][plus(at, c)] -= (1.0 - fy) * d;
                }
            }
        }
        Ok(())
    }
}
