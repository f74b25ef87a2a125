//! The interface weights: `φ^{1/2}` at centres, the corners' solid fraction from the PLIC
//! quarter cells and their series factors, the solid bounding box, and the reset of pure-fluid
//! cells.

use super::{Kernels, NEAR, PHI_MIN, Window};
use efsi_core::Field;
use efsi_linalg::par;

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
    /// The weights `w = φ^{1/2}` (centres, ghosts included) and their corner averages, from `phi`
    /// with ghosts filled.
    pub(super) fn set_weights(&mut self, phi: &Field) {
        let (nx, ny) = self.nxy();
        // Every entry, ghosts included (one padded shape for all fields), in parallel chunks.
        let pd = phi.data();
        par::chunks(self.w.data_mut()).for_each(|o, w| {
            for (w, f) in w.iter_mut().zip(&pd[o..]) {
                *w = if *f < PHI_MIN { 0.0 } else { f.min(1.0).sqrt() };
            }
        });
        // The bounding boxes of the solid (`w > 0`) and of any material (`φ > 0`).
        let (mut c, mut m) = (Window::new(nx, -1, ny, -1), Window::new(nx, -1, ny, -1));
        let wd = self.w.data();
        for j in -1..=ny {
            let o = self.w.idx(-1, j);
            for (f, d, b) in [(wd, 0.0, &mut c), (pd, 0.0, &mut m)] {
                let row = &f[o..o + (nx + 2) as usize];
                if let Some(first) = row.iter().position(|&w| w > d) {
                    let last = row.iter().rposition(|&w| w > d).unwrap_or(first);
                    *b = Window::new(
                        b.i0.min(first as isize - 1),
                        b.i1.max(last as isize - 1),
                        b.j0.min(j),
                        b.j1.max(j),
                    );
                }
            }
        }
        self.solid_c = if c.i0 > c.i1 { Window::EMPTY } else { c };
        self.solid_k = self.solid_c.corners(nx, ny);
        // Where B can matter: the material grown by `NEAR` cells (see `Kernels::near_c`).
        self.near_c = if m.i0 > m.i1 {
            Window::EMPTY
        } else {
            Window::new(
                (m.i0 - NEAR).max(-1),
                (m.i1 + NEAR).min(nx),
                (m.j0 - NEAR).max(-1),
                (m.j1 + NEAR).min(ny),
            )
        };
        self.near_k = self.near_c.corners(nx, ny);
        let (mu_f, mu_s) = (self.mu_f, self.mu_s);
        let g = efsi_core::G;
        // Corners none of whose cells holds solid: no weight, no series factors, the plain
        // average, and a normal of no consequence (it multiplies a zero extra shear rate).
        for f in [&mut self.wc, &mut self.wk, &mut self.ks, &mut self.rc] {
            f.fill(0.0);
        }
        self.sf.fill(1.0);
        self.ny2.fill(0.5);
        for f in &mut self.kwt {
            f.fill(0.25);
        }
        let c = self.solid_c;
        if c.i0 > c.i1 {
            return;
        }
        self.set_quarters(phi);
        // The corners of the solid's centres, ghost corners included.
        let (i0, i1) = (c.i0.max(1 - g), (c.i1 + 1).min(nx + g));
        let (j0, j1) = (c.j0.max(1 - g), (c.j1 + 1).min(ny + g));
        for j in j0..=j1 {
            for i in i0..=i1 {
                self.wc[(i, j)] = 0.25
                    * (self.w[(i - 1, j - 1)]
                        + self.w[(i, j - 1)]
                        + self.w[(i - 1, j)]
                        + self.w[(i, j)]);
                // The corner's solid fraction: the four quarter cells around it.
                let cells = [(i - 1, j - 1, 3), (i, j - 1, 2), (i - 1, j, 1), (i, j, 0)];
                let q = cells.map(|(ci, cj, n)| self.quarter[n][(ci, cj)]);
                let a = 0.25 * (q[0] + q[1] + q[2] + q[3]);
                let lam = std::array::from_fn::<f64, 4, _>(|n| {
                    let (ci, cj, _) = cells[n];
                    if self.w[(ci, cj)] > 0.0 { q[n] } else { 0.0 }
                });
                let sum: f64 = lam.iter().sum();
                let solid = cells.map(|(ci, cj, _)| f64::from(u8::from(self.w[(ci, cj)] > 0.0)));
                let count: f64 = solid.iter().sum();
                // The interface normal ∝ ∇φ across the corner.
                let f = |ci: isize, cj: isize| phi[(ci, cj)].clamp(0.0, 1.0);
                let gx = f(i, j) + f(i, j - 1) - f(i - 1, j) - f(i - 1, j - 1);
                let gy = f(i, j) + f(i - 1, j) - f(i, j - 1) - f(i - 1, j - 1);
                let g2 = gx * gx + gy * gy;
                self.ny2[(i, j)] = if g2 > 0.0 { gy * gy / g2 } else { 0.5 };
                for n in 0..4 {
                    self.kwt[n][(i, j)] = if sum > 0.0 {
                        lam[n] / sum
                    } else if count > 0.0 {
                        solid[n] / count
                    } else {
                        0.25
                    };
                }
                // (w_k, s, 1/κ, r): fluid, solid, interface in series.
                let (wk, sf, ks, rc) = if self.wc[(i, j)] == 0.0 {
                    (0.0, 1.0, 0.0, 0.0)
                } else if a >= 1.0 {
                    (1.0, 1.0, 1.0, 0.0)
                } else if mu_f == 0.0 {
                    // An inviscid fluid carries no shear: neither does the interface.
                    (1.0, 1.0, 0.0, 0.0)
                } else {
                    // aκ = a + μ_s (1 − a)/μ_f: finite where the corner's quarters hold no
                    // solid (a = 0) beside a cell that does.
                    let ak = a + mu_s * (1.0 - a) / mu_f;
                    if ak > 0.0 {
                        let (sf, rc) = sliver_rates(a, ak, mu_f);
                        (1.0, sf, a / ak, rc)
                    } else {
                        // No solid at an inviscid solid's corner: no shear carried.
                        (1.0, 1.0, 0.0, 0.0)
                    }
                };
                self.wk[(i, j)] = wk;
                self.sf[(i, j)] = sf;
                self.ks[(i, j)] = ks;
                self.rc[(i, j)] = rc;
            }
        }
    }

    /// The solid fraction of each quarter of every centre ([`Kernels::quarter`]): in a cut cell
    /// of `[−1, nx] × [−1, ny]`, the share of the quarter below the cell's PLIC line (Youngs
    /// normal, the line cutting the cell's φ off a `dx × dy` cell, as the VOF reconstruction
    /// does in planar geometry); elsewhere φ (clamped to `[0, 1]`).
    pub(super) fn set_quarters(&mut self, phi: &Field) {
        let (nx, ny) = self.nxy();
        let (dx, dy) = (self.grid.dx, self.grid.dy);
        let pd = phi.data();
        // The cells around the solid's corners: its window and one more all round.
        let c = self.solid_c;
        let g = efsi_core::G;
        let (lo, hi) = (
            phi.idx(-g, (c.j0 - 1).max(-g)),
            phi.idx(-g, (c.j1 + 1).min(ny + g - 1)) + phi.stride(),
        );
        for q in &mut self.quarter {
            for (w, f) in q.data_mut()[lo..hi].iter_mut().zip(&pd[lo..hi]) {
                *w = f.clamp(0.0, 1.0);
            }
        }
        let c = self.solid_c;
        let s = phi.stride();
        for j in c.j0.max(-1)..=c.j1.min(ny) {
            for i in c.i0.max(-1)..=c.i1.min(nx) {
                let k = phi.idx(i, j);
                let f = pd[k];
                if f <= 0.0 || f >= 1.0 {
                    continue;
                }
                let cl = |k: usize| pd[k].clamp(0.0, 1.0);
                let b = [
                    [cl(k - s - 1), cl(k - s), cl(k - s + 1)],
                    [cl(k - 1), cl(k), cl(k + 1)],
                    [cl(k + s - 1), cl(k + s), cl(k + s + 1)],
                ];
                let (mx, my) = crate::vof::plic::youngs_normal(&b, dx, dy);
                let line = crate::vof::plic::Line::planar(mx, my, f, dx, dy);
                let (hx, hy) = (0.5 * dx, 0.5 * dy);
                let boxes = [
                    ((0.0, 0.0), (hx, hy)),
                    ((hx, 0.0), (dx, hy)),
                    ((0.0, hy), (hx, dy)),
                    ((hx, hy), (dx, dy)),
                ];
                for (n, (lo, hi)) in boxes.into_iter().enumerate() {
                    self.quarter[n].data_mut()[k] = line.area_fraction(lo, hi).clamp(0.0, 1.0);
                }
            }
        }
    }

    /// Reset B to the identity, and its rates to zero, where there is no solid (`w = 0`): the
    /// fluid has no memory of deformation, and B there only enters neighbouring averages and
    /// fluxes; this keeps it bounded (stale rates would otherwise compound step after step).
    pub(super) fn reset_fluid(&self, d: &mut super::Deformation) {
        self.reset_fluid_b(&mut d.b);
        for c in 0..4 {
            let wt = if c == 3 { &self.wc } else { &self.w };
            for (k, &w) in wt.data().iter().enumerate() {
                if w == 0.0 {
                    d.advection[c].data_mut()[k] = 0.0;
                    d.advection_prev[c].data_mut()[k] = 0.0;
                    d.stretching[c].data_mut()[k] = 0.0;
                }
            }
        }
    }

    /// Reset B (not its rates) to the identity where there is no solid (`w = 0`, the
    /// corners: `w_c = 0`). The end-of-step update calls it before it takes the next step's
    /// rates, which then see the fluid undeformed (see "Pure fluid" in the module docs).
    pub(super) fn reset_fluid_b(&self, b: &mut [Field; 4]) {
        for (c, b) in b.iter_mut().enumerate() {
            let (wt, one) = if c == 3 {
                (&self.wc, 0.0)
            } else {
                (&self.w, 1.0)
            };
            for (b, &w) in b.data_mut().iter_mut().zip(wt.data()) {
                if w == 0.0 {
                    *b = one;
                }
            }
        }
    }
}
