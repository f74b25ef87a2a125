//! The law batches (stress and tangent at centres and on the edges of each shear pair,
//! weighted), the block multigrid's effective stiffness, and the stress divergence on the faces.
//!
//! **The law on the full tensor.** On a two-dimensional grid the law sees `[11, 22, 33, 12]`
//! (law ABI version 1's in-plane tensor), on a three-dimensional one `[11, 22, 33, 12, 23, 13]`
//! (version 2's). At a centre the normal components are the cell's own and each shear the mean
//! of the cell's four edges of its pair; on an edge of the pair `(a, b)` the normal components
//! are the solid-weighted average of its four cells, its own shear is its own, and (three
//! dimensions) each other shear is the mean of the four edges of its pair around the edge
//! (the pair `(a, c)` at `I − {0, e_b} + {0, e_c}`, `(b, c)` at `I − {0, e_a} + {0, e_c}`).
//! The stress a location applies is its own rows: 11, 22, 33 at centres, `τ_ab` on the
//! `(a, b)`-edges.
//!
//! **The divergence.** On the faces normal to `a`, volume-weighted,
//! `V (∇·τ)_a = Σ_b A_b (τ_ab(I + ½e_b) − τ_ab(I − ½e_b))`, `A_b = Π_{c≠b} h_c` the face
//! area across `b` (radius-weighted along r, less the hoop term `V τ_θθ / r` on the radial
//! faces of an axisymmetric grid): the normal stress from the two cells, each shear from the
//! two edges of its pair beside the face.

use super::{Four, Kernels, PAIR, SHEAR, cells_of_edge, corner_weights, edges_of_cell, plus};
use efsi_core::operators::minus;
use efsi_core::{Field, Index, Line, Region, Stagger, unit};

/// The face location of each axis' normal velocity.
const FACES: [Stagger; 3] = [Stagger::XFace, Stagger::YFace, Stagger::ZFace];
use efsi_laws_host::ConstitutiveLaw;
use efsi_laws_host::LawError;

/// The law on a flat batch of `m`-component tensors: `b` into `tau` (and the `m²`-entry tangent
/// into `tangent`): [`ConstitutiveLaw::evaluate`] for `m = 4`, `evaluate_full` for `m = 6`.
pub(super) fn eval(
    law: &dyn ConstitutiveLaw,
    m: usize,
    b: &[f64],
    tau: &mut [f64],
    tangent: Option<&mut [f64]>,
) -> Result<(), LawError> {
    if m == 4 {
        let j = tangent.map(|j| j.as_chunks_mut::<16>().0);
        law.evaluate(b.as_chunks::<4>().0, tau.as_chunks_mut::<4>().0, j)
    } else {
        let j = tangent.map(|j| j.as_chunks_mut::<36>().0);
        law.evaluate_full(b.as_chunks::<6>().0, tau.as_chunks_mut::<6>().0, j)
    }
}

/// The law's stress in the undeformed state `B = I` (the same at every point), its first `m`
/// components.
pub(super) fn rest_stress(law: &dyn ConstitutiveLaw, m: usize) -> Result<[f64; 6], String> {
    let mut b = [0.0; 6];
    b[..3].fill(1.0);
    let mut r = [0.0; 6];
    eval(law, m, &b[..m], &mut r[..m], None).map_err(|e| e.to_string())?;
    Ok(r)
}

/// `a · x` over the `x.len()` entries, summed in order from the first product.
#[inline(always)]
fn dot(a: &[f64], x: &[f64]) -> f64 {
    let a = &a[..x.len()];
    let mut s = a[0] * x[0];
    for k in 1..x.len() {
        s += a[k] * x[k];
    }
    s
}

/// Swap the points `p` and `q` (`m` entries each) of a flat batch.
#[inline(always)]
fn swap(v: &mut [f64], m: usize, p: usize, q: usize) {
    let (p, q) = (p.min(q), p.max(q));
    if p != q {
        // One block move each way (the blocks are disjoint: `p < q`).
        let (lo, hi) = v.split_at_mut(q * m);
        lo[p * m..(p + 1) * m].swap_with_slice(&mut hi[..m]);
    }
}

/// `eval(b, tau, tangent)` on the points `q` of a flat batch of `m`-component tensors with
/// `live(q)` only, in one call: the live points are moved to the front (a sequence of swaps),
/// evaluated, and the swaps undone, so that every array is back in the batch's order with the
/// live points' results, the stress `dead` and a zero tangent at the others, and `b` unchanged.
/// An error's cell is the batch index `q` of the live point it names.
fn live_only(
    live: impl Fn(usize) -> bool,
    (m, n): (usize, usize),
    dead: &[f64],
    b: &mut [f64],
    tau: &mut [f64],
    mut tangent: Option<&mut [f64]>,
    eval: impl FnOnce(&[f64], &mut [f64], Option<&mut [f64]>) -> Result<(), LawError>,
) -> Result<(), LawError> {
    let mut k = 0;
    for q in 0..n {
        if live(q) {
            swap(b, m, k, q);
            k += 1;
        }
    }
    let result = eval(
        &b[..k * m],
        &mut tau[..k * m],
        tangent.as_deref_mut().map(|j| &mut j[..k * m * m]),
    );
    for t in tau[k * m..n * m].chunks_exact_mut(m) {
        t.copy_from_slice(dead);
    }
    if let Some(j) = tangent.as_deref_mut() {
        j[k * m * m..n * m * m].fill(0.0);
    }
    for q in (0..n).rev() {
        if live(q) {
            k -= 1;
            swap(b, m, k, q);
            swap(tau, m, k, q);
            if let Some(j) = tangent.as_deref_mut() {
                swap(j, m * m, k, q);
            }
        }
    }
    result.map_err(|mut e| {
        e.cell = e.cell.and_then(|c| (0..n).filter(|&q| live(q)).nth(c));
        e
    })
}

/// The shifts of the four edges of the shear pair `q` around an edge of the pair `p` (`p ≠ q`,
/// three dimensions): with `y` the axis of `p` not in `q` and `c` the axis of `q` not in `p`,
/// `{0, −e_y} × {0, +e_c}`.
fn around(p: usize, q: usize) -> [Index; 4] {
    let (pp, qq) = (SHEAR[p].0, SHEAR[q].0);
    let y = if qq.contains(&pp[0]) { pp[1] } else { pp[0] };
    let c = if pp.contains(&qq[0]) { qq[1] } else { qq[0] };
    let (ey, ec) = (minus(y), unit(c));
    [[0; 3], ey, ec, plus(ey, ec)]
}

impl Kernels {
    /// The law on the centre batch (`cb` into `ct`, and `cj` if `tangent`), or on the batch of
    /// the edges of the shear pair `edge` (`kb`, `kt`, `kj`), at the points with a weight only
    /// (`w > 0` at a centre, `w_k > 0` on an edge: those holding or touching solid), in one
    /// call; the others get the stress `dead` and a zero tangent ([`live_only`]). A law's error
    /// names the grid point.
    pub(super) fn batch(
        &mut self,
        law: &dyn ConstitutiveLaw,
        edge: Option<usize>,
        tangent: bool,
        dead: &[f64],
    ) -> Result<(), String> {
        let (win, weights) = match edge {
            Some(p) => (self.solid_k[p], &self.edge[p].wk),
            None => (self.solid_c, &self.w),
        };
        let (m, n) = (self.m, win.points());
        // Whether each point of the window (in its line order) is live.
        let mut mask = std::mem::take(&mut self.mask);
        mask.clear();
        if n > 0 {
            let r = win.region(&self.grid);
            for l in (0..r.lines()).map(|k| r.line(k)) {
                mask.extend(weights.at(&l, [0; 3]).iter().map(|&w| w != 0.0));
            }
        }
        debug_assert_eq!(mask.len(), n, "one flag per point of the window");
        let live = |q: usize| mask[q];
        let (b, t, j) = match edge {
            Some(p) => (&mut self.kb[p], &mut self.kt[p], &mut self.kj[p]),
            None => (&mut self.cb, &mut self.ct, &mut self.cj),
        };
        let result = live_only(
            live,
            (m, n),
            &dead[..m],
            &mut b[..n * m],
            &mut t[..n * m],
            tangent.then_some(&mut j[..n * m * m]),
            |b, t, j| eval(law, m, b, t, j),
        );
        self.mask = mask;
        result.map_err(|e| self.locate(e, edge))
    }

    /// τ (and J if `tangent`) of `b` into the batches and `tau`. The law sees the solid's
    /// centres and edges only ([`Kernels::solid_c`], `solid_k`, packed in that order: see
    /// [`Kernels::ci`]), and of those only the ones with a weight (`w > 0`, `w_k > 0`): it is
    /// never called on a point without solid. Elsewhere the weights `w`, `1/κ` vanish and so
    /// does `tau`.
    pub(super) fn evaluate(
        &mut self,
        law: &dyn ConstitutiveLaw,
        b: &[Field],
        tau: &mut [Field],
        tangent: bool,
    ) -> Result<(), String> {
        let (cw, m) = (self.solid_c, self.m);
        let nc = cw.points();
        self.gather_batches(b);
        for f in tau.iter_mut() {
            f.fill(0.0);
        }
        if nc == 0 {
            return Ok(());
        }
        // The law is called only where the weight is not zero (centres with solid, edges
        // touching it): the window's other points hold no solid — the fluid's B = I at a
        // centre, nothing (B̃ = 0, outside many laws' domains) on an edge. Their stress is the
        // rest stress at a centre (nothing once it is subtracted) and zero on an edge, their
        // tangent zero; all of it is weighted by zero.
        let r = rest_stress(law, m)?;
        self.batch(law, None, tangent, &r)?;
        for p in 0..self.edge.len() {
            self.batch(law, Some(p), tangent, &[0.0; 6])?;
        }
        // Subtract the stress of the stress-free state B = I (B̃ = w I): isotropic, so only a
        // change of pressure — but it jumps across the interface, and fed through the implicit
        // solve it would not stay a pure gradient (see "Stress-free reference" in the docs).
        for t in self.ct[..nc * m].chunks_exact_mut(m) {
            for c in 0..3 {
                t[c] -= r[c];
            }
        }
        let (normal, shear) = tau.split_at_mut(3);
        let [t11, t22, t33] = normal else {
            unreachable!("three normal components")
        };
        let (ct, w) = (&self.ct, &self.w);
        cw.region(&self.grid)
            .for_each((t11, t22, t33), |l, (t11, t22, t33)| {
                let w = w.at(&l, [0; 3]);
                let rows = ct[l.n * l.len * m..][..l.len * m].chunks_exact(m);
                for (n, t) in rows.enumerate() {
                    t11[n] = w[n] * t[0];
                    t22[n] = w[n] * t[1];
                    t33[n] = w[n] * t[2];
                }
            });
        for (p, tab) in shear.iter_mut().enumerate().take(self.edge.len()) {
            let (kt, ks) = (&self.kt[p], &self.edge[p].ks);
            self.solid_k[p].region(&self.grid).for_each(tab, |l, tab| {
                let ks = ks.at(&l, [0; 3]);
                let rows = kt[l.n * l.len * m..][..l.len * m].chunks_exact(m);
                for (n, t) in rows.enumerate() {
                    tab[n] = ks[n] * t[3 + p];
                }
            });
        }
        Ok(())
    }

    /// The shears of `b` at the centres of `l`: each the mean of the cell's four edges of its
    /// pair (the last pair repeated past the grid's pairs).
    pub(super) fn centre_shears<'a>(&self, b: &'a [Field], l: &Line) -> [Four<'a>; 3] {
        let four = |p: usize| Four::new(&b[3 + p], l, edges_of_cell(SHEAR[p].0));
        let first = four(0);
        if self.edge.len() == 3 {
            [first, four(1), four(2)]
        } else {
            [first; 3]
        }
    }

    /// The batches' B̃ from `b`: at the solid's centres ([`Kernels::solid_c`]) the normal
    /// components and each shear the mean of the cell's edges of its pair, on the solid's
    /// edges ([`Kernels::gather_edges`]).
    fn gather_batches(&mut self, b: &[Field]) {
        let m = self.m;
        let cells = self.solid_c.region(&self.grid);
        for l in (0..cells.lines()).map(|n| cells.line(n)) {
            let [b11, b22, b33] = [0, 1, 2].map(|c| b[c].at(&l, [0; 3]));
            let sh = self.centre_shears(b, &l);
            let rows = self.cb[l.n * l.len * m..][..l.len * m].chunks_exact_mut(m);
            for (n, x) in rows.enumerate() {
                x[..3].copy_from_slice(&[b11[n], b22[n], b33[n]]);
                for (x, s) in x[3..].iter_mut().zip(&sh) {
                    *x = s.avg(n);
                }
            }
        }
        for p in 0..self.edge.len() {
            self.gather_edges(b, p);
        }
    }

    /// The batch of the shear pair `p`'s B̃ from `b` on the solid's edges
    /// ([`Kernels::solid_k`]): the solid-weighted normal components, the edge's own shear and
    /// (three dimensions) the others averaged around it, times the edge's weight `w_k`.
    pub(super) fn gather_edges(&mut self, b: &[Field], p: usize) {
        if self.m == 6 {
            self.gather_edges_m::<6>(b, p);
        } else {
            self.gather_edges_m::<4>(b, p);
        }
    }

    /// [`Kernels::gather_edges`] on tensors of `M` components.
    fn gather_edges_m<const M: usize>(&mut self, b: &[Field], p: usize) {
        let pairs = M - 3;
        let edges = self.solid_k[p].region(&self.grid);
        let cells = cells_of_edge(SHEAR[p].0);
        let kb = &mut self.kb[p];
        for l in (0..edges.lines()).map(|n| edges.line(n)) {
            let wt = corner_weights(&self.edge[p].kwt, &l);
            let b11 = Four::new(&b[0], &l, cells);
            let b22 = Four::new(&b[1], &l, cells);
            let b33 = Four::new(&b[2], &l, cells);
            let (own, w) = (b[3 + p].at(&l, [0; 3]), self.edge[p].wk.at(&l, [0; 3]));
            // The other pairs' shears around the edge (three dimensions only).
            let others = (M == 6).then(|| {
                let four = |q: usize| match q == p {
                    true => Four::new(&b[3 + q], &l, [[0; 3]; 4]),
                    false => Four::new(&b[3 + q], &l, around(p, q)),
                };
                [four(0), four(1), four(2)]
            });
            let rows = kb[l.n * l.len * M..][..l.len * M].chunks_exact_mut(M);
            for (n, x) in rows.enumerate() {
                x[0] = w[n] * b11.weighted(&wt, n);
                x[1] = w[n] * b22.weighted(&wt, n);
                x[2] = w[n] * b33.weighted(&wt, n);
                x[3 + p] = w[n] * own[n];
                if let Some(others) = &others {
                    for q in (0..pairs).filter(|&q| q != p) {
                        x[3 + q] = w[n] * others[q].avg(n);
                    }
                }
            }
        }
    }

    /// `dtau = J·db` with the tangents of the last [`Kernels::evaluate`] (rows 11, 22, 33 at
    /// centres, `ab` on the `(a, b)`-edges; the other components gathered to the location as
    /// the batches gather B̃). Only at the solid's centres and edges ([`Kernels::solid_c`],
    /// `solid_k`): `dtau` is zero elsewhere, and there it is left untouched.
    pub(super) fn apply_tangent(&self, db: &[Field], dtau: &mut [Field]) {
        if self.m == 6 {
            self.apply_tangent_m::<6>(db, dtau);
        } else {
            self.apply_tangent_m::<4>(db, dtau);
        }
    }

    /// [`Kernels::apply_tangent`] on tensors of `M` components.
    fn apply_tangent_m<const M: usize>(&self, db: &[Field], dtau: &mut [Field]) {
        let (g, pairs) = (&self.grid, M - 3);
        let (normal, shear) = dtau.split_at_mut(3);
        let [t11, t22, t33] = normal else {
            unreachable!("three normal components")
        };
        self.solid_c
            .region(g)
            .for_each((t11, t22, t33), |l, (t11, t22, t33)| {
                let rows = [t11, t22, t33];
                let (w, d11) = (self.w.at(&l, [0; 3]), db[0].at(&l, [0; 3]));
                let (d22, d33) = (db[1].at(&l, [0; 3]), db[2].at(&l, [0; 3]));
                let sh = self.centre_shears(db, &l);
                let jms = self.cj[l.n * l.len * M * M..][..l.len * M * M].chunks_exact(M * M);
                for (n, jm) in jms.enumerate() {
                    let mut x = [0.0; M];
                    (x[0], x[1], x[2]) = (d11[n], d22[n], d33[n]);
                    for c in 3..M {
                        x[c] = sh[c - 3].avg(n);
                    }
                    for c in 0..3 {
                        rows[c][n] = w[n] * dot(&jm[M * c..], &x);
                    }
                }
            });
        for (p, tab) in shear.iter_mut().enumerate().take(pairs) {
            let cells = cells_of_edge(SHEAR[p].0);
            let kj = &self.kj[p];
            self.solid_k[p].region(g).for_each(tab, |l, tab| {
                let wt = corner_weights(&self.edge[p].kwt, &l);
                let d11 = Four::new(&db[0], &l, cells);
                let d22 = Four::new(&db[1], &l, cells);
                let d33 = Four::new(&db[2], &l, cells);
                let (w, own) = (self.edge[p].wk.at(&l, [0; 3]), db[3 + p].at(&l, [0; 3]));
                let ks = self.edge[p].ks.at(&l, [0; 3]);
                // The other pairs' shears around the edge (three dimensions only).
                let others = (M == 6).then(|| {
                    let four = |q: usize| match q == p {
                        true => Four::new(&db[3 + q], &l, [[0; 3]; 4]),
                        false => Four::new(&db[3 + q], &l, around(p, q)),
                    };
                    [four(0), four(1), four(2)]
                });
                let jms = kj[l.n * l.len * M * M..][..l.len * M * M].chunks_exact(M * M);
                for (n, jm) in jms.enumerate() {
                    let mut x = [0.0; M];
                    x[0] = w[n] * d11.weighted(&wt, n);
                    x[1] = w[n] * d22.weighted(&wt, n);
                    x[2] = w[n] * d33.weighted(&wt, n);
                    x[3 + p] = w[n] * own[n];
                    if let Some(others) = &others {
                        for q in (0..pairs).filter(|&q| q != p) {
                            x[3 + q] = w[n] * others[q].avg(n);
                        }
                    }
                    tab[n] = ks[n] * dot(&jm[M * (3 + p)..], &x);
                }
            });
        }
    }

    /// `eta += a·G_eff`: the stiffness of the tangent of the last [`Kernels::evaluate`] as the
    /// viscosity it acts like in the implicit system (module docs: `J : H(δ) ≈ 2 G_eff D(δ)`).
    /// At a centre `G_eff` is the mean of `J_aaaa B̃_aa` over the grid's axes (the normal
    /// stresses), on an edge of the pair `(a, b)` `G_eff = J_abab (n_b² B̃_bb + n_a² B̃_aa)`
    /// times the interface factors of the shear in series (stress `1/κ`, shear rate `s`) and
    /// this step's relaxation divisor `relax` of the pair; negative values count zero.
    /// `eta_e` holds one field per shear pair.
    pub(super) fn stiffness(
        &mut self,
        relax: &[Field],
        a: f64,
        eta: &mut Field,
        eta_e: &mut [Field],
    ) {
        if self.place.is_none() {
            return self.stiffness_here(relax, a, eta, eta_e);
        }
        // On a window: the grid's values there copied in, added to, and the points written
        // copied back.
        let o = self.origin;
        let mut w = std::mem::take(&mut self.eta);
        let (wc, we) = w.split_at_mut(1);
        super::bodies::copy_in(eta, &mut wc[0], o);
        for (w, f) in we.iter_mut().zip(&*eta_e) {
            super::bodies::copy_in(f, w, o);
        }
        self.stiffness_here(relax, a, &mut wc[0], we);
        let g = &self.grid;
        super::bodies::copy_out(&wc[0], eta, o, &self.solid_c.region(g));
        for ((w, f), k) in we.iter().zip(eta_e.iter_mut()).zip(&self.solid_k) {
            super::bodies::copy_out(w, f, o, &k.region(g));
        }
        self.eta = w;
    }

    /// [`Kernels::stiffness`] into fields of the kernels' own grid.
    fn stiffness_here(&self, relax: &[Field], a: f64, eta: &mut Field, eta_e: &mut [Field]) {
        if self.m == 6 {
            self.stiffness_m::<6>(relax, a, eta, eta_e);
        } else {
            self.stiffness_m::<4>(relax, a, eta, eta_e);
        }
    }

    /// [`Kernels::stiffness`] on tensors of `M` components (`M = 4`: two axes, `6`: three).
    fn stiffness_m<const M: usize>(
        &self,
        relax: &[Field],
        a: f64,
        eta: &mut Field,
        eta_e: &mut [Field],
    ) {
        let g = &self.grid;
        self.solid_c.region(g).for_each(eta, |l, eta| {
            let w = self.w.at(&l, [0; 3]);
            let q0 = l.n * l.len;
            let jms = self.cj[q0 * M * M..][..l.len * M * M].chunks_exact(M * M);
            let bs = self.cb[q0 * M..][..l.len * M].chunks_exact(M);
            for (n, ((eta, jm), b)) in eta.iter_mut().zip(jms).zip(bs).enumerate() {
                let g = if M == 4 {
                    w[n] * 0.5 * (jm[0] * b[0] + jm[M + 1] * b[1])
                } else {
                    w[n] * (jm[0] * b[0] + jm[M + 1] * b[1] + jm[2 * M + 2] * b[2]) / 3.0
                };
                *eta += a * g.max(0.0);
            }
        });
        for (p, eta) in eta_e.iter_mut().enumerate().take(M - 3) {
            let [pa, pb] = SHEAR[p].0;
            let e = &self.edge[p];
            let (kj, kb, d) = (&self.kj[p], &self.kb[p], (3 + p) * (M + 1));
            self.solid_k[p].region(g).for_each(eta, |l, eta| {
                let (ks, sf) = (e.ks.at(&l, [0; 3]), e.sf.at(&l, [0; 3]));
                let (relax, fy) = (relax[p].at(&l, [0; 3]), e.share.at(&l, [0; 3]));
                let q0 = l.n * l.len;
                let jms = kj[q0 * M * M..][..l.len * M * M].chunks_exact(M * M);
                let bs = kb[q0 * M..][..l.len * M].chunks_exact(M);
                for (n, ((eta, jm), b)) in eta.iter_mut().zip(jms).zip(bs).enumerate() {
                    let f = ks[n] * sf[n] * relax[n];
                    let g = f * jm[d] * (fy[n] * b[pb] + (1.0 - fy[n]) * b[pa]);
                    *eta += a * g.max(0.0);
                }
            });
        }
    }

    /// Volume-weighted `(∇·τ)_a` on the faces normal to `a` of `l` of a grid of `D` axes:
    /// `f(n, value)` for each point `n` (see the module docs).
    #[inline(always)]
    fn force_axis<const D: usize>(
        &self,
        tau: &[Field],
        a: usize,
        l: &Line,
        mut f: impl FnMut(usize, f64),
    ) {
        let g = &self.grid;
        let (m, area) = (&g.metric, &self.area);
        let own = if a == 0 { m.rx_on(l, 0) } else { m.rc_on(l, 0) };
        // Along x the radii of the two stress points; along the others the face's.
        let (rlo, rhi) = if a == 0 {
            (m.rc_on(l, -1), m.rc_on(l, 0))
        } else {
            (m.rx_on(l, 0), m.rx_on(l, 1))
        };
        // τ_ab below and above the face along b.
        let mut t: [(&[f64], &[f64]); D] = [(&[], &[]); D];
        for (b, t) in t.iter_mut().enumerate() {
            *t = if b == a {
                (tau[a].at(l, minus(a)), tau[a].at(l, [0; 3]))
            } else {
                let c = &tau[3 + PAIR[a][b]];
                (c.at(l, [0; 3]), c.at(l, unit(b)))
            };
        }
        let hoop = (a == 0 && D == 2).then(|| {
            let t33 = (tau[2].at(l, minus(0)), tau[2].at(l, [0; 3]));
            (m.hoop_x_on(l, 0), t33, g.dx * g.dy)
        });
        for n in 0..l.len {
            let mut s = area[0] * (rhi[n] * t[0].1[n] - rlo[n] * t[0].0[n]);
            for b in 1..D {
                s += area[b] * own[n] * (t[b].1[n] - t[b].0[n]);
            }
            if let Some((hoop, (t33w, t33e), vol)) = hoop {
                let t33f = 0.5 * (t33w[n] + t33e[n]);
                s -= vol * own[n] * hoop[n] * t33f;
            }
            f(n, s);
        }
    }

    /// [`Kernels::force_axis`] on the grid's axes.
    #[inline(always)]
    fn force_on(&self, tau: &[Field], a: usize, l: &Line, f: impl FnMut(usize, f64)) {
        if self.grid.is_3d() {
            self.force_axis::<3>(tau, a, l, f);
        } else {
            self.force_axis::<2>(tau, a, l, f);
        }
    }

    /// Volume-weighted `∇·τ` on the unknown faces, into `out` (compact).
    pub(super) fn force(&self, tau: &[Field], out: &mut [f64]) {
        if self.place.is_some() {
            // On a window `tau` vanishes outside the solid, and so does the force.
            out.fill(0.0);
            return self.force_sub(tau, -1.0, out);
        }
        for (a, o) in self.faces.split_mut(out).into_iter().enumerate() {
            let r = self.faces.region(a);
            for l in (0..r.lines()).map(|n| r.line(n)) {
                let row = &mut o[l.n * l.len..][..l.len];
                self.force_on(tau, a, &l, |n, f| row[n] = f);
            }
        }
    }

    /// `y −= a·vol·∇·τ` for a `tau` that vanishes outside the solid's centres and edges
    /// ([`Kernels::solid_c`], `solid_k`): only the unknown faces next to them see a force —
    /// on a face normal to `a` the normal stress at the two centres across it and each shear
    /// at the two edges of its pair beside it: the faces of the solid's centres, and one row
    /// more on each side across the other axes.
    pub(super) fn force_sub(&self, tau: &[Field], a: f64, y: &mut [f64]) {
        let cw = self.solid_c;
        if cw.points() == 0 {
            return;
        }
        let (dims, o) = (self.grid.dims(), self.origin);
        // The solid's centres in the whole grid's indices (the faces').
        let (lo, hi) = (plus(cw.lo(), o), plus(cw.hi(), o));
        for (x, y) in self.faces.split_mut(y).into_iter().enumerate().take(dims) {
            let r = self.faces.region(x);
            let mut part = r;
            for b in 0..dims {
                let (rl, rh) = (r.lo()[b], r.hi()[b]);
                let (l0, h0) = if b == x {
                    (lo[b], hi[b] + 1)
                } else {
                    (lo[b] - 1, hi[b] + 1)
                };
                part = part.range(b, l0.max(rl), (h0 + 1).min(rh));
            }
            if self.place.is_none() {
                for l in (0..part.lines()).map(|n| part.line(n)) {
                    let row = &mut y[compact(&r, l.start)..][..l.len];
                    self.force_on(tau, x, &l, |n, f| row[n] -= a * f);
                }
                continue;
            }
            // On a window: the same faces as the window's points, line for line.
            let (pl, ph) = (part.lo(), part.hi());
            let local = (0..3).fold(Region::of(&self.grid, FACES[x]), |r, b| {
                r.range(b, pl[b] - o[b], ph[b] - o[b])
            });
            for n in 0..part.lines() {
                let (lp, l) = (part.line(n), local.line(n));
                let row = &mut y[compact(&r, lp.start)..][..l.len];
                self.force_on(tau, x, &l, |n, f| row[n] -= a * f);
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
