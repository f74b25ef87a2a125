//! The coupled elastic step (`numerics.elastic.coupling: Coupled`): the implicit
//! viscous–elastic system solved together with the divergence constraint.
//!
//! # The system
//!
//! With `A = M − θΔt K_v − (Δt²/2) K_J` the elastic step's operator, `G` the discrete gradient
//! and `D` the divergence of the projection (`D = −Gᵀ` on the MAC grid, face volumes in `G`),
//! the split step solves `A δ = b` and then projects with the mass alone,
//! `M δ_p = −Δt G p`, `D(V + δ_p) = 0`. The correction `δ_p` strains the solid (`B̃^{n+1}` is
//! stretched by it) without the solid's stiffness answering within the step: the strain is
//! stored at stiffness G and given back next step, which pumps energy once the shear wave
//! crosses ≈ 5 cells a step. The coupled step asks the correction to meet the same implicit
//! stiffness:
//!
//! ```text
//!   A δ_p = −Δt G p,   D (V^{n+2/3} + δ_p) = 0      (a saddle-point system in δ_p and p)
//! ```
//!
//! so that `V^{n+2/3} + δ_p` is divergence-free and `B̃(V^{n+2/3} + δ_p)` is the deformation
//! the stiffness was solved with. Eliminating `δ_p`, the pressure solves the Schur complement
//! `S p = D V^{n+2/3}/Δt`, `S = −D A⁻¹ G`.
//!
//! # The iteration
//!
//! Flexible GMRES (restarted every `RESTART` iterations) on the Schur complement in the
//! volume fluxes: find `p` with `F(Δ(p)) = −F(V^{n+2/3})`, `F` the net outflux of each cell and
//! `Δ(p)` the solution of `A Δ = −Δt G p` (BiCGSTAB, the elastic step's preconditioner), until
//! the residual's norm is `coupling_tolerance` × its start; then `V += Δ(p)` (kept from the
//! iterations, no extra solve) and the pressure is left in the state. The projection stage
//! removes what divergence is left with the mass alone (it solves for it from zero and adds
//! its pressure). Plain Richardson (Uzawa) with the same preconditioner stalls: a cell with a
//! sliver of solid has air's mass but stiff faces, and the preconditioner's eigenvalues spread
//! over (0, 3] there. The preconditioner is Cahouet–Chabard's for unsteady Stokes:
//! per unit volume `A ≈ ρ − η Δ` with `η = θΔt μ + (Δt²/2) G_eff` (the effective viscosity of
//! the block multigrid), and on a gradient `A ∇q = ∇(ρ q − 2η Δq)`, so
//!
//! ```text
//!   S⁻¹ ≈ Δt⁻¹ (ρ Δ⁻¹ + 2η)   ⇒   q = s − (2η/Δt) ∇·V,   ∇·(∇s/ρ) = ∇·V/Δt
//! ```
//!
//! — the projection's own Poisson solve plus a local term, exact for uniform coefficients
//! (one iteration), and in a fluid (`G_eff = 0`, `η = θΔt μ`) the viscous-coupled projection.
//! Each iteration costs one Poisson solve (multigrid-preconditioned CG) and one solve with `A`
//! (BiCGSTAB, the elastic step's preconditioner).

use super::err;
use super::solve::ElasticStage;
use crate::projection;
use crate::viscous_operator::CompactFaces;
use efsi_core::ops;
use efsi_core::{Field, StageError, State, StepContext};
use efsi_linalg::par::for_each_row;
use efsi_linalg::{Multigrid, Norm, Pcg, Stencil5};

/// Krylov vectors kept before FGMRES restarts.
const RESTART: usize = 30;

/// The coupled step's work space: the projection's Poisson system and vectors.
pub(super) struct Coupling {
    /// Stop when the divergence left is this fraction of the elastic step's (scene
    /// `numerics.elastic.coupling_tolerance`), or the projection's tolerance.
    pub(super) rel_tol: f64,
    pub(super) proj_tol: f64,
    pub(super) max_iter: usize,
    poisson: Stencil5,
    mg: Multigrid,
    pcg: Pcg,
    /// Per cell: the Poisson right-hand side, its solution, the residual weights `Δt²/dV`.
    b: Vec<f64>,
    s: Vec<f64>,
    weight: Vec<f64>,
    /// A pressure as a cell field with ghosts (for its gradient), and the pressure found.
    q: Field,
    p: Field,
    /// FGMRES: the Arnoldi basis (flux residuals), the preconditioned vectors (pressures),
    /// the velocity increments `Δ(z_i)`, the Hessenberg matrix, Givens rotations and the
    /// residual's projections.
    basis: Vec<Vec<f64>>,
    z: Vec<Vec<f64>>,
    dz: Vec<Vec<f64>>,
    h: Vec<Vec<f64>>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    /// Per unknown face: the right-hand side `−Δt G z`; per cell: the flux change `F(Δ)`.
    rhs: Vec<f64>,
    w: Vec<f64>,
    /// The step's velocity increment `Δ(p)` (per unknown face), the residual at a restart (per
    /// cell) and the restart's Krylov coefficients: allocated once.
    total: Vec<f64>,
    y0: Vec<f64>,
    coef: Vec<f64>,
    /// The Δt of `weight` (it changes only with Δt).
    weight_dt: f64,
}

/// What one coupled step did.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CouplingStats {
    /// Uzawa iterations, and the inner solves' iterations summed.
    pub(super) iterations: usize,
    pub(super) inner: usize,
    /// `max |∇·V|·Δt` after the elastic step, and after the coupling.
    pub(super) before: f64,
    pub(super) after: f64,
}

impl Coupling {
    pub(super) fn new(
        grid: &efsi_core::Grid,
        bc: &efsi_core::BoundarySet,
        faces: usize,
        el: &super::ElasticOptions,
        proj_tol: f64,
    ) -> Self {
        let n = grid.cells();
        Coupling {
            rel_tol: el.coupling_tolerance,
            proj_tol,
            max_iter: el.coupling_iterations,
            poisson: Stencil5::new(grid.nx, grid.ny, bc.periodic(0), bc.periodic(1)),
            mg: Multigrid::new(2),
            pcg: Pcg::new(n),
            b: vec![0.0; n],
            s: vec![0.0; n],
            weight: vec![0.0; n],
            q: Field::zeros(grid),
            p: Field::zeros(grid),
            basis: vec![vec![0.0; n]; RESTART + 1],
            z: vec![vec![0.0; n]; RESTART],
            dz: vec![vec![0.0; faces]; RESTART],
            h: vec![vec![0.0; RESTART]; RESTART + 1],
            cs: vec![0.0; RESTART],
            sn: vec![0.0; RESTART],
            g: vec![0.0; RESTART + 1],
            rhs: vec![0.0; faces],
            w: vec![0.0; n],
            total: vec![0.0; faces],
            y0: vec![0.0; n],
            coef: vec![0.0; RESTART],
            weight_dt: f64::NAN,
        }
    }
}

impl ElasticStage {
    /// The coupled step after the elastic solve (see the module docs): FGMRES on the pressure
    /// until the divergence left is small, the velocity updated through `A`; the pressure
    /// found is left in the state for the projection stage to complete.
    pub(super) fn couple(
        &mut self,
        ctx: &StepContext,
        state: &mut State,
        d: &super::Deformation,
    ) -> Result<CouplingStats, StageError> {
        let Some(mut cp) = self.coupling.take() else {
            return Ok(CouplingStats::default());
        };
        let r = self.couple_with(&mut cp, ctx, state, d);
        self.coupling = Some(cp);
        r
    }

    fn couple_with(
        &mut self,
        cp: &mut Coupling,
        ctx: &StepContext,
        state: &mut State,
        d: &super::Deformation,
    ) -> Result<CouplingStats, StageError> {
        let g = ctx.grid;
        let bc = ctx.bc;
        let dt = ctx.dt;
        let (nx, ny) = (g.nx, g.ny);
        let n = nx * ny;
        // The effective viscosities η at the centres (the block multigrid's).
        self.effective_viscosity(d);
        projection::assemble(&mut cp.poisson, g, bc, &state.rho);
        cp.mg.setup(&cp.poisson);
        if dt != cp.weight_dt {
            for_each_row(&mut cp.weight, nx, |_, row| {
                for (i, w) in row.iter_mut().enumerate() {
                    *w = dt * dt / g.cell_volume(i as isize);
                }
            });
            cp.weight_dt = dt;
        }
        let singular = !bc.has_pressure_reference();
        let max_div = |f: &[f64]| -> f64 {
            let mut worst = 0.0f64;
            for j in 0..ny {
                for i in 0..nx {
                    worst = worst.max((f[j * nx + i] / g.cell_volume(i as isize)).abs() * dt);
                }
            }
            worst
        };
        // The net outfluxes of V^{n+2/3}: the target is F(Δ(p)) = −F.
        bc.fill_velocity(g, &mut state.u, &mut state.v, ctx.t + dt, false);
        let y = &mut cp.basis[0];
        for j in 0..ny {
            for i in 0..nx {
                y[j * nx + i] = -ops::net_outflux(g, &state.u, &state.v, i as isize, j as isize);
            }
        }
        let mut stats = CouplingStats {
            before: max_div(&cp.basis[0]),
            ..CouplingStats::default()
        };
        cp.p.fill(0.0);
        cp.total.fill(0.0);
        cp.y0.copy_from_slice(&cp.basis[0]);
        let beta0 = norm(&cp.y0);
        let target = cp.rel_tol * beta0;
        let mut beta = beta0;
        while beta > target && stats.before > cp.proj_tol && stats.iterations < cp.max_iter {
            // A restart cycle from the current residual y0.
            for (b, y) in cp.basis[0].iter_mut().zip(&cp.y0) {
                *b = y / beta;
            }
            cp.g.fill(0.0);
            cp.g[0] = beta;
            let mut k = 0;
            while k < RESTART && stats.iterations < cp.max_iter {
                stats.iterations += 1;
                // z_k = P⁻¹ v_k: the projection's Poisson solve plus the local term.
                {
                    let v = &cp.basis[k];
                    for (b, v) in cp.b.iter_mut().zip(v) {
                        *b = v / dt;
                    }
                    if singular {
                        let mean = cp.b.iter().sum::<f64>() / n as f64;
                        cp.b.iter_mut().for_each(|b| *b -= mean);
                    }
                    cp.s.fill(0.0);
                    let st = cp.pcg.solve_norm(
                        &mut cp.poisson,
                        &cp.mg,
                        &cp.b,
                        &mut cp.s,
                        1e-3 * cp.rel_tol * max_div(v).max(f64::MIN_POSITIVE),
                        10_000,
                        Norm::MaxWeighted(&cp.weight),
                    );
                    stats.inner += st.iterations;
                    let z = &mut cp.z[k];
                    for j in 0..ny {
                        for i in 0..nx {
                            let c = j * nx + i;
                            let (ii, jj) = (i as isize, j as isize);
                            z[c] = cp.s[c]
                                + 2.0 * self.eta[(ii, jj)] * v[c] / (dt * g.cell_volume(ii));
                        }
                    }
                }
                // w = S z_k = F(Δ(z_k)), Δ(z_k) kept.
                let it = self.flux_response(cp, k, ctx, d)?;
                stats.inner += it;
                // Arnoldi (modified Gram–Schmidt).
                for i in 0..=k {
                    let hij = dot(&cp.w, &cp.basis[i]);
                    cp.h[i][k] = hij;
                    for (w, b) in cp.w.iter_mut().zip(&cp.basis[i]) {
                        *w -= hij * b;
                    }
                }
                let hn = norm(&cp.w);
                cp.h[k + 1][k] = hn;
                if hn > 0.0 {
                    for (b, w) in cp.basis[k + 1].iter_mut().zip(&cp.w) {
                        *b = w / hn;
                    }
                }
                // Givens rotations.
                for i in 0..k {
                    let (a, b) = (cp.h[i][k], cp.h[i + 1][k]);
                    cp.h[i][k] = cp.cs[i] * a + cp.sn[i] * b;
                    cp.h[i + 1][k] = -cp.sn[i] * a + cp.cs[i] * b;
                }
                let (a, b) = (cp.h[k][k], cp.h[k + 1][k]);
                let rr = a.hypot(b);
                let (c, s) = if rr > 0.0 {
                    (a / rr, b / rr)
                } else {
                    (1.0, 0.0)
                };
                cp.cs[k] = c;
                cp.sn[k] = s;
                cp.h[k][k] = rr;
                cp.h[k + 1][k] = 0.0;
                cp.g[k + 1] = -s * cp.g[k];
                cp.g[k] *= c;
                beta = cp.g[k + 1].abs();
                k += 1;
                if beta <= target || hn == 0.0 {
                    break;
                }
            }
            // Solve the triangular system and update p and the velocity increment.
            let coef = &mut cp.coef[..k];
            for i in (0..k).rev() {
                let mut sum = cp.g[i];
                for j in i + 1..k {
                    sum -= cp.h[i][j] * coef[j];
                }
                coef[i] = sum / cp.h[i][i];
            }
            for (i, c) in coef.iter().enumerate() {
                for j in 0..ny {
                    for ii in 0..nx {
                        cp.p[(ii as isize, j as isize)] += c * cp.z[i][j * nx + ii];
                    }
                }
                for (t, dz) in cp.total.iter_mut().zip(&cp.dz[i]) {
                    *t += c * dz;
                }
            }
            // The true residual for the restart: y0 = −F(V) − F(Δ(p)).
            self.op
                .k
                .faces
                .scatter(&cp.total, &mut self.scratch.xu, &mut self.scratch.xv);
            bc.fill_velocity(g, &mut self.scratch.xu, &mut self.scratch.xv, 0.0, true);
            for j in 0..ny {
                for i in 0..nx {
                    let (ii, jj) = (i as isize, j as isize);
                    cp.y0[j * nx + i] = -ops::net_outflux(g, &state.u, &state.v, ii, jj)
                        - ops::net_outflux(g, &self.scratch.xu, &self.scratch.xv, ii, jj);
                }
            }
            beta = norm(&cp.y0);
            if !beta.is_finite() {
                return Err(err(
                    "elastic",
                    format!(
                        "coupled step: the divergence became {beta} after {} iterations",
                        stats.iterations
                    ),
                ));
            }
        }
        stats.after = max_div(&cp.y0);
        // V += Δ(p); the pressure for the projection to complete (it adds what it finds).
        {
            let (u, v) = (&mut state.u, &mut state.v);
            self.op.k.faces.for_each(|c, is_u, q| {
                if is_u {
                    u.data_mut()[q] += cp.total[c];
                } else {
                    v.data_mut()[q] += cp.total[c];
                }
            });
        }
        if singular {
            let mut sum = 0.0;
            for j in 0..ny as isize {
                for i in 0..nx as isize {
                    sum += cp.p[(i, j)];
                }
            }
            let mean = sum / n as f64;
            for j in 0..ny as isize {
                for i in 0..nx as isize {
                    cp.p[(i, j)] -= mean;
                }
            }
        }
        state.p.copy_from(&cp.p);
        bc.fill_scalar(g, &mut state.p, true);
        Ok(stats)
    }

    /// `w = F(Δ(z_k))`: the velocity increment the pressure `z_k` drives through `A`
    /// (`A Δ = −Δt G z_k`, kept as `dz[k]`) and the net outflux it makes in each cell.
    /// Returns BiCGSTAB's iterations.
    fn flux_response(
        &mut self,
        cp: &mut Coupling,
        k: usize,
        ctx: &StepContext,
        d: &super::Deformation,
    ) -> Result<usize, StageError> {
        let g = ctx.grid;
        let (nx, ny) = (g.nx, g.ny);
        for j in 0..ny {
            for i in 0..nx {
                cp.q[(i as isize, j as isize)] = cp.z[k][j * nx + i];
            }
        }
        ctx.bc.fill_scalar(g, &mut cp.q, true);
        let (m, (dx, dy)) = (&g.metric, (g.dx, g.dy));
        let q = &cp.q;
        let s = q.stride();
        let dt = ctx.dt;
        let rhs = &mut cp.rhs;
        self.op.k.faces.for_each(|c, is_u, f| {
            let i = (f % s) as isize - efsi_core::G;
            rhs[c] = if is_u {
                -dt * m.rx(i) * dy * (q.data()[f] - q.data()[f - 1])
            } else {
                -dt * m.rc(i) * dx * (q.data()[f] - q.data()[f - s])
            };
        });
        let bnorm = norm(&cp.rhs);
        let delta = &mut cp.dz[k];
        delta.fill(0.0);
        let st = if bnorm > 0.0 {
            let st = self.solve_a(d, &cp.rhs, delta, 1e-2 * cp.rel_tol * bnorm);
            if !st.converged {
                return Err(err(
                    "elastic",
                    format!(
                        "coupled step: BiCGSTAB did not converge in {} iterations (relative residual {:.3e}); raise numerics.elastic.max_iterations or reduce the time step",
                        st.iterations,
                        st.residual / bnorm
                    ),
                ));
            }
            st.iterations
        } else {
            0
        };
        let sc = &mut self.scratch;
        self.op.k.faces.scatter(&cp.dz[k], &mut sc.xu, &mut sc.xv);
        ctx.bc.fill_velocity(g, &mut sc.xu, &mut sc.xv, 0.0, true);
        for j in 0..ny {
            for i in 0..nx {
                cp.w[j * nx + i] = ops::net_outflux(g, &sc.xu, &sc.xv, i as isize, j as isize);
            }
        }
        Ok(st)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
