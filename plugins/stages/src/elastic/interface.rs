//! The interface weights: `φ^{1/2}` at centres, the edges' solid fraction from the PLIC
//! quarter cells (lines in two dimensions, the planes' traces in the edges' midpoint sections
//! in three) and their series factors, the solid bounding box, and the reset of pure-fluid
//! cells.

use super::{Four, Kernels, NEAR, PHI_MIN, SHEAR, Window, cells_of_edge, plus, shear_pairs};
use efsi_core::{Field, Index, Line, Region};

/// The least `aκ` the series corner's rates take (see [`sliver_rates`]).
const SLIVER: f64 = 0.1;

/// The solid shear-rate factor `s` and the relaxation coefficient `r` of a series corner
/// (`a` its solid fraction, `aκ = a + μ_s (1 − a)/μ_f > 0`): `s = 1/max(aκ, A)` and
/// `r = (1 − a)/(μ_f max(aκ, A))` with `A` = 0.1.
///
/// In series the solid of a corner is a spring of length `aκ` (`a` for an inviscid solid) in
/// series with the fluid's dashpot: its stiffness `G/(aκ)` and relaxation rate `G r` grow without
/// bound as the corner's solid share goes to zero, a sliver of a cut cell, which only a solid
/// viscosity keeps finite. A purely elastic solid (`μ_s = 0`) whose interface cuts cells
/// arbitrarily (the oscillating disk) then pumps energy in whatever the time step. Below `A`
/// the spring is taken `A` long: `s` and `r` both scale by `aκ/A`, so their ratio, and with it
/// the stress the corner settles to under a sustained shear (`τ_e = (s/r) 2D = μ_f 2D/(1 − a)`,
/// the fluid's), is unchanged; only the relaxation time `μ_f A/((1 − a) G)` is longer than the
/// sliver's own, which matters only where it is not short against the flow. The stress weight
/// `1/κ = a/(aκ)` is untouched. A corner with `aκ ≥ A` (every corner of a solid with
/// `μ_s ≥ A μ_f`, and of an interface on the grid's faces, `a ∈ {0, ½, 1}`) keeps the series
/// closure exactly.
fn sliver_rates(a: f64, ak: f64, mu_f: f64) -> (f64, f64) {
    let k = ak.max(SLIVER);
    (1.0 / k, (1.0 - a) / (mu_f * k))
}

impl Kernels {
    /// The weights `w = φ^{1/2}` (centres, ghosts included) and their edge averages, from `phi`
    /// with ghosts filled; the solid's and the material's windows.
    pub(super) fn set_weights(&mut self, phi: &Field) {
        let g = &self.grid;
        let (n, dims) = (g.n().map(|n| n as isize), g.dims());
        // Every entry, ghosts included.
        Region::whole(g).for_each(&mut self.w, |l, w| {
            for (w, f) in w.iter_mut().zip(phi.at(&l, [0; 3])) {
                *w = if *f < PHI_MIN { 0.0 } else { f.min(1.0).sqrt() };
            }
        });
        let (lo, hi): (Index, Index) = (
            std::array::from_fn(|a| if a < dims { -1 } else { 0 }),
            std::array::from_fn(|a| if a < dims { n[a] } else { 0 }),
        );
        let (c, m) = self.bounding_boxes(phi, (lo, hi));
        self.solid_c = if c.i0 > c.i1 { Window::EMPTY } else { c };
        let solid_c = self.solid_c;
        for (k, &(_, at)) in self.solid_k.iter_mut().zip(shear_pairs(dims)) {
            *k = solid_c.edges(g, at);
        }
        // Where B can matter: the material grown by `NEAR` cells (see `Kernels::near_c`).
        self.near_c = if m.i0 > m.i1 {
            Window::EMPTY
        } else {
            let (ml, mh) = (m.lo(), m.hi());
            Window::boxed(
                std::array::from_fn(|a| (ml[a] - NEAR).max(lo[a])),
                std::array::from_fn(|a| (mh[a] + NEAR).min(hi[a])),
            )
        };
        // Edges none of whose cells holds solid: no weight, no series factors, the plain
        // average, and a normal of no consequence (it multiplies a zero extra shear rate).
        // Everywhere the first time; then only on the edges the last call set from the solid
        // (elsewhere the fields still hold these values).
        let set = self.edges_set.take();
        for (p, e) in self.edge.iter_mut().enumerate() {
            let fields = [
                (&mut e.wc, 0.0),
                (&mut e.wk, 0.0),
                (&mut e.ks, 0.0),
                (&mut e.rc, 0.0),
                (&mut e.sf, 1.0),
                (&mut e.share, 0.5),
            ];
            let [k0, k1, k2, k3] = &mut e.kwt;
            let quarters = [(k0, 0.25), (k1, 0.25), (k2, 0.25), (k3, 0.25)];
            for (f, v) in fields.into_iter().chain(quarters) {
                match set {
                    None => f.fill(v),
                    Some(set) if set[p].points() > 0 => {
                        set[p].region(g).for_each(f, |_, row| row.fill(v));
                    }
                    Some(_) => {}
                }
            }
        }
        let c = self.solid_c;
        if c.i0 > c.i1 {
            self.edges_set = Some([Window::EMPTY; 3]);
            return;
        }
        self.set_quarters(phi);
        // The edges of the solid's centres, ghost edges included (those whose four cells lie
        // in the fields' storage).
        let whole = Region::whole(&self.grid);
        let (lo, hi) = (whole.lo(), whole.hi());
        let mut set = [Window::EMPTY; 3];
        for (p, &(axes, at)) in shear_pairs(dims).iter().enumerate() {
            let nodal = at.nodal();
            let (cl, ch) = (c.lo(), c.hi());
            set[p] = Window::boxed(
                std::array::from_fn(|a| cl[a].max(lo[a] + nodal[a] as isize)),
                std::array::from_fn(|a| (ch[a] + nodal[a] as isize).min(hi[a] - 1)),
            );
            let edges = set[p].region(&self.grid);
            for l in (0..edges.lines()).map(|n| edges.line(n)) {
                self.set_edges(phi, p, axes, &l);
            }
        }
        self.edges_set = Some(set);
    }

    /// The bounding boxes of the solid (`w > 0`) and of any material (`φ > 0`) among the
    /// centres `lo..=hi` (each empty, `i0 > i1`, where there is none).
    fn bounding_boxes(&self, phi: &Field, (lo, hi): (Index, Index)) -> (Window, Window) {
        let none = Window::boxed(hi, lo);
        let (mut c, mut m) = (none, none);
        let batch = Window::boxed(lo, hi).region(&self.grid);
        for l in (0..batch.lines()).map(|n| batch.line(n)) {
            for (f, b) in [(&self.w, &mut c), (phi, &mut m)] {
                let row = f.at(&l, [0; 3]);
                if let Some(first) = row.iter().position(|&w| w > 0.0) {
                    let last = row.iter().rposition(|&w| w > 0.0).unwrap_or(first);
                    let (mut p, mut q) = (l.start, l.start);
                    (p[0], q[0]) = (p[0] + first as isize, q[0] + last as isize);
                    let (bl, bh) = (b.lo(), b.hi());
                    *b = Window::boxed(
                        std::array::from_fn(|a| bl[a].min(p[a])),
                        std::array::from_fn(|a| bh[a].max(q[a])),
                    );
                }
            }
        }
        (c, m)
    }

    /// The weights of the edges `l` of the shear pair `p` (axes `[a, b]`) from their four
    /// cells: the average `w_c` of their `φ^{1/2}`, the cells' weights in the normal
    /// components, the normal's share `n_b²` and the series factors (`w_k`, `s`, `1/κ`, `r`) of
    /// the interface closure.
    fn set_edges(&mut self, phi: &Field, p: usize, axes: [usize; 2], l: &Line) {
        let cells = cells_of_edge(axes);
        let w = Four::new(&self.w, l, cells);
        // The edge's solid fraction: the four quarter cells around it (each cell's quarter
        // at the edge: the edge is its upper-right, upper-left, lower-right, lower-left).
        let qs = &self.quarter[p];
        let quarter = |n: usize| qs[3 - n].at(l, cells[n]);
        let quarters = [quarter(0), quarter(1), quarter(2), quarter(3)];
        let f = Four::new(phi, l, cells);
        let e = &mut self.edge[p];
        let [k0, k1, k2, k3] = &mut e.kwt;
        let kwt = [k0, k1, k2, k3].map(|k| k.at_mut(l, [0; 3]));
        let (wc, share) = (e.wc.at_mut(l, [0; 3]), e.share.at_mut(l, [0; 3]));
        let (wk, sf) = (e.wk.at_mut(l, [0; 3]), e.sf.at_mut(l, [0; 3]));
        let (ks, rc) = (e.ks.at_mut(l, [0; 3]), e.rc.at_mut(l, [0; 3]));
        for i in 0..l.len {
            let w = [w.get(0, i), w.get(1, i), w.get(2, i), w.get(3, i)];
            wc[i] = 0.25 * (w[0] + w[1] + w[2] + w[3]);
            let q = [
                quarters[0][i],
                quarters[1][i],
                quarters[2][i],
                quarters[3][i],
            ];
            let a = 0.25 * (q[0] + q[1] + q[2] + q[3]);
            let lam = |n: usize| if w[n] > 0.0 { q[n] } else { 0.0 };
            let lam = [lam(0), lam(1), lam(2), lam(3)];
            let sum: f64 = lam.iter().sum();
            let solid = |n: usize| f64::from(u8::from(w[n] > 0.0));
            let solid = [solid(0), solid(1), solid(2), solid(3)];
            let count: f64 = solid.iter().sum();
            // The interface normal ∝ ∇φ across the edge.
            let f = |n: usize| f.get(n, i).clamp(0.0, 1.0);
            let f = [f(0), f(1), f(2), f(3)];
            let gx = f[3] + f[1] - f[2] - f[0];
            let gy = f[3] + f[2] - f[1] - f[0];
            let g2 = gx * gx + gy * gy;
            share[i] = if g2 > 0.0 { gy * gy / g2 } else { 0.5 };
            for n in 0..4 {
                kwt[n][i] = if sum > 0.0 {
                    lam[n] / sum
                } else if count > 0.0 {
                    solid[n] / count
                } else {
                    0.25
                };
            }
            (wk[i], sf[i], ks[i], rc[i]) = series(self.mu_f, self.mu_s, wc[i], a);
        }
    }
}

/// `(w_k, s, 1/κ, r)` of an edge whose cells' weights average `wc` and whose solid fraction is
/// `a` (viscosities `mu_f`, `mu_s`): fluid, solid, interface in series.
fn series(mu_f: f64, mu_s: f64, wc: f64, a: f64) -> (f64, f64, f64, f64) {
    if wc == 0.0 {
        (0.0, 1.0, 0.0, 0.0)
    } else if a >= 1.0 {
        (1.0, 1.0, 1.0, 0.0)
    } else if mu_f == 0.0 {
        // An inviscid fluid carries no shear: neither does the interface.
        (1.0, 1.0, 0.0, 0.0)
    } else {
        // aκ = a + μ_s (1 − a)/μ_f: finite where the edge's quarters hold no solid (a = 0)
        // beside a cell that does.
        let ak = a + mu_s * (1.0 - a) / mu_f;
        if ak > 0.0 {
            let (sf, rc) = sliver_rates(a, ak, mu_f);
            (1.0, sf, a / ak, rc)
        } else {
            // No solid at an inviscid solid's edge: no shear carried.
            (1.0, 1.0, 0.0, 0.0)
        }
    }
}

impl Kernels {
    /// The solid fraction of each quarter of every centre in the plane of each shear pair
    /// ([`Kernels::quarter`]): in a cut cell of the solid's window (within `[−1, n]` along each
    /// axis), the share of the quarter below the cell's interface as the VOF step reconstructs
    /// it — on a two-dimensional grid the PLIC line (Youngs normal, the line cutting the cell's
    /// φ off a `dx × dy` cell), on a three-dimensional one the trace of the PLIC plane (mixed
    /// Youngs–centred normal, the plane cutting φ off the `dx × dy × dz` cell) in the cell's
    /// section through its centre along the third axis, for the pair `(a, b)` the a–b section
    /// ("Edges in three dimensions" in the module docs); elsewhere φ (clamped to `[0, 1]`).
    pub(super) fn set_quarters(&mut self, phi: &Field) {
        let c = self.solid_c;
        let whole = Region::whole(&self.grid);
        // The cells around the solid's edges: its window's rows and one more on each side
        // along y, whole rows (short of the storage's last).
        let (lo, hi) = (whole.lo()[1], whole.hi()[1]);
        let rows = whole.range(1, (c.j0 - 1).max(lo), (c.j1 + 2).min(hi - 1));
        for q in self.quarter.iter_mut().flatten() {
            rows.for_each(q, |l, q| {
                for (w, f) in q.iter_mut().zip(phi.at(&l, [0; 3])) {
                    *w = f.clamp(0.0, 1.0);
                }
            });
        }
        let n = self.grid.n().map(|n| n as isize);
        let dims = self.grid.dims();
        let cut = Window::boxed(
            std::array::from_fn(|a| if a < dims { c.lo()[a].max(-1) } else { 0 }),
            std::array::from_fn(|a| if a < dims { c.hi()[a].min(n[a]) } else { 0 }),
        );
        let cells = cut.region(&self.grid);
        for l in (0..cells.lines()).map(|n| cells.line(n)) {
            for at in l.indices() {
                let f = phi[at];
                if f <= 0.0 || f >= 1.0 {
                    continue;
                }
                if dims == 3 {
                    self.cut_quarters_3d(phi, at);
                } else {
                    self.cut_quarters(phi, at);
                }
            }
        }
    }

    /// The quarters of the cut cell `at` of a two-dimensional grid (see
    /// [`Kernels::set_quarters`]).
    fn cut_quarters(&mut self, phi: &Field, at: Index) {
        let (dx, dy) = (self.grid.dx, self.grid.dy);
        let cl = |di: isize, dj: isize| phi[plus(at, [di, dj, 0])].clamp(0.0, 1.0);
        let b = [
            [cl(-1, -1), cl(0, -1), cl(1, -1)],
            [cl(-1, 0), cl(0, 0), cl(1, 0)],
            [cl(-1, 1), cl(0, 1), cl(1, 1)],
        ];
        let (mx, my) = crate::vof::plic::youngs_normal(&b, dx, dy);
        let line = crate::vof::plic::Line::planar(mx, my, phi[at], dx, dy);
        let (hx, hy) = (0.5 * dx, 0.5 * dy);
        let boxes = [
            ((0.0, 0.0), (hx, hy)),
            ((hx, 0.0), (dx, hy)),
            ((0.0, hy), (hx, dy)),
            ((hx, hy), (dx, dy)),
        ];
        for (n, (lo, hi)) in boxes.into_iter().enumerate() {
            self.quarter[0][n][at] = line.area_fraction(lo, hi).clamp(0.0, 1.0);
        }
    }

    /// The quarters of the cut cell `at` of a three-dimensional grid in the plane of each
    /// shear pair (see [`Kernels::set_quarters`]): for the pair `(a, b)`, the solid share of
    /// each quarter square of the cell's section through its centre along the third axis `c`
    /// (the section through the midpoints of the cell's `(a, b)`-edges), below the trace of the
    /// PLIC plane `n·ξ ≤ α` there, the line `n_a ξ_a + n_b ξ_b ≤ α − n_c h_c/2`.
    fn cut_quarters_3d(&mut self, phi: &Field, at: Index) {
        use crate::vof::plic::rect_fraction;
        use crate::vof::plic3d::{Block, Plane, myc_normal};
        let d = self.grid.h();
        let block: Block = std::array::from_fn(|k| {
            std::array::from_fn(|j| {
                std::array::from_fn(|i| {
                    let s = [i as isize - 1, j as isize - 1, k as isize - 1];
                    phi[plus(at, s)].clamp(0.0, 1.0)
                })
            })
        });
        let Plane { n: m, alpha } = Plane::new(myc_normal(&block, d), phi[at], d);
        for (p, &([a, b], _)) in SHEAR.iter().enumerate() {
            let c = 3 - a - b;
            // The trace's constant in the section ξ_c = h_c/2.
            let section = alpha - m[c] * 0.5 * d[c];
            let (ha, hb) = (0.5 * d[a], 0.5 * d[b]);
            for n in 0..4 {
                let la = if n % 2 == 0 { 0.0 } else { ha };
                let lb = if n < 2 { 0.0 } else { hb };
                let f = rect_fraction(m[a], m[b], section - m[a] * la - m[b] * lb, ha, hb);
                self.quarter[p][n][at] = f.clamp(0.0, 1.0);
            }
        }
    }

    /// Reset B to the identity, and its rates to zero, where there is no solid (`w = 0`): the
    /// fluid has no memory of deformation, and B there only enters neighbouring averages and
    /// fluxes; this keeps it bounded (stale rates would otherwise compound step after step).
    pub(super) fn reset_fluid(&self, d: &mut super::Deformation) {
        self.reset_fluid_b(&mut d.b);
        let whole = Region::whole(&self.grid);
        for c in 0..d.b.len() {
            let wt = if c < 3 { &self.w } else { &self.edge[c - 3].wc };
            let rates = (
                &mut d.advection[c],
                &mut d.advection_prev[c],
                &mut d.stretching[c],
            );
            whole.for_each(rates, |l, (a, p, s)| {
                for (n, _) in wt
                    .at(&l, [0; 3])
                    .iter()
                    .enumerate()
                    .filter(|(_, w)| **w == 0.0)
                {
                    (a[n], p[n], s[n]) = (0.0, 0.0, 0.0);
                }
            });
        }
    }

    /// Reset B (not its rates) to the identity where there is no solid (`w = 0`, the
    /// corners: `w_c = 0`). The end-of-step update calls it before it takes the next step's
    /// rates, which then see the fluid undeformed (see "Pure fluid" in the module docs).
    pub(super) fn reset_fluid_b(&self, b: &mut [Field]) {
        for (c, b) in b.iter_mut().enumerate() {
            let (wt, one) = if c < 3 {
                (&self.w, 1.0)
            } else {
                (&self.edge[c - 3].wc, 0.0)
            };
            for (b, &w) in b.data_mut().iter_mut().zip(wt.data()) {
                if w == 0.0 {
                    *b = one;
                }
            }
        }
    }
}
