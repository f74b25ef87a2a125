//! A block multigrid preconditioner for implicit momentum systems whose stiff part acts like a
//! viscosity.
//!
//! **Matrix.** On the compact unknown faces ([`UnknownFaces`]: u first, then v) it takes
//! `A = M − K_η` with `M = diag(mass)` and `K_η = vol·∇·(2η D)` discretised as the viscous stage's
//! operator (see [`crate::viscous`]): normal stresses `2η ∂u/∂x`, `2η ∂v/∂y` with a cell field
//! `η`, shear `η_k (∂u/∂y + ∂v/∂x)` with a corner field `η_k`, the hoop term `2η u_r/r²`. The
//! coefficients are *effective viscosities times Δt* — `θΔt μ` for the viscous step, plus
//! `(Δt²/2) G_eff` for the elastic step, whose implicit tangent acts like an extra viscosity
//! `GΔt/2` (see [`crate::elastic`]). The preconditioner keeps the u–u and v–v diagonal blocks
//! of `A`, two five-point symmetric M-matrices (the u–v coupling of the shear stress is
//! dropped, and left to the Krylov solver): each diagonal is the mass plus the sum of every
//! coupling of the row, wall ones included, so the blocks are diagonally dominant.
//!
//! **Cycle.** One multigrid V(1,1)-cycle per block ([`Multigrid`], the mass carried whole to the
//! coarse levels): symmetric positive definite, so it serves conjugate gradients as well as
//! BiCGSTAB. Rows run in parallel with fixed results ([`efsi_linalg::par`]): the same bits
//! on any number of threads. [`ViscousBlocks::new`] allocates the hierarchies; later set-ups and
//! applications allocate nothing.

use efsi_core::{BoundarySet, Field, Grid, bc::UnknownFaces};
use efsi_linalg::{Multigrid, Preconditioner, Stencil5};

/// Where the blocks' diagonals come from (see [`ViscousBlocks::setup`]).
#[derive(Clone, Copy)]
pub(crate) enum Diagonal<'a> {
    /// The mass of each unknown; the diagonal is it plus the row's couplings.
    FromMass(&'a [f64]),
    /// The diagonal itself.
    Given(&'a [f64]),
}

/// Multigrid on the u–u and v–v blocks of `M − K_η` (see the module docs).
pub(crate) struct ViscousBlocks {
    faces: UnknownFaces,
    au: Stencil5,
    av: Stencil5,
    mu: Multigrid,
    mv: Multigrid,
}

impl ViscousBlocks {
    /// The blocks of `grid` under `bc`, hierarchies allocated (with a unit placeholder matrix).
    pub(crate) fn new(grid: &Grid, bc: &BoundarySet) -> Self {
        let faces = UnknownFaces::new(grid, bc);
        let nur = (faces.ux.hi - faces.ux.lo).max(0) as usize;
        let nvr = (faces.vy.hi - faces.vy.lo).max(0) as usize;
        let mg = || Multigrid::new(1).with_w_cycle(false).with_excess_scale(1.0);
        let mut b = ViscousBlocks {
            faces,
            au: Stencil5::new(nur, grid.ny, bc.periodic(0), bc.periodic(1)),
            av: Stencil5::new(grid.nx, nvr, bc.periodic(0), bc.periodic(1)),
            mu: mg(),
            mv: mg(),
        };
        b.au.diag.fill(1.0);
        b.av.diag.fill(1.0);
        if !b.au.is_empty() {
            b.mu.setup(&b.au);
        }
        if !b.av.is_empty() {
            b.mv.setup(&b.av);
        }
        b
    }

    /// Assemble the blocks of `diag(mass) − K_η` for the cell coefficients `scale·eta` and the
    /// corner coefficients `scale·eta_k` (both ≥ 0, viscosity × time), then refresh the
    /// hierarchies. The blocks' diagonals are the mass plus the row's couplings, or `diagonal`
    /// itself when given (the viscous stage passes its operator's, wall terms exact).
    pub(crate) fn setup(
        &mut self,
        g: &Grid,
        diagonal: Diagonal,
        eta: &Field,
        eta_k: &Field,
        scale: f64,
    ) {
        let m = &g.metric;
        let (dx, dy) = (g.dx, g.dy);
        let (e, ek) = (eta.data(), eta_k.data());
        let s = eta.stride();
        let (ux, vy) = (self.faces.ux, self.faces.vy);
        let (nur, nx, ny) = (self.au.nx, g.nx, g.ny);
        let (px, py) = (self.au.periodic_x, self.au.periodic_y);
        for j in 0..ny {
            for c in 0..nur {
                let i = ux.lo + c as isize;
                let k = eta.idx(i, j as isize);
                let kc = j * nur + c;
                // u(i) – u(i+1) through the normal stress at cell i; u(j) – u(j+1) through the
                // shear stress at corner (i, j+1).
                let east = scale * dy * m.rc(i) * 2.0 * e[k] / dx;
                let north = scale * dx * m.rx(i) * ek[k + s] / dy;
                self.au.east[kc] = if c + 1 < nur || px { east } else { 0.0 };
                self.au.north[kc] = if j + 1 < ny || py { north } else { 0.0 };
                self.au.diag[kc] = match diagonal {
                    Diagonal::Given(d) => d[kc],
                    Diagonal::FromMass(mass) => {
                        let west = scale * dy * m.rc(i - 1) * 2.0 * e[k - 1] / dx;
                        let south = scale * dx * m.rx(i) * ek[k] / dy;
                        let h = m.hoop_x(i);
                        let hoop = scale * dx * dy * m.rx(i) * (e[k - 1] + e[k]) * h * h;
                        mass[kc] + east + west + north + south + hoop
                    }
                };
            }
        }
        let nu = nur * ny;
        let nvr = self.av.ny;
        for jr in 0..nvr {
            let j = vy.lo + jr as isize;
            for i in 0..nx {
                let k = eta.idx(i as isize, j);
                let kc = jr * nx + i;
                let ii = i as isize;
                let east = scale * dy * m.rx(ii + 1) * ek[k + 1] / dx;
                let north = scale * dx * m.rc(ii) * 2.0 * e[k] / dy;
                self.av.east[kc] = if i + 1 < nx || px { east } else { 0.0 };
                self.av.north[kc] = if jr + 1 < nvr || py { north } else { 0.0 };
                self.av.diag[kc] = match diagonal {
                    Diagonal::Given(d) => d[nu + kc],
                    Diagonal::FromMass(mass) => {
                        let west = scale * dy * m.rx(ii) * ek[k] / dx;
                        let south = scale * dx * m.rc(ii) * 2.0 * e[k - s] / dy;
                        mass[nu + kc] + east + west + north + south
                    }
                };
            }
        }
        if !self.au.is_empty() {
            self.mu.setup(&self.au);
        }
        if !self.av.is_empty() {
            self.mv.setup(&self.av);
        }
    }
}

impl Preconditioner for ViscousBlocks {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let nu = self.au.len();
        let (zu, zv) = z.split_at_mut(nu);
        if nu > 0 {
            self.mu.apply(&r[..nu], zu);
        }
        if !self.av.is_empty() {
            self.mv.apply(&r[nu..], zv);
        }
    }
}
