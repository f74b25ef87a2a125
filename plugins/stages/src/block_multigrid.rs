//! A block multigrid preconditioner for implicit momentum systems whose stiff part acts like a
//! viscosity.
//!
//! **Matrix.** On the compact unknown faces ([`UnknownFaces`]: u first, then v) it takes
//! `A = M − K_η`, `K_η = vol·∇·(2η D)` with the coefficients of the one viscous operator
//! ([`crate::viscous_operator`]) — `η = θΔt μ` for the viscous step, plus `(Δt²/2) G_eff` for the
//! elastic step, whose implicit tangent acts like an extra viscosity `GΔt/2` (see
//! [`crate::elastic`]). The preconditioner keeps the u–u and v–v diagonal blocks of `A`
//! ([`Coefficients::blocks`]), two five-point symmetric M-matrices (the u–v coupling of the shear
//! stress is dropped, and left to the Krylov solver), with the diagonal the caller gives: the
//! operator's own, or the mass plus every coupling of the row, wall ones included
//! ([`Coefficients::diagonal`]), so the blocks are diagonally dominant.
//!
//! **Cycle.** One multigrid V(1,1)-cycle per block ([`Multigrid`], the mass carried whole to the
//! coarse levels): symmetric positive definite, so it serves conjugate gradients as well as
//! BiCGSTAB. Rows run in parallel with fixed results ([`efsi_linalg::par`]): the same bits
//! on any number of threads. [`ViscousBlocks::new`] allocates the hierarchies; later set-ups and
//! applications allocate nothing.

use crate::faces::UnknownFaces;
use crate::viscous_operator::Coefficients;
use efsi_core::{BoundarySet, Grid};
use efsi_linalg::{Multigrid, Preconditioner, Stencil5};

/// Multigrid on the u–u and v–v blocks of `M − K_η` (see the module docs).
pub(crate) struct ViscousBlocks {
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

    /// Take the blocks of `diag(diagonal) − K` from the coefficients `k` and refresh the
    /// hierarchies.
    pub(crate) fn setup(&mut self, k: &Coefficients, diagonal: &[f64]) {
        k.blocks(diagonal, &mut self.au, &mut self.av);
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
