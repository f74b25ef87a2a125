//! The transport kernels of B: the velocity gradient (centres and edges), the stretching
//! `H(V; B) = L B + B Lᵀ` with the interface edges' solid gradient, the relaxation of the
//! corners' shear, and the conservative advection `∇·(V B)` — one kernel for two and three
//! dimensions, over the shear pairs of the grid ([`shear_pairs`]).
//!
//! **Stretching on the staggered layout.** With `L_ab = ∂u_a/∂x_b`, `H_ab = Σ_k (L_ak B_kb +
//! B_ak L_bk)`. At a centre, `H_aa = 2 Σ_k L_ak B_ka`: `L_aa B_aa` there and, for each `k ≠ a`,
//! the mean over the cell's four edges of the pair `(a, k)` of `L_ak B_ak` (in two dimensions
//! the hoop direction couples to itself only, `H₃₃ = 2 L₃₃ B₃₃`). On an edge of the pair
//! `(a, b)`, `H_ab = L_aa B_ab + L_ab B_bb + B_aa L_ba + B_ab L_bb` with the normal components
//! from the four cells (`L` averaged, B solid-weighted), plus on a three-dimensional grid the
//! terms of the third axis `c`, `L_ac B_cb + B_ac L_bc`, each factor the mean of the four edges
//! of its pair around the edge (`(a, c)`-edges at `I − {0, e_b} + {0, e_c}`, `(b, c)`-edges at
//! `I − {0, e_a} + {0, e_c}`). The interface relaxation (`relax`, "Interface corners" in the
//! parent module) acts on every edge family alike, each in its own plane, with the law on the
//! full tensor in three dimensions.

use super::{
    Four, Kernels, PAIR, SHEAR, Window, cells_of_edge, corner_weights, edges_of_cell, on, plus,
    shear_pairs,
};
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

/// The bulk shear gradient's stencil along axis `a` on a run of corners: the velocity
/// component `f` at `I − 2e_a … I + e_a` and the solid weights `w` there and at the cells
/// beside them across the corner (`− e_b`), addressed in the fields' storage from the linear
/// index `base` of the run's first point by the offsets `sa`, `sb` of `e_a`, `e_b`. It covers
/// the points `off..off + len` of the corner line it serves.
struct Bulk<'a> {
    w: &'a [f64],
    f: &'a [f64],
    base: usize,
    sa: isize,
    sb: isize,
    off: usize,
    len: usize,
}

impl Bulk<'_> {
    /// `h D₄ f` at point `n` of the corner line, if the stencil covers it and its eight cells
    /// are all the solid's bulk ([`BULK_PHI`]).
    #[inline(always)]
    fn d4(&self, n: usize) -> Option<f64> {
        let m = n.checked_sub(self.off).filter(|&m| m < self.len)?;
        let i = (self.base + m) as isize;
        let at = |d: isize, e: isize| (i + d * self.sa - e * self.sb) as usize;
        let (w, f) = (self.w, self.f);
        let solid = |d: isize, e: isize| w[at(d, e)] * w[at(d, e)] >= BULK_PHI;
        let bulk = (-2..2).all(|d| solid(d, 0) && solid(d, 1));
        bulk.then(|| {
            let f = |d: isize| f[at(d, 0)];
            BULK_NEAR * (f(0) - f(-1)) + BULK_FAR * (f(1) - f(-2))
        })
    }
}

/// A field's values along axis `a` at `I − 2e_a … I + 2e_a` on a line, for the van Leer fluxes
/// through the faces below and above each point.
struct Flux<'a>([&'a [f64]; 5]);

impl<'a> Flux<'a> {
    #[inline(always)]
    fn new(f: &'a Field, line: &Line, a: usize) -> Self {
        let at = |d: isize| {
            let mut s = [0; 3];
            s[a] = d;
            f.at(line, s)
        };
        Flux([at(-2), at(-1), at(0), at(1), at(2)])
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
    /// Velocity gradients of `vel` (`[u, v]` or `[u, v, w]`, ghosts filled), wherever
    /// [`Kernels::stretch`] reads them (near the material, [`Kernels::near_c`]).
    pub(super) fn gradient(&mut self, vel: &[&Field]) {
        self.gradient_in(vel, self.near_c);
    }

    /// Velocity gradients of `vel` (ghosts filled) wherever [`Kernels::stretch_in`] at the
    /// centres `c` reads them ([`Kernels::gradient_windows`]): `L₁₁, L₂₂, L₃₃` at centres
    /// (`L₃₃ = u_r/r` axisymmetric, 0 planar), `L_ab, L_ba` on the edges of each shear pair.
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
    /// solid the gradient stays the two-point one (the series closure there). Every edge
    /// family does the same in its own plane.
    pub(super) fn gradient_in(&mut self, vel: &[&Field], c: Window) {
        let (cw, ew) = self.gradient_windows(c);
        let g = &self.grid;
        let (h, dims) = (g.h(), g.dims());
        assert!(vel.len() >= dims, "one velocity component per axis");
        let [l11, l22, l33] = &mut self.lc;
        cw.region(g)
            .for_each((l11, l22, l33), |l, (r11, r22, r33)| {
                let mut rows = [r11, r22, r33];
                for (a, row) in rows.iter_mut().enumerate().take(dims) {
                    let (lo, hi) = (vel[a].at(&l, [0; 3]), vel[a].at(&l, unit(a)));
                    for n in 0..l.len {
                        row[n] = (hi[n] - lo[n]) / h[a];
                    }
                }
                if dims == 2 {
                    let (uw, ue) = (vel[0].at(&l, [0; 3]), vel[0].at(&l, unit(0)));
                    let hoop = g.metric.hoop_c_on(&l, 0);
                    for n in 0..l.len {
                        rows[2][n] = 0.5 * (uw[n] + ue[n]) * hoop[n];
                    }
                }
            });
        for (p, ew) in ew
            .into_iter()
            .enumerate()
            .take(super::shear_pairs(dims).len())
        {
            self.edge_gradient(vel, p, ew);
        }
    }

    /// The solid's shear gradients `L_ab, L_ba` on the edges `ew` of the shear pair `p`: the
    /// shear rate times `s` (1 away from interfaces), the extra going to the derivative across
    /// the interface — `L_ab` by the share `n_b²`, `L_ba` by `n_a²` (see "Interface
    /// corners"). In the solid's bulk the derivative across the edge takes the four-point
    /// stencil `D₄` (see "Bulk shear gradient" in the docs of [`Kernels::gradient_in`])
    /// wherever that stencil and the cells beside it lie within the fields' storage.
    fn edge_gradient(&mut self, vel: &[&Field], p: usize, ew: Window) {
        let ([a, b], _) = SHEAR[p];
        let g = &self.grid;
        let h = g.h();
        let (sf, share, w) = (&self.edge[p].sf, &self.edge[p].share, &self.w);
        let (ua, ub) = (vel[a], vel[b]);
        let edges = ew.region(g);
        let whole = Region::whole(g);
        let (lo, hi) = (whole.lo(), whole.hi());
        // `D₄` of u_a along b (the cells across along a) and of u_b along a.
        let (along_b, along_a) = (
            bulk_columns(&edges, lo, hi, b, a),
            bulk_columns(&edges, lo, hi, a, b),
        );
        // Each line's part in the columns: its first point and length.
        let part = |cols: Region| match cols.len(0) {
            0 => (0, 0),
            len => ((cols.lo()[0] - edges.lo()[0]) as usize, len),
        };
        let (along_b_part, along_a_part) = (part(along_b), part(along_a));
        let (sa, sb) = (w.offset(unit(a)), w.offset(unit(b)));
        let [gab, gba] = &mut self.lk[p];
        edges.for_each((gab, gba), |l, (rab, rba)| {
            // `D₄` of u_a along b (`true`) or of u_b along a.
            let bulk = |along_b: bool| {
                let ([d, x], f, (off, len), [sd, sx]) = if along_b {
                    ([b, a], ua, along_b_part, [sb, sa])
                } else {
                    ([a, b], ub, along_a_part, [sa, sb])
                };
                bulk_fits(&l, lo, hi, d, x).then_some(Bulk {
                    w: w.data(),
                    f: f.data(),
                    base: l.linear(off),
                    sa: sd,
                    sb: sx,
                    off,
                    len,
                })
            };
            let (db, da) = (bulk(true), bulk(false));
            let (uc, us) = (ua.at(&l, [0; 3]), ua.at(&l, minus(b)));
            let (vc, vw) = (ub.at(&l, [0; 3]), ub.at(&l, minus(a)));
            let (sf, share) = (sf.at(&l, [0; 3]), share.at(&l, [0; 3]));
            for n in 0..l.len {
                let lab = match db.as_ref().and_then(|s| s.d4(n)) {
                    Some(d) => d / h[b],
                    None => (uc[n] - us[n]) / h[b],
                };
                let lba = match da.as_ref().and_then(|s| s.d4(n)) {
                    Some(d) => d / h[a],
                    None => (vc[n] - vw[n]) / h[a],
                };
                let e = (sf[n] - 1.0) * (lab + lba);
                rab[n] = lab + share[n] * e;
                rba[n] = lba + (1.0 - share[n]) * e;
            }
        });
    }

    /// `out = base + a·H(V; b)` for the gradients of the last [`Kernels::gradient`] call
    /// (`base` may be `None` for zero), near the material ([`Kernels::near_c`] and its edges;
    /// `out` is left untouched elsewhere). At interface edges the shear rate is the solid's
    /// share (factor `s`), and with `relax` the xy-edges' result is divided by this step's
    /// relaxation.
    pub(super) fn stretch(
        &self,
        b: &[Field],
        a: f64,
        base: Option<(&[Field], &[Field])>,
        relax: Option<&[Field]>,
        out: &mut [Field],
    ) {
        self.stretch_in(b, a, base, relax, out, self.near_c);
    }

    /// [`Kernels::stretch`] at the centres `cw` and the edges touching them
    /// ([`Window::edges`]) only (the gradients of the last [`Kernels::gradient_in`] there).
    pub(super) fn stretch_in(
        &self,
        b: &[Field],
        a: f64,
        base: Option<(&[Field], &[Field])>,
        relax: Option<&[Field]>,
        out: &mut [Field],
        cw: Window,
    ) {
        let g = &self.grid;
        let dims = g.dims();
        let pairs = shear_pairs(dims).len();
        let (normal, shear) = out.split_at_mut(3);
        let [o11, o22, o33] = normal else {
            unreachable!("three normal components")
        };
        let normal = (o11, o22, o33);
        if dims == 3 {
            self.stretch_centres::<3, 3>(b, a, base, normal, cw);
        } else {
            self.stretch_centres::<2, 1>(b, a, base, normal, cw);
        }
        for (p, out) in shear.iter_mut().enumerate().take(pairs) {
            match (dims, p) {
                (3, 0) => self.stretch_edges::<3, 0>(b, a, base, relax, out, cw),
                (3, 1) => self.stretch_edges::<3, 1>(b, a, base, relax, out, cw),
                (3, 2) => self.stretch_edges::<3, 2>(b, a, base, relax, out, cw),
                _ => self.stretch_edges::<2, 0>(b, a, base, relax, out, cw),
            }
        }
    }

    /// The edges' part of [`Kernels::stretch_in`] for the shear pair `P` of [`SHEAR`] on a grid
    /// of `D` axes: `H_ab` from the four cells' normal components and, with `D = 3`, the third
    /// axis's terms.
    fn stretch_edges<const D: usize, const P: usize>(
        &self,
        b: &[Field],
        a: f64,
        base: Option<(&[Field], &[Field])>,
        relax: Option<&[Field]>,
        out: &mut Field,
        cw: Window,
    ) {
        let g = &self.grid;
        let (lc, lk) = (&self.lc, &self.lk);
        let (axes, at_) = SHEAR[P];
        let [pa, pb] = axes;
        let cells = cells_of_edge(axes);
        let kwt = &self.edge[P].kwt;
        // The third axis's terms `L_ac B_cb + B_ac L_bc` (three dimensions).
        let third = (D == 3).then(|| {
            let pc = 3 - pa - pb;
            let (qa, qb) = (PAIR[pa][pc], PAIR[pb][pc]);
            let around = |x: usize| {
                let (ex, ec) = (minus(x), unit(pc));
                [[0; 3], ex, ec, plus(ex, ec)]
            };
            // (a, c)-edges around the edge, then (b, c)-edges.
            let (sa, sb) = (around(pb), around(pa));
            let lac = &lk[qa][usize::from(pa > pc)];
            let lbc = &lk[qb][usize::from(pb > pc)];
            ((lac, &b[3 + qb], sa, sb), (&b[3 + qa], lbc, sa, sb))
        });
        cw.edges(g, at_).region(g).for_each(out, |l, row| {
            let at = |f| on(f, &l);
            let (bab, gab, gba) = (at(&b[3 + P]), at(&lk[P][0]), at(&lk[P][1]));
            // The solid's velocity gradient; the solid's own normal components
            // (solid-weighted).
            let four = |f| Four::new(f, &l, cells);
            let (laa, lbb, baa, bbb) = (four(&lc[pa]), four(&lc[pb]), four(&b[pa]), four(&b[pb]));
            let wt = corner_weights(kwt, &l);
            let third = third.map(|((lac, bcb, sa, sb), (bac, lbc, _, _))| {
                [
                    Four::new(lac, &l, sa),
                    Four::new(bcb, &l, sb),
                    Four::new(bac, &l, sa),
                    Four::new(lbc, &l, sb),
                ]
            });
            let base = base.map(|(x, y)| (at(&x[3 + P]), at(&y[3 + P])));
            let relax = relax.map(|r| at(&r[P]));
            for n in 0..l.len {
                let mut hab = laa.avg(n) * bab[n]
                    + gab[n] * bbb.weighted(&wt, n)
                    + baa.weighted(&wt, n) * gba[n]
                    + bab[n] * lbb.avg(n);
                if D == 3
                    && let Some([lac, bcb, bac, lbc]) = &third
                {
                    hab += lac.avg(n) * bcb.avg(n) + bac.avg(n) * lbc.avg(n);
                }
                let base = base.map_or(0.0, |(x, y)| x[n] + y[n]);
                let q = relax.map_or(1.0, |r| r[n]);
                row[n] = q * (base + a * hab);
            }
        });
    }

    /// The centres' part of [`Kernels::stretch_in`] on a grid of `D` axes and `P` shear pairs
    /// (`(2, 1)` or `(3, 3)`): `H_aa = 2 Σ_k L_ak B_ka` in the order of `k`, the centre's own
    /// term `L_aa B_aa` or the mean over the cell's edges of the pair `(a, k)`; the hoop
    /// direction of a two-dimensional grid its own term only.
    fn stretch_centres<const D: usize, const P: usize>(
        &self,
        b: &[Field],
        a: f64,
        base: Option<(&[Field], &[Field])>,
        out: (&mut Field, &mut Field, &mut Field),
        cw: Window,
    ) {
        let g = &self.grid;
        let (lc, lk) = (&self.lc, &self.lk);
        let pairs: [[usize; 2]; P] = std::array::from_fn(|p| SHEAR[p].0);
        // `base + a·h`, or `a·h` alone without a base (as `0 + a·h`: the same bits).
        cw.region(g).for_each(out, |l, (r11, r22, r33)| {
            let rows = [r11, r22, r33];
            let at = |f| on(f, &l);
            let laa = [at(&lc[0]), at(&lc[1]), at(&lc[2])];
            let baa = [at(&b[0]), at(&b[1]), at(&b[2])];
            // The solid's gradients and the shear at the cell's edges of each pair.
            let edges: [[Four; 3]; P] = std::array::from_fn(|p| {
                let e = edges_of_cell(pairs[p]);
                let four = |f| Four::new(f, &l, e);
                [four(&lk[p][0]), four(&lk[p][1]), four(&b[3 + p])]
            });
            let base = base.map(|(x, y)| {
                let xy = |c: usize| (at(&x[c]), at(&y[c]));
                [xy(0), xy(1), xy(2)]
            });
            for n in 0..l.len {
                // ¼ Σ L_ab B_ab and ¼ Σ L_ba B_ab over the cell's edges of each pair.
                let mut s = [[0.0; 2]; P];
                for (s, [gab, gba, bab]) in s.iter_mut().zip(&edges) {
                    for m in 0..4 {
                        s[0] += 0.25 * gab.get(m, n) * bab.get(m, n);
                        s[1] += 0.25 * gba.get(m, n) * bab.get(m, n);
                    }
                }
                let mut h = [0.0; 3];
                for (c, h) in h.iter_mut().enumerate() {
                    let own = laa[c][n] * baa[c][n];
                    if c >= D {
                        *h = 2.0 * own;
                        continue;
                    }
                    let term = |k: usize| {
                        if k == c {
                            own
                        } else {
                            s[PAIR[c][k]][usize::from(c > k)]
                        }
                    };
                    let mut sum = term(0);
                    for k in 1..D {
                        sum += term(k);
                    }
                    *h = 2.0 * sum;
                }
                for c in 0..3 {
                    rows[c][n] = match base {
                        Some(xy) => xy[c].0[n] + xy[c].1[n] + a * h[c],
                        None => 0.0 + a * h[c],
                    };
                }
            }
        });
    }

    /// `out = ∇·(V b)` (conservative, van Leer face values) for the velocity `vel`, at the
    /// interior centres and edges near the material ([`Kernels::near_c`] and its edges; `out`
    /// is left untouched elsewhere); lines in parallel (each writes only its own entries: the
    /// same bits on any number of threads).
    ///
    /// A centre's control volume is its cell; an edge's is the box between the centres of the
    /// cells on either side along its nodal axes and between the cell's faces along its centred
    /// axis. The advecting velocity on a face of an edge's box is the mean of the four values
    /// of the velocity component around it.
    pub(super) fn advect(&self, vel: &[&Field], b: &[Field], out: &mut [Field]) {
        let g = &self.grid;
        let m = &g.metric;
        let (h, dims) = (g.h(), g.dims());
        let near = self.near_c.region(g);
        let centres = clip(near, Region::of(g, Stagger::Cell));
        let (normal, shear) = out.split_at_mut(3);
        for (c, out) in normal.iter_mut().enumerate() {
            centres.for_each(out, |l, row| {
                let bx = Flux::new(&b[c], &l, 0);
                let (uw, ue) = (vel[0].at(&l, [0; 3]), vel[0].at(&l, unit(0)));
                let (rw, re, rc) = (m.rx_on(&l, 0), m.rx_on(&l, 1), m.rc_on(&l, 0));
                // The faces across the other axes (no metric there).
                let face = |x: usize| {
                    (x < dims).then(|| {
                        let v = vel[x];
                        (
                            Flux::new(&b[c], &l, x),
                            v.at(&l, [0; 3]),
                            v.at(&l, unit(x)),
                            h[x],
                        )
                    })
                };
                let other = [face(1), face(2)];
                for n in 0..l.len {
                    // x-faces i, i+1 (between cells i−1|i and i|i+1); then the others'.
                    let (fw, fe) = (bx.lower(uw[n], n), bx.upper(ue[n], n));
                    let mut r = (re[n] * fe - rw[n] * fw) / (rc[n] * h[0]);
                    for (f, vl, vu, hx) in other.iter().flatten() {
                        r += (f.upper(vu[n], n) - f.lower(vl[n], n)) / hx;
                    }
                    row[n] = r;
                }
            });
        }
        for ((p, &(axes, at)), out) in shear_pairs(dims).iter().enumerate().zip(shear) {
            let edges = clip(self.near_c.edges(g, at).region(g), Region::of(g, at));
            // Along x the radius factors of the box's faces and of the edge: at the cell
            // centres i−1, i and the face i for an edge on x-faces, else as a cell's.
            let nodal_x = at.nodal()[0] == 1;
            let faces = [0, 1, 2].map(|x| advecting(axes, x));
            edges.for_each(out, |l, row| {
                let flux = |x: usize| {
                    (x < dims).then(|| {
                        let [up, low] = faces[x];
                        let (up, low) = (Four::new(vel[x], &l, up), Four::new(vel[x], &l, low));
                        (Flux::new(&b[3 + p], &l, x), up, low, h[x])
                    })
                };
                let fluxes = [flux(0), flux(1), flux(2)];
                let (ru, rl, rv) = if nodal_x {
                    (m.rc_on(&l, 0), m.rc_on(&l, -1), m.rx_on(&l, 0))
                } else {
                    (m.rx_on(&l, 1), m.rx_on(&l, 0), m.rc_on(&l, 0))
                };
                for n in 0..l.len {
                    let r = rv[n];
                    if r == 0.0 {
                        row[n] = 0.0;
                        continue;
                    }
                    let mut sum = 0.0;
                    for (x, (f, up, low, hx)) in fluxes.iter().flatten().enumerate() {
                        let (fu, fl) = (f.upper(up.avg(n), n), f.lower(low.avg(n), n));
                        if x == 0 {
                            sum = (ru[n] * fu - rl[n] * fl) / (r * hx);
                        } else {
                            sum += (fu - fl) / hx;
                        }
                    }
                    row[n] = sum;
                }
            });
        }
    }

    /// The interface relaxation of the edges' shear for this step (see "Interface corners"):
    /// per shear pair, evaluates the law on the solid's edges of `start` (Bⁿ), folds the
    /// linearised relaxation's explicit part into the pair's `explicit` component and sets its
    /// divisor `relax[p]` (1 away from interfaces).
    pub(super) fn relaxation(
        &mut self,
        law: &dyn ConstitutiveLaw,
        start: &[Field],
        dt: f64,
        explicit: &mut [Field],
        relax: &mut [Field],
    ) -> Result<(), String> {
        for (p, relax) in relax.iter_mut().enumerate().take(self.edge.len()) {
            self.relax_pair(law, start, dt, explicit, relax, p)?;
        }
        Ok(())
    }

    /// [`Kernels::relaxation`] of the shear pair `p` (axes `[a, b]`).
    fn relax_pair(
        &mut self,
        law: &dyn ConstitutiveLaw,
        start: &[Field],
        dt: f64,
        explicit: &mut [Field],
        relax: &mut Field,
        p: usize,
    ) -> Result<(), String> {
        relax.fill(1.0);
        // Only the solid's edges relax (`r > 0` needs a solid cell beside the edge).
        let edges = self.solid_k[p].region(&self.grid);
        self.gather_edges(start, p);
        let any = edges.fold(
            false,
            |l| on(&self.edge[p].rc, &l).iter().any(|&r| r > 0.0),
            |a, p| a || p,
        );
        if !any {
            return Ok(());
        }
        // On the edges touching solid only (the law may be undefined at B = 0).
        self.batch(law, Some(p), true, &[0.0; 6])?;
        let (m, c) = (self.m, 3 + p);
        let [pa, pb] = SHEAR[p].0;
        let around = cells_of_edge(SHEAR[p].0);
        let third = (self.grid.dims() == 3).then(|| third_axis_pairs(pa, pb));
        for l in (0..edges.lines()).map(|n| edges.line(n)) {
            for (n, at) in l.indices().enumerate() {
                let rc = self.edge[p].rc[at];
                if rc == 0.0 {
                    continue;
                }
                let q = l.n * l.len + n;
                let (kb, kt) = (&self.kb[p][q * m..], &self.kt[p][q * m..]);
                // The shear-rate change times the B it stretches (as in `stretch_in`).
                let fy = self.edge[p].share[at];
                let bbar = fy * kb[pb] + (1.0 - fy) * kb[pa];
                let jt = self.kj[p][q * m * m + c * (m + 1)].max(0.0);
                let lambda = dt * rc * bbar;
                // The relaxation at θ_r = ½ + ½ z/(1 + z), `z = λ J` its stiffness over the
                // step: trapezoidal where it is slow (θ_r − ½ = O(Δt), second order), backward
                // Euler where it is stiff (a solid in air; monotone for every z).
                let z = lambda * jt;
                let th = 0.5 + 0.5 * z / (1.0 + z);
                let bab = start[c][at];
                relax[at] = 1.0 / (1.0 + th * z);
                explicit[c][at] -= lambda * (kt[c] - th * jt * bab);
                // The same relaxation of the solid's shear rate stretches the normal components
                // of the four cells around (explicit, at Bⁿ): `Ḃ_aa = 2 L_ab B_ab`,
                // `Ḃ_bb = 2 L_ba B_ab` averaged over a centre's edges, with the share n_b² to
                // L_ab. The relaxation as the edge's implicit step applies it (× q): bounded
                // where it is stiff (a solid in air), where the explicit rate would blow up.
                let d = 0.5 * dt * rc * kt[c] * bab * relax[at];
                for s in around {
                    explicit[pa][plus(at, s)] -= fy * d;
                    explicit[pb][plus(at, s)] -= (1.0 - fy) * d;
                }
                // In three dimensions the same change of `L_ab` (`L_ba`) stretches the shear of
                // the pair (a, c) (of (b, c)) on the edges around: `Ḃ_ac = L_ab B_bc`,
                // `Ḃ_bc = L_ba B_ac`, a quarter on each of the four edges whose average takes
                // this one (B at this edge as the batch gathers it).
                if let Some([(qa, sa), (qb, sb)]) = third {
                    let e = 0.5 * dt * rc * kt[c] * relax[at];
                    let (bbc, bac) = (kb[3 + qb], kb[3 + qa]);
                    for (ta, tb) in sa.into_iter().zip(sb) {
                        explicit[3 + qa][plus(at, ta)] -= 0.5 * fy * e * bbc;
                        explicit[3 + qb][plus(at, tb)] -= 0.5 * (1.0 - fy) * e * bac;
                    }
                }
            }
        }
        Ok(())
    }
}

/// In three dimensions, for the shear pair of axes `(a, b)`: the pairs `(a, c)` and `(b, c)` with
/// the third axis `c`, each with the shifts to its edges whose averages take the pair `(a, b)`'s
/// edge (`I + {0, +e_c} × {0, −e_b}` and `I + {0, +e_c} × {0, −e_a}`).
fn third_axis_pairs(pa: usize, pb: usize) -> [(usize, [Index; 4]); 2] {
    let pc = 3 - pa - pb;
    let shifts = |x: usize| {
        let (ex, ec) = (minus(x), unit(pc));
        [[0; 3], ex, ec, plus(ex, ec)]
    };
    [(PAIR[pa][pc], shifts(pb)), (PAIR[pb][pc], shifts(pa))]
}

/// `r` restricted to `to` along every axis.
fn clip(r: Region, to: Region) -> Region {
    (0..3).fold(r, |r, a| {
        r.range(a, r.lo()[a].max(to.lo()[a]), r.hi()[a].min(to.hi()[a]))
    })
}

/// The shifts of the velocity component `u_x` averaged on the upper and the lower face along
/// axis `x` of the control volume of an edge of the pair `[p, q]`, each four points with the
/// offset along `p` varying fastest: along a nodal axis the two faces between the edge's
/// neighbours along `x` (the cell centres), the other nodal axis at the edge's two cells; along
/// the centred axis the cell's faces, at the four cells around the edge.
fn advecting([p, q]: [usize; 2], x: usize) -> [[Index; 4]; 2] {
    let points = |op: [isize; 2], oq: [isize; 2], extra: isize| {
        let at = |a: isize, b: isize| {
            let mut s = [0; 3];
            (s[p], s[q]) = (a, b);
            if x != p && x != q {
                s[x] = extra;
            }
            s
        };
        [
            at(op[0], oq[0]),
            at(op[1], oq[0]),
            at(op[0], oq[1]),
            at(op[1], oq[1]),
        ]
    };
    if x == p {
        [points([0, 1], [0, -1], 0), points([-1, 0], [0, -1], 0)]
    } else if x == q {
        [points([0, -1], [0, 1], 0), points([0, -1], [-1, 0], 0)]
    } else {
        [points([0, -1], [0, -1], 1), points([0, -1], [0, -1], 0)]
    }
}

/// The columns of the edge region `edges` (within the storage `lo..hi`) where the bulk
/// stencil of the derivative along `d`, the cells across along `x`, fits: `I − 2e_d … I + e_d`
/// and the cells at `− e_x`.
fn bulk_columns(edges: &Region, lo: Index, hi: Index, d: usize, x: usize) -> Region {
    let (mut c0, mut c1) = (edges.lo()[0], edges.hi()[0]);
    if d == 0 {
        (c0, c1) = (c0.max(lo[0] + 2), c1.min(hi[0] - 2));
    }
    if x == 0 {
        c0 = c0.max(lo[0] + 1);
    }
    edges.range(0, c0, c1)
}

/// Whether the bulk stencil of [`bulk_columns`] fits along the line's other axes.
fn bulk_fits(l: &Line, lo: Index, hi: Index, d: usize, x: usize) -> bool {
    (d == 0 || (lo[d] + 2..hi[d] - 2).contains(&l.start[d])) && (x == 0 || l.start[x] > lo[x])
}
